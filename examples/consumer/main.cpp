// Uses an installed pumasim (CMakeLists.txt beside it): loads the PUMA 560
// from the installed robot file, computes forward dynamics with two back-ends
// and checks that they agree, then runs a shipped scene for half a second
// through the simulation layer. Exit status 1 if anything disagrees or fails.
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>

#include "integrators/registry.hpp"     // find_integrator
#include "models/dynamics/backend.hpp"  // make_backend
#include "models/robot/robot_file.hpp"  // load_robot_file
#include "models/scene/scene.hpp"       // load_scene
#include "simulation/run.hpp"           // plan_run, simulate_scene

int main() try {
  using namespace pumasim;
  const std::string data = PUMASIM_DATA_DIR;  // from the package: pumasim_DATA_DIR
  // A scene names its robot ("puma560"); the library looks names up here.
  setenv("PUMASIM_ROBOTS_DIR", (data + "/robots").c_str(), 1);

  // Forward dynamics qdd = H^-1 (tau - h) at the nominal pose, two algorithms.
  const RobotModel puma = load_robot_file(data + "/robots/puma560.toml");
  const int n = puma.dof();
  const Eigen::VectorXd q = puma.pose("qn")->q;
  const Eigen::VectorXd qd = Eigen::VectorXd::LinSpaced(n, 0.1, 0.6);   // [rad/s]
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(n, 5.0, -5.0);  // [N m]
  Eigen::VectorXd qdd_crba(n), qdd_probing(n);
  make_backend("crba", puma)->forward_dynamics(q, qd, tau, qdd_crba);
  make_backend("rnea-probing", puma)->forward_dynamics(q, qd, tau, qdd_probing);
  const double rel = (qdd_crba - qdd_probing).norm() / qdd_crba.norm();
  std::cout << "robot " << puma.name << " (" << n << " joints) from " << puma.source << "\n"
            << "qdd crba         " << qdd_crba.transpose() << "\n"
            << "qdd rnea-probing " << qdd_probing.transpose() << "\n"
            << "relative difference " << rel << "\n";
  if (!(rel <= 1e-9)) {
    std::cerr << "consumer: the back-ends disagree\n";
    return 1;
  }

  // A shipped scene (six joints, hybrid stick-slip, CVODE BDF), its first 0.5 s,
  // with the scene's own integrator settings.
  // plan_run (the front door's first half, simulation/run.hpp) applies the
  // options to the scene with pumasim run's checks.
  const RunPlan plan = plan_run(load_scene(data + "/scenes/paper_slow_6dof_hybrid.toml"), {.t_end = 0.5});
  const Scene& scene = plan.scene;
  std::ostringstream trajectory;  // trajectory.csv's text, as `pumasim run` writes it
  const SceneRun run = simulate_scene(scene, plan.controls, {.trajectory = &trajectory});
  std::cout << "scene " << scene.name << " (robot from " << scene.plant.robot.source << "), "
            << scene.integrator.name << ": " << (run.result.ok ? "ok" : run.result.failure) << ", t = "
            << run.result.t_final << " s, " << run.stats.steps << " steps, " << run.stats.rhs_evaluations
            << " right-hand sides\n";
  // The final state, from the trajectory's last row (time, then the state in
  // the plant's order); the row itself too, to compare with `pumasim run`.
  const std::string csv = trajectory.str();
  const std::size_t end = csv.find_last_not_of('\n'), start = csv.rfind('\n', end) + 1;
  const std::string row = csv.substr(start, end + 1 - start);
  std::istringstream cells(row);
  std::string cell;
  std::getline(cells, cell, ',');
  std::cout << "final state at t = " << cell << " s:";
  for (const std::string& name : run.state_names) {
    std::getline(cells, cell, ',');
    std::cout << " " << name << "=" << cell;
  }
  std::cout << "\nfinal row " << row << "\n";
  return run.result.ok ? 0 : 1;
} catch (const std::exception& e) {
  std::cerr << "consumer: " << e.what() << "\n";
  return 1;
}
