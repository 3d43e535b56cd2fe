// The one integration loop: any integrator on the plant, stopping exactly
// where the right-hand side changes -- controller samples, set-point updates,
// the reference's breakpoints (the plant's time events) and, for integrators
// that find them, friction roots; the plant updates its discrete state at
// each such stop and the integrator restarts there (CVodeReInit, a fresh
// multistep history). Outputs in between come from the integrator's dense
// output, so the output grid changes neither the steps nor the cost. A
// failure ends the run as a reported result.
#pragma once

#include <atomic>
#include <functional>
#include <string>

#include "integrators/integrator.hpp"
#include "models/plant/plant.hpp"

namespace pumasim {

// The plant as an OdeSystem: exact Jacobian, named states, friction roots.
class PlantSystem final : public OdeSystem {
 public:
  explicit PlantSystem(Plant& p) : p_(p), mode_(static_cast<std::size_t>(p.size())) {}
  int size() const override { return p_.size(); }
  void rhs(double t, const double* x, double* xdot) override { p_.rhs(t, x, xdot); }
  void jacobian(double t, const double* x, Eigen::MatrixXd& J) override { p_.jacobian_exact(t, x, J); }
  bool has_exact_jacobian() const override { return true; }
  int time_derivative(double t, const double* x, double* dfdt) override { return p_.time_derivative(t, x, dfdt); }
  void rhs_split(double t, const double* x, double* fe, double* fi) override { p_.rhs_split(t, x, fe, fi); }
  void linear_diagonal(double* lambda) const override { p_.linear_diagonal(lambda); }
  std::string state_name(int i) const override { return p_.layout().names[static_cast<std::size_t>(i)]; }
  double tolerance_scale(int i) const override { return p_.tolerance_scale(i); }
  double physical_bound(int i) const override { return p_.physical_bound(i); }
  std::string physical_bound_why(int i) const override { return p_.physical_bound_why(i); }
  int num_roots() const override { return p_.num_roots(); }
  void roots(double t, const double* x, double* g) override { p_.roots(t, x, g); }
  // Set-valued friction for time-stepping (Plant::rhs_smooth and the rest).
  int set_valued_rows() const override { return p_.set_valued_joints(); }
  SetValuedRow set_valued_row(int c) const override;
  void rhs_smooth(double t, const double* x, double* f) override { p_.rhs_smooth(t, x, f); }
  void jacobian_smooth(double t, const double* x, Eigen::MatrixXd& J) override { p_.jacobian_smooth(t, x, J); }
  void set_valued_directions(double, const double* x, double* B) override { p_.set_valued_directions(x, B); }
  SetValuedSolve solve_set_valued(int k, const double* W, const double* b, const double* s, const double* kin,
                                  double* r) override;
  // The plant's residual form (PlantModel::residual), or the reason it has none.
  ImplicitForm* implicit_form(std::string& refusal) override {
    refusal = why_no_implicit_form(p_.config());
    return refusal.empty() ? &implicit_ : nullptr;
  }
  // A lossless, unforced arm's mechanics (why_not_conservative, Plant::lagrangian_gradient).
  ConservativeMechanics* conservative_mechanics(std::string& why_not) override {
    why_not = why_not_conservative(p_.config());
    return why_not.empty() ? &mechanics_ : nullptr;
  }

 private:
  class Mechanics final : public ConservativeMechanics {
   public:
    explicit Mechanics(Plant& p) : p_(p) {}
    int dof() const override { return p_.layout().n; }
    int position(int j) const override { return p_.layout().q + j; }
    int velocity(int j) const override { return p_.layout().qd + j; }
    void mass_matrix(const double* q, Eigen::MatrixXd& M) override { p_.mass_matrix(q, M); }
    void lagrangian_gradient(const double* q, const double* qd, double* g) override {
      p_.lagrangian_gradient(q, qd, g);
    }

   private:
    Plant& p_;
  };
  class Implicit final : public ImplicitForm {
   public:
    explicit Implicit(Plant& p) : p_(p) {}
    void residual(double t, const double* x, const double* xp, double* r) override { p_.residual(t, x, xp, r); }
    void newton_matrix(double t, const double* x, const double*, double c, Eigen::MatrixXd& J) override {
      p_.residual_newton_matrix(t, x, c, J);
    }
    bool newton_matrix_again(double c, Eigen::MatrixXd& J) override { return p_.residual_newton_matrix_again(c, J); }
    bool algebraic(int i) const override { return p_.model().algebraic_state(i); }

