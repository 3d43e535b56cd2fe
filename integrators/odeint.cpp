// Boost.Odeint behind the Integrator interface: the adaptive explicit
// Dormand-Prince 5(4) pair, and rosenbrock4 (a linearly implicit, L-stable
// order-4 method) with the system's Jacobian.
//
// rosenbrock4's coefficients: Boost 1.74's default_rosenbrock_coefficients has
// d4 = +0.0362, and d_i multiplies h df/dt in stage i. A Rosenbrock method's
// consistency needs d_i = gamma_i = sum_j gamma_ij (Hairer & Wanner II, Sec.
// IV.7, (7.4)-(7.5) with alpha_i, gamma_i), and in the transformed form that
// odeint steps (c_ij = diag(1/gamma) - Gamma^-1, (7.25)) the row sums of Gamma
// follow from the table's own c_ij: Gamma 1 = s with (I/gamma - C) s = 1. That
// gives d1..d3 as shipped and d4 = -0.0362 (the value of Hairer's RODAS
// table). With +0.0362 the method is first order on every problem with
// explicit time dependence (on y0' = -50 (y0 - cos t), y1' = y0 - y1 it took
// far more steps than with the corrected value; measured: commit 40c54a3) and
// exact on autonomous ones, which is why an order test on y' = -y passed.
// ConsistentRosenbrockCoefficients recomputes d1..d4 from that condition.
//
// Care taken (Boost.Odeint's pitfalls): steppers are kept as members and
// driven step by step with try_step, so no copy drops their state and no
// integrate_* function adapts the step behind our back; statistics are
// counted by wrapping the system, not inferred. rosenbrock4 wants uBLAS
// vectors and matrices: the system and its Jacobian are adapted to them
// (copies of n doubles per call), the plant's code is not duplicated. Its
// dfdt (the explicit time dependence, through the reference) is a forward
// difference in t. Roots: after an accepted step over which a root function
// changes sign, the zero is located by the Illinois variant of regula falsi,
// each trial point one step of the method itself from the step's start (no
// interpolant needed, so the located state has the method's own accuracy);
// the run stops just past the zero, like CVODE, and the step that ends there
// is taken once more from its start so that its dense output covers it.
// Dense output: each stepper's own continuous extension (dopri5's order-4
// interpolant from its stages; rosenbrock4's order-3 one, prepared after the
// accepted step) -- no extra right-hand side. Absolute tolerances per
// component (atol * the system's tolerance_scale): dopri5 through its own
// error checker; rosenbrock4's controller takes one atol, so it integrates
// the scaled state y_i = x_i / scale_i, whose error test is the same.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <boost/numeric/odeint.hpp>

#include "core/time_rule.hpp"
#include "integrators/integrator.hpp"
#include "integrators/rosenbrock_coefficients.hpp"

namespace pumasim {
namespace {

namespace odeint = boost::numeric::odeint;

class OdeintBase : public Integrator {
 public:
  explicit OdeintBase(const IntegratorOptions& o) : Integrator(o.max_steps), opt_(o) {
    if (!(o.rtol > 0) || !(o.atol > 0)) throw std::invalid_argument("odeint: expected rtol > 0 and atol > 0");
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    if (sys_) ++stats_.restarts;
    sys_ = &sys;
    t_ = t_start_ = t0;
    h_ = 0.0;  // chosen at the first step
    load(x0, sys.size());
    g_.resize(sys.num_roots()), g_new_.resize(sys.num_roots());
    if (!g_.empty()) sys.roots(t_, x0, g_.data());
    fresh_stepper();
  }
  double time() const override { return t_; }
  double step_start() const override { return t_start_; }
  void dense_state(double t, double* x) override {
    if (t >= t_ || t_ == t_start_) {
      std::copy(data(), data() + sys_->size(), x);
      return;
    }
    interpolate(std::max(t, t_start_), x);
  }

 protected:
  virtual void load(const double* x0, int n) = 0;
  virtual void fresh_stepper() = 0;
  // One attempted step from t_ with size h; true if accepted (t_, state, h
  // updated, and the dense output prepared for [t_ - h, t_]).
  virtual bool try_step(double& h) = 0;
  virtual const double* data() const = 0;
  // One step of the underlying method (no error control) of size h from
  // (t0, x0) into out; and overwrite the current state.
  virtual void step_from(const double* x0, double t0, double h, double* out) = 0;
  // After a root: the step from (t0, x0) of size h taken once more, so that
  // the current state and the dense output are that step's.
  virtual void retake_step(const double* x0, double t0, double h) = 0;
  // The state at t within the last accepted step, from the stepper's dense output.
  virtual void interpolate(double t, double* x) = 0;
  virtual void set_state(const double* x) = 0;

