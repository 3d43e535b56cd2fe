#include "models/plant/plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/dynamics/chain.hpp"

namespace pumasim {

const char* to_string(FrictionModel m) {
  switch (m) {
    case FrictionModel::kNone: return "none";
    case FrictionModel::kViscous: return "viscous";
    case FrictionModel::kPaper: return "paper";
    case FrictionModel::kHybrid: return "hybrid";
    case FrictionModel::kKarnopp: return "karnopp";
    case FrictionModel::kTanh: return "tanh";
  }
  return "?";
}

int StateLayout::index(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (names[k] == name) return static_cast<int>(k);
  }
  return -1;
}

template <class S>
struct Plant::Workspace {
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  std::unique_ptr<BasicDynamicsBackend<S>> backend;
  Vec q, qd, u, ea, tau, qdd, h, tm, applied;
  Mat H, Hc;
  Cholesky<S, Eigen::Dynamic> chol;
  explicit Workspace(int n)
      : q(n), qd(n), u(n), ea(n), tau(n), qdd(n), h(n), tm(n), applied(n), H(n, n), Hc(n, n), chol(n) {}
};

namespace {

bool is_electrical(const PlantConfig& c) {
  if (!c.drive) return false;
  const bool any = std::any_of(c.motor.begin(), c.motor.end(),
                               [](const MotorParams& m) { return m.inductance > 0; });
  const bool all = std::all_of(c.motor.begin(), c.motor.end(),
                               [](const MotorParams& m) { return m.inductance > 0; });
  if (any && !all) {
    throw std::invalid_argument("plant: armature inductance must be > 0 for every joint or 0 for "
                                "every joint (the reduced model)");
  }
  return all;
}

bool on_grid(double t, double period) {
  if (!(period > 0)) return false;
  const double k = t / period;
  return std::abs(k - std::round(k)) < 1e-9 * std::max(1.0, std::abs(k));
}

double next_on_grid(double t, double period) {
  return (std::floor(t / period + 1e-9) + 1.0) * period;
}

}  // namespace

RobotModel simulated_robot(const RobotModel& robot, int n, const Eigen::Matrix<double, 6, 1>& q_held) {
  return n < robot.dof() ? lock_joints(robot, n, q_held.head(robot.dof())) : robot;
}

Plant::Plant(PlantConfig config) : cfg_(std::move(config)) {
  const int n = cfg_.n;
  if (cfg_.robot.dof() != 6 && cfg_.n != cfg_.robot.dof()) {
    throw std::invalid_argument("plant: held joints need a 6-joint robot");
  }
  if (n < 1 || n > cfg_.robot.dof()) throw std::invalid_argument("plant: joint count out of range");
  const auto sized = [n](std::size_t s) { return s == static_cast<std::size_t>(n); };
  if (!sized(cfg_.friction.size())) throw std::invalid_argument("plant: one friction block per joint");
  if (cfg_.drive && (!sized(cfg_.amplifier.size()) || !sized(cfg_.motor.size()))) {
    throw std::invalid_argument("plant: one amplifier and motor per joint");
  }
  if (cfg_.controller != ControllerMode::kNone) {
    if (!sized(cfg_.piv.size())) throw std::invalid_argument("plant: one PIV controller per joint");
    if (!cfg_.reference && cfg_.q0.size() != n) {
      throw std::invalid_argument("plant: a controller needs a reference, or initial angles to hold");
    }
    if (!cfg_.drive) throw std::invalid_argument("plant: a controller needs the drive (amplifier, motor)");
  } else if (cfg_.drive) {
    throw std::invalid_argument("plant: a drive needs a controller");
  } else if (cfg_.q0.size() != n) {
    throw std::invalid_argument("plant: a passive arm needs n initial angles");
  }
  if (cfg_.controller == ControllerMode::kSampled && !(cfg_.servo_period > 0)) {
    throw std::invalid_argument("plant: a sampled controller needs a servo period > 0");
  }
  model_ = simulated_robot(cfg_.robot, n, cfg_.q_held);

  // State layout.
  layout_.n = n;
  layout_.q = 0;
  layout_.qd = n;
  int next = 2 * n;
  if (is_electrical(cfg_)) layout_.i = next, next += n;
  if (cfg_.controller == ControllerMode::kContinuous) layout_.z = next, next += n;
  if (cfg_.energy_ledger) layout_.e = next, next += 3;
  layout_.size = next;
  const auto add = [&](const char* prefix) {
    for (int j = 0; j < n; ++j) layout_.names.push_back(prefix + std::to_string(j + 1));
  };
  add("q");
  add("qd");
  if (layout_.i >= 0) add("i_motor");
  if (layout_.z >= 0) add("z_piv");
  if (layout_.e >= 0) {
    for (const char* name : {"e_in", "e_copper", "e_friction"}) layout_.names.emplace_back(name);
  }
  // Typical magnitudes (tolerance_scale): angles 1 rad, speeds 1 rad/s; a
  // current its stall value at full command, min(K_A u_max, V_max) / (R0 + R);
  // a PIV integral its full range, integral_limit / |Ki|; energies 1 J.
  scale_.assign(static_cast<std::size_t>(layout_.size), 1.0);
  for (int j = 0; j < n; ++j) {
    if (layout_.i >= 0) {
      const AmplifierParams& A = cfg_.amplifier[j];
      const double v = command_voltage_range(A, cfg_.piv[j]);
      const double r = A.output_resistance + cfg_.motor[j].resistance;
      if (v > 0 && r > 0 && std::isfinite(v / r)) scale_[layout_.i + j] = v / r;
    }
    if (layout_.z >= 0 && cfg_.piv[j].ki != 0) scale_[layout_.z + j] = cfg_.piv[j].integral_limit / std::abs(cfg_.piv[j].ki);
  }

  wd_ = std::make_unique<Workspace<double>>(n);
  wd_->backend = find_backend(cfg_.backend).make(model_);
  wj_ = std::make_unique<Workspace<Dual>>(n);
  wj_->backend = find_backend(cfg_.backend).make_dual(model_);
  for (const auto& f : cfg_.friction) {
    needs_bias_ |= f.model == FrictionModel::kPaper || f.model == FrictionModel::kKarnopp;
    hybrid_ |= f.model == FrictionModel::kHybrid;
  }
  u_held_.assign(n, 0.0);
  integral_.assign(n, 0.0);
  mode_.assign(n, SlipMode::kStuck);
  xtmp_.resize(layout_.size);
  ftmp_.resize(layout_.size);
  for (auto& v : ft_) v.resize(layout_.size);
}

