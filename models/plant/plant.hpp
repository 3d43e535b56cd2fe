// The coupled electro-mechanical plant as one state-space ODE x' = f(t, x),
// assembled from blocks (models/plant/blocks/), per simulated joint:
//   reference -> controller (a law: controller/) -> amplifier -> DC motor -> gear and rotor
//   -> friction -> rigid body (any back-end from the registry)
// plus an optional energy ledger. A scene includes only what it needs, and
// leaving a block out removes its states. Each block declares its slice of
// the state (names, typical magnitudes) and computes its derivatives; its
// parameters are const. The state is [q | qd | i | z | e] over the n
// simulated joints:
//   q, qd   rigid body, always (joints n+1..6 are held: their links ride on link n)
//   i       motor currents, only with a drive whose La > 0 (La = 0: algebraic)
//   z       the controller law's memory (the PIV integrals), only with a continuous controller
//   e       the energy ledger, when asked for
// The scratch of one evaluation (PlantWorkspace) and the discrete state
// (PlantDiscreteState: held set-point and controller output, stick/slip
// modes) are separate objects. Discrete parts are events for the
// integrators: controller samples, set-point updates and the rows of an
// open-loop input at known times (next_time_event / on_time_event), and, for
// the hybrid friction model, root functions (roots / on_root).
// An open-loop input (controller/open_loop.hpp) commands either the
// amplifier (a voltage, with the drive) or the joints directly (torques,
// without a drive); a drive needs a controller, and a controller other than a
// torque input needs the drive.
//
// The torque that friction must resist at rest ("applied torque", motor
// side) is K i - h_j / Z_j for the paper's rule and Karnopp (the coupling
// through H's off-diagonal terms is neglected, as in their single-joint
// models); the hybrid model computes it exactly from the constrained dynamics.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/dual_n.hpp"
#include "models/plant/blocks/amplifier.hpp"
#include "models/plant/blocks/energy_ledger.hpp"
#include "models/plant/blocks/friction.hpp"
#include "models/plant/blocks/motor.hpp"
#include "models/plant/blocks/rigid_body.hpp"
#include "models/plant/controller/registry.hpp"
#include "models/plant/friction/stick_solve.hpp"
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/reference/reference_table.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct PlantConfig {
  RobotModel robot;                      // all joints
  int n = 6;                             // simulated joints: the first n
  Eigen::Matrix<double, 6, 1> q_held = Eigen::Matrix<double, 6, 1>::Zero();  // joints > n [rad]
  std::string backend = "crba";
  bool drive = true;                     // amplifier + motor (needs a controller commanding a voltage)
  ControllerMode controller = ControllerMode::kContinuous;  // its timing
  double servo_period = 0.0;             // [s], sampled controller
  double setpoint_interval = 0.0;        // [s], reference held between updates; 0 = continuous
  std::vector<AmplifierParams> amplifier;  // one per simulated joint
  std::vector<MotorParams> motor;
  std::vector<FrictionParams> friction;
  ControllerParams controller_params;  // the law (controller/registry.hpp) and its parameters per joint
  std::shared_ptr<const Reference> reference;  // what a controller follows
  // A Cartesian path's continuously followed reference from per-piece
  // Chebyshev interpolants (reference_table.hpp) instead of the inverse
  // kinematics at every time; false: the exact reference everywhere.
  bool tabulate_reference = true;
  Eigen::VectorXd q0;  // initial angles without a reference [rad]; a controller then holds them
  // Energy ledger: three quadrature states e_in, e_copper, e_friction [J]
  // (electrical input e_a i, or a torque input's mechanical tau qd; copper
  // loss (R0 + R) i^2, friction loss tau_f w_m; summed over the joints),
  // integrated with the rest.
  bool energy_ledger = false;
};

// The parameters of controller law Law (its name must be the configuration's).
template <class Law>
std::vector<typename Law::Params>& law_params(PlantConfig& c) {
  return std::get<LawParams<Law>>(c.controller_params).joints;
}
template <class Law>
const std::vector<typename Law::Params>& law_params(const PlantConfig& c) {
  return std::get<LawParams<Law>>(c.controller_params).joints;
}

// The model the plant simulates: the first n joints of `robot`, the others
// held at q_held with their links riding on link n.
RobotModel simulated_robot(const RobotModel& robot, int n, const Eigen::Matrix<double, 6, 1>& q_held);

struct DriveSignals {
  double u = 0;   // controller output (DAC) [V]
  double ea = 0;  // amplifier output voltage [V]
  double i = 0;   // motor current [A]
};

