// One interface for every integrator, and the ODE systems they advance.
//
// An Integrator advances an OdeSystem from reset(t0, x0) with advance_to(t):
// it stops exactly at t, or earlier at the first root of the system's root
// functions (if it finds roots), or reports a failure that names the time
// and the state components involved. Statistics are counted the same way
// for every method. Options a method cannot honour are errors, not no-ops.
#pragma once

#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace pumasim {

// One row of a system's set-valued friction (OdeSystem::set_valued_row).
struct SetValuedRow {
  int velocity = 0;            // the state component of the speed
  double scale = 1.0;          // the law's speed is scale * x[velocity] (a gear ratio: motor speed)
  double static_level = 0.0;   // s >= kinetic_level (a torque or force)
  double kinetic_level = 0.0;
  // The law's "zero speed" band (its speed within +-band counts as rest: the
  // paper's rule, Karnopp's); 0 for an exact law. Its edges are the switching
  // surfaces a driver watches for chattering.
  double band = 0.0;
};

// How one coupled set-valued solve went (OdeSystem::solve_set_valued).
struct SetValuedSolve {
  int iterations = 0;      // sweeps of the iterative method
  double residual = 0.0;   // relative violation of the law by the returned r
  bool converged = true;   // the iteration met its stopping rule
};

// A lossless, unforced mechanical system inside an OdeSystem (the symplectic
// methods' view of it, symplectic_midpoint.hpp): the state holds generalized
// coordinates q_j and velocities qd_j at components position(j) and
// velocity(j), j < dof(); every other component is constant; and the motion
// is Lagrange's equations for
//   L(q, qd) = 1/2 qd' M(q) qd - V(q)
// with no generalized force, so that, in the canonical coordinates
// (q, p = M(q) qd), it is Hamilton's equations for
//   Ham(q, p) = 1/2 p' M(q)^-1 p + V(q):  q' = M^-1 p,  p' = dL/dq(q, M^-1 p).
class ConservativeMechanics {
 public:
  virtual ~ConservativeMechanics() = default;
  virtual int dof() const = 0;
  virtual int position(int j) const = 0;
  virtual int velocity(int j) const = 0;
  // M(q) (symmetric positive definite) into M, sized dof() x dof().
  virtual void mass_matrix(const double* q, Eigen::MatrixXd& M) = 0;
  // dL/dq at (q, qd), dof() values.
  virtual void lagrangian_gradient(const double* q, const double* qd, double* dLdq) = 0;
};

