// SUNDIALS CVODE (6.x API, linked as CVODES, its superset: the same calls,
// one library for these methods and the forward sensitivities, since the two
// export the same symbols) behind the Integrator interface: BDF and Adams,
// both with Newton iterations and a dense direct linear solver; the Jacobian
// by CVODE's difference quotients or the system's exact one. Only this file
// (and the ARKODE adapter) include SUNDIALS headers.
//
// The C callbacks catch every exception: a non-finite derivative is reported
// as recoverable (CVODE shrinks the step), anything else as fatal and rethrown
// after CVode returns. A failure names CVODE's flag, the time, and the state
// components with the largest weighted local error estimate.
#include <algorithm>
#include <cstdio>
#include <cmath>
#include <exception>
#include <numeric>
#include <stdexcept>
#include <string>

#include <cvodes/cvodes.h>  // CVODES, a superset of CVODE: the same calls, and the forward sensitivities
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "integrators/integrator.hpp"
#include "integrators/sundials_common.hpp"
#include "integrators/sundials_dense_lu.hpp"

#if SUNDIALS_VERSION_MAJOR != 6
#error "pumasim's CVODE adapter is written for the SUNDIALS 6.x API"
#endif

namespace pumasim {
namespace {

class Cvode final : public Integrator {
 public:
  Cvode(const IntegratorOptions& o, int method) : Integrator(o.max_steps), opt_(o), method_(method) {
    if (!(o.rtol > 0) || !(o.atol > 0)) throw std::invalid_argument("cvode: expected rtol > 0 and atol > 0");
    if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::runtime_error("cvode: SUNContext_Create failed");
  }
  ~Cvode() override { release(); SUNContext_Free(&ctx_); }

  const char* name() const override { return method_ == CV_BDF ? "cvode-bdf" : "cvode-adams"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = true;
    c.order = method_ == CV_BDF ? 5 : 12;
    c.implicit = true;
    c.uses_jacobian = true;
    c.exact_jacobian = true;
    c.jacobian_choice = true;
    c.finds_roots = true;
    return c;
  }

  void reset(OdeSystem& sys, double t0, const double* x0) override {
    const int n = sys.size();
    if (sys_ == &sys && mem_ && n == n_) {  // same system: CVodeReInit keeps the set-up
      std::copy(x0, x0 + n, N_VGetArrayPointer(y_));
      check(CVodeReInit(mem_, t0, y_), "CVodeReInit");
      base_ = {};  // the re-initialisation restarts SUNDIALS' counters
      ++stats_.restarts;
    } else {
      release();
      sys_ = &sys;
      n_ = n;
      y_ = detail::make_state_vector(ctx_, n);
      dky_ = detail::make_view_vector(ctx_, n);
      std::copy(x0, x0 + n, N_VGetArrayPointer(y_));
      mem_ = CVodeCreate(method_, ctx_);
      if (!mem_) throw std::runtime_error("cvode: CVodeCreate failed");
      check(CVodeInit(mem_, &Cvode::rhs, t0, y_), "CVodeInit");
      check(CVodeSetUserData(mem_, this), "CVodeSetUserData");
      check(CVodeSetErrHandlerFn(mem_, &Cvode::on_error, this), "CVodeSetErrHandlerFn");
      check(detail::set_absolute_tolerances(sys, opt_.atol, ctx_,
                                            [&](N_Vector a) { return CVodeSVtolerances(mem_, opt_.rtol, a); }),
            "CVodeSVtolerances");
      check(CVodeSetMaxNumSteps(mem_, opt_.max_steps), "CVodeSetMaxNumSteps");
      A_ = detail::make_dense_matrix(ctx_, n);
      LS_ = detail::make_dense_lu(ctx_, n);
      check(CVodeSetLinearSolver(mem_, LS_, A_), "CVodeSetLinearSolver");
      if (opt_.exact_jacobian && sys.has_exact_jacobian()) {
        check(CVodeSetJacFn(mem_, &Cvode::jac), "CVodeSetJacFn");
        J_.resize(n, n);
      }
      nroots_ = sys.num_roots();
      if (nroots_ > 0) check(CVodeRootInit(mem_, nroots_, &Cvode::rootfn), "CVodeRootInit");
      rootsfound_.assign(static_cast<std::size_t>(std::max(nroots_, 1)), 0);
      base_ = {};
    }
    t_ = t0;
  }

