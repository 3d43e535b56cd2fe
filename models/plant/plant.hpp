// The plant as one simulator: a const model (plant_model.hpp: the blocks,
// f), its context (the discrete state) and its evaluators, with the events
// that change the context: time events (controller samples, set-point
// updates, the reference's and an input's pieces) and the friction modes
// (friction/stick_slip.hpp). What the integrators see, through PlantSystem
// (simulation/driver.hpp). Several Plants may share one model:
// Plant(std::shared_ptr<const PlantModel>) makes a context and evaluators of
// its own, so that threads each with their own Plant evaluate f on one
// model.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/plant/friction/stick_slip.hpp"
#include "models/plant/plant_model.hpp"

namespace pumasim {

class Plant {
 public:
  explicit Plant(PlantConfig config);  // std::invalid_argument on an inconsistent configuration
  explicit Plant(std::shared_ptr<const PlantModel> model);  // shares the model
  ~Plant();
  Plant(const Plant&) = delete;
  Plant& operator=(const Plant&) = delete;

  const PlantModel& model() const { return *model_; }
  const std::shared_ptr<const PlantModel>& shared_model() const { return model_; }
  const PlantContext& context() const { return context_; }

  const StateLayout& layout() const { return model_->layout(); }
  const PlantConfig& config() const { return model_->config(); }
  int size() const { return model_->size(); }
  // A typical magnitude of state component i, in its unit (the integrators'
  // absolute tolerance is atol times this).
  double tolerance_scale(int i) const { return layout().scale[static_cast<std::size_t>(i)]; }
  // |x_i| <= physical_bound(i) on every trajectory of the model (+inf: no
  // bound known; models/plant/physical_bounds.hpp), and the formula.
  double physical_bound(int i) const { return layout().bound[static_cast<std::size_t>(i)]; }
  const std::string& physical_bound_why(int i) const { return layout().bound_why[static_cast<std::size_t>(i)]; }

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
  void linear_diagonal(double* lambda) const { model_->linear_diagonal(lambda); }
  // df/dx exactly; differences are OdeSystem::jacobian's
  // (integrators/registry.cpp). One pass of f per kJacobianTangents states on
  // the multi-tangent dual number (DualN), the dynamics' tangents analytical
  // (TangentBackend: the back-end's values in double, the analytical partials
  // of inverse dynamics, rnea_derivatives.hpp).
  // Allocation-free after the first call (which makes the evaluator).
  static constexpr int kJacobianTangents = PlantModel::kJacobianTangents;
  void jacobian_exact(double t, const double* x, Eigen::MatrixXd& J) { jacobian(FrictionPart::kAll, t, x, J); }
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
  double next_time_event(double t) const { return model_->next_time_event(t); }
  // May release stuck hybrid-friction joints (settle_modes), hence x non-const.
  // settle_modes false: the discrete update alone, for a method that solves
  // the set-valued friction itself (moreau-jean): the hybrid modes are then
  // not kept along the run, and settling them would stop a moving joint whose
  // stale mode says it passed a reversal.
  void on_time_event(double t, double* x, bool settle_modes = true);

  // Root functions (hybrid friction, one per joint) and the mode switches:
  // friction/stick_slip.hpp.
  int num_roots() const { return stick_slip_.num_roots(); }
  void roots(double t, const double* x, double* g) { stick_slip_.roots(context_, *evaluator_, t, x, g); }
  void on_root(int joint, double t, double* x) { stick_slip_.on_root(context_, *evaluator_, joint, t, x); }
  void settle_modes(double t, double* x) { stick_slip_.settle(context_, *evaluator_, t, x); }
  SlipMode slip_mode(int joint) const { return context_.modes[static_cast<std::size_t>(joint)]; }
  // The hybrid model's mode changes so far, the modes at t = 0 first (one per
  // joint with events), then each net change after a discrete update
  // (on_root, on_time_event). Empty without events.
  const std::vector<ModeChange>& mode_changes() const { return stick_slip_.mode_changes(); }

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
                      bool always_applied = false, bool speed_only = false) {
    stick_slip_.classify(context_, *evaluator_, t, x, stick_speed, mode, applied, always_applied, speed_only);
  }
  // Joint j's law has Coulomb levels (Fs or Fk > 0): stick and slip mean something.
  bool joint_has_modes(int j) const { return model_->joint_has_modes(j); }
  bool has_mode_events() const { return model_->has_mode_events(); }
  // The last coupled stick solve's report (settle_modes, on_root).
  const StickResult& last_stick_solve() const { return stick_slip_.last_solve(); }
  using StickStats = StickSlip::Stats;
  const StickStats& stick_stats() const { return stick_slip_.stats(); }

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
  void jacobian_smooth(double t, const double* x, Eigen::MatrixXd& J) { jacobian(FrictionPart::kSmooth, t, x, J); }
  int set_valued_joints() const { return model_->set_valued_joints(); }
  int set_valued_joint(int c) const { return model_->set_valued_joint(c); }
  // B_c at x, column-major (size() x set_valued_joints()).
  void set_valued_directions(const double* x, double* B) { stick_slip_.set_valued_directions(*evaluator_, x, B); }
  // The coupled solve itself (friction/stick_solve.hpp).
  StickResult solve_stick(const StickProblem& p, double* r, int* mode) { return stick_slip_.solve(p, r, mode); }

