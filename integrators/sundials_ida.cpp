// SUNDIALS IDA (6.x API) behind the Integrator interface: variable-order BDF
// (1-5) on the system's implicit form F(t, x, x') = 0 (OdeSystem::implicit_form;
// a system without one: F = x' - f(t, x)), Newton iterations with a dense
// direct linear solver on IDA's matrix dF/dx + c dF/dx' -- the system's own
// (ImplicitForm::newton_matrix; without a form, c I - df/dx from the
// system's Jacobian) or, with exact_jacobian false, IDA's difference
// quotients of F. Roots are IDA's (IDARootInit). A system that refuses a
// residual form (implicit_form's reason) is refused here.
//
// IDA forms its Newton matrix at every linear-solver set-up (whenever c has
// moved by a quarter, or Newton's iteration failed), where CVODE keeps its
// Jacobian over steps and re-forms only I - gamma J. With a form that keeps
// its derivatives (ImplicitForm::newton_matrix_again) this adapter does the
// same: a set-up re-forms the matrix for the new c from the last Jacobian
// unless that Jacobian is 51 steps old (CVODE's default limit), or a Newton
// iteration failed to converge since the last set-up, or IDA restarted;
// jacobian_evaluations counts the Jacobians evaluated.
//
// A form with algebraic unknowns (ImplicitForm::algebraic: a semi-explicit
// index-1 DAE) has them marked for IDA (IDASetId), their x' started at 0,
// and every start -- the first and each restart after an event -- made
// consistent by IDACalcIC (IDA_YA_YDP_INIT: the algebraic unknowns and the
// differential states' x' for the differential states given), so that an
// algebraic unknown may jump at an event (a sampled controller's new output
// moves the currents at once). The local error test leaves them out
// (IDASetSuppressAlg): an algebraic unknown is a function of the
// differential states (the plant's currents, i = (e_a - K w_m) / (R0 + R),
// e_a through the controller's gains), so its error is theirs, amplified;
// kept in the test, it rejected every other step (paper_slow_viscous with
// La = 0, rtol 1e-8: 179,659 steps, 179,070 error-test failures; left out,
// 517 and 5, where the reduced ODE takes 523 steps). IDA's guide
// discourages this for index 1 in general; the test of the run against the
// reduced ODE (tests/test_dae_current.cpp) is what vouches for it here. (The
// same rejections, milder, hit the current states with La > 0: the
// integrators guide's known anomaly. Keeping the currents in the test with a
// looser absolute tolerance would be the alternative; not tried.) With them
// out of the test, the balance is kept by Newton's iteration at each step's
// end but not controlled at interpolated outputs (IDAGetDky); the plant puts
// the currents back on it at every event (PlantModel::settle_currents).
//
// The C callbacks catch every exception: a non-finite residual is reported as
// recoverable (IDA shrinks the step), anything else as fatal and rethrown
// after IDASolve returns. A failure names IDA's flag, the time, and the
// state components with the largest weighted local error estimate.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "integrators/integrator.hpp"
#include "integrators/sundials_common.hpp"
#include "integrators/sundials_dense_lu.hpp"

#if SUNDIALS_VERSION_MAJOR != 6
#error "pumasim's IDA adapter is written for the SUNDIALS 6.x API"
#endif

namespace pumasim {
namespace {

class Ida final : public Integrator {
 public:
  explicit Ida(const IntegratorOptions& o) : Integrator(o.max_steps), opt_(o) {
    if (!(o.rtol > 0) || !(o.atol > 0)) throw std::invalid_argument("ida: expected rtol > 0 and atol > 0");
    if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::runtime_error("ida: SUNContext_Create failed");
  }
  ~Ida() override {
    release();
    SUNContext_Free(&ctx_);
  }

  const char* name() const override { return "ida"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = true;
    c.order = 5;
    c.implicit = true;
    c.uses_jacobian = true;
    c.exact_jacobian = true;
    c.jacobian_choice = true;
    c.finds_roots = true;
    return c;
  }