  IntegratorOptions opt_;
  OdeSystem* sys_ = nullptr;
  double t_ = 0, h_ = 0, t_start_ = 0;

  // Attempts until one step is accepted (or a root, or a failure).
  Outcome step(double t_stop) override {
    if (h_ <= 0) h_ = std::min(1e-4, std::max(t_stop - t_, 0.0));
    for (;;) {
      // A stop at the same instant (time_rule.hpp) is reached.
      if (!before(t_, t_stop, t_stop)) {
        t_start_ = t_ = t_stop;
        return {};
      }
      double h = std::min(h_, t_stop - t_);
      const bool last = h >= t_stop - t_;
      const double t_before = t_;
      if (!g_.empty()) x_start_.assign(data(), data() + sys_->size());
      if (try_step(h)) {
        ++stats_.steps;
        t_start_ = t_before;
        if (last && t_ >= t_before + (t_stop - t_before) * (1 - 1e-12)) t_ = t_stop;
        if (!last) h_ = h;  // after a step shortened to reach t_stop, the earlier proposal stands
        if (const std::string bad = non_finite_components(*sys_, t_, data()); !bad.empty()) {
          return {Outcome::kFailed, -1, std::string(name()) + ": " + bad};
        }
        if (!g_.empty()) {
          sys_->roots(t_, data(), g_new_.data());
          if (first_crossing(g_, g_new_) >= 0) return {Outcome::kRoot, locate_root(t_before), ""};
          g_ = g_new_;
        }
        return {};
      }
      ++stats_.rejected_steps;
      h_ = h;
      // Underflow: a step that no longer moves t by more than rounding at the
      // time reached (not at the stop: a run to t = 1e11 s must still take
      // microsecond steps near t = 0, as Robertson's problem does).
      if (!(h_ > 1e-14 * std::max(1.0, std::abs(t_))) || !std::isfinite(h_)) {
        return {Outcome::kFailed, -1,
                std::string(name()) + ": step size underflow (h = " + std::to_string(h_) + ") at t = " +
                    std::to_string(t_) + " s" + non_finite_suffix()};
      }
    }
  }

 private:
  // The step from (t0, x_start_) to (t_, data()) crossed a zero of some root
  // function (g_ before, g_new_ after). Shrinks the bracket [a, b] of step
  // sizes around the earliest zero until it is 100 eps (|t| + |h|) wide, moves
  // to the state at t0 + b (past the zero) and returns the root's index.
  int locate_root(double t0) {
    const int n = sys_->size(), m = static_cast<int>(g_.size());
    std::vector<double> ga = g_, gb = g_new_, gs(m), xs(n);
    double a = 0.0, b = t_ - t0;
    const double tol = 100 * std::numeric_limits<double>::epsilon() * (std::abs(t0) + b);
    const int k = locate_earliest_root(ga, gb, gs, a, b, tol, [&](double s, std::vector<double>& g) {
      step_from(x_start_.data(), t0, s, xs.data());
      sys_->roots(t0 + s, xs.data(), g.data());
    });
    retake_step(x_start_.data(), t0, b);  // the state xb again, with the step's dense output
    t_ = t0 + b;
    g_ = gb;
    return k;
  }
  // The non-finite components, or else the fastest-changing one.
  std::string non_finite_suffix() const {
    const std::string bad = non_finite_components(*sys_, t_, data());
    if (!bad.empty()) return "; " + bad;
    return "; fastest-changing component " + fastest_component(*sys_, t_, data());
  }
  std::vector<double> g_, g_new_, x_start_;
};

// odeint's default error test, max_i |err_i| / (atol_i + rtol (|x_i| + |h| |x'_i|)),
// with one absolute tolerance per component.
class ComponentErrorChecker {
 public:
  using value_type = double;
  using algebra_type = odeint::range_algebra;
  using operations_type = odeint::default_operations;
  ComponentErrorChecker() = default;
  ComponentErrorChecker(std::vector<double> atol, double rtol) : atol_(std::move(atol)), rtol_(rtol) {}
  template <class State, class Deriv, class Err, class Time>
  double error(algebra_type&, const State& x_old, const Deriv& dxdt_old, Err& x_err, Time dt) const {
    double e = 0.0;
    for (std::size_t i = 0; i < atol_.size(); ++i) {
      const double sk = atol_[i] + rtol_ * (std::abs(x_old[i]) + std::abs(dt) * std::abs(dxdt_old[i]));
      e = std::max(e, std::abs(x_err[i]) / sk);
    }
    return e;
  }

 private:
  std::vector<double> atol_;
  double rtol_ = 0.0;
};

class Dopri5 final : public OdeintBase {
  using State = std::vector<double>;
  using Stepper = odeint::controlled_runge_kutta<odeint::runge_kutta_dopri5<State>, ComponentErrorChecker>;

