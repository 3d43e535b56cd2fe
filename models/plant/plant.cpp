#include "models/plant/plant.hpp"

#include <algorithm>
#include <cmath>

#include "models/plant/profile.hpp"

namespace pumasim {

Plant::Plant(PlantConfig config) : Plant(std::make_shared<const PlantModel>(std::move(config))) {}

Plant::Plant(std::shared_ptr<const PlantModel> model)
    : model_(std::move(model)),
      context_(model_->make_context()),
      evaluator_(model_->make_workspace<double>()),
      stick_slip_(*model_) {
  const auto m = static_cast<std::size_t>(model_->size());
  f_.resize(m);
  for (auto& v : ft_) v.resize(m);
}

Plant::~Plant() = default;

// The integrator's f: the profiled build's f context (models/plant/profile.hpp).
void Plant::rhs(double t, const double* x, double* xdot) {
  PUMASIM_PROFILE_CONTEXT(kRhs);
  model_->rhs(context_, *evaluator_, t, x, xdot);
}

void Plant::rhs_smooth(double t, const double* x, double* xdot) {
  PUMASIM_PROFILE_CONTEXT(kRhs);
  model_->rhs(context_, *evaluator_, t, x, xdot, FrictionPart::kSmooth);
}

void Plant::rhs_split(double t, const double* x, double* fe, double* fi) {
  PUMASIM_PROFILE_CONTEXT(kRhs);
  model_->rhs(context_, *evaluator_, t, x, fi);                       // the whole f
  model_->rhs(context_, *evaluator_, t, x, fe, FrictionPart::kNone);  // f without friction
  const StateLayout& L = layout();
  for (int k = 0; k < L.size; ++k) fi[k] -= fe[k];  // the friction's part
  if (L.i >= 0) {
    for (int j = 0; j < L.n; ++j) {  // the current equation: all implicit
      fi[L.i + j] += fe[L.i + j];
      fe[L.i + j] = 0.0;
    }
  }
}

void Plant::jacobian(FrictionPart part, double t, const double* x, Eigen::MatrixXd& J) {
  PUMASIM_PROFILE_CONTEXT(kJacobian);
  const int m = size();
  if (!tangent_evaluator_) {
    tangent_evaluator_ = model_->make_workspace<Tangent>();
    tx_.resize(static_cast<std::size_t>(m));
    tf_.resize(static_cast<std::size_t>(m));
  }
  J.resize(m, m);
  constexpr int N = kJacobianTangents;
  for (int first = 0; first < m; first += N) {  // states first..first+N-1 in one pass
    for (int i = 0; i < m; ++i) tx_[i].seed(x[i], i - first);
    model_->eval(context_, *tangent_evaluator_, part, t, tx_.data(), tf_.data());
    const int last = std::min(m, first + N);
    for (int k = first; k < last; ++k) {
      for (int r = 0; r < m; ++r) J(r, k) = tf_[r].deriv(k - first);
    }
  }
}

PlantWorkspace<Dual>& Plant::dual_evaluator() {
  if (!dual_evaluator_) {
    dual_evaluator_ = model_->make_workspace<Dual>();
    jx_.resize(static_cast<std::size_t>(size()));
    jf_.resize(static_cast<std::size_t>(size()));
  }
  return *dual_evaluator_;
}

void Plant::jacobian_per_column(double t, const double* x, Eigen::MatrixXd& J) {
  const int m = size();
  dual_evaluator();
  J.resize(m, m);
  for (int k = 0; k < m; ++k) {
    for (int i = 0; i < m; ++i) jx_[i] = Dual(x[i], i == k ? 1.0 : 0.0);
    model_->eval(context_, *dual_evaluator_, FrictionPart::kAll, t, jx_.data(), jf_.data());
    for (int r = 0; r < m; ++r) J(r, k) = jf_[r].deriv();
  }
}

void Plant::residual_newton_matrix(double t, const double* x, double c, Eigen::MatrixXd& J) {
  const int m = size(), n = layout().n;
  if (newton_H_.rows() != n) {
    newton_Jf_.resize(m, m), newton_H_.resize(n, n), newton_rows_.resize(n, m);
    newton_held_.assign(static_cast<std::size_t>(n), 0);
  }
  jacobian_exact(t, x, newton_Jf_);
  mass_matrix(x + layout().q, newton_H_);
  for (int j = 0; j < n; ++j) newton_held_[static_cast<std::size_t>(j)] = model_->friction().stuck(j, context_.modes);
  residual_newton_matrix_again(c, J);
}

bool Plant::residual_newton_matrix_again(double c, Eigen::MatrixXd& J) {
  const int n = layout().n, qd = layout().qd;
  if (newton_H_.rows() != n) return false;
  J = -newton_Jf_;
  J.diagonal().array() += c;
  newton_rows_.noalias() = newton_H_ * J.middleRows(qd, n);
  for (int j = 0; j < n; ++j) {
    if (newton_held_[static_cast<std::size_t>(j)]) continue;  // a held joint's row stays c e
    J.row(qd + j) = newton_rows_.row(j);
  }
  if (model_->motor().algebraic()) {  // -(e_a - (R0 + R) i - K w_m): no xp, so no c
    for (int j = 0; j < n; ++j) J(layout().i + j, layout().i + j) = -newton_Jf_(layout().i + j, layout().i + j);
  }
  return true;
}

void Plant::mass_matrix(const double* q, Eigen::MatrixXd& M) {
  PlantWorkspace<double>& w = *evaluator_;
  w.last_valid = false;  // its scratch no longer holds the last f's
  for (int j = 0; j < layout().n; ++j) w.q[j] = q[j];
  w.backend->mass_matrix(w.q, M);
}

void Plant::lagrangian_gradient(const double* q, const double* qd, double* dLdq) {
  const int n = layout().n;
  PlantWorkspace<Dual>& wd = dual_evaluator();
  for (int j = 0; j < n; ++j) wd.q[j] = Dual(q[j], qd[j]);
  wd.backend->mass_matrix(wd.q, wd.H);  // H and, in the tangents, Mdot
  PlantWorkspace<double>& w = *evaluator_;
  w.last_valid = false;
  for (int j = 0; j < n; ++j) w.q[j] = q[j], w.qd[j] = qd[j];
  w.backend->bias(w.q, w.qd, w.h);
  for (int i = 0; i < n; ++i) {
    double mdot_qd = 0;
    for (int k = 0; k < n; ++k) mdot_qd += wd.H(i, k).deriv() * qd[k];
    dLdq[i] = mdot_qd - w.h[i];
  }
}

int Plant::time_derivative(double t, const double* x, double* dfdt) {
  const int m = size();
  if (!model_->depends_on_time()) {
    std::fill(dfdt, dfdt + m, 0.0);
    return 0;
  }
  // Forward, so that the first step of a run (t = 0) and of a piece look only
  // into the piece; f(t) too on the continued piece (at t = 0 or a breakpoint
  // the reference itself may jump: a joint spline's acceleration at the start
  // of the motion); the piece continued past its end, so that a step that
  // starts just before a breakpoint does not see it; so is the piece of a
  // law's own input (an open-loop input's row). Truncation O(d^2),
  // rounding about eps |f| / d. Rosenbrock methods multiply df/dt by h d_i in
  // every stage and their step control is sensitive to its error:
  // odeint-rodas4p took about the same number of steps with this, with a
  // fourth-order difference, and with d from 1e-3 s to 1e-5 s, and far more
  // with a first-order forward difference of step sqrt(eps) max(1, t)
  // (measured: commit 5fadac5).
  constexpr double d = 1e-5;  // [s]
  struct Continued {  // the continued piece for the duration of the difference, even on a throw
    explicit Continued(PlantWorkspace<double>& w) : w_(w) { w_.extend_piece = true; }
    ~Continued() { w_.extend_piece = false; }
    PlantWorkspace<double>& w_;
  } continued(*evaluator_);
  rhs(t, x, dfdt);
  rhs(t + d, x, ft_[0].data());
  rhs(t + 2 * d, x, ft_[1].data());
  for (int r = 0; r < m; ++r) dfdt[r] = (-3 * dfdt[r] + 4 * ft_[0][r] - ft_[1][r]) / (2 * d);
  return 3;
}

void Plant::on_time_event(double t, double* x, bool settle_modes) {
  PUMASIM_PROFILE_CONTEXT(kEvents);
  if (!model_->time_event(context_, *evaluator_, t, x)) return;  // no controller: nothing happens at a time event
  model_->settle_currents(context_, *evaluator_, t, x);          // a tick's new output moves algebraic currents at once
  if (!settle_modes) return;
  stick_slip_.settle(context_, *evaluator_, t, x);
  stick_slip_.record(context_, *evaluator_, t);
}

void Plant::initial_state(double* x) {
  stick_slip_.clear_log();
  model_->start_state(context_, *evaluator_, x);
  on_time_event(0.0, x);  // first set-point and controller sample (e = 0 on the reference)
  model_->input_currents(context_, *evaluator_, x);   // (algebraic currents: settled by on_time_event)
  stick_slip_.settle(context_, *evaluator_, 0.0, x);  // hybrid joints start stuck unless already pushed past Fs
  stick_slip_.start_log(context_, *evaluator_, 0.0);  // the modes at t = 0, one entry per joint with events
}

Eigen::Vector3d Plant::tool_position(const double* x) const {
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  tool_pose(x, R, p);
  return p;
}

}  // namespace pumasim
