// The coupled electro-mechanical plant as one state-space ODE x' = f(t, x),
// in three parts (as Pinocchio's Model/Data, MuJoCo's mjModel/mjData, Drake's
// System/Context):
//   PlantModel      what the scene describes: the blocks and their
//                   parameters, the state layout, the back-end's name.
//                   Immutable once made; shared by every thread and run that
//                   simulates it.
//   PlantContext    the discrete state: what changes only at events (the held
//                   set-point, the sampled controller's output and memory,
//                   the friction modes). One per run.
//   PlantWorkspace  an evaluator on one scalar type (workspace.hpp): the
//                   scratch of f, its own back-end instance. One per thread
//                   and scalar, built when first needed.
// f is a const function of (model, context, t, x), with what it includes of
// friction an explicit argument; the events that change the context are in
// plant.hpp (time events, the controller's samples) and
// friction/stick_slip.hpp (the hybrid model's modes).
//
// The blocks (models/plant/blocks/), per simulated joint:
//   reference -> controller (a law: controller/) -> amplifier -> DC motor -> gear and rotor
//   -> friction -> rigid body (any back-end from the registry)
// plus an optional energy ledger. A scene includes only what it needs, and
// leaving a block out removes its states. Each block declares its slice of
// the state (names, typical magnitudes) and computes its derivatives; its
// parameters are const. The state is [q | qd | i | z | e] over the n
// simulated joints:
//   q, qd   rigid body, always (joints n+1..6 are held: their links ride on link n)
//   i       motor currents, only with a drive whose La > 0 (La = 0: eliminated,
//           or algebraic unknowns with PlantConfig::algebraic_current)
//   z       the controller law's memory (the PIV integrals), only with a continuous controller
//   e       the energy ledger, when asked for
// An open-loop input (controller/open_loop.hpp) commands either the
// amplifier (a voltage, with the drive) or the joints directly (torques,
// without a drive); a drive needs a controller, and a controller other than a
// torque input needs the drive.
//
// The torque that friction must resist at rest ("applied torque", motor
// side) is K i - h_j / Z_j for the paper's rule and Karnopp (the coupling
// through H's off-diagonal terms is neglected, as in their single-joint
// models); the hybrid model computes it exactly from the constrained dynamics.
//
// Where varied parameters live. A parameter set (masses, friction levels,
// gains: anything in PlantConfig) is a PlantConfig of its own, and makes its
// own const PlantModel; models never change. What is expensive to build and
// does not depend on those parameters is shared between such models as an
// immutable part held by shared_ptr<const ...>: the reference (its inverse
// kinematics' branch table, PlantConfig::reference) and its Chebyshev table
// (PlantModel(config, shared) takes it from another model when the two
// follow the same reference). Those parts are const and thread-safe. So an
// ensemble or an identification makes one model per parameter set, cheaply,
// and one context and evaluator per run.
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
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/reference/reference_table.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct PlantConfig {
  RobotModel robot;                      // all joints
  int n = 6;                             // simulated joints: the first n
  Eigen::VectorXd q_held;  // all the robot's joints (empty: zeros); those beyond n are held there [rad or m]
  std::string backend = "crba";
  bool drive = true;                     // amplifier + motor (needs a controller commanding a voltage)
  ControllerMode controller = ControllerMode::kContinuous;  // its timing
  double servo_period = 0.0;             // [s], sampled controller
  double setpoint_interval = 0.0;        // [s], reference held between updates; 0 = continuous
  std::vector<AmplifierParams> amplifier;  // one per simulated joint
  std::vector<MotorParams> motor;
  // With La = 0 for every joint: false, the reduced model (the current
  // eliminated, i = (e_a - K w_m) / (R0 + R): an ODE); true, the currents
  // kept as algebraic unknowns i_motor1..n with 0 = e_a - (R0 + R) i - K w_m,
  // the drive's index-1 DAE (the limit La -> 0 of the current states), which
  // only a residual-form method integrates (why_no_ode_form).
  bool algebraic_current = false;
  std::vector<FrictionParams> friction;
  ControllerParams controller_params;  // the law (controller/registry.hpp) and its parameters per joint
  std::shared_ptr<const Reference> reference;  // what a controller follows
  // A Cartesian path's continuously followed reference from per-piece
  // Chebyshev interpolants (reference_table.hpp) instead of the inverse
  // kinematics at every time; false: the exact reference everywhere.
  bool tabulate_reference = true;
  // The reference's table when one is shared between configurations (a
  // SceneTemplate's loads: their runs fill one table); used only when it is
  // the table of `reference`, else the model makes its own.
  std::shared_ptr<const ReferenceTable> reference_table;
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
RobotModel simulated_robot(const RobotModel& robot, int n, const Eigen::VectorXd& q_held);

// The simulated joints' angles at t = 0: the reference's start, or q0.
Eigen::VectorXd start_pose(const PlantConfig& c);

// Empty when the plant has a residual form (PlantModel::residual): every
// friction law either smooth or with stick/slip events; else why not,
// naming the joint and the law (the paper's rule and Karnopp's switch inside
// a speed band on the applied torque, without events).
std::string why_no_implicit_form(const PlantConfig& c);

// Empty when the plant is an ODE x' = f(t, x); else why not, naming the scene
// key: algebraic currents (PlantConfig::algebraic_current) make it an
// index-1 DAE, whose current rows have no rate (their f is the residual
// e_a - (R0 + R) i - K w_m), so that only the residual form integrates it.
std::string why_no_ode_form(const PlantConfig& c);

// Empty when the configuration is a lossless, unforced arm -- passive (no
// controller, hence no drive) and no joint with friction: Lagrange's
// equations with no force, whose motion conserves the mechanical energy (the
// symplectic methods' systems, Plant::lagrangian_gradient); else why not,
// naming the scene key.
std::string why_not_conservative(const PlantConfig& c);

struct DriveSignals {
  double u = 0;   // controller output (DAC) [V]
  double ea = 0;  // amplifier output voltage [V]
  double i = 0;   // motor current [A]
};

// The discrete state: what changes only at events. The reference as the
// controller sees it (the held set-point, and the smooth piece since the
// last time event), the sampled controller's held output and memory, and
// the friction's stuck/slipping modes.
struct PlantContext {
  ReferenceSample ref_held{};
  int ref_segment = 0;
  ControllerDiscreteState controller;
  FrictionModes modes;
};

// Which friction f includes: all of it; none (the IMEX split's explicit
// part); the smooth part (time-stepping with set-valued friction).
enum class FrictionPart { kAll, kNone, kSmooth };

class PlantModel {
 public:
  static constexpr int kJacobianTangents = 24;
  using Tangent = DualN<kJacobianTangents>;

  // std::invalid_argument on an inconsistent configuration. Builds no
  // back-end, except for a passive arm (no controller), whose speed bounds
  // need H at its start pose.
  explicit PlantModel(PlantConfig config);
  // A model for another parameter set that shares `shared`'s immutable
  // parts where they are the same (the reference table, when both follow
  // the same reference).
  PlantModel(PlantConfig config, const PlantModel& shared);
  PlantModel(const PlantModel&) = delete;
  PlantModel& operator=(const PlantModel&) = delete;
  ~PlantModel();

  // The checks a model makes, without making one (no back-end, no table):
  // std::invalid_argument naming what is inconsistent.
  static void validate(const PlantConfig& config);

  const PlantConfig& config() const { return cfg_; }
  const StateLayout& layout() const { return layout_; }
  int size() const { return layout_.size; }
  int joints() const { return layout_.n; }
  const RobotModel& simulated() const { return model_; }
  double gear_ratio(int j) const { return body_.gear_ratio(j); }
  const FrictionBlock& friction() const { return friction_; }
  const MotorBlock& motor() const { return motor_; }
  // Algebraic currents (PlantConfig::algebraic_current) set to the
  // balance's solution at (t, x) under c, i = (e_a - K w_m) / (R0 + R) as
  // the reduced model computes it; nothing without them. The plant calls it
  // wherever the events change what the currents depend on (the start, a
  // controller's tick, a joint stopped at a stick), before the friction modes
  // are decided from the currents' torques.
  void settle_currents(const PlantContext& c, PlantWorkspace<double>& w, double t, double* x) const;
  // State i is an algebraic unknown (a current with PlantConfig::algebraic_current), not a state with a rate.
  bool algebraic_state(int i) const { return motor_.algebraic() && i >= layout_.i && i < layout_.i + layout_.n; }
  // The continuously followed reference's Chebyshev table (null: none).
  const ReferenceTable* reference_table() const { return ref_table_.get(); }

  // A context at t = 0 before initial_state: sized, nothing held.
  PlantContext make_context() const;
  // A new evaluator on scalar S with its own back-end instance (S: double,
  // Dual, Tangent).
  template <class S>
  std::unique_ptr<PlantWorkspace<S>> make_workspace() const;

  // f(t, x) under the context c, in the evaluator w. Allocation-free; no
  // change to the model or the context.
  template <class S>
  void eval(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, double t, const S* x, S* xdot) const;
  void rhs(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, double* xdot,
           FrictionPart part = FrictionPart::kAll) const {
    eval(c, w, part, t, x, xdot);
  }
  // The implicit form F(t, x, xp) = 0 of f under c (why_no_implicit_form
  // empty): xp - f on every row but the speeds', there inverse dynamics
  // minus the joint torques, ID(q, qd, xp_qd) - tau (xp_qd for a joint the
  // hybrid model holds), and -(e_a - (R0 + R) i - K w_m) on algebraic
  // currents' rows. No factorisation of H. Allocation-free.
  void residual(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, const double* xp,
                double* r) const;
  // The reference the controller uses at t under c (held set-point or at t).
  template <class S>
  const ReferenceSample& reference(const PlantContext& c, PlantWorkspace<S>& w, double t) const;
  // f depends on t (a continuously followed reference, or a law's own input).
  bool depends_on_time() const;
  // The constant diagonal linear part of f: the armature's -(R0 + R_j)/La_j
  // on each current state, 0 elsewhere.
  void linear_diagonal(double* lambda) const;

  // The next time event strictly after t (+inf if none): controller
  // samples, set-point updates, the reference's breakpoints and an
  // open-loop input's rows.
  double next_time_event(double t) const;
  // At a time event: the reference's and the input's piece from t on, a new
  // set-point, a controller sample (the friction modes: StickSlip). False
  // without a controller (nothing changes at a time event).
  bool time_event(PlantContext& c, PlantWorkspace<double>& w, double t, const double* x) const;
  // The start of x(0) and c (Plant::initial_state puts the steps together):
  // on the reference (or q0) at rest, with a drive's currents and a
  // controller's integrals in equilibrium with gravity; c at t = 0, every
  // joint with stick/slip events stuck.
  void start_state(PlantContext& c, PlantWorkspace<double>& w, double* x) const;
  // An open-loop input on the drive: the currents its output at t = 0 drives
  // at rest (after the first time event; nothing otherwise).
  void input_currents(const PlantContext& c, PlantWorkspace<double>& w, double* x) const;
  // The current slice on the balance's solution at (t, x) (settle_currents, input_currents).
  void balance_currents(const PlantContext& c, PlantWorkspace<double>& w, double t, double* x) const;

  // Controller output, amplifier output voltage and motor current of every
  // simulated joint at (t, x) under c: the controller and the drive of f's
  // evaluation, into w (xdot: scratch; no friction, no dynamics).
  void drive_signals(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, double* xdot,
                     DriveSignals* out) const;
  // True when the drive signals depend on a discrete state besides (t, x).
  bool holds_drive_state() const {
    return cfg_.drive && (cfg_.controller == ControllerMode::kSampled || cfg_.setpoint_interval > 0);
  }

  // Joint j's law has Coulomb levels (Fs or Fk > 0): stick and slip mean something.
  bool joint_has_modes(int j) const;
  bool has_mode_events() const { return friction_.has_events(); }
  int set_valued_joints() const { return static_cast<int>(sv_joint_.size()); }
  int set_valued_joint(int c) const { return sv_joint_[static_cast<std::size_t>(c)]; }

  // Stored energy at x [J]: kinetic (1/2 qd' H qd, H from w's back-end) plus
  // potential; magnetic (1/2 La i^2).
  double mechanical_energy(PlantWorkspace<double>& w, const double* x, double* kinetic) const;
  double magnetic_energy(const double* x) const;
  // Flange frame for the state x: orientation R (base frame) and position p [m].
  void tool_pose(const double* x, Eigen::Matrix3d& R, Eigen::Vector3d& p) const;

 private:
  PlantModel(PlantConfig config, const PlantModel* shared);
  static PlantConfig checked(PlantConfig config);
  void declare_bounds(const std::vector<double>& full_command);
  template <class S>
  void controller_output(const PlantContext& c, PlantWorkspace<S>& w, double t, const S* x) const;
  template <class S>
  void drive(const S* x, S* xdot, PlantWorkspace<S>& w) const;
  template <class S, class Accelerations>
  void derivatives(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, double t, const S* x, S* xdot,
                   Accelerations&& accelerations) const;
  template <class S>
  void accelerations(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, bool need_bias) const;
  template <class S>
  bool friction_torques(const PlantContext& c, PlantWorkspace<S>& w, FrictionPart part, const S* x, S* xdot) const;
  void hold_gravity(PlantContext& c, PlantWorkspace<double>& w, const Eigen::VectorXd& q, double* x) const;

  const PlantConfig cfg_;
  const RobotModel model_;  // the simulated joints (held links merged)
  const BackendInfo& backend_;
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
  std::shared_ptr<const ReferenceTable> ref_table_;  // with tabulate_reference, on a Cartesian path
  std::vector<int> sv_joint_;  // joints with set-valued friction
  bool bias_tangents_ = true;  // the exact Jacobian needs h's tangents (see the constructor)
};

}  // namespace pumasim