 public:
  using OdeintBase::OdeintBase;
  const char* name() const override { return "odeint-dopri5"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = true;
    c.finds_roots = true;
    c.order = 5;
    return c;
  }
  const double* state() const override { return x_.data(); }

 protected:
  auto odeint_system() {
    return [this](const State& x, State& dx, double t) {
      dx.resize(x.size());
      sys_->rhs(t, x.data(), dx.data());
      ++stats_.rhs_evaluations;
    };
  }
  void load(const double* x0, int n) override {
    x_.assign(x0, x0 + n);
    atol_.resize(n);
    for (int i = 0; i < n; ++i) atol_[i] = opt_.atol * sys_->tolerance_scale(i);
    x_old_ = x_, f_old_.resize(n), f_.resize(n), x_new_.resize(n), f_new_.resize(n);
    have_f_ = false;  // f at the step's start: evaluated by the first step, then carried (first same as last)
  }
  void fresh_stepper() override { stepper_ = Stepper(ComponentErrorChecker(atol_, opt_.rtol)); }
  bool try_step(double& h) override {
    double t = t_;
    if (!have_f_) odeint_system()(x_, f_, t_), have_f_ = true;
    if (stepper_.try_step(odeint_system(), x_, f_, t, x_new_, f_new_, h) != odeint::success) return false;
    accept(t_, t);
    return true;
  }
  const double* data() const override { return x_.data(); }
  void step_from(const double* x0, double t0, double h, double* out) override {
    xin_.assign(x0, x0 + x_.size());
    xout_.resize(x_.size());
    odeint::runge_kutta_dopri5<State> rk;  // fresh: no first-same-as-last state carried over
    rk.do_step(odeint_system(), xin_, t0, xout_, h);
    std::copy(xout_.begin(), xout_.end(), out);
  }
  void retake_step(const double* x0, double t0, double h) override {
    x_.assign(x0, x0 + x_.size());
    odeint_system()(x_, f_, t0);
    have_f_ = true;
    stepper_.stepper().do_step(odeint_system(), x_, f_, t0, x_new_, f_new_, h);
    accept(t0, t0 + h);
  }
  void interpolate(double t, double* x) override {
    xout_.resize(x_.size());
    stepper_.stepper().calc_state(t, xout_, x_old_, f_old_, t_old_, x_, f_, t_new_);
    std::copy(xout_.begin(), xout_.end(), x);
  }
  void set_state(const double* x) override { std::copy(x, x + x_.size(), x_.begin()); }

 private:
  // The accepted step [t0, t1]: keep its start for the dense output, move to its end.
  void accept(double t0, double t1) {
    x_old_.swap(x_), f_old_.swap(f_);
    x_.swap(x_new_), f_.swap(f_new_);
    t_old_ = t0, t_new_ = t1, t_ = t1;
  }
  State x_, f_, x_old_, f_old_, x_new_, f_new_, xin_, xout_, atol_;
  double t_old_ = 0, t_new_ = 0;
  bool have_f_ = false;
  Stepper stepper_;
};

// odeint's rosenbrock4 stepper and controller with a RODAS-form coefficient
// set (integrators/rosenbrock_coefficients.hpp).
template <class Coefficients>
class Rosenbrock4 final : public OdeintBase {
  using Vec = boost::numeric::ublas::vector<double>;
  using Mat = boost::numeric::ublas::matrix<double>;
  using Method = odeint::rosenbrock4<double, Coefficients>;
  using Stepper = odeint::rosenbrock4_controller<Method>;

 public:
  Rosenbrock4(const IntegratorOptions& o, const char* name) : OdeintBase(o), name_(name) {}
  const char* name() const override { return name_; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = true;
    c.finds_roots = true;
    c.order = 4;
    c.implicit = true;
    c.uses_jacobian = true;
    c.exact_jacobian = true;
    return c;
  }
  const double* state() const override { return x_.data(); }

