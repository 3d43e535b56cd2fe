// Identification benchmark: the joint-torque regressor Y(q, qd, qdd) of
// models/dynamics/regressor.hpp, computed two ways in one run:
//   regressor/<robot>/direct    the recursive form (one outward pass, the
//                               links' 6 x 10 wrench blocks carried inwards)
//   regressor/<robot>/probing   one RNEA per parameter column on a chain
//                               whose parameters are a unit vector (the
//                               paper's probing, applied to parameters)
// and the inverse dynamics (id: the crba back-end's, the RNEA) beside them, for the PUMA
// 560, the Panda and random chains of 12 and 24 joints, with the rotor and
// friction columns. experiments/regressor_table.py turns the JSON into
// results/identification/regressor.md (ratios within the one run).
//
//   bench_identification --benchmark_out=FILE.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "experiments/bench_main.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/regressor.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"

namespace {

struct Robot {
  std::string label;
  pumasim::RobotModel model;
};

std::vector<Robot> robots() {
  std::vector<Robot> r;
  r.push_back({"puma560", pumasim::load_robot("puma560")});
  r.push_back({"panda", pumasim::load_robot("panda")});
  for (int n : {12, 24}) r.push_back({"random" + std::to_string(n), pumasim::random_chain(n, 1000 + n)});
  return r;
}

enum class Way { kDirect, kProbing, kInverseDynamics };

void run(benchmark::State& state, const pumasim::RobotModel* model, Way way) {
  const int n = model->dof();
  pumasim::Rng rng(42);
  const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5);
  const Eigen::VectorXd qd = rng.uniform_vector(n, -1.0, 1.0);
  const Eigen::VectorXd qdd = rng.uniform_vector(n, -5.0, 5.0);
  pumasim::JointTorqueRegressor regressor(*model);
  auto rnea = pumasim::make_backend("crba", *model);  // its inverse dynamics is the RNEA (rnea.hpp)
  Eigen::MatrixXd Y(n, regressor.parameters());
  Eigen::VectorXd tau(n);
  for (auto _ : state) {
    switch (way) {
      case Way::kDirect:
        regressor.compute(q, qd, qdd, Y);
        break;
      case Way::kProbing:
        regressor.compute_by_probing(q, qd, qdd, Y);
        break;
      case Way::kInverseDynamics:
        rnea->inverse_dynamics(q, qd, qdd, tau);
        break;
    }
    benchmark::DoNotOptimize(Y.data());
    benchmark::DoNotOptimize(tau.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = n;
  state.counters["columns"] = regressor.parameters();
}

}  // namespace

int main(int argc, char** argv) {
  static const std::vector<Robot> all = robots();
  for (const Robot& r : all) {
    for (const auto& [label, way] : {std::pair{"direct", Way::kDirect}, std::pair{"probing", Way::kProbing},
                                     std::pair{"id", Way::kInverseDynamics}}) {
      const std::string name = "regressor/" + r.label + "/" + label;
      benchmark::RegisterBenchmark(name.c_str(), run, &r.model, way)->Unit(benchmark::kNanosecond);
    }
  }
  return pumasim::run_registered_benchmarks(argc, argv);
}