Plant::~Plant() = default;

const ReferenceSample& Plant::current_reference(double t) {
  if (cfg_.setpoint_interval > 0 || !cfg_.reference) return ref_held_;
  if (t != ref_time_) {
    cfg_.reference->eval(t, ref_now_, ref_segment_, extend_piece_);
    ref_time_ = t;
  }
  return ref_now_;
}

const ReferenceSample& Plant::reference_at(double t) { return current_reference(t); }

template <class S>
void Plant::controller(double t, const S* x, Workspace<S>& w) {
  const int n = layout_.n;
  if (cfg_.controller == ControllerMode::kSampled) {
    for (int j = 0; j < n; ++j) w.u[j] = S(u_held_[j]);
    return;
  }
  if (cfg_.controller == ControllerMode::kNone) {
    for (int j = 0; j < n; ++j) w.u[j] = S(0);
    return;
  }
  const ReferenceSample& r = current_reference(t);
  for (int j = 0; j < n; ++j) {
    // Motor-side angles: the card reads the motor encoder.
    const PivParams& P = cfg_.piv[j];
    const double Z = cfg_.robot.joints[j].gear_ratio;
    const S e = S(Z) * (S(r.q[j]) - w.q[j]);
    const S z = x[layout_.z + j];
    const S v = S(P.kp) * e + S(P.ki) * z - S(P.kv * Z) * w.qd[j] + S(P.kvff * Z * r.qd[j]) +
                S(P.kaff * Z * r.qdd[j]) + S(P.offset);
    w.u[j] = saturate(v, P.output_limit);
  }
}

