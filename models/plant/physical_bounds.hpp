// The physically possible range of the plant's states, from the blocks'
// parameters alone (issue 31: a diverged run is a named failure, not `ok`).
//
// A bound b_k says |x_k| <= b_k for every trajectory the model can have; the
// driver ends a run whose state passes kUnstableFactor * b_k as "unstable"
// (a margin for what the derivations below leave out: back-driving by
// gravity past the no-load speed, H varying along the path). Components with
// no bound (angles, the PIV integral, the energy ledger) carry +inf.
//
// - Driven joint j (amplifier + motor): the largest voltage the controller
//   can command is V = min(K_A u_max, V_max) (command_voltage_range). The
//   motor's no-load speed V / K bounds its speed: |qd_j| <= V / (K Z). The
//   current obeys La di/dt = e_a - (R0 + R) i - K w_m with |e_a| <= V and
//   |w_m| <= V / K, so it stays within (V + K w_max) / (R0 + R) = 2 V / (R0 + R)
//   from rest.
// - A passive arm (no controller) of revolute joints: friction only
//   dissipates, so the kinetic energy stays below E_avail = T(0) + V(q0) -
//   V_min, with V_min >= -sum_i m_i |g| r_i, r_i a bound on the distance of
//   link i's centre of mass from the base origin (|base_p| + sum_{k<=i}
//   (|a_k| + |d_k|) + |c_i|). Then qd' H qd <= 2 E_avail gives |qd_j| <=
//   sqrt(2 E_avail / lambda), lambda a lower bound of H(q)'s eigenvalues over
//   every q: min_j Z_j^2 Im_j (the rotors; H is the links' positive
//   semidefinite part plus that diagonal), or without rotors
//   lambda_min(H(q0)), valid at the start pose only (the 10x margin covers
//   H's variation on the shipped arms). A prismatic joint's reach is not
//   bounded (the plant enforces no joint limits): no bound then.
// - A torque-driven arm, or a drive whose command is unbounded: no bound.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/dynamics/robot_model.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

// How far past its bound a state may go before the run ends as unstable.
inline constexpr double kUnstableFactor = 10.0;

struct PhysicalBounds {
  std::vector<double> qd;                 // [rad/s or m/s] per joint; +inf: none
  std::vector<std::string> qd_why;
  std::vector<double> current;            // [A] per joint; +inf: none
  std::vector<std::string> current_why;
};

// A driven arm's bounds: full_command[j] = V (command_voltage_range).
PhysicalBounds drive_bounds(const std::vector<AmplifierParams>& amplifier, const std::vector<MotorParams>& motor,
                            const std::vector<double>& gear_ratio, const std::vector<double>& full_command);

// A passive arm's speed bounds from its energy at rest at q0 (qd0 = 0) and
// H(q0) (with the rotor inertias, as the plant's H).
PhysicalBounds passive_bounds(const RobotModel& sim, const Eigen::VectorXd& q0, const Eigen::MatrixXd& H0);

// An upper bound on the distance of link j's centre of mass from the base
// origin over every joint value within range [m]; +inf for a prismatic
// joint without a finite range.
double reach_bound(const RobotModel& model, int j);

}  // namespace pumasim