// The system in implicit form F(t, x, x') = 0, with the solutions of
// x' = f(t, x) (the residual methods' view of it: ida). Its rows need not be
// x' - f: a mechanical system's may be M(q) qdd + h(q, qd) - tau, one
// inverse-dynamics call with no factorisation of M.
class ImplicitForm {
 public:
  virtual ~ImplicitForm() = default;
  // F(t, x, xp) into r (size() values).
  virtual void residual(double t, const double* x, const double* xp, double* r) = 0;
  // The Newton matrix dF/dx + c dF/dxp at (t, x, xp) into J (size() x size()).
  virtual void newton_matrix(double t, const double* x, const double* xp, double c, Eigen::MatrixXd& J) = 0;
  // The Newton matrix for a new c from the derivatives of the last
  // newton_matrix call (as CVODE reuses its Jacobian over steps, re-forming
  // only I - gamma J), if the form keeps them; false if it does not.
  virtual bool newton_matrix_again(double /*c*/, Eigen::MatrixXd& /*J*/) { return false; }
  // State i is an algebraic unknown: no row of F reads its x'_i, and a
  // consistent start solves for it (a semi-explicit index-1 DAE; the
  // default, none: F is an ODE's).
  virtual bool algebraic(int /*i*/) const { return false; }
};

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  virtual int size() const = 0;
  virtual void rhs(double t, const double* x, double* xdot) = 0;
  // df/dx; the default is forward differences.
  virtual void jacobian(double t, const double* x, Eigen::MatrixXd& J);
  virtual bool has_exact_jacobian() const { return false; }
  // The explicit time dependence df/dt at (t, x), for the methods that use it
  // (Rosenbrock). Returns the number of right-hand-side evaluations it cost
  // (0 for a closed form; the integrator adds them to its count), or -1 if the
  // system does not provide it, and the method then takes a difference in t.
  // Problems with a known df/dt (Prothero-Robinson) supply it, so a method's
  // order is tested without that noise.
  virtual int time_derivative(double /*t*/, const double* /*x*/, double* /*dfdt*/) { return -1; }
  // IMEX split f = fe + fi (fe explicit, fi implicit). The default puts all of
  // f in the implicit part; systems with a natural split override it.
  virtual void rhs_split(double t, const double* x, double* fe, double* fi) {
    rhs(t, x, fi);
    for (int k = 0; k < size(); ++k) fe[k] = 0.0;
  }
  // A constant diagonal linear part of f, f(t, x) = diag(lambda) x + N(t, x),
  // lambda_i <= 0: the stiff decay the exponential methods (etd-*) integrate
  // exactly, leaving N to their explicit formula. The default: none (every
  // lambda_i = 0, and those methods are their explicit parents). Systems with
  // a linear stiff component (the armature currents) override it.
  virtual void linear_diagonal(double* lambda) const {
    for (int k = 0; k < size(); ++k) lambda[k] = 0.0;
  }
  virtual std::string state_name(int i) const { return std::string("x").append(std::to_string(i + 1)); }
  // The adaptive methods' absolute tolerance per component: atol_i =
  // atol * tolerance_scale(i), so that one --atol means the same thing for
  // states of different units and sizes (an angle, a current, an integral).
  // A component's scale is a typical magnitude of it; the default is 1.
  virtual double tolerance_scale(int /*i*/) const { return 1.0; }
  // The physically possible range of component i, |x_i| <= bound (+inf: none
  // known), and the formula it came from; a driver ends a run that leaves it
  // by a wide margin as unstable (a diverged method, not a result).
  virtual double physical_bound(int /*i*/) const { return std::numeric_limits<double>::infinity(); }
  virtual std::string physical_bound_why(int /*i*/) const { return {}; }
  // Root functions g(t, x): the integrators that find roots stop where one changes sign.
  virtual int num_roots() const { return 0; }
  virtual void roots(double /*t*/, const double* /*x*/, double* /*g*/) {}

  // Set-valued friction, for time-stepping (moreau-jean). A system with
  // set_valued_rows() = k > 0 is f = f_smooth + sum_c B_c(x) r_c, where each
  // r_c obeys a Coulomb law on the speed v_c = scale_c x[velocity_c]: stuck
  // (v_c = 0, |r_c| <= static_level_c) or slipping (r_c = -sign(v_c)
  // kinetic_level_c). Its root functions, if any, are then the event-driven
  // treatment of the same friction, which time-stepping replaces.
  virtual int set_valued_rows() const { return 0; }
  virtual SetValuedRow set_valued_row(int /*c*/) const { return {}; }
  // f_smooth and its Jacobian (the defaults: f and jacobian).
  virtual void rhs_smooth(double t, const double* x, double* f) { rhs(t, x, f); }
  virtual void jacobian_smooth(double t, const double* x, Eigen::MatrixXd& J) { jacobian(t, x, J); }
  // B(x), column-major, size() x set_valued_rows().
  virtual void set_valued_directions(double /*t*/, const double* /*x*/, double* /*B*/) {}
  // The coupled problem v = b + W r (W row-major k x k) under the rows'
  // laws with the levels s >= kin given (a step's impulses): r, and how the
  // solve went.
  virtual SetValuedSolve solve_set_valued(int k, const double* W, const double* b, const double* s,
                                          const double* kin, double* r);

  // The system's own implicit form (ImplicitForm), for the residual methods;
  // nullptr with an empty refusal: it has none, and they integrate
  // F = x' - f(t, x); nullptr with a refusal: no residual form of it can be
  // integrated, and why (they refuse the system).
  virtual ImplicitForm* implicit_form(std::string& refusal) {
    refusal.clear();
    return nullptr;
  }

  // The system as a conservative mechanical one (ConservativeMechanics), for
  // the symplectic methods; nullptr, with the reason in why_not, when it is
  // not one (the default).
  virtual ConservativeMechanics* conservative_mechanics(std::string& why_not) {
    why_not = "the system declares no conservative mechanical structure (q, qd, M(q), dL/dq)";
    return nullptr;
  }
};

