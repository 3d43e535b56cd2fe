// One right-hand side of the plant beside its back-end's forward dynamics, in
// the same run (issue 17's target: f of the 6-joint plant at most twice the
// forward dynamics' time). Per scene: fd/<scene> times the scene's back-end
// on the simulated arm (held links merged) at the initial state's q, qd and a
// fixed torque; rhs/<scene> times Plant::rhs at the initial state, each call
// at a new time (1e-5 s apart, cycling through [0.5, 1.5] s, inside the
// reference's first smooth piece), so that the reference is evaluated at
// every call as in an integration; its counter ratio_to_fd is its time over
// fd/<scene>'s, which runs first. rhs-exact-reference/<scene>: the same
// with the inverse kinematics at every call (PlantConfig::tabulate_reference
// off), as before the reference was tabulated. The scenes: the PUMA's two
// headline scenes (6 and 3 joints), the Panda tracking a Cartesian path (7
// joints, redundant: the reference's inverse kinematics follows the
// redundancy rule), and random12, a random 12-joint chain
// (random_chain(12, 12)) as planar2_passive's passive arm with viscous
// friction (no reference: no rhs-exact-reference row). residual/<scene>:
// the plant's implicit form F(t, x, x') (Plant::residual: inverse dynamics
// on the speeds' rows, no factorisation of H) at the same points with x' =
// f(t0, x), each call at a new time as rhs's; its counter ratio_to_rhs is its
// time over rhs/<scene>'s, which runs first.
//
//   bench_plant --benchmark_out=results/bench/plant.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "experiments/bench_main.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_writer.hpp"
#include "models/scene/scene.hpp"

namespace {

struct BenchScene {
  const char* name;
  bool reference;  // a reference to evaluate (the rhs-exact-reference row)
};
const BenchScene kScenes[] = {
    {"paper_slow_6dof_hybrid", true}, {"paper_slow", true}, {"panda_tracking", true}, {"random12", false}};
constexpr int kSceneCount = sizeof kScenes / sizeof kScenes[0];

std::string scene_file(const std::string& name) { return std::string(PUMASIM_SCENES_DIR) + "/" + name + ".toml"; }

// random12: its robot file written once under /tmp, removed at exit.
struct RandomRobotFile {
  std::string path = "/tmp/pumasim_bench_random12_" + std::to_string(::getpid()) + ".toml";
  RandomRobotFile() {
    std::ofstream(path) << pumasim::robot_file_text(pumasim::random_chain(12, 12), "bench_plant: random_chain(12, 12)");
  }
  ~RandomRobotFile() { std::remove(path.c_str()); }
};

pumasim::Scene load(int k) {
  if (std::string(kScenes[k].name) != "random12") return pumasim::load_scene(scene_file(kScenes[k].name));
  static const RandomRobotFile robot;
  return pumasim::load_scene(scene_file("planar2_passive"),
                             {"scene.name=\"random12\"", "scene.robot=\"" + robot.path + "\"", "scene.joints=12",
                              "friction.viscous=0.01", "initial.q=[0.1, -0.2, 0.3, 0.1, -0.2, 0.3, 0.1, -0.2, 0.3, 0.1, -0.2, 0.3]"});
}

double fd_ns[kSceneCount] = {};   // per scene, from the fd benchmark
double rhs_ns[kSceneCount] = {};  // and from the rhs benchmark (the table's)

double per_call_ns(benchmark::State& state, std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double, std::nano>(d).count() / static_cast<double>(state.iterations());
}

void fd(benchmark::State& state, int k) {
  const pumasim::Scene sc = load(k);
  pumasim::Plant plant(sc.plant);
  std::vector<double> x(plant.size());
  plant.initial_state(x.data());
  const int n = plant.layout().n;
  const pumasim::RobotModel model = pumasim::simulated_robot(sc.plant.robot, n, sc.plant.q_held);
  auto backend = pumasim::find_backend(sc.plant.backend).make(model);
  Eigen::VectorXd q(n), qd(n), tau = Eigen::VectorXd::Constant(n, 1.0), out(n);
  for (int j = 0; j < n; ++j) q[j] = x[plant.layout().q + j], qd[j] = 0.1;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    backend->forward_dynamics(q, qd, tau, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  fd_ns[k] = per_call_ns(state, std::chrono::steady_clock::now() - start);
  state.counters["n"] = n;
}

void rhs(benchmark::State& state, int k, bool table) {
  pumasim::Scene sc = load(k);
  sc.plant.tabulate_reference = table;
  pumasim::Plant plant(sc.plant);
  std::vector<double> x(plant.size()), f(plant.size());
  plant.initial_state(x.data());
  double t = 0.5;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    t = t < 1.5 ? t + 1e-5 : 0.5;
    plant.rhs(t, x.data(), f.data());
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  const double ns = per_call_ns(state, std::chrono::steady_clock::now() - start);
  if (table) rhs_ns[k] = ns;
  state.counters["n"] = plant.layout().n;
  if (fd_ns[k] > 0) state.counters["ratio_to_fd"] = ns / fd_ns[k];
}

void residual(benchmark::State& state, int k) {
  const pumasim::Scene sc = load(k);
  pumasim::Plant plant(sc.plant);
  std::vector<double> x(plant.size()), xp(plant.size()), r(plant.size());
  plant.initial_state(x.data());
  plant.rhs(0.5, x.data(), xp.data());
  double t = 0.5;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    t = t < 1.5 ? t + 1e-5 : 0.5;
    plant.residual(t, x.data(), xp.data(), r.data());
    benchmark::DoNotOptimize(r.data());
    benchmark::ClobberMemory();
  }
  const double ns = per_call_ns(state, std::chrono::steady_clock::now() - start);
  state.counters["n"] = plant.layout().n;
  if (rhs_ns[k] > 0) state.counters["ratio_to_rhs"] = ns / rhs_ns[k];
}

}  // namespace

int main(int argc, char** argv) {
  for (int k = 0; k < kSceneCount; ++k) {
    const std::string name = kScenes[k].name;
    benchmark::RegisterBenchmark(("fd/" + name).c_str(), fd, k)->Unit(benchmark::kNanosecond);
    benchmark::RegisterBenchmark(("rhs/" + name).c_str(), rhs, k, true)->Unit(benchmark::kNanosecond);
    if (pumasim::why_no_implicit_form(load(k).plant).empty()) {  // the paper's rule has none
      benchmark::RegisterBenchmark(("residual/" + name).c_str(), residual, k)->Unit(benchmark::kNanosecond);
    }
    if (kScenes[k].reference) {
      benchmark::RegisterBenchmark(("rhs-exact-reference/" + name).c_str(), rhs, k, false)
          ->Unit(benchmark::kNanosecond);
    }
  }
  return pumasim::run_registered_benchmarks(argc, argv);
}