// What changes only at events: the reference as the controller sees it (the
// held set-point, the cached sample and the smooth piece since the last time
// event), the sampled controller's held output and memory, and the hybrid
// friction's stuck/slipping modes.
// One change of a joint's friction mode (experiments/simulation/mode_log.hpp
// writes them as events.csv): at time t, joint (0-based) entered `mode`;
// `applied` is the applied torque that decided it [N m, motor side] (the
// hybrid model: the constraint torque holding the joint after a stick, or the
// one that reached Fs before a release; the laws without modes: K i - h_j / Z
// at the step classified, NaN for a law that does not read it).
struct ModeChange {
  double t = 0;
  int joint = 0;
  SlipMode mode = SlipMode::kStuck;
  double applied = 0;
};

struct PlantDiscreteState {
  ReferenceSample ref_held{}, ref_now{};
  double ref_time = std::numeric_limits<double>::quiet_NaN();
  int ref_segment = 0;
  bool extend_piece = false;  // inside time_derivative: the reference piece continued past its ends
  ControllerDiscreteState controller;
  FrictionModes modes;
};

class Plant {
 public:
  explicit Plant(PlantConfig config);  // std::invalid_argument on an inconsistent configuration
  ~Plant();
  Plant(const Plant&) = delete;
  Plant& operator=(const Plant&) = delete;

  const StateLayout& layout() const { return layout_; }
  const PlantConfig& config() const { return cfg_; }
  int size() const { return layout_.size; }
  // A typical magnitude of state component i, in its unit (the integrators'
  // absolute tolerance is atol times this).
  double tolerance_scale(int i) const { return layout_.scale[static_cast<std::size_t>(i)]; }
  // |x_i| <= physical_bound(i) on every trajectory of the model (+inf: no
  // bound known; models/plant/physical_bounds.hpp), and the formula.
  double physical_bound(int i) const { return layout_.bound[static_cast<std::size_t>(i)]; }
  const std::string& physical_bound_why(int i) const { return layout_.bound_why[static_cast<std::size_t>(i)]; }

  // x(0): on the reference at rest, currents and integrals in equilibrium
  // with gravity (an open-loop input: the currents its first output drives at
  // rest); also (re)starts the discrete state at t = 0.
  void initial_state(double* x);

  // f(t, x). Allocation-free.
  void rhs(double t, const double* x, double* xdot);
  // IMEX split f = fe + fi: fi holds the stiff parts, the armature current
  // equation and the friction torques' effect on qdd (f minus f without
  // friction); fe the rigid body (q' = qd, qdd without friction) and the PIV
  // integrals. Allocation-free.
  void rhs_split(double t, const double* x, double* fe, double* fi);
  // The constant diagonal linear part of f (OdeSystem::linear_diagonal): the
  // armature's -(R0 + R_j)/La_j on each current state, 0 elsewhere (and 0
  // everywhere without current states).
  void linear_diagonal(double* lambda) const;
  // df/dx exactly; differences are OdeSystem::jacobian's
  // (integrators/registry.cpp). One pass of f per kJacobianTangents states on
  // the multi-tangent dual number (DualN), the dynamics' tangents analytical
  // (TangentBackend: the back-end's values in double, the analytical partials
  // of inverse dynamics, rnea_derivatives.hpp).
  // Allocation-free after the first call.
  static constexpr int kJacobianTangents = 24;
  void jacobian_exact(double t, const double* x, Eigen::MatrixXd& J);
  // The same, one single-tangent dual pass of f per state through the
  // back-end's own algorithm on Dual: m passes, an independent computation
  // (the tests compare the two).
  void jacobian_per_column(double t, const double* x, Eigen::MatrixXd& J);
  // df/dt at (t, x): f depends on t only through a continuously followed
  // reference, whose smooth piece since the last time event is continued for
  // the difference (so that it never straddles a breakpoint): a second-order
  // one-sided difference forward in t. Returns the right-hand sides it took
  // (0 when f does not depend on t). Allocation-free.
  int time_derivative(double t, const double* x, double* dfdt);

  // Time events: controller samples, set-point updates, the reference's
  // breakpoints and an open-loop input's rows. The next event time
  // strictly after t (+inf if none); at such a time, update the discrete state.
  double next_time_event(double t) const;
  // May release stuck hybrid-friction joints (settle_modes), hence x non-const.
  void on_time_event(double t, double* x);