template <class S>
void Plant::eval(double t, const S* x, S* xdot, Workspace<S>& w) {
  const int n = layout_.n;
  for (int j = 0; j < n; ++j) {
    w.q[j] = x[layout_.q + j];
    w.qd[j] = x[layout_.qd + j];
  }
  controller(t, x, w);
  S p_in(0), p_cu(0), p_f(0);  // energy ledger: power in, copper and friction losses [W]
  // Drive: amplifier and motor.
  for (int j = 0; j < n; ++j) {
    if (!cfg_.drive) {
      w.tm[j] = S(0);
      w.ea[j] = S(0);
      continue;
    }
    const AmplifierParams& A = cfg_.amplifier[j];
    const MotorParams& M = cfg_.motor[j];
    const S wm = S(cfg_.robot.joints[j].gear_ratio) * w.qd[j];
    const S ea = saturate(S(A.gain) * w.u[j], A.voltage_limit);
    w.ea[j] = ea;
    const S R = S(A.output_resistance + M.resistance);
    S i;
    if (layout_.i >= 0) {
      i = x[layout_.i + j];
      xdot[layout_.i + j] = (ea - R * i - S(M.torque_constant) * wm) / S(M.inductance);
    } else {
      i = (ea - S(M.torque_constant) * wm) / R;
    }
    w.tm[j] = S(M.torque_constant) * i;
    if (layout_.e >= 0) {
      p_in += ea * i;
      p_cu += R * i * i;
    }
  }
  // Friction and the joint torques.
  const bool hybrid = hybrid_ && friction_on_;
  const bool need_bias = needs_bias_ || hybrid;
  if (need_bias) w.backend->bias(w.q, w.qd, w.h);
  for (int j = 0; j < n; ++j) {
    const double Z = cfg_.robot.joints[j].gear_ratio;
    const S wm = S(Z) * w.qd[j];
    w.applied[j] = need_bias ? S(w.tm[j] - w.h[j] / S(Z)) : w.tm[j];
    const S tf = friction_on_ ? friction_torque(cfg_.friction[j], wm, w.applied[j], mode_[j]) : S(0);
    w.tau[j] = S(Z) * (w.tm[j] - tf);
    if (layout_.e >= 0) p_f += tf * wm;  // a stuck hybrid joint has wm = 0: no loss
  }
  if (!hybrid) {
    w.backend->forward_dynamics(w.q, w.qd, w.tau, w.qdd);
  } else {
    // Hybrid stick/slip: a stuck joint has qdd_j = 0 and its friction is
    // whatever holds it. Solve H qdd = tau - h with the stuck joints' rows and
    // columns replaced by the identity (the free block is unchanged since
    // qdd_stuck = 0); then each stuck joint's row of H gives the torque its
    // friction must resist: applied = K i - (h_j + H_j. qdd) / Z_j.
    const auto stuck = [&](int j) {
      return cfg_.friction[j].model == FrictionModel::kHybrid && mode_[j] == SlipMode::kStuck;
    };
    w.backend->mass_matrix(w.q, w.H);
    w.Hc = w.H;
    for (int j = 0; j < n; ++j) {
      w.qdd[j] = w.tau[j] - w.h[j];
      if (!stuck(j)) continue;
      w.qdd[j] = S(0);
      for (int k = 0; k < n; ++k) w.Hc(j, k) = w.Hc(k, j) = S(k == j ? 1 : 0);
    }
    w.chol.factor(w.Hc);
    w.chol.solve_in_place(w.qdd);
    for (int j = 0; j < n; ++j) {
      if (!stuck(j)) continue;
      S sum = w.h[j];
      for (int k = 0; k < n; ++k) sum += w.H(j, k) * w.qdd[k];
      w.applied[j] = w.tm[j] - sum / S(cfg_.robot.joints[j].gear_ratio);
    }
  }
  for (int j = 0; j < n; ++j) {
    xdot[layout_.q + j] = w.qd[j];
    xdot[layout_.qd + j] = w.qdd[j];
  }
  if (layout_.e >= 0) {
    xdot[layout_.e] = p_in;
    xdot[layout_.e + 1] = p_cu;
    xdot[layout_.e + 2] = p_f;
  }
  if (layout_.z >= 0) {
    const ReferenceSample& r = current_reference(t);
    for (int j = 0; j < n; ++j) {
      const PivParams& P = cfg_.piv[j];
      const S e = S(cfg_.robot.joints[j].gear_ratio) * (S(r.q[j]) - w.q[j]);
      const S iz = S(P.ki) * x[layout_.z + j];
      const S ie = S(P.ki) * e;
      const bool windup = (iz >= S(P.integral_limit) && ie > S(0)) ||
                          (iz <= S(-P.integral_limit) && ie < S(0));
      xdot[layout_.z + j] = windup ? S(0) : e;
    }
  }
}

void Plant::rhs(double t, const double* x, double* xdot) { eval(t, x, xdot, *wd_); }

void Plant::rhs_split(double t, const double* x, double* fe, double* fi) {
  eval(t, x, fi, *wd_);  // the whole f
  friction_on_ = false;
  eval(t, x, fe, *wd_);  // f without friction
  friction_on_ = true;
  for (int k = 0; k < layout_.size; ++k) fi[k] -= fe[k];  // the friction's part
  if (layout_.i >= 0) {
    for (int j = 0; j < layout_.n; ++j) {  // the current equation: all implicit
      fi[layout_.i + j] += fe[layout_.i + j];
      fe[layout_.i + j] = 0.0;
    }
  }
}

