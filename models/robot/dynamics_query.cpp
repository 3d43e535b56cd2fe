#include "models/robot/dynamics_query.hpp"

#include <cmath>
#include <stdexcept>

#include "models/robot/robot_file.hpp"

namespace pumasim {
namespace {

void check_size(const Eigen::VectorXd& v, int n, const char* what) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(n) + " values (one per joint), got " +
                                std::to_string(v.size()));
  }
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw std::invalid_argument(std::string(what) + ": expected finite numbers, got " + std::to_string(v[i]) +
                                  " for joint " + std::to_string(i + 1));
    }
  }
}

// A result that overflowed (finite arguments of absurd size: qd = 1e200 makes
// h = inf) is refused, naming the arguments it came from: JSON cannot hold
// it (`pumasim dynamics` printed null), and a caller would take it as a value.
void check_finite(const Eigen::MatrixXd& v, const char* what) {
  for (Eigen::Index j = 0; j < v.cols(); ++j) {
    for (Eigen::Index i = 0; i < v.rows(); ++i) {
      if (!std::isfinite(v(i, j))) {
        const char* value = std::isnan(v(i, j)) ? "nan" : v(i, j) > 0 ? "inf" : "-inf";
        throw std::invalid_argument(std::string(what) + " is not finite (" + value + " for joint " +
                                    std::to_string(i + 1) + "): the arguments are beyond what a double holds there");
      }
    }
  }
}

}  // namespace

RobotDynamics robot_dynamics(const std::string& robot, const std::string& backend, bool rotor_inertia) {
  RobotDynamics rd;
  rd.model = load_robot(robot);
  rd.rotor_inertia = rotor_inertia;
  if (!rotor_inertia) rd.model = without_rotor_inertia(rd.model);
  rd.backend = make_backend(backend, rd.model);
  return rd;
}

Eigen::VectorXd pose_angles(const RobotModel& model, const std::string& name, const std::string& what) {
  if (const NamedPose* p = model.pose(name)) return p->q;
  std::string poses;
  for (const auto& p : model.poses) poses += (poses.empty() ? "" : ", ") + p.name;
  throw std::invalid_argument(what + ": expected a pose name of " + model.name + " (" +
                              (poses.empty() ? "it has none" : poses) + ") or " + std::to_string(model.dof()) +
                              " numbers, got '" + name + "'");
}

DynamicsValues evaluate_dynamics(DynamicsBackend& backend, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                 const std::optional<Eigen::VectorXd>& qdd, const std::optional<Eigen::VectorXd>& tau) {
  const int n = backend.dof();
  check_size(q, n, "q");
  check_size(qd, n, "qd");
  if (qdd) check_size(*qdd, n, "qdd");
  if (tau) check_size(*tau, n, "tau");
  DynamicsValues v;
  v.mass_matrix.resize(n, n);
  v.bias.resize(n);
  v.gravity.resize(n);
  backend.mass_matrix(q, v.mass_matrix);
  backend.bias(q, qd, v.bias);
  backend.gravity(q, v.gravity);
  if (qdd) {
    v.tau.emplace(n);
    backend.inverse_dynamics(q, qd, *qdd, *v.tau);
  }
  if (tau) {
    v.qdd.emplace(n);
    backend.forward_dynamics(q, qd, *tau, *v.qdd);
  }
  check_finite(v.mass_matrix, "mass_matrix H(q)");
  check_finite(v.bias, "bias h(q, qd)");
  check_finite(v.gravity, "gravity g(q)");
  if (v.tau) check_finite(*v.tau, "tau = ID(q, qd, qdd)");
  if (v.qdd) check_finite(*v.qdd, "qdd = FD(q, qd, tau)");
  return v;
}

}  // namespace pumasim
