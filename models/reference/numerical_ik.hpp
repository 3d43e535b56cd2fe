// Numerical inverse kinematics for any serial arm, of any number of joints:
// damped least squares on the geometric Jacobian (Wampler 1986; Nakamura &
// Hanafusa 1986; Siciliano et al., Robotics: Modelling, Planning and Control,
// 2009, sec. 3.7), with the damping adapted as in Levenberg-Marquardt: a step
// that lowers the error is taken and the damping divided by 10, one that does
// not is refused and the damping multiplied by 10. Near the solution the
// damping vanishes and the iteration is Gauss-Newton (quadratic convergence),
// so a converged solution is exact to rounding, not to a tolerance.
//
// The task: the flange origin at p (m = 3 rows), and with an orientation also
// the flange frame at R (m = 6 rows; the orientation error is the rotation
// vector of R R(q)^T, in the base frame like the Jacobian's angular rows).
//
// A redundant arm (n > m simulated joints) reaches the task on a manifold of
// poses. The rule that picks one, given a rest pose q_r: the pose of the
// manifold nearest q_r (in the Euclidean norm of the joint angles), locally:
// the solution of the n + m equations
//     e(q) = 0,   q - q_r = J(q)^T mu,
// i.e. q - q_r has no component in J's null space (the first-order condition
// of min |q - q_r|^2 on the manifold; Siciliano et al. 2009, sec. 3.5.1, the
// null-space pull of k0 (q_r - q) taken to convergence). Found by damped
// least squares onto the manifold, then Newton's method on those equations
// (quadratic convergence; mu by least squares). Its solution is a smooth
// function of the task where their Jacobian [J 0; I - M, -J^T] is regular
// (M = d(J^T mu)/dq), so a reference along a path is a continuous branch,
// and its rates come from that same Jacobian (task_rates).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include "models/dynamics/dual.hpp"
#include "models/dynamics/jet2.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

struct IkSolveResult {
  bool reached = false;    // the task's error converged (damped least squares)
  bool converged = false;  // and, for a redundant task with a rest pose, the rule's equations too
  int iterations = 0;
  double error = 0;  // the final error's norm ([m] and [rad] rows together; redundant: with the null-space rows)
};

struct DlsOptions {
  int max_iterations = 200;  // each stage's: the damped least squares, then the rule's Newton solve
  double tolerance = 1e-12;  // converged: error norm below this [m, rad] (the rule's: times max(1, |q - q_r|)) ...
  int polish = 2;            // ... then up to this many more steps while the error still falls
  double damping = 1e-2;     // initial lambda^2 [m^2]
};

// All the storage of dls_ik and task_rates for n simulated joints of a
// dof-joint robot and an m-row task (3 or 6): sized once, so that neither
// allocates. One per thread.
struct IkWorkspace {
  IkWorkspace() = default;
  IkWorkspace(int dof, int n, int m);
  int dof = 0, n = 0, m = 0;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J, Jdot;  // 6 x dof
  Eigen::MatrixXd A, K, M;                                      // n x n, (n + m)^2, n x n
  Eigen::MatrixXd JJt;                                          // m x m
  Eigen::VectorXd b, step, trial, rhs, sol, mu, mu_rate, r;  // n, n, dof, n + m, n + m, m, m, n
  Eigen::Matrix<double, 6, 1> e, e_trial;
  Eigen::LDLT<Eigen::MatrixXd> ldlt, ldlt_m;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu, lu_n;  // (n + m)^2, n x n
  Eigen::Matrix<Dual, Eigen::Dynamic, 1> q_dual;
  Eigen::Matrix<Dual, 6, Eigen::Dynamic> J_dual;
  Eigen::Matrix<Jet2, Eigen::Dynamic, 1> q_jet;
  Eigen::Matrix<Jet2, 6, Eigen::Dynamic> J_jet;
};

// Solves for the first n joints of `robot` (the others kept at q's entries),
// starting from q (the warm start, dof entries), which it overwrites with the
// last accepted iterate. R: the flange orientation, or nullptr for position
// only. rest: for a redundant task (n > m), the rest pose q_r (dof entries;
// see the head of this file); nullptr: damped least squares alone, which
// stops at whichever pose of the manifold it reaches first.
// Allocation-free with a workspace of the right sizes (ws.n = n,
// ws.m = R ? 6 : 3); the overload without one allocates it.
IkSolveResult dls_ik(const RobotModel& robot, int n, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                     Eigen::Ref<Eigen::VectorXd> q, IkWorkspace& ws, const Eigen::VectorXd* rest = nullptr,
                     const DlsOptions& options = {});
IkSolveResult dls_ik(const RobotModel& robot, int n, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                     Eigen::Ref<Eigen::VectorXd> q, const DlsOptions& options = {});

// The joint rates of a task moving with velocity v and acceleration a (the
// flange origin's; the orientation, if any, fixed) at a solution q of it:
//   n = m: J qd = v_task, J qdd = a_task - Jdot qd (Jdot exactly, one pass
//          on dual numbers);
//   n < m: the same in least squares (normal equations; exact when v and a
//          are tangent to what the joints can reach, as along a reachable
//          path);
//   n > m, with rest: the derivatives of the rule's solution q(t)
//          (without one: the same equations with mu = 0, M = 0, i.e. the
//          rule with its rest pose at the current q):
//          [J 0; I - M, -J^T] [qd; mu'] = [v_task; 0] and
//          [J 0; I - M, -J^T] [qdd; mu''] = [a_task - Jdot qd; J''^T mu + 2 Jdot^T mu'],
//          J'' the second derivative of J along qd (a pass on Jet2).
// qd, qdd: dof entries, zero beyond n. Allocation-free, as dls_ik.
void task_rates(const RobotModel& robot, int n, bool orientation, const Eigen::VectorXd& q,
                const Eigen::VectorXd* rest, const Eigen::Vector3d& v, const Eigen::Vector3d& a,
                Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd, IkWorkspace& ws);

}  // namespace pumasim