struct IntegratorSettings;  // models/scene/scene.hpp: name, dt, rtol, atol

struct IntegratorOptions {
  double dt = 5e-4;             // fixed-step methods [s]
  double rtol = 1e-6;           // adaptive methods
  double atol = 1e-8;           // times the system's tolerance_scale(i) per component
  // Methods that take either Jacobian (capabilities().jacobian_choice: cvode-*,
  // arkode-dirk): the system's exact one where it has one
  // (OdeSystem::has_exact_jacobian), else the integrator's difference
  // quotients; false: the difference quotients always.
  bool exact_jacobian = true;
  long max_steps = 50'000'000;  // per advance_to; beyond it, a reported failure
  // Fixed-step methods: a reset at the time already reached (after an event)
  // keeps the multistep history instead of restarting it, as a simulation loop
  // that updates a sampled controller between steps and carries its
  // Adams-Bashforth history across does (the paper's LabVIEW loop, by our
  // reading). The history then mixes right-hand sides from before and after
  // the event: a modelling choice to study, not a consistent method.
  bool keep_history = false;
};

struct IntegratorStats {
  long steps = 0;
  long rhs_evaluations = 0;
  long jacobian_evaluations = 0;
  long linear_solves = 0;       // factorisations and solves of the Newton matrix
  long rejected_steps = 0;
  long nonlinear_iterations = 0;
  long restarts = 0;            // resets after events
  // Set-valued friction solved per step (moreau-jean): solves, their
  // iterations in all (projected Gauss-Seidel sweeps), how many missed the
  // iteration's stopping rule or ended inconsistent (the plant's solve then
  // answers from an enumeration of the modes, when k <= 8), and the worst
  // residual of the returned impulses (relative, see stick_solve.hpp).
  long friction_solves = 0;
  long friction_iterations = 0;
  long friction_unconverged = 0;
  double friction_worst_residual = 0.0;
  double wall_time = 0.0;       // [s], of advance_to and step_toward calls
};

struct IntegratorCapabilities {
  bool adaptive = false;
  int order = 0;
  bool implicit = false;
  bool uses_jacobian = false;
  // Uses the system's Jacobian (OdeSystem::jacobian: its exact one where it
  // has one); else (arkode-imex, of its implicit part) its own differences.
  bool exact_jacobian = false;
  // And, with IntegratorOptions::exact_jacobian false, its own difference
  // quotients instead (cvode-*, arkode-dirk).
  bool jacobian_choice = false;
  bool finds_roots = false;  // locates roots; fixed-step methods check signs per step
  // Treats a system's set-valued friction itself (OdeSystem::set_valued_rows:
  // moreau-jean), not through the system's root functions and modes.
  bool set_valued_friction = false;
};

// Which Jacobian a method with these capabilities and options uses on a
// system that has its exact one: "exact", "differences" or "none".
inline const char* jacobian_used(const IntegratorCapabilities& c, const IntegratorOptions& o) {
  if (!c.uses_jacobian) return "none";
  return c.exact_jacobian && (o.exact_jacobian || !c.jacobian_choice) ? "exact" : "differences";
}

struct Outcome {
  enum Status { kReached, kRoot, kFailed } status = kReached;
  int root = -1;        // with kRoot: which root function
  std::string message;  // with kFailed: what, when, which components
};