  // Root functions (hybrid friction, one per joint): zero at a slipping joint's
  // speed reversal and at a stuck joint's break-away. on_root switches the
  // joint's mode (a slipping joint's speed is set to exactly zero in x, and
  // it is stuck), then the coupled stick solve (friction/stick_solve.hpp) sets
  // the modes of every joint at rest at once: the stuck ones, and a joint at
  // its break-away, which may only slip. settle_modes does that solve alone
  // (after a controller sample, or at the start). The problem is at
  // acceleration level, on the motor side: W = Z (H^-1)_CC Z over the joints
  // C at rest, b = W tau_applied,C (the torques their friction resists when
  // all of them are held; then a_C = b + W r, r the friction torque on the
  // joints), levels max(Fs, Fk) and Fk. After it each stuck joint's root
  // function is >= 0 (when Fs >= Fk) and each slipping joint at rest
  // accelerates in its slip direction (or not at all).
  int num_roots() const;
  void roots(double t, const double* x, double* g);
  void on_root(int joint, double t, double* x);
  void settle_modes(double t, double* x);
  SlipMode slip_mode(int joint) const { return ds_.modes[static_cast<std::size_t>(joint)]; }
  // The hybrid model's mode changes so far, the modes at t = 0 first (one per
  // joint with events), then each net change after a discrete update
  // (on_root, on_time_event): a joint stuck at a speed reversal and released
  // again by settle_modes at the same instant shows as one change, from
  // slipping one way to the other. Empty without events. Recorded outside the
  // right-hand side (it may allocate).
  const std::vector<ModeChange>& mode_changes() const { return mode_log_; }

  // Friction modes for laws without them (the paper's rule, Karnopp, tanh):
  // joint j counts as stuck at (t, x) when |w_m| <= stick_speed [rad/s, motor
  // side] and, for a law with a stick branch (the rule, Karnopp: it reads the
  // applied torque), when that branch would hold it: |applied| <= Fs; else it
  // slips in the direction of w_m (of the applied torque at w_m = 0).
  // mode[j] and applied[j] (0 where not evaluated) for every joint; joint_has_modes(j)
  // says where this means anything. Costs one right-hand side when some joint
  // is that slow under a law with a stick branch; never called by the integrators.
  // always_applied: evaluate the applied torques even when no joint is slow.
  // applied[j] is NaN for a law that does not read it (tanh).
  // speed_only: the speed alone decides (no stick branch, applied NaN): for
  // time-stepping, whose step solved the friction law (a stuck joint's speed 0).
  void classify_modes(double t, const double* x, double stick_speed, SlipMode* mode, double* applied,
                      bool always_applied = false, bool speed_only = false);
  // Joint j's law has Coulomb levels (Fs or Fk > 0): stick and slip mean something.
  bool joint_has_modes(int j) const;
  bool has_mode_events() const { return friction_.has_events(); }
  // The last coupled stick solve's report (settle_modes, on_root).
  const StickResult& last_stick_solve() const { return stick_result_; }
  // The hybrid model's coupled mode solves since the plant was made: how
  // many, their PGS sweeps in all, how many missed PGS's stopping rule or
  // its exact check (the enumeration then answered, when k <= 8), the worst
  // relative residual.
  struct StickStats {
    long solves = 0, iterations = 0, unconverged = 0;
    double worst_residual = 0.0;
  };
  const StickStats& stick_stats() const { return stick_stats_; }

  // Time-stepping with set-valued friction (moreau-jean, OdeSystem's
  // set-valued interface): f = f_smooth + sum_c B_c r_c over the joints whose
  // law has a set-valued Coulomb part with a level > 0 (hybrid, paper,
  // karnopp: set_valued_joint(c)); r_c the friction torque on joint c's motor
  // shaft, acting on the joint (stuck: its motor speed 0 and |r_c| <= Fs;
  // slipping: r_c = -Fk sign(w_m)). f_smooth: f with those laws' Coulomb part
  // left out (B w_m stays) and no stuck-joint constraint; the other laws'
  // torques (tanh, viscous) whole. The paper's and Karnopp's zero-speed bands
  // play no part there. Allocation-free.
  void rhs_smooth(double t, const double* x, double* xdot);
  // d f_smooth / dx, exactly (dual numbers).
  void jacobian_smooth(double t, const double* x, Eigen::MatrixXd& J);
  int set_valued_joints() const { return static_cast<int>(sv_joint_.size()); }
  int set_valued_joint(int c) const { return sv_joint_[static_cast<std::size_t>(c)]; }
  // B_c at x, column-major (size() x set_valued_joints()): a unit friction
  // torque on joint c's shaft changes qdd by H^-1 e_c Z_c, nothing else.
  void set_valued_directions(const double* x, double* B);
  // The coupled solve itself (friction/stick_solve.hpp).
  StickResult solve_stick(const StickProblem& p, double* r, int* mode) { return stick_.solve(p, r, mode); }

  // Stored energy at x [J]: mechanical (1/2 qd' H qd + V(q), rotor inertia
  // included) and magnetic (1/2 La i^2). With the ledger, the balance
  //   (mechanical + magnetic)(t) - (mechanical + magnetic)(0) = e_in - e_copper - e_friction
  // holds exactly for the ODE; its residual measures the integration error.
  double mechanical_energy(const double* x, double* kinetic = nullptr);
  double magnetic_energy(const double* x) const;