  void reset(OdeSystem& sys, double t0, const double* x0) override {
    const int n = sys.size();
    if (sys_ != &sys || !mem_ || n != n_) {
      std::string refusal;
      ImplicitForm* form = sys.implicit_form(refusal);
      if (!form && !refusal.empty()) throw std::invalid_argument("ida: " + refusal);
      create(sys, form, t0, x0);
    } else {
      std::copy(x0, x0 + n, N_VGetArrayPointer(y_));
      consistent_derivative(t0);
      check(IDAReInit(mem_, t0, y_, yp_), "IDAReInit");
      consistent_start(t0);
      base_ = {};  // the re-initialisation restarts SUNDIALS' counters
      jacobians_since_reinit_ = 0, jacobian_valid_ = false;
      ++stats_.restarts;
    }
    t_ = t0;
  }

  // One internal step (IDA_ONE_STEP) that does not pass t_stop.
  Outcome step(double t_stop) override {
    Outcome out;
    if (t_stop > t_) {
      check(IDASetStopTime(mem_, t_stop), "IDASetStopTime");
      error_.clear();
      pending_ = nullptr;
      double t = t_;
      const int flag = IDASolve(mem_, t_stop, &t, y_, yp_, IDA_ONE_STEP);
      if (pending_) std::rethrow_exception(pending_);
      t_ = t;
      if (flag == IDA_ROOT_RETURN) {
        check(IDAGetRootInfo(mem_, rootsfound_.data()), "IDAGetRootInfo");
        out.status = Outcome::kRoot;
        out.root = detail::first_root_found(rootsfound_);
      } else if (flag < 0) {
        out.status = Outcome::kFailed;
        out.message = failure(flag);
      }
    }
    collect_stats();
    return out;
  }
  double step_start() const override { return detail::last_step_start(mem_, t_, IDAGetCurrentTime, IDAGetLastStep); }
  void dense_state(double t, double* x) override {
    detail::interpolated_state(mem_, IDAGetDky, t, t_, y_, dky_, x, "ida", "IDAGetDky");
  }
  double time() const override { return t_; }
  const double* state() const override { return N_VGetArrayPointer(y_); }

 private:
  void create(OdeSystem& sys, ImplicitForm* form, double t0, const double* x0) {
    release();
    sys_ = &sys;
    form_ = form;
    n_ = sys.size();
    dae_ = false;
    for (int i = 0; i < n_ && form_; ++i) dae_ = dae_ || form_->algebraic(i);
    y_ = detail::make_state_vector(ctx_, n_);
    yp_ = detail::make_state_vector(ctx_, n_);
    dky_ = detail::make_view_vector(ctx_, n_);
    std::copy(x0, x0 + n_, N_VGetArrayPointer(y_));
    consistent_derivative(t0);
    mem_ = IDACreate(ctx_);
    if (!mem_) throw std::runtime_error("ida: IDACreate failed");
    check(IDAInit(mem_, &Ida::residual, t0, y_, yp_), "IDAInit");
    check(IDASetUserData(mem_, this), "IDASetUserData");
    check(IDASetErrHandlerFn(mem_, &Ida::on_error, this), "IDASetErrHandlerFn");
    check(detail::set_absolute_tolerances(sys, opt_.atol, ctx_,
                                          [&](N_Vector a) { return IDASVtolerances(mem_, opt_.rtol, a); }),
          "IDASVtolerances");
    check(IDASetMaxNumSteps(mem_, opt_.max_steps), "IDASetMaxNumSteps");
    A_ = detail::make_dense_matrix(ctx_, n_);
    LS_ = detail::make_dense_lu(ctx_, n_);
    check(IDASetLinearSolver(mem_, LS_, A_), "IDASetLinearSolver");
    own_jacobian_ = opt_.exact_jacobian && (form_ || sys.has_exact_jacobian());
    if (own_jacobian_) {
      check(IDASetJacFn(mem_, &Ida::jac), "IDASetJacFn");
      J_.resize(n_, n_);
    }
    nroots_ = sys.num_roots();
    if (nroots_ > 0) check(IDARootInit(mem_, nroots_, &Ida::rootfn), "IDARootInit");
    rootsfound_.assign(static_cast<std::size_t>(std::max(nroots_, 1)), 0);
    if (dae_) {
      id_ = detail::make_state_vector(ctx_, n_);
      for (int i = 0; i < n_; ++i) N_VGetArrayPointer(id_)[i] = form_->algebraic(i) ? 0.0 : 1.0;
      check(IDASetId(mem_, id_), "IDASetId");
      check(IDASetSuppressAlg(mem_, SUNTRUE), "IDASetSuppressAlg");
    }
    consistent_start(t0);
    base_ = {};
    jacobians_since_reinit_ = 0, jacobian_valid_ = false;
  }

