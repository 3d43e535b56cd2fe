#include "models/plant/plant_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/dynamics/chain.hpp"
#include "models/dynamics/tangent_backend.hpp"
#include "models/plant/physical_bounds.hpp"
#include "models/plant/profile.hpp"

namespace pumasim {

namespace {

// t on the grid k * period (sample times, set-point updates), to rounding.
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

ControllerBlock controller_block(const PlantConfig& c) {
  return make_controller(c.controller, c.controller_params, {gear_ratios(c), c.servo_period, c.amplifier, c.motor});
}

bool has_tabulated_reference(const PlantConfig& c) {
  return c.tabulate_reference && c.reference && ReferenceTable::tabulates(*c.reference);
}

}  // namespace

RobotModel simulated_robot(const RobotModel& robot, int n, const Eigen::VectorXd& q_held) {
  if (n >= robot.dof()) return robot;
  return lock_joints(robot, n, q_held.size() == 0 ? Eigen::VectorXd::Zero(robot.dof()) : q_held);
}

Eigen::VectorXd start_pose(const PlantConfig& c) {
  if (!c.reference) return c.q0;
  ReferenceSample s;
  c.reference->eval(0.0, s);
  return s.q.head(c.n);
}

PlantConfig PlantModel::checked(PlantConfig c) {
  const int n = c.n;
  if (c.q_held.size() == 0) c.q_held = Eigen::VectorXd::Zero(c.robot.dof());
  if (c.q_held.size() != c.robot.dof()) throw std::invalid_argument("plant: q_held needs one entry per joint");
  if (n < 1 || n > c.robot.dof()) throw std::invalid_argument("plant: joint count out of range");
  if (c.reference && (c.reference->simulated_joints() != n || c.reference->robot_joints() != c.robot.dof())) {
    throw std::invalid_argument("plant: the reference is for " + std::to_string(c.reference->simulated_joints()) +
                                " of " + std::to_string(c.reference->robot_joints()) + " joints, the plant simulates " +
                                std::to_string(n) + " of " + std::to_string(c.robot.dof()));
  }
  const auto sized = [n](std::size_t s) { return s == static_cast<std::size_t>(n); };
  if (!sized(c.friction.size())) throw std::invalid_argument("plant: one friction block per joint");
  if (c.drive && (!sized(c.amplifier.size()) || !sized(c.motor.size()))) {
    throw std::invalid_argument("plant: one amplifier and motor per joint");
  }
  if (c.algebraic_current && (!c.drive || std::any_of(c.motor.begin(), c.motor.end(),
                                                      [](const MotorParams& m) { return m.inductance != 0; }))) {
    throw std::invalid_argument("plant: algebraic currents need a drive with La = 0 for every joint");
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
  for (const FrictionParams& f : c.friction) {
    if (c.energy_ledger && friction_states(f.model) > 0) {
      throw std::invalid_argument(std::string("plant: the energy ledger does not count the potential energy of ") +
                                  to_string(f.model) +
                                  "'s bristles (sigma0 z^2 / 2); expected scene.energy_ledger = false, or a law "
                                  "without a state");
    }
  }
  if (c.controller == ControllerMode::kSampled && !(c.servo_period > 0)) {
    throw std::invalid_argument("plant: a sampled controller needs a servo period > 0");
  }
  return c;
}

std::string why_no_implicit_form(const PlantConfig& c) {
  for (std::size_t j = 0; j < c.friction.size(); ++j) {
    const FrictionModel m = c.friction[j].model;
    if (needs_applied_torque(m) && !has_stick_slip_events(m)) {
      return "joint " + std::to_string(j + 1) + "'s friction law (friction.model = \"" + to_string(m) +
             "\") switches at rest inside a speed band on the torque applied there, with no event: its friction "
             "depends on the accelerations' own solve (h, then H^-1), and it jumps at the band's edges where no root "
             "function tells the integrator; the residual form has neither. Expected a law with events (\"hybrid\") "
             "or a smooth one";
    }
  }
  return {};
}

std::string why_no_ode_form(const PlantConfig& c) {
  if (c.drive && c.algebraic_current) {
    return "motor.current = \"algebraic\" keeps the currents as algebraic unknowns (0 = e_a - (R0 + R) i - K w_m, "
           "La = 0): the drive is an index-1 DAE, which only a residual-form method (ida) integrates and which "
           "has no right-hand side f for ODE methods and analyses; motor.current = \"eliminated\" (the default) "
           "is the same model as an ODE";
  }
  return {};
}

std::string why_not_conservative(const PlantConfig& c) {
  if (c.controller != ControllerMode::kNone) {
    return "the arm is driven (a [controller] and its drive); expected a passive arm: no [controller], no [drive]";
  }
  for (std::size_t j = 0; j < c.friction.size(); ++j) {
    if (!c.friction[j].model.none()) {
      return "joint " + std::to_string(j + 1) + " has friction (friction.model = \"" + to_string(c.friction[j].model) +
             "\"); expected friction.model = \"none\": a lossless arm";
    }
  }
  return {};
}

void PlantModel::validate(const PlantConfig& config) {
  const PlantConfig c = checked(config);
  const std::string why = find_backend(c.backend).why_unsupported(simulated_robot(c.robot, c.n, c.q_held));
  if (!why.empty()) throw std::invalid_argument(why);
  const MotorBlock motor(if_drive(c, c.motor), if_drive(c, c.amplifier), c.drive && c.algebraic_current);
  const ControllerBlock controller = controller_block(c);
  (void)motor, (void)controller;
}

PlantModel::PlantModel(PlantConfig config) : PlantModel(std::move(config), nullptr) {}

PlantModel::PlantModel(PlantConfig config, const PlantModel& shared) : PlantModel(std::move(config), &shared) {}

PlantModel::PlantModel(PlantConfig config, const PlantModel* shared)
    : cfg_(checked(std::move(config))),
      model_(simulated_robot(cfg_.robot, cfg_.n, cfg_.q_held)),
      backend_(find_backend(cfg_.backend)),
      body_(gear_ratios(cfg_)),
      amplifier_(if_drive(cfg_, cfg_.amplifier)),
      motor_(if_drive(cfg_, cfg_.motor), if_drive(cfg_, cfg_.amplifier), cfg_.drive && cfg_.algebraic_current),
      friction_(cfg_.friction),
      controller_(controller_block(cfg_)),
      ledger_(cfg_.energy_ledger),
      torque_input_(cfg_.controller != ControllerMode::kNone &&
                    controller_command(cfg_.controller_params) == ControllerCommand::kTorque),
      law_input_(std::visit([](const auto& c) { return std::decay_t<decltype(c)>::kHasInput; }, controller_)) {
  const int n = cfg_.n;
  if (const std::string why = backend_.why_unsupported(model_); !why.empty()) throw std::invalid_argument(why);
  layout_.n = n;
  body_.declare(layout_);
  std::vector<double> full_command;  // the stall current's scale: min(K_A u_max, V_max)
  for (int j = 0; j < n && cfg_.drive; ++j) {
    full_command.push_back(command_voltage_range(cfg_.amplifier[j], controller_output_limit(cfg_.controller_params, j)));
  }
  motor_.declare(layout_, full_command);
  std::visit([&](const auto& c) { c.declare(layout_); }, controller_);
  friction_.declare(layout_);
  ledger_.declare(layout_);
  declare_bounds(full_command);
  for (int j = 0; j < n; ++j) {
    if (friction_.set_valued(j)) sv_joint_.push_back(j);
  }
  if (has_tabulated_reference(cfg_)) {
    const bool same = shared && shared->ref_table_ && shared->cfg_.reference == cfg_.reference;
    const bool given = cfg_.reference_table && &cfg_.reference_table->reference() == cfg_.reference.get();
    ref_table_ = same    ? shared->ref_table_
                 : given ? cfg_.reference_table
                         : std::make_shared<const ReferenceTable>(*cfg_.reference);
  }
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
}

PlantModel::~PlantModel() = default;

void PlantModel::declare_bounds(const std::vector<double>& full_command) {
  const int n = layout_.n;
  PhysicalBounds b;
  if (cfg_.drive) {
    b = drive_bounds(cfg_.amplifier, cfg_.motor, gear_ratios(cfg_), full_command);
  } else if (cfg_.controller == ControllerMode::kNone) {  // passive: at rest at q0
    Eigen::MatrixXd H(n, n);
    backend_.make(model_)->mass_matrix(cfg_.q0, H);
    b = passive_bounds(model_, cfg_.q0, H);
  }
  for (int j = 0; j < n && !b.qd.empty(); ++j) {
    const auto k = static_cast<std::size_t>(j);
    layout_.set_bound(layout_.qd + j, b.qd[k], b.qd_why[k]);
    if (layout_.i >= 0) layout_.set_bound(layout_.i + j, b.current[k], b.current_why[k]);
  }
}

PlantContext PlantModel::make_context() const {
  PlantContext c;
  const int n = layout_.n;
  c.controller.u_held.assign(static_cast<std::size_t>(n), 0.0);
  c.controller.memory.assign(std::visit([](const auto& b) { return b.discrete_size(); }, controller_), 0.0);
  c.modes.assign(static_cast<std::size_t>(n), SlipMode::kStuck);
  if (cfg_.reference) {
    c.ref_held = cfg_.reference->sample();
  } else {
    c.ref_held.q = cfg_.q_held;
    c.ref_held.qd = c.ref_held.qdd = Eigen::VectorXd::Zero(cfg_.q_held.size());
    c.ref_held.p.setZero();
    c.ref_held.v.setZero();
  }
  return c;
}

template <class S>
std::unique_ptr<PlantWorkspace<S>> PlantModel::make_workspace() const {
  auto w = std::make_unique<PlantWorkspace<S>>(layout_.n, layout_.size);
  if (cfg_.reference) w->reference = cfg_.reference->sample();
  if constexpr (std::is_same_v<S, double>) {
    w->backend = backend_.make(model_);
  } else if constexpr (std::is_same_v<S, Dual>) {
    w->backend = backend_.make_dual(model_);
  } else {
    w->backend = std::make_unique<TangentBackend<kJacobianTangents>>(model_, backend_.make(model_));
  }
  return w;
}

template <class S>
const ReferenceSample& PlantModel::reference(const PlantContext& c, PlantWorkspace<S>& w, double t) const {
  if (cfg_.setpoint_interval > 0 || !cfg_.reference) return c.ref_held;
  if (t != w.reference_t || c.ref_segment != w.reference_segment || w.extend_piece != w.reference_extended) {
    PUMASIM_PROFILE_PART(kReference);
    if (ref_table_) {
      ref_table_->eval(t, w.reference, c.ref_segment, w.extend_piece);
    } else {
      cfg_.reference->eval(t, w.reference, c.ref_segment, w.extend_piece);
    }
    w.reference_t = t;
    w.reference_segment = c.ref_segment;
    w.reference_extended = w.extend_piece;
  }
  return w.reference;
}

template <class S>
void PlantModel::controller_output(const PlantContext& c, PlantWorkspace<S>& w, double t, const S* x) const {
  PUMASIM_PROFILE_PART(kController);
  if (cfg_.controller == ControllerMode::kContinuous) {
    const ControllerClock clock{t, c.controller.piece, w.extend_piece};
    std::visit([&](const auto& law) { law.output(clock, reference(c, w, t), x, layout_, w); }, controller_);
    return;
  }
  const bool held = cfg_.controller == ControllerMode::kSampled;  // else no controller: u = 0
  for (int j = 0; j < layout_.n; ++j) w.u[j] = held ? S(c.controller.u_held[static_cast<std::size_t>(j)]) : S(0);
}

// Amplifier and motor: e_a, the current (state or algebraic), K i; the
// electrical powers for the ledger. Without a drive the motor torque is 0, or
// a torque input's joint torque u reflected to the motor side, u / Z, which
// puts in the power u qd.
template <class S>
void PlantModel::drive(const S* x, S* xdot, PlantWorkspace<S>& w) const {
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

// f's blocks in their order: the joints, the controller, the drive, the
// friction and joint torques, then `accelerations(need_bias)` (which sets
// w.qdd: f's forward dynamics, or the residual's given qdd), then the rows
// that store them, the ledger and the controller's rates into xdot.
template <class S, class Accelerations>
void PlantModel::derivatives(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, double t, const S* x,
                             S* xdot, Accelerations&& accelerations) const {
  body_.load(layout_, x, w);
  controller_output(c, w, t, x);
  ledger_.reset(w);
  drive(x, xdot, w);
  accelerations(friction_torques(c, w, part, x, xdot));
  body_.store(layout_, w, xdot);
  ledger_.store(layout_, w, xdot);
  if (cfg_.controller == ControllerMode::kContinuous) {
    PUMASIM_PROFILE_PART(kController);
    std::visit([&](const auto& law) { law.rates(reference(c, w, t), x, layout_, w, xdot); }, controller_);
  }
}

// The accelerations of f (constrained where the hybrid model holds a joint).
template <class S>
void PlantModel::accelerations(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, bool need_bias) const {
  PUMASIM_PROFILE_PART(kDynamics);
  if (part == FrictionPart::kAll && friction_.has_events()) {
    body_.constrained_accelerations(w, [&](int j) { return friction_.stuck(j, c.modes); });
  } else {
    body_.accelerations(w, need_bias);
  }
}

// Friction and the joint torques w.tau (the friction states' rates into
// xdot); true when it formed w.h = bias(q, qd) (a law that reads the applied torque).
template <class S>
bool PlantModel::friction_torques(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, const S* x,
                                  S* xdot) const {
  const bool all = part == FrictionPart::kAll;
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
    if (friction_.has_state(j)) {  // smooth: all of it in the smooth part; none of it (z held) without friction
      S zdot(0);
      if (part != FrictionPart::kNone) tf = friction_.state_torque(j, wm, x[layout_.zf + j], zdot);
      xdot[layout_.zf + j] = zdot;
    } else {
      if (all) tf = friction_.torque(j, wm, w.applied[j], c.modes);
      if (part == FrictionPart::kSmooth) tf = friction_.smooth_torque(j, wm);
      if (friction_.has_state()) xdot[layout_.zf + j] = S(0);  // a stateless law's component stays at 0
    }
    w.tau[j] = S(Z) * (w.tm[j] - tf);
    if (ledger_.on()) w.p_f += tf * wm;  // a stuck hybrid joint has wm = 0: no loss
  }
  return need_bias;
}

// F(t, x, xp) = xp - f(t, x) on every row but the speeds', where it is the
// inverse dynamics ID(q, qd, qdd = xp_qd) - tau (one back-end call, no
// factorisation of H), or qdd_j for a joint the hybrid model holds (its
// friction is whatever holds it, which the other rows do not need), and but
// algebraic currents' rows, -(e_a - (R0 + R) i - K w_m) (no xp).
void PlantModel::residual(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, const double* xp,
                          double* r) const {
  w.last_valid = false;
  const int n = layout_.n;
  // f's rows into r, with qdd = xp_qd and its inverse dynamics (the speeds' rows are replaced below).
  derivatives(c, w, FrictionPart::kAll, t, x, r, [&](bool) {
    for (int j = 0; j < n; ++j) w.qdd[j] = xp[layout_.qd + j];
    PUMASIM_PROFILE_PART(kDynamics);
    w.backend->inverse_dynamics(w.q, w.qd, w.qdd, w.id);
  });
  const int a0 = motor_.algebraic() ? layout_.i : layout_.size, a1 = motor_.algebraic() ? layout_.i + n : 0;
  for (int i = 0; i < layout_.size; ++i) r[i] = i >= a0 && i < a1 ? -r[i] : xp[i] - r[i];
  const bool events = friction_.has_events();
  for (int j = 0; j < n; ++j) {
    r[layout_.qd + j] = events && friction_.stuck(j, c.modes) ? xp[layout_.qd + j] : w.id[j] - w.tau[j];
  }
}

template <class S>
void PlantModel::eval(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, double t, const S* x,
                      S* xdot) const {
  if constexpr (std::is_same_v<S, double>) w.last_valid = false;
  derivatives(c, w, part, t, x, xdot, [&](bool need_bias) { accelerations(c, w, part, need_bias); });
  if constexpr (std::is_same_v<S, double>) {
    // Remembered for the root functions: f of the continued piece (a
    // difference in t) is not quite f at (t, x).
    if (w.extend_piece || part != FrictionPart::kAll) return;
    w.last_t = t;
    std::copy(x, x + layout_.size, w.last_x.begin());
    w.last_valid = true;
  }
}

bool PlantModel::depends_on_time() const {
  // A sampled controller holds its output and a held set-point holds the
  // reference: then f does not depend on t.
  const bool continuous = cfg_.controller == ControllerMode::kContinuous;
  return continuous && ((cfg_.reference && cfg_.setpoint_interval == 0) || law_input_);
}

void PlantModel::linear_diagonal(double* lambda) const {
  std::fill(lambda, lambda + layout_.size, 0.0);
  if (layout_.i < 0 || motor_.algebraic()) return;  // an algebraic row has no rate (no ODE method integrates it)
  for (int j = 0; j < layout_.n; ++j) {
    lambda[layout_.i + j] = -motor_.loop_resistance(j) / motor_.params(j).inductance;
  }
}

double PlantModel::next_time_event(double t) const {
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

bool PlantModel::time_event(PlantContext& c, PlantWorkspace<double>& w, double t, const double* x) const {
  w.last_valid = false;
  if (cfg_.controller == ControllerMode::kNone) return false;
  c.controller.piece = std::visit([t](const auto& law) { return law.piece_after(t); }, controller_);
  if (cfg_.reference) c.ref_segment = cfg_.reference->segment_after(t);  // the reference's smooth piece from here on
  if (cfg_.reference && cfg_.setpoint_interval > 0 && on_grid(t, cfg_.setpoint_interval)) {
    cfg_.reference->eval(t, c.ref_held);
  }
  if (cfg_.controller == ControllerMode::kSampled && on_grid(t, cfg_.servo_period)) {
    const ControllerClock clock{t, c.controller.piece, false};
    std::visit([&](const auto& law) { law.sample(clock, reference(c, w, t), x, layout_, w, c.controller); },
               controller_);
  }
  return true;
}

// At rest at q: the currents hold gravity and the controller's memory (the
// PIV integrals) supplies the voltage that drives them.
void PlantModel::hold_gravity(PlantContext& c, PlantWorkspace<double>& w, const Eigen::VectorXd& q,
                              double* x) const {
  Eigen::VectorXd g(layout_.n);
  w.backend->gravity(q, g);
  for (int j = 0; j < layout_.n; ++j) {
    const double i = motor_.holding_current(j, g[j], body_.gear_ratio(j));
    if (layout_.i >= 0) x[layout_.i + j] = i;
    const double u = motor_.loop_resistance(j) * i / amplifier_.params(j).gain;
    std::visit([&](const auto& law) { law.hold(j, u, x, layout_, c.controller); }, controller_);
  }
}

void PlantModel::settle_currents(const PlantContext& c, PlantWorkspace<double>& w, double t, double* x) const {
  if (motor_.algebraic()) balance_currents(c, w, t, x);
}

// The current slice set to the balance's solution at (t, x) under c, i = (e_a - K w_m) / (R0 + R).
void PlantModel::balance_currents(const PlantContext& c, PlantWorkspace<double>& w, double t, double* x) const {
  w.last_valid = false;
  body_.load(layout_, x, w);
  controller_output(c, w, t, x);
  for (int j = 0; j < layout_.n; ++j) {
    const double wm = body_.gear_ratio(j) * w.qd[j];
    x[layout_.i + j] = motor_.current(j, amplifier_.output(j, w.u[j]), wm, x, static_cast<double*>(nullptr), -1);
  }
}

// An open-loop input holds nothing: at rest, the currents its first output
// drives through each loop (di/dt = 0 at the start; the reduced model's
// algebraic current is that already).
void PlantModel::input_currents(const PlantContext& c, PlantWorkspace<double>& w, double* x) const {
  if (!(cfg_.drive && law_input_) || layout_.i < 0) return;
  balance_currents(c, w, 0.0, x);  // w_m = 0 at rest: i = e_a / (R0 + R)
}

// The discrete state at t = 0: no held output or integral, every joint with
// stick/slip events stuck (the others slip: a law without modes ignores
// them, and the hybrid law without friction levels, slipping, is B w_m), the
// set-point the reference's start (or, without a reference, the initial pose
// q, which a controller then holds).
void PlantModel::start_state(PlantContext& c, PlantWorkspace<double>& w, double* x) const {
  const int n = layout_.n;
  std::fill(x, x + layout_.size, 0.0);
  c = make_context();
  Eigen::VectorXd q(n);
  if (cfg_.reference) {
    cfg_.reference->eval(0.0, c.ref_held);
    q = c.ref_held.q.head(n);
  } else {
    q = cfg_.q0;
    c.ref_held.q.head(n) = q;
  }
  for (int j = 0; j < n; ++j) c.modes[j] = friction_.has_events(j) ? SlipMode::kStuck : SlipMode::kPositive;
  w.last_valid = false;
  for (int j = 0; j < n; ++j) x[layout_.q + j] = q[j];
  if (cfg_.drive && !law_input_) hold_gravity(c, w, q, x);
}

void PlantModel::drive_signals(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x,
                               double* xdot, DriveSignals* out) const {
  // eval()'s first steps: the signals come before the friction and the
  // dynamics, which they do not need (the current is a state, or the
  // motor's algebraic current from e_a and w_m).
  w.last_valid = false;
  body_.load(layout_, x, w);
  controller_output(c, w, t, x);
  ledger_.reset(w);
  drive(x, xdot, w);  // the root functions do not take the recorder's f (history: commit ffb6d3d)
  for (int j = 0; j < layout_.n; ++j) {
    out[j] = {w.u[j], w.ea[j], cfg_.drive ? w.tm[j] / motor_.params(j).torque_constant : 0.0};
  }
}

bool PlantModel::joint_has_modes(int j) const {
  const FrictionParams& f = friction_.params(j);
  return friction_keys(f.model).levels && (f.static_torque > 0 || f.kinetic_torque > 0);
}

double PlantModel::mechanical_energy(PlantWorkspace<double>& w, const double* x, double* kinetic) const {
  const int n = layout_.n;
  Eigen::VectorXd q(n), qd(n);
  for (int j = 0; j < n; ++j) q[j] = x[layout_.q + j], qd[j] = x[layout_.qd + j];
  Eigen::MatrixXd H(n, n);
  w.backend->mass_matrix(q, H);
  const double T_kin = 0.5 * qd.dot(H * qd);
  if (kinetic) *kinetic = T_kin;
  return T_kin + potential_energy(model_, q);  // the simulated links, held ones merged into the last
}

double PlantModel::magnetic_energy(const double* x) const {
  if (layout_.i < 0) return 0.0;
  double E = 0;
  for (int j = 0; j < layout_.n; ++j) E += 0.5 * motor_.params(j).inductance * x[layout_.i + j] * x[layout_.i + j];
  return E;
}

void PlantModel::tool_pose(const double* x, Eigen::Matrix3d& R, Eigen::Vector3d& p) const {
  // The simulated joints from x, the others held (no copy of q_held).
  struct Joints {
    const double* x;
    int n;
    const Eigen::VectorXd& held;
    double operator[](int j) const { return j < n ? x[j] : held[j]; }
  };
  forward_kinematics<double>(cfg_.robot, Joints{x + layout_.q, layout_.n, cfg_.q_held}, R, p);
}

template std::unique_ptr<PlantWorkspace<double>> PlantModel::make_workspace<double>() const;
template std::unique_ptr<PlantWorkspace<Dual>> PlantModel::make_workspace<Dual>() const;
template std::unique_ptr<PlantWorkspace<PlantModel::Tangent>> PlantModel::make_workspace<PlantModel::Tangent>() const;
template void PlantModel::eval<double>(const PlantContext&, PlantWorkspace<double>&, FrictionPart, double,
                                       const double*, double*) const;
template void PlantModel::eval<Dual>(const PlantContext&, PlantWorkspace<Dual>&, FrictionPart, double, const Dual*,
                                     Dual*) const;
template void PlantModel::eval<PlantModel::Tangent>(const PlantContext&, PlantWorkspace<PlantModel::Tangent>&,
                                                    FrictionPart, double, const Tangent*, Tangent*) const;
template const ReferenceSample& PlantModel::reference<double>(const PlantContext&, PlantWorkspace<double>&,
                                                              double) const;

}  // namespace pumasim
