// Numerical inverse kinematics for any serial arm of at most 6 joints:
// damped least squares on the geometric Jacobian (Wampler 1986; Nakamura &
// Hanafusa 1986; Siciliano et al., Robotics: Modelling, Planning and Control,
// 2009, sec. 3.7), with the damping adapted as in Levenberg-Marquardt: a step
// that lowers the error is taken and the damping divided by 10, one that does
// not is refused and the damping multiplied by 10. Near the solution the
// damping vanishes and the iteration is Gauss-Newton (quadratic convergence),
// so a converged solution is exact to rounding, not to a tolerance.
//
// The task: the flange origin at p (3 rows), and with an orientation also the
// flange frame at R (6 rows; the orientation error is the rotation vector of
// R R(q)^T, in the base frame like the Jacobian's angular rows).
#pragma once

#include <Eigen/Core>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

struct IkSolveResult {
  bool converged = false;
  int iterations = 0;
  double error = 0;  // the final error's norm ([m] and [rad] rows together)
};

struct DlsOptions {
  int max_iterations = 200;
  double tolerance = 1e-12;  // converged: error norm below this [m, rad] ...
  int polish = 2;            // ... then up to this many more steps while the error still falls
  double damping = 1e-2;     // initial lambda^2 [m^2]
};

// Solves for the first n joints of `robot` (the others kept at q's entries),
// starting from q (the warm start), which it overwrites with the last
// accepted iterate. R: the flange orientation, or nullptr for position only.
// Allocation-free.
IkSolveResult dls_ik(const RobotModel& robot, int n, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                     Eigen::Matrix<double, 6, 1>& q, const DlsOptions& options = {});

}  // namespace pumasim