  // One internal step (CV_ONE_STEP) that does not pass t_stop.
  Outcome step(double t_stop) override {
    Outcome out;
    if (t_stop > t_) {
      check(CVodeSetStopTime(mem_, t_stop), "CVodeSetStopTime");
      error_.clear();
      pending_ = nullptr;
      double t = t_;
      const int flag = CVode(mem_, t_stop, y_, &t, CV_ONE_STEP);
      if (pending_) std::rethrow_exception(pending_);
      t_ = t;
      if (flag == CV_ROOT_RETURN) {
        check(CVodeGetRootInfo(mem_, rootsfound_.data()), "CVodeGetRootInfo");
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
  double step_start() const override { return detail::last_step_start(mem_, t_, CVodeGetCurrentTime, CVodeGetLastStep); }
  void dense_state(double t, double* x) override {
    detail::interpolated_state(mem_, CVodeGetDky, t, t_, y_, dky_, x, "cvode", "CVodeGetDky");
  }

  double time() const override { return t_; }
  const double* state() const override { return N_VGetArrayPointer(y_); }

 private:
  static int rhs(double t, N_Vector y, N_Vector ydot, void* self) {
    auto* me = static_cast<Cvode*>(self);
    try {
      me->sys_->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
      const double* d = N_VGetArrayPointer(ydot);
      for (int i = 0; i < me->n_; ++i) {
        if (!std::isfinite(d[i])) return 1;  // recoverable: CVODE retries with a smaller step
      }
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static int jac(double t, N_Vector y, N_Vector, SUNMatrix J, void* self, N_Vector, N_Vector, N_Vector) {
    auto* me = static_cast<Cvode*>(self);
    try {
      me->sys_->jacobian(t, N_VGetArrayPointer(y), me->J_);
      for (int c = 0; c < me->n_; ++c)
        for (int r = 0; r < me->n_; ++r) SM_ELEMENT_D(J, r, c) = me->J_(r, c);
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static int rootfn(double t, N_Vector y, double* g, void* self) {
    auto* me = static_cast<Cvode*>(self);
    try {
      me->sys_->roots(t, N_VGetArrayPointer(y), g);
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static void on_error(int, const char* module, const char* function, char* msg, void* self) {
    static_cast<Cvode*>(self)->error_ = std::string(module) + "." + function + ": " + msg;
  }

  std::string failure(int flag) {
    return detail::failure_message(name(), flag, CVodeGetReturnFlagName(flag), t_, error_, *sys_, mem_, y_,
                                   CVodeGetEstLocalErrors, CVodeGetErrWeights);
  }

  void collect_stats() {
    long v = 0;
    auto get = [&](int (*fn)(void*, long*)) { v = 0; fn(mem_, &v); return v; };
    IntegratorStats now;
    now.steps = get(CVodeGetNumSteps);
    now.rhs_evaluations = get(CVodeGetNumRhsEvals) + get(CVodeGetNumLinRhsEvals);
    now.jacobian_evaluations = get(CVodeGetNumJacEvals);
    now.linear_solves = get(CVodeGetNumLinSolvSetups);
    now.rejected_steps = get(CVodeGetNumErrTestFails);
    now.nonlinear_iterations = get(CVodeGetNumNonlinSolvIters);
    detail::accumulate_since_reinit(stats_, base_, now);
  }

  void check(int flag, const char* what) const { detail::check_flag(flag, "cvode", what); }
  void release() {
    if (mem_) CVodeFree(&mem_);
    if (LS_) SUNLinSolFree(LS_), LS_ = nullptr;
    if (A_) SUNMatDestroy(A_), A_ = nullptr;
    if (y_) N_VDestroy(y_), y_ = nullptr;
    if (dky_) N_VDestroy(dky_), dky_ = nullptr;
  }

  IntegratorOptions opt_;
  int method_;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector dky_ = nullptr;  // the dense output's target (make_view_vector)
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  OdeSystem* sys_ = nullptr;
  int n_ = 0, nroots_ = 0;
  double t_ = 0;
  Eigen::MatrixXd J_;
  std::vector<int> rootsfound_;
  std::exception_ptr pending_;
  std::string error_;
  IntegratorStats base_;
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_cvode_bdf(const IntegratorOptions& o) { return std::make_unique<Cvode>(o, CV_BDF); }
std::unique_ptr<Integrator> make_cvode_adams(const IntegratorOptions& o) { return std::make_unique<Cvode>(o, CV_ADAMS); }
}  // namespace detail

}  // namespace pumasim