void Plant::jacobian_fd(double t, const double* x, Eigen::MatrixXd& J) {
  const int m = layout_.size;
  J.resize(m, m);
  std::vector<double> f0(m);
  rhs(t, x, f0.data());
  std::copy(x, x + m, xtmp_.begin());
  for (int k = 0; k < m; ++k) {
    const double h = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(x[k]));
    xtmp_[k] = x[k] + h;
    rhs(t, xtmp_.data(), ftmp_.data());
    xtmp_[k] = x[k];
    for (int r = 0; r < m; ++r) J(r, k) = (ftmp_[r] - f0[r]) / h;
  }
}

void Plant::jacobian_exact(double t, const double* x, Eigen::MatrixXd& J) {
  const int m = layout_.size;
  J.resize(m, m);
  std::vector<Dual> xx(m), ff(m);
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
  const bool depends_on_t =
      cfg_.reference && cfg_.setpoint_interval == 0 && cfg_.controller == ControllerMode::kContinuous;
  if (!depends_on_t) {
    std::fill(dfdt, dfdt + m, 0.0);
    return 0;
  }
  // Forward, so that the first step of a run (t = 0) and of a piece look only
  // into the piece; f(t) too on the continued piece (at t = 0 or a breakpoint
  // the reference itself may jump: a joint spline's acceleration at the start
  // of the motion); the piece continued past its end, so that a step that
  // starts just before a breakpoint does not see it. Truncation O(d^2),
  // rounding about eps |f| / d. Rosenbrock methods multiply df/dt by h d_i in
  // every stage and their step control is sensitive to its error: measured
  // while this was written, odeint-rodas4p on paper_slow_viscous at rtol 1e-8
  // took about the same number of steps with this, with a fourth-order
  // difference, and with d from 1e-3 s to 1e-5 s, and three times as many with
  // a first-order forward difference of step sqrt(eps) max(1, t).
  constexpr double d = 1e-5;  // [s]
  struct Continued {  // the continued piece for the duration of the difference, even on a throw
    explicit Continued(Plant& p) : p_(p) { p_.extend_piece_ = true, p_.ref_time_ = std::nan(""); }
    ~Continued() { p_.extend_piece_ = false, p_.ref_time_ = std::nan(""); }  // the cache held a continued piece
    Plant& p_;
  } continued(*this);
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
  return next;
}

void Plant::sample_controller(double t, const double* x) {
  const ReferenceSample& r = current_reference(t);
  for (int j = 0; j < layout_.n; ++j) {
    const PivParams& P = cfg_.piv[j];
    const double Z = cfg_.robot.joints[j].gear_ratio;
    const double q = x[layout_.q + j], qd = x[layout_.qd + j];
    const double e = Z * (r.q[j] - q);
    integral_[j] += e * cfg_.servo_period;
    if (P.ki != 0) {
      const double lim = P.integral_limit / std::abs(P.ki);
      integral_[j] = std::clamp(integral_[j], -lim, lim);
    }
    const double v = P.kp * e + P.ki * integral_[j] - P.kv * Z * qd + P.kvff * Z * r.qd[j] +
                     P.kaff * Z * r.qdd[j] + P.offset;
    u_held_[j] = saturate(v, P.output_limit);
  }
}

void Plant::on_time_event(double t, double* x) {
  if (cfg_.controller == ControllerMode::kNone) return;
  if (cfg_.reference) {  // the reference's smooth piece from here on
    ref_segment_ = cfg_.reference->segment_after(t);
    ref_time_ = std::numeric_limits<double>::quiet_NaN();
  }
  if (cfg_.reference && cfg_.setpoint_interval > 0 && on_grid(t, cfg_.setpoint_interval)) {
    cfg_.reference->eval(t, ref_held_);
  }
  if (cfg_.controller == ControllerMode::kSampled && on_grid(t, cfg_.servo_period)) {
    sample_controller(t, x);
  }
  settle_modes(t, x);
}

int Plant::num_roots() const { return hybrid_ ? layout_.n : 0; }

void Plant::roots(double t, const double* x, double* g) {
  rhs(t, x, ftmp_.data());  // fills the applied torques
  for (int j = 0; j < layout_.n; ++j) {
    const FrictionParams& f = cfg_.friction[j];
    if (f.model != FrictionModel::kHybrid) {
      g[j] = 1.0;
      continue;
    }
    const double wm = cfg_.robot.joints[j].gear_ratio * x[layout_.qd + j];
    g[j] = mode_[j] == SlipMode::kStuck ? f.static_torque - std::abs(wd_->applied[j])
                                        : wm * static_cast<int>(mode_[j]);
  }
}

