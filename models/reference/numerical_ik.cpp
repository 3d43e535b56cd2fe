#include "models/reference/numerical_ik.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "models/robot/kinematics.hpp"

namespace pumasim {
namespace {

// The task error at q: [p - p(q); rotation vector of R R(q)^T] (the last
// three zero without R).
template <class Q>
void task_error(const RobotModel& robot, const Eigen::Vector3d& p, const Eigen::Matrix3d* R, const Q& q,
                Eigen::Matrix<double, 6, 1>& e) {
  Eigen::Matrix3d Rq;
  Eigen::Vector3d pq;
  forward_kinematics<double>(robot, q, Rq, pq);
  e.setZero();
  e.head<3>() = p - pq;
  if (R) {
    const Eigen::AngleAxisd aa(Eigen::Matrix3d(*R * Rq.transpose()));
    e.tail<3>() = aa.angle() * aa.axis();
  }
}

// The damped step (J^T J + lambda^2 I) dq = J^T e over the first n joints
// (the task's rows of J only), into ws.step.
void damped_step(IkWorkspace& ws, double lambda2) {
  const auto Jt = ws.J.topLeftCorner(ws.m, ws.n);
  ws.A.noalias() = Jt.transpose() * Jt;
  ws.A.diagonal().array() += lambda2;
  ws.b.noalias() = Jt.transpose() * ws.e.head(ws.m);
  ws.ldlt.compute(ws.A);
  ws.step = ws.ldlt.solve(ws.b);
}

// mu = (J J^T)^-1 J (q - q_r) (J: the task rows, first n columns, in ws.J),
// the least-squares multiplier of q - q_r = J^T mu; leaves r = q - q_r.
void least_squares_mu(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::VectorXd& rest, IkWorkspace& ws) {
  const auto Jt = ws.J.topLeftCorner(ws.m, ws.n);
  ws.JJt.noalias() = Jt * Jt.transpose();
  ws.ldlt_m.compute(ws.JJt);
  ws.r = q.head(ws.n) - rest.head(ws.n);
  ws.mu.noalias() = Jt * ws.r;
  ws.mu = ws.ldlt_m.solve(ws.mu);
}

// The redundant rule's residual at q: e (m rows) and r = (q - q_r) - J^T mu
// with mu by least squares (r: the part of q - q_r in J's null space).
// Leaves J, mu, r and e in ws; returns the norm of [e; r].
double rule_residual(const RobotModel& robot, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                     const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::VectorXd& rest, IkWorkspace& ws) {
  task_error(robot, p, R, q, ws.e);
  geometric_jacobian(robot, q, ws.n, ws.J);
  least_squares_mu(q, rest, ws);
  ws.r.noalias() -= ws.J.topLeftCorner(ws.m, ws.n).transpose() * ws.mu;
  return std::sqrt(ws.e.head(ws.m).squaredNorm() + ws.r.squaredNorm());
}

// M = d(J^T mu)/dq over the first n joints at q (mu fixed): column k is
// (dJ/dq_k)^T mu, one pass on dual numbers per column.
void null_space_curvature(const RobotModel& robot, const Eigen::Ref<const Eigen::VectorXd>& q, IkWorkspace& ws) {
  for (int j = 0; j < ws.dof; ++j) ws.q_dual[j] = Dual(q[j], 0.0);
  for (int k = 0; k < ws.n; ++k) {
    ws.q_dual[k] = Dual(q[k], 1.0);
    geometric_jacobian(robot, ws.q_dual, ws.n, ws.J_dual);
    ws.q_dual[k] = Dual(q[k], 0.0);
    for (int i = 0; i < ws.n; ++i) {
      double s = 0;
      for (int row = 0; row < ws.m; ++row) s += ws.J_dual(row, i).deriv() * ws.mu[row];
      ws.M(i, k) = s;
    }
  }
}

// K = [J 0; I - M, -J^T] (J: the task rows, first n columns), factored in ws.lu.
void factor_rule_jacobian(IkWorkspace& ws) {
  const int n = ws.n, m = ws.m;
  ws.K.setZero();
  ws.K.topLeftCorner(m, n) = ws.J.topLeftCorner(m, n);
  ws.K.bottomLeftCorner(n, n) = -ws.M;
  ws.K.bottomLeftCorner(n, n).diagonal().array() += 1.0;
  ws.K.bottomRightCorner(n, m) = -ws.J.topLeftCorner(m, n).transpose();
  ws.lu.compute(ws.K);
}

// Newton's method on the redundant rule's equations from q (on the manifold
// or near it), with step halving on the residual's norm.
void solve_rule(const RobotModel& robot, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                Eigen::Ref<Eigen::VectorXd> q,
                const Eigen::VectorXd& rest, IkWorkspace& ws, const DlsOptions& opt, IkSolveResult& res) {
  double err = rule_residual(robot, p, R, q, rest, ws);
  // r's rounding grows with |q - q_r| (its terms' size): the tolerance with it.
  const double tol = opt.tolerance * std::max(1.0, (q.head(ws.n) - rest.head(ws.n)).norm());
  int polished = 0, iterations = 0;
  while (iterations < opt.max_iterations && std::isfinite(err)) {
    if (err <= tol && (err == 0.0 || polished++ >= opt.polish)) break;
    ++iterations, ++res.iterations;
    null_space_curvature(robot, q, ws);
    factor_rule_jacobian(ws);
    ws.rhs.head(ws.m) = ws.e.head(ws.m);
    ws.rhs.tail(ws.n) = -ws.r;
    ws.sol = ws.lu.solve(ws.rhs);
    ws.step = ws.sol.head(ws.n);
    bool lowered = false;
    for (double alpha = 1.0; alpha > 1e-6 && !lowered; alpha /= 2) {
      ws.trial = q;
      ws.trial.head(ws.n) += alpha * ws.step;
      const double e_trial = rule_residual(robot, p, R, ws.trial, rest, ws);
      if (e_trial < err) q = ws.trial, err = e_trial, lowered = true;
    }
    if (!lowered) {
      rule_residual(robot, p, R, q, rest, ws);  // ws back at q
      break;  // rounding reached, or no step lowers the residual
    }
  }
  res.error = err;
  res.converged = err <= tol;
}

}  // namespace

IkWorkspace::IkWorkspace(int dof_, int n_, int m_)
    : dof(dof_),
      n(n_),
      m(m_),
      J(6, dof_),
      Jdot(6, dof_),
      A(n_, n_),
      K(n_ + m_, n_ + m_),
      M(n_, n_),
      JJt(m_, m_),
      b(n_),
      step(n_),
      trial(dof_),
      rhs(n_ + m_),
      sol(n_ + m_),
      mu(m_),
      mu_rate(m_),
      r(n_),
      ldlt(n_),
      ldlt_m(m_),
      lu(n_ + m_),
      lu_n(n_),
      q_dual(dof_),
      J_dual(6, dof_),
      q_jet(dof_),
      J_jet(6, dof_) {}

IkSolveResult dls_ik(const RobotModel& robot, int n, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                     Eigen::Ref<Eigen::VectorXd> q, IkWorkspace& ws, const Eigen::VectorXd* rest,
                     const DlsOptions& opt) {
  IkSolveResult res;
  task_error(robot, p, R, q, ws.e);
  double err = ws.e.head(ws.m).norm(), lambda2 = opt.damping;
  int polished = 0;
  while (res.iterations < opt.max_iterations && std::isfinite(err)) {
    if (err <= opt.tolerance && (err == 0.0 || polished++ >= opt.polish)) break;
    ++res.iterations;
    geometric_jacobian(robot, q, n, ws.J);
    damped_step(ws, lambda2);
    ws.trial = q;
    ws.trial.head(n) += ws.step;
    task_error(robot, p, R, ws.trial, ws.e_trial);
    const double err_trial = ws.e_trial.head(ws.m).norm();
    if (err_trial < err) {
      q = ws.trial, ws.e = ws.e_trial, err = err_trial;
      lambda2 = std::max(lambda2 / 10, 1e-30);
    } else if (err <= opt.tolerance) {
      break;  // polishing found no lower error: rounding reached
    } else if ((lambda2 *= 10) > 1e12) {
      break;  // no step lowers the error: a local minimum of it (out of reach)
    }
  }
  res.error = err;
  res.converged = res.reached = err <= opt.tolerance;
  // A redundant task: from this pose of the manifold to the rule's.
  if (res.converged && rest && n > ws.m) solve_rule(robot, p, R, q, *rest, ws, opt, res);
  return res;
}

IkSolveResult dls_ik(const RobotModel& robot, int n, const Eigen::Vector3d& p, const Eigen::Matrix3d* R,
                     Eigen::Ref<Eigen::VectorXd> q, const DlsOptions& options) {
  IkWorkspace ws(robot.dof(), n, R ? 6 : 3);
  return dls_ik(robot, n, p, R, q, ws, nullptr, options);
}

void task_rates(const RobotModel& robot, int n, bool orientation, const Eigen::VectorXd& q,
                const Eigen::VectorXd* rest, const Eigen::Vector3d& v, const Eigen::Vector3d& a,
                Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd, IkWorkspace& ws) {
  const int m = orientation ? 6 : 3;
  Eigen::Matrix<double, 6, 1> vt = Eigen::Matrix<double, 6, 1>::Zero(), at = vt;
  vt.head<3>() = v, at.head<3>() = a;
  qd.setZero(), qdd.setZero();
  geometric_jacobian(robot, q, n, ws.J);
  const auto Jt = ws.J.topLeftCorner(m, n);
  // Jdot = dJ/dt along qd, exactly: the Jacobian on dual numbers q + eps qd
  // (a central difference put noise of about 1e-10 into qdd, which a
  // tight-tolerance reference run could not get past).
  const auto jacobian_rate = [&] {
    for (int j = 0; j < ws.dof; ++j) ws.q_dual[j] = Dual(q[j], qd[j]);
    geometric_jacobian(robot, ws.q_dual, n, ws.J_dual);
    for (int c = 0; c < ws.dof; ++c)
      for (int r = 0; r < 6; ++r) ws.Jdot(r, c) = ws.J_dual(r, c).deriv();
  };
  if (n > m) {
    // The rule's solution q(t) differentiated: mu by least squares at q
    // (zero without a rest pose: the rule with its rest pose at q).
    if (rest) {
      least_squares_mu(q, *rest, ws);
      null_space_curvature(robot, q, ws);
    } else {
      ws.mu.setZero(), ws.M.setZero();
    }
    factor_rule_jacobian(ws);
    ws.rhs.head(m) = vt.head(m);
    ws.rhs.tail(n).setZero();
    ws.sol = ws.lu.solve(ws.rhs);
    qd.head(n) = ws.sol.head(n);
    ws.mu_rate = ws.sol.tail(m);
    jacobian_rate();
    // J'' along qd: the second derivative of J(q + s qd) at s = 0.
    for (int j = 0; j < ws.dof; ++j) ws.q_jet[j] = Jet2(q[j], qd[j], 0.0);
    geometric_jacobian(robot, ws.q_jet, n, ws.J_jet);
    ws.rhs.head(m) = at.head(m) - ws.Jdot.topLeftCorner(m, n) * qd.head(n);
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int row = 0; row < m; ++row) s += ws.J_jet(row, i).d2() * ws.mu[row] + 2 * ws.Jdot(row, i) * ws.mu_rate[row];
      ws.rhs[m + i] = s;
    }
    ws.sol = ws.lu.solve(ws.rhs);
    qdd.head(n) = ws.sol.head(n);
    return;
  }
  if (n == m) {  // the exact solve
    ws.lu_n.compute(Jt);
    qd.head(n) = ws.lu_n.solve(vt.head(m));
    jacobian_rate();
    at.head(m) -= ws.Jdot.topLeftCorner(m, n) * qd.head(n);
    qdd.head(n) = ws.lu_n.solve(at.head(m));
    return;
  }
  // n < m: least squares on the normal equations.
  ws.A.noalias() = Jt.transpose() * Jt;
  ws.ldlt.compute(ws.A);
  ws.b.noalias() = Jt.transpose() * vt.head(m);
  qd.head(n) = ws.ldlt.solve(ws.b);
  jacobian_rate();
  at.head(m) -= ws.Jdot.topLeftCorner(m, n) * qd.head(n);
  ws.b.noalias() = Jt.transpose() * at.head(m);
  qdd.head(n) = ws.ldlt.solve(ws.b);
}

}  // namespace pumasim
