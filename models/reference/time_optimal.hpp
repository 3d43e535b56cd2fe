// Time-optimal timing along a fixed path under the drives' limits: the
// phase-plane method on a grid of arc length (Bobrow, Dubowsky & Gibson 1985;
// Shin & McKay 1985), in the two-pass form of reachability analysis
// (Pham & Pham 2018, TOPP-RA): a backward pass finds at each grid point the
// largest squared speed x = sd^2 from which the arm can still stop at the end;
// a forward pass from rest takes the largest admissible acceleration that
// stays inside those sets. Between grid points the path acceleration u = sdd
// is constant, so x is linear in s (Timing::phase_plane).
//
// Unlike TOPP-RA's linear programs, the admissible accelerations at (s, x)
// come from a callback, because a DC drive's voltage limit is not linear in
// (u, x): the back-EMF and viscous friction grow with sd = sqrt(x). The
// callback returns the interval [lo, hi] of admissible u (empty: lo > hi);
// the passes find the largest x with a bisection, assuming (as for these
// drives) that the admissible squared speeds at a grid point form an
// interval from 0.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/robot/drive.hpp"
#include "models/dynamics/robot_model.hpp"
#include "models/reference/timing.hpp"

namespace pumasim {

class Reference;

struct AccelerationBounds {
  double lo, hi;  // admissible sdd at (s_i, x); lo > hi: none
};
// (grid index i, squared speed x) -> admissible accelerations.
using AdmissibleFn = std::function<AccelerationBounds(int i, double x)>;

struct PhasePlaneResult {
  std::vector<double> s, sd;  // grid and the time-optimal speed at each point
  std::vector<double> x_max;  // the largest x with any admissible u (maximum velocity curve)
  std::vector<double> x_stop; // the largest x from which the arm can still stop at the end
};

// Grid s_0 = 0 < ... < s_N = L (N + 1 points); x_cap bounds the bisection
// for x. Throws std::runtime_error naming the grid point if the path cannot
// be traversed from rest (no admissible acceleration at x = 0).
PhasePlaneResult time_optimal_grid(const std::vector<double>& s, const AdmissibleFn& admissible, double x_cap);

// The drives' limits, per simulated joint, as the planner uses them.
struct DriveLimits {
  std::vector<double> voltage;      // |e_a| <= this [V] (a fraction of min(K_A u_max, V_max))
  std::vector<double> current;      // |i| <= this [A] (inf: none)
  std::vector<double> joint_speed;  // |qd| <= this [rad/s] (inf: none)
};

// What one joint's drive needs at a point of the path moving with (sd, sdd):
// the quasi-static model (La di/dt neglected) of the plant: joint torque
// tau = a sdd + b sd^2 + c from the rigid body (rotor inertia included),
// motor current i = (tau / Z + Fk sgn(w_m) + B w_m) / K, w_m = Z q' sd, and
// voltage e_a = (R0 + R) i + K w_m.
struct PathDynamics {
  // Per grid point and simulated joint: q'(s), q''(s), and a, b, c.
  std::vector<Eigen::VectorXd> dq, a, b, c;
};

class TimeOptimalPlanner {
 public:
  // The drive data of the simulated joints, as the plant has them.
  TimeOptimalPlanner(RobotModel simulated, std::string backend, std::vector<AmplifierParams> amplifier,
                     std::vector<MotorParams> motor, std::vector<FrictionParams> friction,
                     DriveLimits limits);
  // The path's dynamics at grid points (q', q'' from the reference run at unit speed).
  PathDynamics path_dynamics(const Reference& unit_speed_reference, const std::vector<double>& s) const;
  // Admissible sdd at grid point i and squared speed x.
  AccelerationBounds admissible(const PathDynamics& d, int i, double x) const;
  // Voltage [V] and current [A] of joint j at grid point i moving with (sd, sdd).
  void drive_demand(const PathDynamics& d, int i, int j, double sd, double sdd, double& volts, double& amps) const;
  // The time-optimal timing on `grid_points` + 1 equally spaced points.
  Timing plan(const Reference& unit_speed_reference, int grid_points) const;
  const DriveLimits& limits() const { return limits_; }

 private:
  RobotModel model_;
  std::string backend_;
  std::vector<AmplifierParams> amp_;
  std::vector<MotorParams> motor_;
  std::vector<FrictionParams> friction_;
  DriveLimits limits_;
};

}  // namespace pumasim