   private:
    Plant& p_;
  };
  Plant& p_;
  std::vector<int> mode_;  // the solve's modes (not used by the caller)
  Mechanics mechanics_{p_};
  Implicit implicit_{p_};
};

struct RunResult {
  bool ok = true;
  std::string failure;  // what, when, which state components
  // "budget" (steps or wall-clock time), "unstable" (a state past
  // kUnstableFactor times its physical bound), "integrator" (the method's own:
  // a non-finite state, step-size underflow, a convergence failure),
  // "interrupted" (ProgressHook::cancel: Ctrl-C); "" when ok.
  std::string failure_kind;
  double t_final = 0;
  long time_events = 0;
  long root_events = 0;
  double wall_time = 0;  // [s]
};

using Observer = std::function<void(double t, const double* x)>;

// "i_motor2 = 0.123 (|f| / scale = 4.5e+05 1/s, scale 2.1)": the state
// component with the largest |f_i| / scale_i at (t, x), scale_i the system's
// tolerance scale (the state's typical magnitude, which also scales the
// adaptive methods' atol): where a step-size collapse usually comes from. The
// driver's budget failures name it.
std::string fastest_scaled_component(OdeSystem& sys, double t, const double* x);

// Where a run is, for a progress display.
struct RunProgress {
  double t = 0;       // [s] simulated time reached
  long steps = 0;     // the integrator's steps so far (accepted)
  double h = 0;       // [s] the last step's size
  double wall = 0;    // [s] wall-clock time since the run started
};

// The step loop's contact with the outside, by wall-clock time. The loop
// does not read the clock at every step: it counts steps and reads the clock
// every k of them, k adapted as the run goes so that reads fall about 2.5-10
// ms apart (cut at once when steps turn slow); a step costs a counter, and
// the rest happens only at clock reads:
// - report: a progress report, so that a method crawling through tiny steps
//   shows where it is: first after `delay` seconds, then about every
//   `period` seconds (called only when due; it may allocate, the loop does
//   not);
// - cancel: when set, read at every clock read (a relaxed atomic load: no
//   allocation, no call); once true, the run ends as the failure
//   "interrupted" (RunResult). Another thread sets it: the thread that
//   received Ctrl-C, or the one that waits for many runs at once;
// - poll: called at the first clock read and then about every poll_period
//   seconds, before cancel is read (the Python module checks for signals
//   there and sets cancel: python/pumasim_module.cpp).
struct ProgressHook {
  std::function<void(const RunProgress&)> report;  // empty: no reports
  double delay = 1.0;    // [s] before the first report
  double period = 0.25;  // [s] between reports
  const std::atomic<bool>* cancel = nullptr;  // null: the run is never cancelled
  std::function<void()> poll;                 // empty: no polls
  double poll_period = 0.05;                  // [s] between polls
};

// How the driver stops the integrator.
enum class Stops {
  kEvents,             // at time events and roots only; outputs from the dense output (the default)
  kEventsAndOutputs,   // also at every output time (the output grid caps the step; history: commit 46938f1)
  kOutputsLateEvents,  // at outputs and roots only: time events that passed are applied late, at the
                       // next output, in order, with the state then (shows what stepping over samples does)
};

// What run_plant is asked: how far, what it reports, its budgets.
struct PlantRunSpec {
  double t_end = 0;            // [s]
  double output_interval = 0;  // [s] observe at every multiple of it reached
  Observer observe;            // each output (may be empty)
  long max_steps = 0;          // steps in all (0: no limit)
  Stops stops = Stops::kEvents;
  double max_wall = 0;  // [s] wall-clock time (0: no limit)
  ProgressHook progress;
  Observer on_step;  // the end of every accepted step (may be empty)
};

// Runs from the plant's initial state to spec.t_end; observe(t, x) at t = 0
// and at every multiple of output_interval reached. An output at an event's
// instant sees the state after the event. A run that needs more than
// max_steps steps in all (0: no limit) ends as a reported failure, naming
// {{max_steps}} and the state changing fastest relative to its typical
// magnitude (the system's tolerance scale); so does one still running after
// max_wall seconds of wall-clock time (0: no limit), checked whenever the
// loop reads the clock (every few ms, see ProgressHook; one step of any
// method is bounded: it either succeeds or fails); so does one whose
// progress.cancel is set, as "interrupted" at the time reached.
// progress.report and progress.poll, when set, are called as ProgressHook
// says; none of these changes a step. on_step, when set, sees the state at
// the end of every accepted step, before the events there are applied (the
// friction mode log: simulation/mode_log.hpp); it must not change the plant's
// discrete state.
RunResult run_plant(Plant& plant, Integrator& integrator, const PlantRunSpec& spec);

}  // namespace pumasim
