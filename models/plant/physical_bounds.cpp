#include "models/plant/physical_bounds.hpp"

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <limits>

#include <Eigen/Eigenvalues>

namespace pumasim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string g3(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", x);
  return b;
}
}  // namespace

PhysicalBounds drive_bounds(const std::vector<AmplifierParams>& amplifier, const std::vector<MotorParams>& motor,
                            const std::vector<double>& gear_ratio, const std::vector<double>& full_command) {
  const std::size_t n = gear_ratio.size();
  PhysicalBounds b{std::vector<double>(n, kInf), std::vector<std::string>(n), std::vector<double>(n, kInf),
                   std::vector<std::string>(n)};
  for (std::size_t j = 0; j < n && j < full_command.size(); ++j) {
    const double V = full_command[j], K = motor[j].torque_constant, Z = std::abs(gear_ratio[j]);
    const double R = amplifier[j].output_resistance + motor[j].resistance;
    if (!(V > 0) || !std::isfinite(V) || !(K > 0) || !(Z > 0)) continue;
    const double w_max = V / K;  // the motor's no-load speed [rad/s]
    b.qd[j] = w_max / Z;
    b.qd_why[j] = "the drive's no-load speed V / (K Z) = " + g3(V) + " V / (" + g3(K) + " N m/A x " + g3(Z) + ")";
    if (R > 0) {
      b.current[j] = (V + K * w_max) / R;
      b.current_why[j] = "(V + K w_max) / (R0 + R) = (" + g3(V) + " V + " + g3(K) + " N m/A x " + g3(w_max) +
                         " rad/s) / " + g3(R) + " ohm";
    }
  }
  return b;
}

double reach_bound(const RobotModel& model, int j) {
  double r = model.base_p.norm();
  for (int k = 0; k <= j; ++k) {
    const JointParams& J = model.joints[static_cast<std::size_t>(k)];
    double d = std::abs(J.d);
    if (J.prismatic()) {
      d = std::max(std::abs(J.q_min + J.offset), std::abs(J.q_max + J.offset));
    }
    r += std::abs(J.a) + d;
  }
  return r + model.joints[static_cast<std::size_t>(j)].com.norm();
}

PhysicalBounds passive_bounds(const RobotModel& sim, const Eigen::VectorXd& q0, const Eigen::MatrixXd& H0) {
  const std::size_t n = static_cast<std::size_t>(sim.dof());
  PhysicalBounds b{std::vector<double>(n, kInf), std::vector<std::string>(n), std::vector<double>(n, kInf),
                   std::vector<std::string>(n)};
  // The plant does not enforce joint limits: a prismatic joint's reach, and
  // so the potential's lower bound, is then unknown.
  for (const JointParams& J : sim.joints) {
    if (J.prismatic()) return b;
  }
  // A lower bound of lambda_min(H(q)) over every q: the rotors' diag(Z^2 Im)
  // (H = the links' H, positive semidefinite, + that diagonal). Without
  // rotors, lambda_min(H(q0)) stands in: a bound at the start pose only.
  double rotors = kInf;
  for (const JointParams& J : sim.joints) rotors = std::min(rotors, J.gear_ratio * J.gear_ratio * J.rotor_inertia);
  double v_min = 0;  // a lower bound of the potential energy [J]
  for (int j = 0; j < sim.dof(); ++j) {
    v_min -= sim.joints[static_cast<std::size_t>(j)].mass * sim.gravity.norm() * reach_bound(sim, j);
  }
  const double e_avail = potential_energy(sim, q0) - v_min;  // at rest at q0
  double lambda = rotors;
  std::string lambda_what = "min Z^2 Im";
  if (!(rotors > 0)) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H0, Eigen::EigenvaluesOnly);
    lambda = eig.info() == Eigen::Success ? eig.eigenvalues().minCoeff() : 0.0;
    lambda_what = "lambda_min(H(q0))";
  }
  if (!(e_avail > 0) || !std::isfinite(e_avail) || !(lambda > 0)) return b;
  const double w = std::sqrt(2 * e_avail / lambda);
  for (std::size_t j = 0; j < n; ++j) {
    b.qd[j] = w;
    b.qd_why[j] = "a passive arm's energy: sqrt(2 E_avail / " + lambda_what + ") = sqrt(2 x " + g3(e_avail) +
                  " J / " + g3(lambda) + ")";
  }
  return b;
}

}  // namespace pumasim
