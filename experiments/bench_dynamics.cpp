// Dynamics back-end benchmark: forward dynamics (fd), the mass matrix (H) and
// inverse dynamics (id, the RNEA for every RNEA-based back-end), per
// back-end, for the PUMA 560 (6 joints, and 3 joints with the wrist held) and
// random chains n = 3, 6, 12, 24, 48. Inputs are deterministic; every call
// goes through the DynamicsBackend interface (one virtual call per call, as in
// the ODE right-hand side). Each benchmark also carries the operation counts
// of one call (Counted scalar) as user counters, and each forward-dynamics
// benchmark those of H, c = C(q, qd) qd, g, the solve and inverse dynamics
// (prefixes H_, c_, g_, solve_, id_), so that one JSON file holds all;
// experiments/dynamics_table.py turns it into results/dynamics_backends.md.
// `jacobian` rows: the forward dynamics' exact derivatives dqdd/d(q, qd, tau)
// (DynamicsDerivatives: the back-end's h and H, the analytical partials of
// inverse dynamics, rnea_derivatives.hpp), per back-end beside its `fd`. `plant_rhs` and
// `plant_jacobian` rows: one right-hand side f(t, x) of a scene's plant and
// its exact Jacobian df/dx (Plant::jacobian_exact), for the 6-joint hybrid
// scene and the 3-joint paper scene, at the scene's initial state with the
// joints moving.
// The JSON's context names the build that ran (pumasim_flags: -march=native or
// not, pumasim_build_type, pumasim_compiler, pumasim_git_revision), from the
// build information fixed when the program was built (cmake/build_info.cmake).
//
//   bench_dynamics --benchmark_out=results/bench/dynamics.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "experiments/bench_main.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/dynamics_derivatives.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "models/scene/scene.hpp"