  // x'(t0) = f(t0, x0): consistent with F for a form equivalent to the ODE
  // (an algebraic unknown's x' is 0: its f is a residual, not a rate).
  void consistent_derivative(double t0) {
    sys_->rhs(t0, N_VGetArrayPointer(y_), N_VGetArrayPointer(yp_));
    for (int i = 0; i < n_ && dae_; ++i) {
      if (form_->algebraic(i)) N_VGetArrayPointer(yp_)[i] = 0.0;
    }
  }
  // A DAE's start made consistent (IDACalcIC, IDA_YA_YDP_INIT) and read back
  // into y_ and yp_. IDACalcIC takes its Newton step from the first output
  // time's distance, which a step-by-step driver does not give: kCalcIcSpan
  // stands for it.
  void consistent_start(double t0) {
    if (!dae_) return;
    static constexpr double kCalcIcSpan = 1e-3;  // [s]
    error_.clear();
    pending_ = nullptr;
    const int flag = IDACalcIC(mem_, IDA_YA_YDP_INIT, t0 + kCalcIcSpan * std::max(1.0, std::abs(t0)));
    if (pending_) std::rethrow_exception(pending_);
    if (flag < 0)
      throw std::runtime_error("ida: IDACalcIC failed at t = " + std::to_string(t0) +
                               " (the algebraic unknowns have no consistent value): " + error_);
    check(IDAGetConsistentIC(mem_, y_, yp_), "IDAGetConsistentIC");
  }