void Plant::on_root(int j, double t, double* x) {
  if (mode_[j] != SlipMode::kStuck) {  // the speed reached zero: stick
    x[layout_.qd + j] = 0.0;
    mode_[j] = SlipMode::kStuck;
  } else {  // break-away: |applied| crossed Fs, slip in its direction
    rhs(t, x, ftmp_.data());
    mode_[j] = wd_->applied[j] >= 0 ? SlipMode::kPositive : SlipMode::kNegative;
  }
  settle_modes(t, x);
}

void Plant::settle_modes(double t, double* x) {
  if (!hybrid_) return;
  // A mode switch (or a controller sample) changes every stuck joint's applied
  // torque at once through H; release, one at a time, the stuck joint whose
  // applied torque exceeds Fs the most, until the modes are consistent. Each
  // pass releases one joint, so at most n passes. Without this a root
  // function could start past its zero after a restart and never cross it
  // (a joint stuck for the rest of the run).
  for (int pass = 0; pass <= layout_.n; ++pass) {
    rhs(t, x, ftmp_.data());
    int worst = -1;
    double excess = 0.0;
    for (int j = 0; j < layout_.n; ++j) {
      const FrictionParams& f = cfg_.friction[j];
      if (f.model != FrictionModel::kHybrid || mode_[j] != SlipMode::kStuck) continue;
      const double e = std::abs(wd_->applied[j]) - f.static_torque;
      if (e > excess) excess = e, worst = j;
    }
    if (worst < 0) return;
    mode_[worst] = wd_->applied[worst] > 0 ? SlipMode::kPositive : SlipMode::kNegative;
  }
}

void Plant::initial_state(double* x) {
  const int n = layout_.n;
  ref_time_ = std::numeric_limits<double>::quiet_NaN();
  ref_segment_ = 0;
  std::fill(u_held_.begin(), u_held_.end(), 0.0);
  std::fill(integral_.begin(), integral_.end(), 0.0);
  std::fill(mode_.begin(), mode_.end(), SlipMode::kStuck);
  std::fill(x, x + layout_.size, 0.0);
  Eigen::VectorXd q(n);
  if (cfg_.reference) {
    cfg_.reference->eval(0.0, ref_held_);
    q = ref_held_.q.head(n);
  } else {
    q = cfg_.q0;
    // Without a reference a controller holds the initial pose.
    ref_held_ = ReferenceSample{};
    ref_held_.q.setZero();
    ref_held_.qd.setZero();
    ref_held_.qdd.setZero();
    ref_held_.q.head(n) = q;
  }
  for (int j = 0; j < n; ++j) x[layout_.q + j] = q[j];
  if (cfg_.drive) {
    // At rest on the reference: currents hold gravity, integrals supply the voltage.
    Eigen::VectorXd g(n);
    wd_->backend->gravity(q, g);
    for (int j = 0; j < n; ++j) {
      const MotorParams& M = cfg_.motor[j];
      const AmplifierParams& A = cfg_.amplifier[j];
      const PivParams& P = cfg_.piv[j];
      const double i = g[j] / (cfg_.robot.joints[j].gear_ratio * M.torque_constant);
      if (layout_.i >= 0) x[layout_.i + j] = i;
      const double u = (A.output_resistance + M.resistance) * i / A.gain - P.offset;
      const double I = P.ki != 0 ? std::clamp(u / P.ki, -P.integral_limit / std::abs(P.ki),
                                              P.integral_limit / std::abs(P.ki))
                                 : 0.0;
      if (layout_.z >= 0) x[layout_.z + j] = I;
      integral_[j] = I;
    }
  }
  on_time_event(0.0, x);  // first set-point and controller sample (e = 0 on the reference)
  settle_modes(0.0, x);  // hybrid joints start stuck unless already pushed past Fs
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
  for (int j = 0; j < layout_.n; ++j) E += 0.5 * cfg_.motor[j].inductance * x[layout_.i + j] * x[layout_.i + j];
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
  eval(t, x, ftmp_.data(), *wd_);
  for (int j = 0; j < layout_.n; ++j) {
    out[j] = {wd_->u[j], wd_->ea[j], cfg_.drive ? wd_->tm[j] / cfg_.motor[j].torque_constant : 0.0};
  }
}

}  // namespace pumasim