namespace {

using pumasim::Quantity;

struct Robot {
  std::string label;
  pumasim::RobotModel model;
};

std::vector<Robot> robots() {
  const pumasim::RobotModel puma = pumasim::load_robot("puma560");
  std::vector<Robot> r;
  r.push_back({"puma560", puma});
  // The paper's experiment: joints 1-3 move, the wrist is held at zero.
  r.push_back({"puma560-3", pumasim::lock_joints(puma, 3, Eigen::VectorXd::Zero(6))});
  for (int n : {3, 6, 12, 24, 48}) {
    r.push_back({"random" + std::to_string(n), pumasim::random_chain(n, 1000 + n)});
  }
  return r;
}

void add_counts(benchmark::State& state, const std::string& prefix, const pumasim::OpCounts& ops) {
  state.counters[prefix + "mul"] = static_cast<double>(ops.mul);
  state.counters[prefix + "add"] = static_cast<double>(ops.add);
  state.counters[prefix + "div"] = static_cast<double>(ops.div);
  state.counters[prefix + "sqrt"] = static_cast<double>(ops.sqrt);
  state.counters[prefix + "trig"] = static_cast<double>(ops.trig);
}

void run(benchmark::State& state, const pumasim::BackendInfo* info, const pumasim::RobotModel* model,
         Quantity what) {
  const int n = model->dof();
  auto backend = info->make(*model);
  pumasim::Rng rng(42);
  const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5);
  const Eigen::VectorXd qd = rng.uniform_vector(n, -1.0, 1.0);
  const Eigen::VectorXd tau = rng.uniform_vector(n, -10.0, 10.0);
  const Eigen::VectorXd qdd_in = rng.uniform_vector(n, -5.0, 5.0);
  Eigen::VectorXd out(n);
  Eigen::MatrixXd H(n, n);
  for (auto _ : state) {
    switch (what) {
      case Quantity::kForwardDynamics: backend->forward_dynamics(q, qd, tau, out); break;
      case Quantity::kInverseDynamics: backend->inverse_dynamics(q, qd, qdd_in, out); break;
      default: backend->mass_matrix(q, H); break;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::DoNotOptimize(H.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = n;
  add_counts(state, "", info->count_ops(*model, what));
  if (what == Quantity::kForwardDynamics) {
    // The split the paper's claim needs, one standalone call each.
    for (const auto& [prefix, part] :
         {std::pair{"H_", Quantity::kMassMatrix}, std::pair{"c_", Quantity::kCoriolis},
          std::pair{"g_", Quantity::kGravity}, std::pair{"solve_", Quantity::kSolve},
          std::pair{"id_", Quantity::kInverseDynamics}}) {
      add_counts(state, prefix, info->count_ops(*model, part));
    }
  }
}

void run_jacobian(benchmark::State& state, const pumasim::BackendInfo* info, const pumasim::RobotModel* model) {
  const int n = model->dof();
  pumasim::DynamicsDerivatives d(*model, info->make(*model));
  pumasim::Rng rng(42);  // the inputs of `fd` (run above)
  const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5);
  const Eigen::VectorXd qd = rng.uniform_vector(n, -1.0, 1.0);
  const Eigen::VectorXd tau = rng.uniform_vector(n, -10.0, 10.0);
  Eigen::VectorXd qdd(n);
  Eigen::MatrixXd Dq(n, n), Dqd(n, n), Dt(n, n);
  for (auto _ : state) {
    d.forward_dynamics(q, qd, tau, qdd, Dq, Dqd, Dt);
    benchmark::DoNotOptimize(Dq.data());
    benchmark::DoNotOptimize(Dqd.data());
    benchmark::DoNotOptimize(Dt.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = n;
}

// One f(t, x) of the scene's plant, or its exact Jacobian.
void run_plant(benchmark::State& state, const std::string& scene, bool jacobian) {
  pumasim::Plant plant(pumasim::load_scene(std::string(PUMASIM_SCENES_DIR) + "/" + scene + ".toml").plant);
  const int m = plant.size();
  std::vector<double> x(m), f(m);
  plant.initial_state(x.data());
  const pumasim::StateLayout& L = plant.layout();
  for (int j = 0; j < L.n; ++j) x[L.qd + j] = 0.1 * (j + 1);
  plant.settle_modes(0.5, x.data());
  Eigen::MatrixXd J(m, m);
  for (auto _ : state) {
    if (jacobian) {
      plant.jacobian_exact(0.5, x.data(), J);
    } else {
      plant.rhs(0.5, x.data(), f.data());
    }
    benchmark::DoNotOptimize(J.data());
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  state.counters["m"] = m;
  state.counters["n"] = L.n;
}

}  // namespace

int main(int argc, char** argv) {
  static const std::vector<Robot> all = robots();
  for (const Robot& r : all) {
    for (const auto& info : pumasim::backends()) {
      if (!info.why_unsupported(r.model).empty()) continue;  // e.g. a closed form for another arm
      for (const auto& [label, what] :
           {std::pair{"fd", Quantity::kForwardDynamics}, std::pair{"H", Quantity::kMassMatrix},
            std::pair{"id", Quantity::kInverseDynamics}}) {
        const std::string name = std::string(label) + "/" + r.label + "/" + info.name;
        benchmark::RegisterBenchmark(name.c_str(), run, &info, &r.model, what)
            ->Unit(benchmark::kNanosecond);
      }
      const std::string name = "jacobian/" + r.label + "/" + info.name;
      benchmark::RegisterBenchmark(name.c_str(), run_jacobian, &info, &r.model)->Unit(benchmark::kNanosecond);
    }
  }
  for (const char* scene : {"paper_slow_6dof_hybrid", "paper_slow"}) {
    for (const bool jac : {false, true}) {
      const std::string name = std::string(jac ? "plant_jacobian/" : "plant_rhs/") + scene;
      benchmark::RegisterBenchmark(name.c_str(), run_plant, std::string(scene), jac)->Unit(benchmark::kNanosecond);
    }
  }
  return pumasim::run_registered_benchmarks(argc, argv);
}