  // Stored energy at x [J]: mechanical (1/2 qd' H qd + V(q), rotor inertia
  // included) and magnetic (1/2 La i^2). With the ledger, the balance
  //   (mechanical + magnetic)(t) - (mechanical + magnetic)(0) = e_in - e_copper - e_friction
  // holds exactly for the ODE; its residual measures the integration error.
  double mechanical_energy(const double* x, double* kinetic = nullptr) {
    return model_->mechanical_energy(*evaluator_, x, kinetic);
  }
  double magnetic_energy(const double* x) const { return model_->magnetic_energy(x); }

  // The implicit form (why_no_implicit_form(config()) empty;
  // PlantModel::residual): F(t, x, xp), no factorisation of H.
  // Allocation-free.
  void residual(double t, const double* x, const double* xp, double* r) {
    model_->residual(context_, *evaluator_, t, x, xp, r);
  }
  // Its Newton matrix dF/dx + c dF/dxp: D (c I - df/dx), df/dx the exact
  // Jacobian and D the identity but on the speeds' rows, where it is H(q)
  // (F_qd = H (xp_qd - f_qd): exact at xp = f, the consistent point, and
  // off it by (dH/dx)(xp_qd - f_qd), which Newton's iteration tolerates);
  // the rows of joints the hybrid model holds stay c e, and algebraic
  // currents' rows are -df/dx (f there is the residual, not a rate; no xp).
  // Allocation-free after the first call.
  void residual_newton_matrix(double t, const double* x, double c, Eigen::MatrixXd& J);
  // The same for a new c from the last call's df/dx and H (and its held
  // joints); false before any call. Allocation-free.
  bool residual_newton_matrix_again(double c, Eigen::MatrixXd& J);

  // The lossless, unforced arm's mechanics (why_not_conservative(config())
  // empty; ConservativeMechanics, integrators/integrator.hpp): M(q), the
  // back-end's mass matrix (rotor inertia included), and
  //   dL/dq = Mdot qd - h(q, qd),
  // from Lagrange's equations with no force, d/dt (M qd) - dL/dq = 0, and the
  // back-end's M qdd + h = 0; Mdot = sum_k dM/dq_k qd_k is one pass of the
  // back-end's mass matrix on dual numbers (q + eps qd). Allocation-free
  // after the first call.
  void mass_matrix(const double* q, Eigen::MatrixXd& M);
  void lagrangian_gradient(const double* q, const double* qd, double* dLdq);

  // Flange position for the state x (held joints included) [m].
  Eigen::Vector3d tool_position(const double* x) const;
  // Flange frame for the state x: orientation R (base frame) and position p [m].
  void tool_pose(const double* x, Eigen::Matrix3d& R, Eigen::Vector3d& p) const { model_->tool_pose(x, R, p); }
  // The reference the controller currently uses (held set-point or at t).
  const ReferenceSample& reference_at(double t) { return model_->reference(context_, *evaluator_, t); }
  // Controller output, amplifier output voltage and motor current of every
  // simulated joint at (t, x), with the current discrete state (held outputs
  // and set-points: call it at the instant, not after the run).
  void drive_signals(double t, const double* x, DriveSignals* out) {
    model_->drive_signals(context_, *evaluator_, t, x, f_.data(), out);
  }
  // True when the drive signals depend on a discrete state besides (t, x): a
  // sampled controller's held output, or a held set-point.
  bool holds_drive_state() const { return model_->holds_drive_state(); }

 private:
  using Tangent = PlantModel::Tangent;
  void jacobian(FrictionPart part, double t, const double* x, Eigen::MatrixXd& J);
  PlantWorkspace<Dual>& dual_evaluator();  // made at its first use, with jx_ and jf_

  std::shared_ptr<const PlantModel> model_;
  PlantContext context_;
  // The evaluators: double made with the plant, the dual ones at their first use.
  std::unique_ptr<PlantWorkspace<double>> evaluator_;
  std::unique_ptr<PlantWorkspace<Dual>> dual_evaluator_;
  std::unique_ptr<PlantWorkspace<Tangent>> tangent_evaluator_;
  StickSlip stick_slip_;
  std::vector<double> f_;             // f for drive_signals
  std::vector<double> ft_[2];         // time_derivative scratch
  std::vector<Dual> jx_, jf_;         // jacobian_per_column's x and f
  std::vector<Tangent> tx_, tf_;      // jacobian's x and f
  // residual_newton_matrix's df/dx and H at its last point, which joints were held there, and scratch.
  Eigen::MatrixXd newton_Jf_, newton_H_, newton_rows_;
  std::vector<char> newton_held_;
};

}  // namespace pumasim
