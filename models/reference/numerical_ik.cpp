#include "models/reference/numerical_ik.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "models/robot/kinematics.hpp"

namespace pumasim {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// The task error at q: [p - p(q); rotation vector of R R(q)^T] (the last
// three zero without R).
Vec6 task_error(const RobotModel& robot, const Eigen::Vector3d& p, const Eigen::Matrix3d* R, const Vec6& q) {
  Eigen::Matrix3d Rq;
  Eigen::Vector3d pq;
  forward_kinematics<double>(robot, q, Rq, pq);
  Vec6 e = Vec6::Zero();
  e.head<3>() = p - pq;
  if (R) {
    const Eigen::AngleAxisd aa(Eigen::Matrix3d(*R * Rq.transpose()));
    e.tail<3>() = aa.angle() * aa.axis();
  }
  return e;
}

// The damped step (J^T J + lambda^2 I) dq = J^T e over the first n joints
// (the task's rows of J only; the unused joints' equations dq_j = 0).
Vec6 damped_step(const Mat6& J, const Vec6& e, int n, double lambda2) {
  Mat6 A = J.transpose() * J;
  Vec6 b = J.transpose() * e;
  for (int j = 0; j < 6; ++j) {
    if (j < n) {
      A(j, j) += lambda2;
    } else {
      A.row(j).setZero(), A.col(j).setZero(), A(j, j) = 1.0, b[j] = 0.0;
    }
  }
  return A.ldlt().solve(b);
}

}  // namespace

IkSolveResult dls_ik(const RobotModel& robot, int n, const Eigen::Vector3d& p, const Eigen::Matrix3d* R, Vec6& q,
                     const DlsOptions& opt) {
  IkSolveResult res;
  Vec6 e = task_error(robot, p, R, q);
  double err = e.norm(), lambda2 = opt.damping;
  int polished = 0;
  Mat6 J;
  while (res.iterations < opt.max_iterations && std::isfinite(err)) {
    if (err <= opt.tolerance && (err == 0.0 || polished++ >= opt.polish)) break;
    ++res.iterations;
    geometric_jacobian(robot, q, n, J);
    if (!R) J.bottomRows<3>().setZero();  // position only: the angular rows are no task
    const Vec6 trial = q + damped_step(J, e, n, lambda2);
    const Vec6 e_trial = task_error(robot, p, R, trial);
    const double err_trial = e_trial.norm();
    if (err_trial < err) {
      q = trial, e = e_trial, err = err_trial;
      lambda2 = std::max(lambda2 / 10, 1e-30);
    } else if (err <= opt.tolerance) {
      break;  // polishing found no lower error: rounding reached
    } else if ((lambda2 *= 10) > 1e12) {
      break;  // no step lowers the error: a local minimum of it (out of reach)
    }
  }
  res.error = err;
  res.converged = err <= opt.tolerance;
  return res;
}

}  // namespace pumasim