// Stepping and dense output. An integrator takes its own steps; the caller
// stops it only where the right-hand side changes (controller samples,
// set-point updates, the reference's breakpoints, roots) and reads any other
// time from the method's dense output, so an output grid never caps a step
// nor changes a cost figure:
//   step_toward(t_stop)  one step of the method (its own size; the last one
//                        shortened to end exactly at t_stop), or a root or a
//                        failure inside it;
//   dense_state(t, x)    the state at any t of the last step,
//                        [step_start(), time()], from the method's own
//                        continuous extension (CVODE/ARKODE: GetDky; odeint:
//                        the steppers' dense output; fixed-step methods:
//                        their natural extensions, see fixed_step.cpp);
//   advance_to(t)        steps until t (or a root or a failure).
class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual const char* name() const = 0;
  virtual IntegratorCapabilities capabilities() const = 0;
  // (Re)start at (t0, x0): multistep history and step-size memory are dropped.
  // state() is then x0 -- for a DAE (ImplicitForm::algebraic), x0 with its
  // algebraic unknowns solved for, the consistent start.
  virtual void reset(OdeSystem& sys, double t0, const double* x0) = 0;
  // Advances to t (or to a root or failure before it) in steps of the method;
  // more than IntegratorOptions::max_steps steps in one call is a failure.
  // Counts the wall time.
  Outcome advance_to(double t);
  // One step toward t_stop (> time()); counts the wall time.
  Outcome step_toward(double t_stop);
  virtual double time() const = 0;
  virtual const double* state() const = 0;
  // The last step's start; dense_state is valid on [step_start(), time()].
  virtual double step_start() const = 0;
  virtual void dense_state(double t, double* x) = 0;
  const IntegratorStats& stats() const { return stats_; }

 protected:
  explicit Integrator(long max_steps_per_call) : max_steps_per_call_(max_steps_per_call) {}
  // One step of the method toward t_stop (never past it): the integrator's core.
  virtual Outcome step(double t_stop) = 0;
  IntegratorStats stats_;

 private:
  long max_steps_per_call_;
};

// The first root function that crossed zero between two evaluations, or -1.
// A crossing is a strict sign change, or a non-zero value reaching zero;
// leaving zero (where an event was just handled) is not one.
int first_crossing(const std::vector<double>& g_old, const std::vector<double>& g_new);
// The same rule for one root function.
inline bool crossed(double before, double after) {
  return (before > 0 && after <= 0) || (before < 0 && after >= 0);
}

// Of the root functions that crossed between g0 and g1, the one whose zero
// linear interpolation puts first; -1 if none crossed.
inline int earliest_crossing(const std::vector<double>& g0, const std::vector<double>& g1) {
  int k = -1;
  double frac = 2.0;
  for (std::size_t i = 0; i < g0.size(); ++i) {
    if (!crossed(g0[i], g1[i])) continue;
    const double f = g0[i] / (g0[i] - g1[i]);
    if (f < frac) frac = f, k = static_cast<int>(i);
  }
  return k;
}

// The earliest zero of the root functions in [a, b], where ga (at a) and gb
// (at b) show a crossing: the Illinois variant of regula falsi narrows the
// bracket until it is at most tol wide, g_at(s, gs) giving the functions at
// s (into gs, scratch of their size). On return ga and gb hold the
// functions at the bracket's ends; the result is the crossing root
// function's index. The steppers' root location (odeint.cpp, radau5.cpp).
template <class G>
int locate_earliest_root(std::vector<double>& ga, std::vector<double>& gb, std::vector<double>& gs, double& a,
                         double& b, double tol, G&& g_at) {
  int k = earliest_crossing(ga, gb);
  double wa = 1.0, wb = 1.0;  // Illinois weights on the retained end's g
  int side = 0;
  for (int it = 0; it < 200 && b - a > tol; ++it) {
    const double fa = wa * ga[k], fb = wb * gb[k];
    double s = fa != fb ? a + (b - a) * fa / (fa - fb) : 0.5 * (a + b);
    s = std::clamp(s, a + 0.5 * tol, b - 0.5 * tol);
    g_at(s, gs);
    if (const int k2 = earliest_crossing(ga, gs); k2 >= 0) {  // a zero in [a, s]
      b = s, gb = gs, k = k2;
      wb = 1.0;
      if (side == -1) wa *= 0.5;
      side = -1;
    } else {
      a = s, ga = gs;
      wa = 1.0;
      if (side == 1) wb *= 0.5;
      side = 1;
    }
  }
  return k;
}

// "non-finite state at t = 0.123 s: qd2 = nan, i_motor2 = inf" -- or "" if all finite.
std::string non_finite_components(const OdeSystem& sys, double t, const double* x);

// "qd2 = 0.0123 (|f| / max(1, |x|) = 4.5e+03 1/s)": the state component that
// changes fastest at (t, x), where a step-size collapse usually comes from.
std::string fastest_component(OdeSystem& sys, double t, const double* x);

}  // namespace pumasim
