// Forward sensitivities by CVODES (integrators/sensitivity.hpp). Like the
// CVODE adapter, the callbacks catch every exception and hand it back after
// CVode returns; a non-finite derivative is recoverable (CVODES shrinks the step).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "integrators/integrator.hpp"
#include "integrators/sensitivity.hpp"
#include "integrators/sundials_common.hpp"

namespace pumasim {

void SensitivitySystem::initial_sensitivities(double* s0) const {
  for (int k = 0; k < size() * parameters(); ++k) s0[k] = 0.0;
}

double SensitivitySystem::next_stop(double) const { return std::numeric_limits<double>::infinity(); }

namespace {

bool finite(const double* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

// One run's CVODES memory and what its callbacks need.
class Cvodes {
 public:
  Cvodes(SensitivitySystem& sys, double t0, const double* x0, const SensitivityOptions& o)
      : sys_(sys),
        m_(sys.size()),
        p_(sys.parameters()),
        J_(m_, m_),
        Jn_(m_, m_),
        dfdp_(m_, p_),
        at_x_(static_cast<std::size_t>(m_)) {
    if (p_ < 1) throw std::invalid_argument("cvodes: expected at least one parameter");
    check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
    y_ = N_VNew_Serial(m_, ctx_);
    std::copy(x0, x0 + m_, N_VGetArrayPointer(y_));
    yS_ = N_VCloneVectorArray(p_, y_);
    Eigen::MatrixXd s0(m_, p_);
    sys_.initial_sensitivities(s0.data());
    for (int k = 0; k < p_; ++k) std::copy(s0.col(k).data(), s0.col(k).data() + m_, N_VGetArrayPointer(yS_[k]));
    mem_ = CVodeCreate(CV_BDF, ctx_);
    if (!mem_) throw std::runtime_error("cvodes: CVodeCreate failed");
    check(CVodeInit(mem_, &Cvodes::rhs, t0, y_), "CVodeInit");
    check(CVodeSetUserData(mem_, this), "CVodeSetUserData");
    check(CVodeSetErrHandlerFn(mem_, &Cvodes::on_error, this), "CVodeSetErrHandlerFn");
    check(detail::set_absolute_tolerances(sys, o.atol, ctx_,
                                          [&](N_Vector a) { return CVodeSVtolerances(mem_, o.rtol, a); }),
          "CVodeSVtolerances");
    check(CVodeSetMaxNumSteps(mem_, o.max_steps), "CVodeSetMaxNumSteps");
    A_ = SUNDenseMatrix(m_, m_, ctx_);
    LS_ = SUNLinSol_Dense(y_, A_, ctx_);
    check(CVodeSetLinearSolver(mem_, LS_, A_), "CVodeSetLinearSolver");
    check(CVodeSetJacFn(mem_, &Cvodes::jac), "CVodeSetJacFn");
    check(CVodeSensInit(mem_, p_, CV_STAGGERED, &Cvodes::sens_rhs, yS_), "CVodeSensInit");
    for (int k = 0; k < p_; ++k) pbar_.push_back(std::abs(sys.parameter_scale(k)) > 0 ? sys.parameter_scale(k) : 1.0);
    check(CVodeSetSensParams(mem_, nullptr, pbar_.data(), nullptr), "CVodeSetSensParams");
    check(CVodeSensEEtolerances(mem_), "CVodeSensEEtolerances");
    check(CVodeSetSensErrCon(mem_, SUNTRUE), "CVodeSetSensErrCon");
    t_ = t0;
  }
  ~Cvodes() {
    if (mem_) CVodeFree(&mem_);
    if (LS_) SUNLinSolFree(LS_);
    if (A_) SUNMatDestroy(A_);
    if (yS_) N_VDestroyVectorArray(yS_, p_);
    if (y_) N_VDestroy(y_);
    SUNContext_Free(&ctx_);
  }
  Cvodes(const Cvodes&) = delete;
  Cvodes& operator=(const Cvodes&) = delete;

  // Steps no further than t: the next stop, or the run's end (SUNDIALS 6.4
  // has no call to clear a stop time, so one is always set).
  void set_stop(double t) { check(CVodeSetStopTime(mem_, t), "CVodeSetStopTime"); }
  // To `t_to`, an output time (interpolated: the outputs do not cap the
  // steps) or the stop set; false (with `failure`) if CVODES fails.
  bool advance(double t_to, std::string& failure) {
    pending_ = nullptr, error_.clear();
    double t = t_;
    const int flag = CVode(mem_, t_to, y_, &t, CV_NORMAL);
    if (pending_) std::rethrow_exception(pending_);
    collect_stats();
    if (!jump_.empty()) {
      failure = jump_;
      return false;
    }
    if (flag < 0) {
      failure = "cvodes failed with flag " + std::to_string(flag) + " (" +
                detail::flag_name(CVodeGetReturnFlagName(flag)) + ") at t = " + std::to_string(t) + " s" +
                (error_.empty() ? "" : ": " + error_);
      return false;
    }
    t_ = t;
    double ts = t;
    check(CVodeGetSens(mem_, &ts, yS_), "CVodeGetSens");
    return true;
  }
  // A restart at a stop: a fresh history from x and s as they are.
  void restart() {
    check(CVodeReInit(mem_, t_, y_), "CVodeReInit");
    check(CVodeSensReInit(mem_, CV_STAGGERED, yS_), "CVodeSensReInit");
    at_t_ = std::numeric_limits<double>::quiet_NaN();  // the cache belongs to the piece before the stop
    base_ = {}, sens_base_[0] = sens_base_[1] = 0;
    ++stats_.restarts;
  }

  double* state() { return N_VGetArrayPointer(y_); }
  Eigen::MatrixXd sensitivities() const {
    Eigen::MatrixXd s(m_, p_);
    for (int k = 0; k < p_; ++k) s.col(k) = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(yS_[k]), m_);
    return s;
  }
  const IntegratorStats& stats() const { return stats_; }
  long sens_rhs() const { return sens_total_[0]; }
  long sens_jacobians() const { return jacobians_; }
  long sens_fails() const { return sens_total_[1]; }

 private:
  static int rhs(double t, N_Vector y, N_Vector ydot, void* self) {
    auto* me = static_cast<Cvodes*>(self);
    try {
      me->sys_.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
      return finite(N_VGetArrayPointer(ydot), me->m_) ? 0 : 1;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static int jac(double t, N_Vector y, N_Vector, SUNMatrix J, void* self, N_Vector, N_Vector, N_Vector) {
    auto* me = static_cast<Cvodes*>(self);
    try {
      me->sys_.jacobian(t, N_VGetArrayPointer(y), me->Jn_);  // its own buffer: J_ is the sensitivities' cache
      for (int c = 0; c < me->m_; ++c)
        for (int r = 0; r < me->m_; ++r) SM_ELEMENT_D(J, r, c) = me->Jn_(r, c);
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  // s_k' = J s_k + df/dp_k, every k at once.
  static int sens_rhs(int ns, double t, N_Vector y, N_Vector, N_Vector* yS, N_Vector* ySdot, void* self, N_Vector,
                      N_Vector) {
    auto* me = static_cast<Cvodes*>(self);
    try {
      const double* x = N_VGetArrayPointer(y);
      // The staggered corrector calls this at each of its iterations with the
      // same (t, x): J and df/dp are made once per (t, x).
      if (t != me->at_t_ || !std::equal(x, x + me->m_, me->at_x_.begin())) {
        const std::string jump = me->sys_.jump_at(t, x);
        if (!jump.empty()) {
          me->jump_ = jump;
          return -1;  // unrecoverable: CVODES stops, the run reports why
        }
        me->sys_.jacobian(t, x, me->J_);
        ++me->jacobians_;
        me->sys_.parameter_derivatives(t, x, me->dfdp_.data());
        me->at_t_ = t, std::copy(x, x + me->m_, me->at_x_.begin());
      }
      for (int k = 0; k < ns; ++k) {
        Eigen::Map<Eigen::VectorXd> out(N_VGetArrayPointer(ySdot[k]), me->m_);
        out.noalias() = me->J_ * Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(yS[k]), me->m_);
        out += me->dfdp_.col(k);
        if (!finite(out.data(), me->m_)) return 1;
      }
      return 0;
    } catch (...) {
      me->pending_ = std::current_exception();
      return -1;
    }
  }
  static void on_error(int, const char* module, const char* function, char* msg, void* self) {
    static_cast<Cvodes*>(self)->error_ = std::string(module) + "." + function + ": " + msg;
  }
  void collect_stats() {
    long v = 0;
    auto get = [&](int (*fn)(void*, long*)) {
      v = 0;
      fn(mem_, &v);
      return v;
    };
    IntegratorStats now;
    now.steps = get(CVodeGetNumSteps);
    now.rhs_evaluations = get(CVodeGetNumRhsEvals);
    now.jacobian_evaluations = get(CVodeGetNumJacEvals);
    now.linear_solves = get(CVodeGetNumLinSolvSetups);
    now.rejected_steps = get(CVodeGetNumErrTestFails);
    now.nonlinear_iterations = get(CVodeGetNumNonlinSolvIters);
    detail::accumulate_since_reinit(stats_, base_, now);
    const long sens[2] = {get(CVodeGetSensNumRhsEvals), get(CVodeGetSensNumErrTestFails)};
    for (int i = 0; i < 2; ++i) sens_total_[i] += sens[i] - sens_base_[i], sens_base_[i] = sens[i];
  }
  static void check(int flag, const char* what) { detail::check_flag(flag, "cvodes", what); }

  SensitivitySystem& sys_;
  int m_, p_;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector* yS_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  std::vector<double> pbar_;
  Eigen::MatrixXd J_, Jn_, dfdp_;  // the sensitivities' J (cached per (t, x)), the Newton matrix's, df/dp
  double at_t_ = std::numeric_limits<double>::quiet_NaN();  // where J_ and dfdp_ were made
  std::vector<double> at_x_;
  double t_ = 0;
  std::exception_ptr pending_;
  std::string error_;
  std::string jump_;  // the system's jump_at, when it stopped the run
  long jacobians_ = 0;
  IntegratorStats stats_, base_;
  long sens_total_[2] = {0, 0}, sens_base_[2] = {0, 0};
};

}  // namespace

SensitivityRun sensitivity_run(SensitivitySystem& sys, double t0, const double* x0, const std::vector<double>& outputs,
                               const SensitivityOptions& options) {
  SensitivityRun run;
  if (sys.num_roots() > 0) {
    run.ok = false;
    run.failure = "the system has " + std::to_string(sys.num_roots()) +
                  " root functions (events that switch its right-hand side): its sensitivities jump there, "
                  "by a saltation matrix this integrator does not apply";
    return run;
  }
  const auto start = std::chrono::steady_clock::now();
  Cvodes cv(sys, t0, x0, options);
  double t = t0, stop = sys.next_stop(t0);
  const double t_end = outputs.empty() ? t0 : outputs.back();
  cv.set_stop(std::min(stop, t_end));
  std::vector<double> before(static_cast<std::size_t>(sys.size()));
  for (double tout : outputs) {
    while (t < tout) {
      const double to = std::min(tout, stop);
      if (!cv.advance(to, run.failure)) {
        run.ok = false;
        break;
      }
      if (cv.stats().steps > options.max_steps) {
        run.ok = false;
        run.failure = "more than " + std::to_string(options.max_steps) +
                      " steps (the budget) by t = " + std::to_string(to) + " s";
        break;
      }
      t = to;
      if (t < stop) continue;
      std::copy(cv.state(), cv.state() + sys.size(), before.begin());
      sys.on_stop(t, cv.state());
      if (!std::equal(before.begin(), before.end(), cv.state())) {
        run.ok = false;
        run.failure = "the state jumped at the stop at t = " + std::to_string(t) +
                      " s: its sensitivities would need the jump condition";
        break;
      }
      cv.restart();
      stop = sys.next_stop(t);
      cv.set_stop(std::min(stop, t_end));
    }
    if (!run.ok) break;
    run.t.push_back(t);
    run.x.emplace_back(Eigen::Map<const Eigen::VectorXd>(cv.state(), sys.size()));
    run.s.push_back(cv.sensitivities());
  }
  run.stats = cv.stats();
  run.sensitivity_rhs = cv.sens_rhs();
  run.sensitivity_error_test_failures = cv.sens_fails();
  run.sensitivity_jacobians = cv.sens_jacobians();
  run.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.stats.wall_time = run.wall_time;
  return run;
}

}  // namespace pumasim