 protected:
  // The (f, Jacobian) pair odeint's implicit steppers take, over uBLAS types,
  // for the scaled state y = x / s: y' = f(s y) / s, dy'/dy = S^-1 J S.
  auto odeint_system() {
    const int n = static_cast<int>(x_.size());
    auto f = [this, n](const Vec& y, Vec& dy, double t) {
      for (int r = 0; r < n; ++r) xt_[r] = s_[r] * y[r];
      sys_->rhs(t, xt_.data(), f1_.data());
      ++stats_.rhs_evaluations;
      dy.resize(n);
      for (int r = 0; r < n; ++r) dy[r] = f1_[r] / s_[r];
    };
    auto jac = [this, n](const Vec& y, Mat& J, double t, Vec& dfdt) {
      for (int r = 0; r < n; ++r) xt_[r] = s_[r] * y[r];
      sys_->jacobian(t, xt_.data(), Jd_);
      ++stats_.jacobian_evaluations;
      J.resize(n, n);
      for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) J(r, c) = Jd_(r, c) * s_[c] / s_[r];
      // The explicit time dependence: the system's own, or a forward difference in t.
      if (const int cost = sys_->time_derivative(t, xt_.data(), f1_.data()); cost >= 0) {
        stats_.rhs_evaluations += cost;
      } else {
        const double dt = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(t));
        sys_->rhs(t, xt_.data(), f0_.data());
        sys_->rhs(t + dt, xt_.data(), f1_.data());
        stats_.rhs_evaluations += 2;
        for (int r = 0; r < n; ++r) f1_[r] = (f1_[r] - f0_[r]) / dt;
      }
      dfdt.resize(n);
      for (int r = 0; r < n; ++r) dfdt[r] = f1_[r] / s_[r];
    };
    return std::make_pair(f, jac);
  }
  void load(const double* x0, int n) override {
    s_.resize(n);
    for (int i = 0; i < n; ++i) s_[i] = sys_->tolerance_scale(i);
    x_.resize(n), y_.resize(n), y_old_.resize(n), yd_.resize(n);
    f0_.resize(n), f1_.resize(n), xt_.resize(n);
    set_state(x0);
  }
  // rosenbrock4_controller is not assignable (const coefficients): rebuilt on reset.
  void fresh_stepper() override { stepper_ = std::make_unique<Stepper>(opt_.atol, opt_.rtol); }
  bool try_step(double& h) override {
    y_old_ = y_;
    const double t0 = t_;
    const bool ok = stepper_->try_step(odeint_system(), y_, t_, h) == odeint::success;
    ++stats_.linear_solves;  // one LU factorisation per attempted step
    if (ok) accept(t0, t_);
    return ok;
  }
  const double* data() const override { return x_.data(); }
  void step_from(const double* x0, double t0, double h, double* out) override {
    const int n = static_cast<int>(x_.size());
    Vec yin(n), yout(n);
    for (int i = 0; i < n; ++i) yin[i] = x0[i] / s_[i];
    stepper_->stepper().do_step(odeint_system(), yin, t0, yout, h);
    ++stats_.linear_solves;
    for (int i = 0; i < n; ++i) out[i] = s_[i] * yout[i];
  }
  void retake_step(const double* x0, double t0, double h) override {
    for (std::size_t i = 0; i < x_.size(); ++i) y_old_[i] = x0[i] / s_[i];
    stepper_->stepper().do_step(odeint_system(), y_old_, t0, y_, h);
    ++stats_.linear_solves;
    accept(t0, t0 + h);
  }
  void interpolate(double t, double* x) override {
    stepper_->stepper().calc_state(t, yd_, y_old_, t_old_, y_, t_new_);
    for (std::size_t i = 0; i < x_.size(); ++i) x[i] = s_[i] * yd_[i];
  }
  void set_state(const double* x) override {
    for (std::size_t i = 0; i < x_.size(); ++i) x_[i] = x[i], y_[i] = x[i] / s_[i];
  }

 private:
  // The accepted step [t0, t1] (y_old_ to y_): its dense output, and x = s y.
  void accept(double t0, double t1) {
    stepper_->stepper().prepare_dense_output();
    t_old_ = t0, t_new_ = t1;
    for (std::size_t i = 0; i < x_.size(); ++i) x_[i] = s_[i] * y_[i];
  }
  const char* name_;
  Vec y_, y_old_, yd_;                     // the state integrated (x / s); the step's start; scratch
  std::vector<double> x_, s_;              // x = s y, and the scales
  double t_old_ = 0, t_new_ = 0;
  std::unique_ptr<Stepper> stepper_;
  std::vector<double> f0_, f1_, xt_;
  Eigen::MatrixXd Jd_;
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_odeint_dopri5(const IntegratorOptions& o) { return std::make_unique<Dopri5>(o); }
// rosenbrock4 always uses the system's Jacobian (exact for the plant; for a
// system without one, OdeSystem's forward differences).
std::unique_ptr<Integrator> make_odeint_rosenbrock4(const IntegratorOptions& o) {
  return std::make_unique<Rosenbrock4<ConsistentRosenbrockCoefficients<double>>>(o, "odeint-rosenbrock4");
}
std::unique_ptr<Integrator> make_odeint_rodas4p(const IntegratorOptions& o) {
  return std::make_unique<Rosenbrock4<Rodas4PCoefficients<double>>>(o, "odeint-rodas4p");
}
}  // namespace detail

}  // namespace pumasim