  static int residual(double t, N_Vector y, N_Vector yp, N_Vector rr, void* self) {
    auto* me = static_cast<Ida*>(self);
    try {
      const double* x = N_VGetArrayPointer(y);
      const double* xp = N_VGetArrayPointer(yp);
      double* r = N_VGetArrayPointer(rr);
      if (me->form_) {
        me->form_->residual(t, x, xp, r);
      } else {
        me->sys_->rhs(t, x, r);
        for (int i = 0; i < me->n_; ++i) r[i] = xp[i] - r[i];
      }
      for (int i = 0; i < me->n_; ++i) {
        if (!std::isfinite(r[i])) return 1;  // recoverable: IDA retries with a smaller step
      }
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static int jac(double t, double cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* self, N_Vector, N_Vector,
                 N_Vector) {
    auto* me = static_cast<Ida*>(self);
    try {
      const double* x = N_VGetArrayPointer(y);
      if (me->form_) {
        long steps = 0, convergence_failures = 0;
        IDAGetNumSteps(me->mem_, &steps);
        IDAGetNumNonlinSolvConvFails(me->mem_, &convergence_failures);
        const bool reuse = me->jacobian_valid_ && steps - me->jacobian_step_ < kJacobianAge &&
                           convergence_failures == me->convergence_failures_ &&
                           me->form_->newton_matrix_again(cj, me->J_);
        if (!reuse) {
          me->form_->newton_matrix(t, x, N_VGetArrayPointer(yp), cj, me->J_);
          me->jacobian_valid_ = true, me->jacobian_step_ = steps;
          ++me->jacobians_since_reinit_;
        }
        me->convergence_failures_ = convergence_failures;
      } else {
        ++me->jacobians_since_reinit_;
        me->sys_->jacobian(t, x, me->J_);
        me->J_ *= -1.0;
        me->J_.diagonal().array() += cj;
      }
      for (int c = 0; c < me->n_; ++c)
        for (int r = 0; r < me->n_; ++r) SM_ELEMENT_D(J, r, c) = me->J_(r, c);
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static int rootfn(double t, N_Vector y, N_Vector, double* g, void* self) {
    auto* me = static_cast<Ida*>(self);
    try {
      me->sys_->roots(t, N_VGetArrayPointer(y), g);
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static void on_error(int, const char* module, const char* function, char* msg, void* self) {
    static_cast<Ida*>(self)->error_ = std::string(module) + "." + function + ": " + msg;
  }

  std::string failure(int flag) {
    return detail::failure_message(name(), flag, IDAGetReturnFlagName(flag), t_, error_, *sys_, mem_, y_,
                                   IDAGetEstLocalErrors, IDAGetErrWeights);
  }

  void collect_stats() {
    long v = 0;
    auto get = [&](int (*fn)(void*, long*)) {
      v = 0;
      fn(mem_, &v);
      return v;
    };
    IntegratorStats now;
    now.steps = get(IDAGetNumSteps);
    // Residual evaluations (each one f-sized evaluation), with the difference quotients'.
    now.rhs_evaluations = get(IDAGetNumResEvals) + get(IDAGetNumLinResEvals);
    // Evaluated, not re-formed (see the top); IDA's difference quotients: its count.
    now.jacobian_evaluations = own_jacobian_ ? jacobians_since_reinit_ : get(IDAGetNumJacEvals);
    now.linear_solves = get(IDAGetNumLinSolvSetups);
    now.rejected_steps = get(IDAGetNumErrTestFails);
    now.nonlinear_iterations = get(IDAGetNumNonlinSolvIters);
    detail::accumulate_since_reinit(stats_, base_, now);
  }

  void check(int flag, const char* what) const { detail::check_flag(flag, "ida", what); }
  void release() {
    if (mem_) IDAFree(&mem_);
    if (LS_) SUNLinSolFree(LS_), LS_ = nullptr;
    if (A_) SUNMatDestroy(A_), A_ = nullptr;
    for (N_Vector* v : {&y_, &yp_, &dky_, &id_}) {
      if (*v) N_VDestroy(*v), *v = nullptr;
    }
  }

  IntegratorOptions opt_;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr, yp_ = nullptr;
  N_Vector dky_ = nullptr;  // the dense output's target (make_view_vector)
  N_Vector id_ = nullptr;   // 1 differential, 0 algebraic (a DAE's only)
  bool dae_ = false;        // the form has algebraic unknowns
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  OdeSystem* sys_ = nullptr;
  ImplicitForm* form_ = nullptr;
  int n_ = 0, nroots_ = 0;
  double t_ = 0;
  Eigen::MatrixXd J_;
  // The Jacobian's reuse (see the top): whether the form holds one, the step
  // count (since IDA's last start) it was evaluated at, IDA's Newton
  // convergence failures at the last set-up; Jacobians evaluated since the start.
  static constexpr long kJacobianAge = 51;
  bool own_jacobian_ = false;  // IDASetJacFn: the system's (else IDA's difference quotients)
  bool jacobian_valid_ = false;
  long jacobian_step_ = 0, convergence_failures_ = 0, jacobians_since_reinit_ = 0;
  std::vector<int> rootsfound_;
  std::exception_ptr pending_;
  std::string error_;
  IntegratorStats base_;
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_ida(const IntegratorOptions& o) { return std::make_unique<Ida>(o); }
}  // namespace detail

}  // namespace pumasim
