#include "models/plant/plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/dynamics/chain.hpp"
#include "models/plant/physical_bounds.hpp"
#include "models/plant/profile.hpp"
#include "models/dynamics/tangent_backend.hpp"

namespace pumasim {

namespace {

bool on_grid(double t, double period) {
  if (!(period > 0)) return false;
  const double k = t / period;
  return std::abs(k - std::round(k)) < 1e-9 * std::max(1.0, std::abs(k));
}

double next_on_grid(double t, double period) {
  return (std::floor(t / period + 1e-9) + 1.0) * period;
}

std::vector<double> gear_ratios(const PlantConfig& c) {
  std::vector<double> Z;
  for (int j = 0; j < c.n; ++j) Z.push_back(c.robot.joints[static_cast<std::size_t>(j)].gear_ratio);
  return Z;
}

template <class T>
std::vector<T> if_drive(const PlantConfig& c, const std::vector<T>& v) {
  return c.drive ? v : std::vector<T>{};
}

}  // namespace

RobotModel simulated_robot(const RobotModel& robot, int n, const Eigen::Matrix<double, 6, 1>& q_held) {
  return n < robot.dof() ? lock_joints(robot, n, q_held.head(robot.dof())) : robot;
}

PlantConfig Plant::checked(PlantConfig c) {
  const int n = c.n;
  if (c.robot.dof() != 6 && c.n != c.robot.dof()) throw std::invalid_argument("plant: held joints need a 6-joint robot");
  if (n < 1 || n > c.robot.dof()) throw std::invalid_argument("plant: joint count out of range");
  const auto sized = [n](std::size_t s) { return s == static_cast<std::size_t>(n); };
  if (!sized(c.friction.size())) throw std::invalid_argument("plant: one friction block per joint");
  if (c.drive && (!sized(c.amplifier.size()) || !sized(c.motor.size()))) {
    throw std::invalid_argument("plant: one amplifier and motor per joint");
  }
  if (c.controller != ControllerMode::kNone) {
    if (!sized(controller_joints(c.controller_params))) {
      throw std::invalid_argument("plant: one set of controller parameters per joint");
    }
    if (!c.reference && c.q0.size() != n) {
      throw std::invalid_argument("plant: a controller needs a reference, or initial angles to hold");
    }
    const bool torque = controller_command(c.controller_params) == ControllerCommand::kTorque;
    if (torque && c.drive) throw std::invalid_argument("plant: a torque input acts on the joints: no drive with it");
    if (!torque && !c.drive) throw std::invalid_argument("plant: a controller needs the drive (amplifier, motor)");
  } else if (c.drive) {
    throw std::invalid_argument("plant: a drive needs a controller");
  } else if (c.q0.size() != n) {
    throw std::invalid_argument("plant: a passive arm needs n initial angles");
  }
  if (c.controller == ControllerMode::kSampled && !(c.servo_period > 0)) {
    throw std::invalid_argument("plant: a sampled controller needs a servo period > 0");
  }
  return c;
}

Plant::Plant(PlantConfig config)
    : cfg_(checked(std::move(config))),
      model_(simulated_robot(cfg_.robot, cfg_.n, cfg_.q_held)),
      body_(gear_ratios(cfg_)),
      amplifier_(if_drive(cfg_, cfg_.amplifier)),
      motor_(if_drive(cfg_, cfg_.motor), if_drive(cfg_, cfg_.amplifier)),
      friction_(cfg_.friction),
      controller_(make_controller(cfg_.controller, cfg_.controller_params,
                                  {gear_ratios(cfg_), cfg_.servo_period, cfg_.amplifier, cfg_.motor})),
      ledger_(cfg_.energy_ledger),
      torque_input_(cfg_.controller != ControllerMode::kNone &&
                    controller_command(cfg_.controller_params) == ControllerCommand::kTorque),
      law_input_(std::visit([](const auto& c) { return std::decay_t<decltype(c)>::kHasInput; }, controller_)) {
  const int n = cfg_.n;
  layout_.n = n;
  body_.declare(layout_);
  std::vector<double> full_command;  // the stall current's scale: min(K_A u_max, V_max)
  for (int j = 0; j < n && cfg_.drive; ++j) {
    full_command.push_back(command_voltage_range(cfg_.amplifier[j], controller_output_limit(cfg_.controller_params, j)));
  }
  motor_.declare(layout_, full_command);
  std::visit([&](const auto& c) { c.declare(layout_); }, controller_);
  ledger_.declare(layout_);
  declare_bounds(full_command);

  wd_ = std::make_unique<Workspace<double>>(n);
  wd_->backend = find_backend(cfg_.backend).make(model_);
  wj_ = std::make_unique<Workspace<Dual>>(n);
  wj_->backend = find_backend(cfg_.backend).make_dual(model_);
  ds_.controller.u_held.assign(n, 0.0);
  ds_.controller.memory.assign(std::visit([](const auto& c) { return c.discrete_size(); }, controller_), 0.0);
  ds_.modes.assign(n, SlipMode::kStuck);
  released_.assign(static_cast<std::size_t>(n), 0.0);
  ftmp_.resize(layout_.size);
  for (int j = 0; j < n; ++j) {
    if (friction_.set_valued(j)) sv_joint_.push_back(j);
  }
  stick_.reserve(n);
  cand_.resize(n), cand_mode_.resize(n), cw_.resize(static_cast<std::size_t>(n) * n);
  cb_.resize(n), cs_.resize(n), ck_.resize(n), cr_.resize(n), col_.resize(n);
  may_stick_ = std::make_unique<bool[]>(static_cast<std::size_t>(n));
  x_last_.resize(layout_.size);
  for (auto& v : ft_) v.resize(layout_.size);
  jx_.resize(layout_.size);
  jf_.resize(layout_.size);
  if (cfg_.tabulate_reference && cfg_.reference && cfg_.reference->has_path() &&
      cfg_.reference->interpolation() == Interpolation::kCartesian &&
      ReferenceTable::sub_intervals(*cfg_.reference) <= ReferenceTable::kMaxSubs) {
    ref_table_ = std::make_unique<ReferenceTable>(*cfg_.reference);
  }
  wt_ = std::make_unique<Workspace<Tangent>>(n);
  wt_->backend = std::make_unique<TangentBackend<kJacobianTangents>>(model_, find_backend(cfg_.backend).make(model_));
  // h's tangents reach f only through the applied torque of a joint whose
  // law reads it without stick/slip events (a law with events reads it only
  // while the joint is stuck, where the constrained solve replaces it), or
  // through the ledger's friction loss tf w_m (tf is the applied torque at a
  // stuck joint).
  bias_tangents_ = cfg_.energy_ledger;
  for (int j = 0; j < n; ++j) {
    bias_tangents_ = bias_tangents_ ||
                     (needs_applied_torque(cfg_.friction[static_cast<std::size_t>(j)].model) && !friction_.has_events(j));
  }
  tx_.resize(layout_.size);
  tf_.resize(layout_.size);
}

Plant::~Plant() = default;

void Plant::declare_bounds(const std::vector<double>& full_command) {
  const int n = layout_.n;
  PhysicalBounds b;
  if (cfg_.drive) {
    b = drive_bounds(cfg_.amplifier, cfg_.motor, gear_ratios(cfg_), full_command);
  } else if (cfg_.controller == ControllerMode::kNone) {  // passive: at rest at q0
    Eigen::MatrixXd H(n, n);
    find_backend(cfg_.backend).make(model_)->mass_matrix(cfg_.q0, H);
    b = passive_bounds(model_, cfg_.q0, H);
  }
  for (int j = 0; j < n && !b.qd.empty(); ++j) {
    const auto k = static_cast<std::size_t>(j);
    layout_.set_bound(layout_.qd + j, b.qd[k], b.qd_why[k]);
    if (layout_.i >= 0) layout_.set_bound(layout_.i + j, b.current[k], b.current_why[k]);
  }
}

const ReferenceSample& Plant::current_reference(double t) {
  if (cfg_.setpoint_interval > 0 || !cfg_.reference) return ds_.ref_held;
  if (t != ds_.ref_time) {
    PUMASIM_PROFILE_PART(kReference);
    if (ref_table_) {
      ref_table_->eval(t, ds_.ref_now, ds_.ref_segment, ds_.extend_piece);
    } else {
      cfg_.reference->eval(t, ds_.ref_now, ds_.ref_segment, ds_.extend_piece);
    }
    ds_.ref_time = t;
  }
  return ds_.ref_now;
}

const ReferenceSample& Plant::reference_at(double t) { return current_reference(t); }

template <class S>
void Plant::controller_output(double t, const S* x, Workspace<S>& w) {
  PUMASIM_PROFILE_PART(kController);
  if (cfg_.controller == ControllerMode::kContinuous) {
    const ControllerClock clock{t, ds_.controller.piece, ds_.extend_piece};
    std::visit([&](const auto& c) { c.output(clock, current_reference(t), x, layout_, w); }, controller_);
    return;
  }
  const bool held = cfg_.controller == ControllerMode::kSampled;  // else no controller: u = 0
  for (int j = 0; j < layout_.n; ++j) w.u[j] = held ? S(ds_.controller.u_held[static_cast<std::size_t>(j)]) : S(0);
}

// Amplifier and motor: e_a, the current (state or algebraic), K i; the
// electrical powers for the ledger. Without a drive the motor torque is 0, or
// a torque input's joint torque u reflected to the motor side, u / Z, which
// puts in the power u qd.
template <class S>
void Plant::drive(const S* x, S* xdot, Workspace<S>& w) {
  PUMASIM_PROFILE_PART(kDrive);
  for (int j = 0; j < layout_.n; ++j) {
    if (!cfg_.drive) {
      w.tm[j] = torque_input_ ? w.u[j] / S(body_.gear_ratio(j)) : S(0);
      w.ea[j] = S(0);
      if (ledger_.on() && torque_input_) w.p_in += w.u[j] * w.qd[j];
      continue;
    }
    const S wm = S(body_.gear_ratio(j)) * w.qd[j];
    const S ea = amplifier_.output(j, w.u[j]);
    w.ea[j] = ea;
    const S i = motor_.current(j, ea, wm, x, xdot, layout_.i);
    w.tm[j] = S(motor_.params(j).torque_constant) * i;
    if (ledger_.on()) {
      w.p_in += ea * i;
      w.p_cu += S(motor_.loop_resistance(j)) * i * i;
    }
  }
}

// Friction, the joint torques and the accelerations (constrained where the
// hybrid model holds a joint).
template <class S>
void Plant::friction_and_accelerations(Workspace<S>& w) {
  const bool all = friction_part_ == FrictionPart::kAll;
  const bool need_bias = all && friction_.needs_applied_torque();
  if (need_bias) {
    PUMASIM_PROFILE_PART(kDynamics);
    if constexpr (kIsDualN<S>) {  // the exact Jacobian's pass
      if (!bias_tangents_) {
        static_cast<TangentBackend<S::kTangents>&>(*w.backend).bias_value(w.q, w.qd, w.h);
      } else {
        w.backend->bias(w.q, w.qd, w.h);
      }
    } else {
      w.backend->bias(w.q, w.qd, w.h);
    }
  }
  PUMASIM_PROFILE_PART(kFriction);
  for (int j = 0; j < layout_.n; ++j) {
    const double Z = body_.gear_ratio(j);
    const S wm = S(Z) * w.qd[j];
    w.applied[j] = need_bias ? S(w.tm[j] - w.h[j] / S(Z)) : w.tm[j];
    S tf(0);
    if (all) tf = friction_.torque(j, wm, w.applied[j], ds_.modes);
    if (friction_part_ == FrictionPart::kSmooth) tf = friction_.smooth_torque(j, wm);
    w.tau[j] = S(Z) * (w.tm[j] - tf);
    if (ledger_.on()) w.p_f += tf * wm;  // a stuck hybrid joint has wm = 0: no loss
  }
  PUMASIM_PROFILE_PART(kDynamics);
  if (all && friction_.has_events()) {
    body_.constrained_accelerations(w, [&](int j) { return friction_.stuck(j, ds_.modes); });
  } else {
    body_.accelerations(w, need_bias);
  }
}

template <class S>
void Plant::eval(double t, const S* x, S* xdot, Workspace<S>& w) {
  body_.load(layout_, x, w);
  controller_output(t, x, w);
  ledger_.reset(w);
  drive(x, xdot, w);
  friction_and_accelerations(w);
  body_.store(layout_, w, xdot);
  ledger_.store(layout_, w, xdot);
  if (cfg_.controller == ControllerMode::kContinuous) {
    PUMASIM_PROFILE_PART(kController);
    std::visit([&](const auto& c) { c.rates(current_reference(t), x, layout_, w, xdot); }, controller_);
  }
}

void Plant::rhs(double t, const double* x, double* xdot) {
  PUMASIM_PROFILE_CONTEXT(kRhs);
  last_valid_ = false;
  eval(t, x, xdot, *wd_);
  // Remembered for roots(): f of the continued piece (time_derivative) is
  // not quite f at (t, x).
  if (ds_.extend_piece || friction_part_ != FrictionPart::kAll) return;
  t_last_ = t;
  std::copy(x, x + layout_.size, x_last_.begin());
  last_valid_ = true;
}

bool Plant::applied_current(double t, const double* x) const {
  return last_valid_ && t == t_last_ && std::equal(x, x + layout_.size, x_last_.begin());
}

void Plant::rhs_split(double t, const double* x, double* fe, double* fi) {
  last_valid_ = false;
  eval(t, x, fi, *wd_);  // the whole f
  friction_part_ = FrictionPart::kNone;
  eval(t, x, fe, *wd_);  // f without friction
  friction_part_ = FrictionPart::kAll;
  for (int k = 0; k < layout_.size; ++k) fi[k] -= fe[k];  // the friction's part
  if (layout_.i >= 0) {
    for (int j = 0; j < layout_.n; ++j) {  // the current equation: all implicit
      fi[layout_.i + j] += fe[layout_.i + j];
      fe[layout_.i + j] = 0.0;
    }
  }
}

void Plant::linear_diagonal(double* lambda) const {
  std::fill(lambda, lambda + layout_.size, 0.0);
  if (layout_.i < 0) return;
  for (int j = 0; j < layout_.n; ++j) {
    lambda[layout_.i + j] = -motor_.loop_resistance(j) / motor_.params(j).inductance;
  }
}

void Plant::jacobian_exact(double t, const double* x, Eigen::MatrixXd& J) {
  PUMASIM_PROFILE_CONTEXT(kJacobian);
  const int m = layout_.size;
  J.resize(m, m);
  constexpr int N = kJacobianTangents;
  for (int first = 0; first < m; first += N) {  // states first..first+N-1 in one pass
    for (int i = 0; i < m; ++i) tx_[i].seed(x[i], i - first);
    eval(t, tx_.data(), tf_.data(), *wt_);
    const int last = std::min(m, first + N);
    for (int k = first; k < last; ++k) {
      for (int r = 0; r < m; ++r) J(r, k) = tf_[r].deriv(k - first);
    }
  }
}

void Plant::jacobian_per_column(double t, const double* x, Eigen::MatrixXd& J) {
  const int m = layout_.size;
  J.resize(m, m);
  std::vector<Dual>&xx = jx_, &ff = jf_;
  for (int k = 0; k < m; ++k) {
    for (int i = 0; i < m; ++i) xx[i] = Dual(x[i], i == k ? 1.0 : 0.0);
    eval(t, xx.data(), ff.data(), *wj_);
    for (int r = 0; r < m; ++r) J(r, k) = ff[r].deriv();
  }
}

int Plant::time_derivative(double t, const double* x, double* dfdt) {
  const int m = layout_.size;
  // A sampled controller holds its output and a held set-point holds the
  // reference: then f does not depend on t.
  const bool continuous = cfg_.controller == ControllerMode::kContinuous;
  const bool depends_on_t = continuous && ((cfg_.reference && cfg_.setpoint_interval == 0) || law_input_);
  if (!depends_on_t) {
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
  // every stage and their step control is sensitive to its error: measured
  // while this was written, odeint-rodas4p on paper_slow_viscous at rtol 1e-8
  // took about the same number of steps with this, with a fourth-order
  // difference, and with d from 1e-3 s to 1e-5 s, and three times as many with
  // a first-order forward difference of step sqrt(eps) max(1, t).
  constexpr double d = 1e-5;  // [s]
  struct Continued {  // the continued piece for the duration of the difference, even on a throw
    explicit Continued(PlantDiscreteState& s) : s_(s) { s_.extend_piece = true, s_.ref_time = std::nan(""); }
    ~Continued() { s_.extend_piece = false, s_.ref_time = std::nan(""); }  // the cache held a continued piece
    PlantDiscreteState& s_;
  } continued(ds_);
  rhs(t, x, dfdt);
  rhs(t + d, x, ft_[0].data());
  rhs(t + 2 * d, x, ft_[1].data());
  for (int r = 0; r < m; ++r) dfdt[r] = (-3 * dfdt[r] + 4 * ft_[0][r] - ft_[1][r]) / (2 * d);
  return 3;
}

double Plant::next_time_event(double t) const {
  double next = std::numeric_limits<double>::infinity();
  if (cfg_.controller == ControllerMode::kSampled) next = std::min(next, next_on_grid(t, cfg_.servo_period));
  if (cfg_.reference && cfg_.setpoint_interval > 0 && cfg_.controller != ControllerMode::kNone) {
    next = std::min(next, next_on_grid(t, cfg_.setpoint_interval));
  }
  // Where the continuously followed reference has a kink, f(t, x) has one:
  // a stop there keeps every step within a smooth piece.
  if (cfg_.reference && cfg_.setpoint_interval == 0 && cfg_.controller != ControllerMode::kNone) {
    next = std::min(next, cfg_.reference->next_breakpoint(t));
  }
  // And where a law's own input jumps or kinks (an open-loop input's rows).
  if (cfg_.controller != ControllerMode::kNone) {
    next = std::min(next, std::visit([t](const auto& c) { return c.next_time_event(t); }, controller_));
  }
  return next;
}

void Plant::on_time_event(double t, double* x) {
  PUMASIM_PROFILE_CONTEXT(kEvents);
  last_valid_ = false;
  if (cfg_.controller == ControllerMode::kNone) return;
  ds_.controller.piece = std::visit([t](const auto& c) { return c.piece_after(t); }, controller_);
  if (cfg_.reference) {  // the reference's smooth piece from here on
    ds_.ref_segment = cfg_.reference->segment_after(t);
    ds_.ref_time = std::numeric_limits<double>::quiet_NaN();
  }
  if (cfg_.reference && cfg_.setpoint_interval > 0 && on_grid(t, cfg_.setpoint_interval)) {
    cfg_.reference->eval(t, ds_.ref_held);
  }
  if (cfg_.controller == ControllerMode::kSampled && on_grid(t, cfg_.servo_period)) {
    const ControllerClock clock{t, ds_.controller.piece, false};
    std::visit([&](const auto& c) { c.sample(clock, current_reference(t), x, layout_, *wd_, ds_.controller); },
               controller_);
  }
  settle_modes(t, x);
  log_modes(t);
}

int Plant::num_roots() const { return friction_.has_events() ? layout_.n : 0; }

// Only a stuck joint's function needs f's work: its applied torque, from the
// constrained dynamics at (t, x) (the last f's when that was at the same
// (t, x) under the same modes); a slipping joint's is its speed.
void Plant::roots(double t, const double* x, double* g) {
  PUMASIM_PROFILE_CONTEXT(kRoots);
  bool stuck = false;
  for (int j = 0; j < layout_.n; ++j) stuck = stuck || (friction_.has_events(j) && ds_.modes[j] == SlipMode::kStuck);
  if (stuck && !applied_current(t, x)) rhs(t, x, ftmp_.data());  // fills the applied torques
  for (int j = 0; j < layout_.n; ++j) {
    if (!friction_.has_events(j)) {
      g[j] = 1.0;
      continue;
    }
    const double wm = body_.gear_ratio(j) * x[layout_.qd + j];
    g[j] = ds_.modes[j] == SlipMode::kStuck ? friction_.params(j).static_torque - std::abs(applied_torque(j))
                                            : wm * static_cast<int>(ds_.modes[j]);
  }
}

void Plant::on_root(int j, double t, double* x) {
  PUMASIM_PROFILE_CONTEXT(kEvents);
  last_valid_ = false;
  if (ds_.modes[j] != SlipMode::kStuck) {  // the speed reached zero: stick (the solve may release it)
    x[layout_.qd + j] = 0.0;
    ds_.modes[j] = SlipMode::kStuck;
    solve_modes(t, x, -1);
  } else {  // break-away: |applied| reached Fs; it slips, in the direction the solve finds
    solve_modes(t, x, j);
  }
  log_modes(t);
}

// The net changes since the last record, each with the applied torque that
// decided it: for a stick, the constraint torque holding the joint after the
// change (settle_modes' last evaluation was at the final modes); for a
// release, the constraint torque that reached or passed Fs just before it.
void Plant::log_modes(double t) {
  if (!friction_.has_events() || logged_.empty()) return;  // (inside initial_state: not yet)
  for (int j = 0; j < layout_.n; ++j) {
    const auto k = static_cast<std::size_t>(j);
    if (!friction_.has_events(j) || ds_.modes[k] == logged_[k]) continue;
    const double applied = ds_.modes[k] == SlipMode::kStuck ? applied_torque(j) : released_[k];
    mode_log_.push_back({t, j, ds_.modes[k], applied});
    logged_[k] = ds_.modes[k];
  }
}

bool Plant::joint_has_modes(int j) const {
  const FrictionParams& f = friction_.params(j);
  return friction_keys(f.model).levels && (f.static_torque > 0 || f.kinetic_torque > 0);
}

void Plant::classify_modes(double t, const double* x, double stick_speed, SlipMode* mode, double* applied,
                           bool always_applied, bool speed_only) {
  bool evaluate = always_applied && friction_.needs_applied_torque() && !speed_only;
  for (int j = 0; j < layout_.n; ++j) {
    const bool slow = std::abs(body_.gear_ratio(j) * x[layout_.qd + j]) <= stick_speed;
    evaluate |= slow && needs_applied_torque(friction_.params(j).model) && !speed_only;
  }
  if (evaluate) rhs(t, x, ftmp_.data());  // fills the applied torques
  for (int j = 0; j < layout_.n; ++j) {
    const double wm = body_.gear_ratio(j) * x[layout_.qd + j];
    const FrictionParams& f = friction_.params(j);
    const bool branch = needs_applied_torque(f.model) && !speed_only;
    applied[j] = !branch ? std::numeric_limits<double>::quiet_NaN() : evaluate ? applied_torque(j) : 0.0;
    const bool held = !branch || std::abs(applied[j]) <= f.static_torque;
    const double direction = wm != 0 ? wm : applied[j];
    mode[j] = std::abs(wm) <= stick_speed && held ? SlipMode::kStuck
              : direction >= 0                    ? SlipMode::kPositive
                                                  : SlipMode::kNegative;
  }
}

void Plant::settle_modes(double t, double* x) { solve_modes(t, x, -1); }

// W = Z (H^-1)_CC Z over the k joints cand_ (H in wd_ from the last
// evaluation), and b = W applied_C.
void Plant::stick_operator(int k) {
  wd_->chol.factor(wd_->H);
  for (int a = 0; a < k; ++a) {
    const int ja = cand_[a];
    col_.setZero();
    col_[ja] = body_.gear_ratio(ja);
    wd_->chol.solve_in_place(col_);
    for (int c = 0; c < k; ++c) cw_[c * k + a] = body_.gear_ratio(cand_[c]) * col_[cand_[c]];
  }
  for (int a = 0; a < k; ++a) {
    cb_[a] = 0.0;
    for (int c = 0; c < k; ++c) cb_[a] += cw_[a * k + c] * applied_torque(cand_[c]);
  }
}

// The coupled mode solve over the joints at rest (the stuck ones; `breaking`
// among them may only slip), at acceleration level (see num_roots above). A
// mode switch (or a controller sample) changes every held joint's torque at
// once through H, so their modes are one problem; the greedy release it
// replaces (the largest excess first, one at a time) can end in modes that
// are not consistent (tests/test_moreau_jean.cpp).
void Plant::solve_modes(double t, double* x, int breaking) {
  if (!friction_.has_events()) return;
  PUMASIM_PROFILE_CONTEXT(kEvents);
  // A slipping joint whose speed is zero or past it (a fixed-step method
  // stops at the first root of a step only: another joint's reversal in the
  // same step is then already behind, and its root function would never
  // cross zero again) is at a reversal too: stuck, then part of the solve.
  for (int j = 0; j < layout_.n; ++j) {
    const auto mode = ds_.modes[static_cast<std::size_t>(j)];
    if (!friction_.has_events(j) || mode == SlipMode::kStuck) continue;
    if (body_.gear_ratio(j) * x[layout_.qd + j] * static_cast<int>(mode) > 0) continue;
    x[layout_.qd + j] = 0.0;
    ds_.modes[static_cast<std::size_t>(j)] = SlipMode::kStuck;
  }
  rhs(t, x, ftmp_.data());  // the held joints' applied torques, and H
  int k = 0;
  for (int j = 0; j < layout_.n; ++j) {
    if (friction_.stuck(j, ds_.modes)) cand_[k++] = j;
  }
  if (k == 0) return;
  stick_operator(k);
  for (int a = 0; a < k; ++a) {
    const FrictionParams& f = friction_.params(cand_[a]);
    cs_[a] = std::max(f.static_torque, f.kinetic_torque);
    ck_[a] = f.kinetic_torque;
    may_stick_[a] = cand_[a] != breaking;
  }
  const StickProblem p{k, cw_.data(), cb_.data(), cs_.data(), ck_.data(), may_stick_.get()};
  stick_result_ = stick_.solve(p, cr_.data(), cand_mode_.data());
  ++stick_stats_.solves;
  stick_stats_.iterations += stick_result_.iterations;
  if (!(stick_result_.converged && stick_result_.consistent)) ++stick_stats_.unconverged;
  stick_stats_.worst_residual = std::max(stick_stats_.worst_residual, stick_result_.residual);
  for (int a = 0; a < k; ++a) {
    const int m = cand_mode_[a];
    const auto j = static_cast<std::size_t>(cand_[a]);
    if (m != 0) released_[j] = applied_torque(cand_[a]);  // the constraint torque it was released at
    ds_.modes[j] = m == 0 ? SlipMode::kStuck : (m > 0 ? SlipMode::kPositive : SlipMode::kNegative);
  }
  last_valid_ = false;
  rhs(t, x, ftmp_.data());  // the applied torques at the final modes (log_modes reads them)
}

void Plant::rhs_smooth(double t, const double* x, double* xdot) {
  last_valid_ = false;  // wd_ holds this evaluation, not the last f
  friction_part_ = FrictionPart::kSmooth;
  eval(t, x, xdot, *wd_);
  friction_part_ = FrictionPart::kAll;
}

void Plant::jacobian_smooth(double t, const double* x, Eigen::MatrixXd& J) {
  struct Restore {  // even on a throw
    FrictionPart& p;
    ~Restore() { p = FrictionPart::kAll; }
  } restore{friction_part_};
  friction_part_ = FrictionPart::kSmooth;
  jacobian_exact(t, x, J);
}

void Plant::set_valued_directions(const double* x, double* B) {
  const int m = layout_.size, k = set_valued_joints();
  std::fill(B, B + static_cast<std::ptrdiff_t>(m) * k, 0.0);
  if (k == 0) return;
  body_.load(layout_, x, *wd_);
  wd_->backend->mass_matrix(wd_->q, wd_->H);
  wd_->chol.factor(wd_->H);
  for (int c = 0; c < k; ++c) {
    const int j = sv_joint_[static_cast<std::size_t>(c)];
    col_.setZero();
    col_[j] = body_.gear_ratio(j);
    wd_->chol.solve_in_place(col_);
    for (int i = 0; i < layout_.n; ++i) B[static_cast<std::ptrdiff_t>(c) * m + layout_.qd + i] = col_[i];
  }
}

// The discrete state at t = 0: no held output or integral, every hybrid
// joint stuck, the set-point the reference's start (or, without a reference,
// the initial pose q, which a controller then holds).
void Plant::start_discrete_state(const Eigen::VectorXd& q) {
  ds_.ref_time = std::numeric_limits<double>::quiet_NaN();
  ds_.ref_segment = 0;
  ds_.controller.piece = 0;
  std::fill(ds_.controller.u_held.begin(), ds_.controller.u_held.end(), 0.0);
  std::fill(ds_.controller.memory.begin(), ds_.controller.memory.end(), 0.0);
  // Joints with stick/slip events start stuck; the others slip (a law
  // without modes ignores them; the hybrid law without friction levels has
  // no events, and slipping its torque is B w_m).
  for (int j = 0; j < layout_.n; ++j) ds_.modes[j] = friction_.has_events(j) ? SlipMode::kStuck : SlipMode::kPositive;
  if (cfg_.reference) return;
  ds_.ref_held.q.setZero();
  ds_.ref_held.qd.setZero();
  ds_.ref_held.qdd.setZero();
  ds_.ref_held.p.setZero();
  ds_.ref_held.v.setZero();
  ds_.ref_held.q.head(layout_.n) = q;
}

// At rest at q: the currents hold gravity and the controller's memory (the
// PIV integrals) supplies the voltage that drives them.
void Plant::hold_gravity(const Eigen::VectorXd& q, double* x) {
  Eigen::VectorXd g(layout_.n);
  wd_->backend->gravity(q, g);
  for (int j = 0; j < layout_.n; ++j) {
    const double i = motor_.holding_current(j, g[j], body_.gear_ratio(j));
    if (layout_.i >= 0) x[layout_.i + j] = i;
    const double u = motor_.loop_resistance(j) * i / amplifier_.params(j).gain;
    std::visit([&](const auto& c) { c.hold(j, u, x, layout_, ds_.controller); }, controller_);
  }
}

// An open-loop input holds nothing: at rest, the currents its first output
// drives through each loop (di/dt = 0 at the start; the reduced model's
// algebraic current is that already).
void Plant::input_currents(double* x) {
  if (layout_.i < 0) return;
  body_.load(layout_, x, *wd_);
  controller_output(0.0, x, *wd_);
  for (int j = 0; j < layout_.n; ++j) {
    x[layout_.i + j] = amplifier_.output(j, wd_->u[j]) / motor_.loop_resistance(j);
  }
}

void Plant::initial_state(double* x) {
  const int n = layout_.n;
  std::fill(x, x + layout_.size, 0.0);
  logged_.clear();
  Eigen::VectorXd q(n);
  if (cfg_.reference) {
    cfg_.reference->eval(0.0, ds_.ref_held);
    q = ds_.ref_held.q.head(n);
  } else {
    q = cfg_.q0;
  }
  start_discrete_state(q);
  for (int j = 0; j < n; ++j) x[layout_.q + j] = q[j];
  if (cfg_.drive && !law_input_) hold_gravity(q, x);
  on_time_event(0.0, x);  // first set-point and controller sample (e = 0 on the reference)
  if (cfg_.drive && law_input_) input_currents(x);
  settle_modes(0.0, x);  // hybrid joints start stuck unless already pushed past Fs
  mode_log_.clear();     // the modes at t = 0, one entry per joint with events
  logged_.assign(static_cast<std::size_t>(n), SlipMode{2});  // no mode: every joint logged
  log_modes(0.0);
}

double Plant::mechanical_energy(const double* x, double* kinetic) {
  const int n = layout_.n;
  Eigen::VectorXd q(n), qd(n);
  for (int j = 0; j < n; ++j) q[j] = x[layout_.q + j], qd[j] = x[layout_.qd + j];
  Eigen::MatrixXd H(n, n);
  wd_->backend->mass_matrix(q, H);
  const double T_kin = 0.5 * qd.dot(H * qd);
  if (kinetic) *kinetic = T_kin;
  return T_kin + potential_energy(model_, q);  // the simulated links, held ones merged into the last
}

double Plant::magnetic_energy(const double* x) const {
  if (layout_.i < 0) return 0.0;
  double E = 0;
  for (int j = 0; j < layout_.n; ++j) E += 0.5 * motor_.params(j).inductance * x[layout_.i + j] * x[layout_.i + j];
  return E;
}

Eigen::Vector3d Plant::tool_position(const double* x) const {
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  tool_pose(x, R, p);
  return p;
}

void Plant::tool_pose(const double* x, Eigen::Matrix3d& R, Eigen::Vector3d& p) const {
  Eigen::Matrix<double, 6, 1> q = cfg_.q_held;
  for (int j = 0; j < layout_.n; ++j) q[j] = x[layout_.q + j];
  forward_kinematics<double>(cfg_.robot, q, R, p);
}

void Plant::drive_signals(double t, const double* x, DriveSignals* out) {
  last_valid_ = false;
  eval(t, x, ftmp_.data(), *wd_);
  for (int j = 0; j < layout_.n; ++j) {
    out[j] = {wd_->u[j], wd_->ea[j], cfg_.drive ? wd_->tm[j] / motor_.params(j).torque_constant : 0.0};
  }
}

}  // namespace pumasim