  // Flange position for the state x (held joints included) [m].
  Eigen::Vector3d tool_position(const double* x) const;
  // Flange frame for the state x: orientation R (base frame) and position p [m].
  void tool_pose(const double* x, Eigen::Matrix3d& R, Eigen::Vector3d& p) const;
  // The reference the controller currently uses (held set-point or at t).
  const ReferenceSample& reference_at(double t);
  // Controller output, amplifier output voltage and motor current of every
  // simulated joint at (t, x), with the current discrete state (held outputs
  // and set-points: call it at the instant, not after the run).
  void drive_signals(double t, const double* x, DriveSignals* out);
  // True when the drive signals depend on a discrete state besides (t, x): a
  // sampled controller's held output, or a held set-point.
  bool holds_drive_state() const {
    return cfg_.drive && (cfg_.controller == ControllerMode::kSampled || cfg_.setpoint_interval > 0);
  }

 private:
  template <class S>
  using Workspace = PlantWorkspace<S>;
  static PlantConfig checked(PlantConfig config);
  void declare_bounds(const std::vector<double>& full_command);
  template <class S>
  void eval(double t, const S* x, S* xdot, Workspace<S>& w);
  template <class S>
  void controller_output(double t, const S* x, Workspace<S>& w);
  template <class S>
  void drive(const S* x, S* xdot, Workspace<S>& w);
  template <class S>
  void friction_and_accelerations(Workspace<S>& w);
  const ReferenceSample& current_reference(double t);
  void start_discrete_state(const Eigen::VectorXd& q);
  void hold_gravity(const Eigen::VectorXd& q, double* x);
  void input_currents(double* x);
  double applied_torque(int joint) const { return wd_->applied[joint]; }
  void log_modes(double t);
  void solve_modes(double t, double* x, int breaking);
  void stick_operator(int k);

  const PlantConfig cfg_;
  const RobotModel model_;  // the simulated joints (held links merged)
  // The blocks.
  const RigidBodyBlock body_;
  const AmplifierBlock amplifier_;
  const MotorBlock motor_;
  const FrictionBlock friction_;
  const ControllerBlock controller_;  // dispatched once per evaluation
  const EnergyLedgerBlock ledger_;
  const bool torque_input_;  // the law's output is joint torque (no drive)
  const bool law_input_;     // the law has an input of its own in time (open loop)
  StateLayout layout_;
  std::unique_ptr<Workspace<double>> wd_;
  std::unique_ptr<Workspace<Dual>> wj_;
  std::unique_ptr<ReferenceTable> ref_table_;  // with tabulate_reference, on a Cartesian path
  PlantDiscreteState ds_;
  std::vector<double> ftmp_;        // f for roots, drive_signals and settle_modes
  // The (t, x) of the last rhs() whose workspace (wd_: the applied torques)
  // is still that of f there under the current discrete state; roots()
  // reuses it. Invalidated by every other evaluation and every event.
  std::vector<double> x_last_;
  double t_last_ = 0;
  bool last_valid_ = false;
  bool applied_current(double t, const double* x) const;
  std::vector<double> ft_[2];        // time_derivative scratch
  std::vector<Dual> jx_, jf_;        // jacobian_per_column's x and f
  std::vector<ModeChange> mode_log_;  // mode_changes()
  FrictionModes logged_;              // the modes the log last recorded
  std::vector<double> released_;     // per joint: the applied torque at its last release [N m]
  // Which friction f includes: all of it; none (inside rhs_split); the smooth
  // part (rhs_smooth, jacobian_smooth).
  enum class FrictionPart { kAll, kNone, kSmooth } friction_part_ = FrictionPart::kAll;
  // The coupled stick solve (hybrid model's modes; time-stepping through PlantSystem).
  StickSolver stick_;
  StickResult stick_result_;
  StickStats stick_stats_;
  std::vector<int> sv_joint_;        // joints with set-valued friction
  std::vector<int> cand_, cand_mode_;  // the joints at rest in a mode solve, their modes
  std::vector<double> cw_, cb_, cs_, ck_, cr_;  // its W (row-major), b, levels, r
  std::unique_ptr<bool[]> may_stick_;
  Eigen::VectorXd col_;              // a column of H^-1
  using Tangent = DualN<kJacobianTangents>;
  std::unique_ptr<Workspace<Tangent>> wt_;
  std::vector<Tangent> tx_, tf_;     // jacobian_exact's x and f
  bool bias_tangents_ = true;        // jacobian_exact needs h's tangents (see the constructor)
};

}  // namespace pumasim
