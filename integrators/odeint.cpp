// Boost.Odeint behind the Integrator interface: the adaptive explicit
// Dormand-Prince 5(4) pair, and rosenbrock4 (a linearly implicit, L-stable
// order-4 method) with the system's Jacobian.
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
// the run stops just past the zero, like CVODE. Absolute tolerances per
// component (atol * the system's tolerance_scale): dopri5 through its own
// error checker; rosenbrock4's controller takes one atol, so it integrates
// the scaled state y_i = x_i / scale_i, whose error test is the same.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <boost/numeric/odeint.hpp>

#include "integrators/integrator.hpp"
#include "integrators/registry_entries.hpp"

namespace pumasim {
namespace {

namespace odeint = boost::numeric::odeint;

class OdeintBase : public Integrator {
 public:
  explicit OdeintBase(const IntegratorOptions& o) : opt_(o) {
    if (!(o.rtol > 0) || !(o.atol > 0)) throw std::invalid_argument("odeint: expected rtol > 0 and atol > 0");
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    if (sys_) ++stats_.restarts;
    sys_ = &sys;
    t_ = t0;
    h_ = 0.0;  // chosen at the first step
    load(x0, sys.size());
    g_.resize(sys.num_roots()), g_new_.resize(sys.num_roots());
    if (!g_.empty()) sys.roots(t_, x0, g_.data());
    fresh_stepper();
  }
  Outcome advance(double t_stop) override { return run(t_stop); }
  double time() const override { return t_; }

 protected:
  virtual void load(const double* x0, int n) = 0;
  virtual void fresh_stepper() = 0;
  // One attempted step from t_ with size h; true if accepted (t_, state, h updated).
  virtual bool try_step(double& h) = 0;
  virtual const double* data() const = 0;
  // One step of the underlying method (no error control) of size h from
  // (t0, x0) into out; and overwrite the current state.
  virtual void step_from(const double* x0, double t0, double h, double* out) = 0;
  virtual void set_state(const double* x) = 0;

  IntegratorOptions opt_;
  OdeSystem* sys_ = nullptr;
  double t_ = 0, h_ = 0;

 private:
  Outcome run(double t_stop) {
    long taken = 0;
    const double span = std::max(1.0, std::abs(t_stop));
    if (h_ <= 0) h_ = std::min(1e-4, std::max(t_stop - t_, 0.0));
    while (t_ < t_stop) {
      // A stop closer than rounding (a sample grid k * period computed apart
      // from the time reached) is reached: a step of 1e-18 s would drag the
      // step-size controller down to an underflow.
      if (t_stop - t_ <= 1e-12 * span) {
        t_ = t_stop;
        break;
      }
      double h = std::min(h_, t_stop - t_);
      const bool last = h >= t_stop - t_;
      const double t_before = t_;
      if (!g_.empty()) x_start_.assign(data(), data() + sys_->size());
      if (try_step(h)) {
        ++stats_.steps;
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
      } else {
        ++stats_.rejected_steps;
        h_ = h;
      }
      if (!(h_ > 1e-14 * span) || !std::isfinite(h_)) {
        return {Outcome::kFailed, -1,
                std::string(name()) + ": step size underflow (h = " + std::to_string(h_) + ") at t = " +
                    std::to_string(t_) + " s" + non_finite_suffix()};
      }
      if (++taken > opt_.max_steps) {
        return {Outcome::kFailed, -1,
                std::string(name()) + ": too many steps (" + std::to_string(opt_.max_steps) +
                    ") at t = " + std::to_string(t_) + " s"};
      }
    }
    return {};
  }
  // The step from (t0, x_start_) to (t_, data()) crossed a zero of some root
  // function (g_ before, g_new_ after). Shrinks the bracket [a, b] of step
  // sizes around the earliest zero until it is 100 eps (|t| + |h|) wide, moves
  // to the state at t0 + b (past the zero) and returns the root's index.
  int locate_root(double t0) {
    const int n = sys_->size(), m = static_cast<int>(g_.size());
    std::vector<double> ga = g_, gb = g_new_, gs(m), xs(n), xb(data(), data() + n);
    double a = 0.0, b = t_ - t0;
    const double tol = 100 * std::numeric_limits<double>::epsilon() * (std::abs(t0) + b);
    // The crossing that linear interpolation puts first.
    auto earliest = [&](const std::vector<double>& g0, const std::vector<double>& g1, double& frac) {
      int k = -1;
      frac = 2.0;
      for (int i = 0; i < m; ++i) {
        if (!crossed(g0[i], g1[i])) continue;
        const double f = g0[i] / (g0[i] - g1[i]);
        if (f < frac) frac = f, k = i;
      }
      return k;
    };
    double frac;
    int k = earliest(ga, gb, frac);
    double wa = 1.0, wb = 1.0;  // Illinois weights on the retained end's g
    int side = 0;
    for (int it = 0; it < 200 && b - a > tol; ++it) {
      const double fa = wa * ga[k], fb = wb * gb[k];
      double s = fa != fb ? a + (b - a) * fa / (fa - fb) : 0.5 * (a + b);
      s = std::clamp(s, a + 0.5 * tol, b - 0.5 * tol);
      step_from(x_start_.data(), t0, s, xs.data());
      sys_->roots(t0 + s, xs.data(), gs.data());
      double f2;
      const int k2 = earliest(ga, gs, f2);
      if (k2 >= 0) {  // a zero in [a, s]
        b = s, gb = gs, xb = xs, k = k2;
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
    t_ = t0 + b;
    set_state(xb.data());
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
  }
  void fresh_stepper() override { stepper_ = Stepper(ComponentErrorChecker(atol_, opt_.rtol)); }
  bool try_step(double& h) override { return stepper_.try_step(odeint_system(), x_, t_, h) == odeint::success; }
  const double* data() const override { return x_.data(); }
  void step_from(const double* x0, double t0, double h, double* out) override {
    xin_.assign(x0, x0 + x_.size());
    xout_.resize(x_.size());
    odeint::runge_kutta_dopri5<State> rk;  // fresh: no first-same-as-last state carried over
    rk.do_step(odeint_system(), xin_, t0, xout_, h);
    std::copy(xout_.begin(), xout_.end(), out);
  }
  void set_state(const double* x) override { std::copy(x, x + x_.size(), x_.begin()); }

 private:
  State x_, xin_, xout_, atol_;
  Stepper stepper_;
};

class Rosenbrock4 final : public OdeintBase {
  using Vec = boost::numeric::ublas::vector<double>;
  using Mat = boost::numeric::ublas::matrix<double>;
  using Stepper = odeint::rosenbrock4_controller<odeint::rosenbrock4<double>>;

 public:
  using OdeintBase::OdeintBase;
  const char* name() const override { return "odeint-rosenbrock4"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = true;
    c.finds_roots = true;
    c.order = 4;
    c.implicit = true;
    c.uses_jacobian = true;
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
      // Explicit time dependence by a forward difference in t.
      const double dt = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(t));
      sys_->rhs(t, xt_.data(), f0_.data());
      sys_->rhs(t + dt, xt_.data(), f1_.data());
      stats_.rhs_evaluations += 2;
      dfdt.resize(n);
      for (int r = 0; r < n; ++r) dfdt[r] = (f1_[r] - f0_[r]) / dt / s_[r];
    };
    return std::make_pair(f, jac);
  }
  void load(const double* x0, int n) override {
    s_.resize(n);
    for (int i = 0; i < n; ++i) s_[i] = sys_->tolerance_scale(i);
    x_.resize(n), y_.resize(n);
    f0_.resize(n), f1_.resize(n), xt_.resize(n);
    set_state(x0);
  }
  // rosenbrock4_controller is not assignable (const coefficients): rebuilt on reset.
  void fresh_stepper() override { stepper_ = std::make_unique<Stepper>(opt_.atol, opt_.rtol); }
  bool try_step(double& h) override {
    const bool ok = stepper_->try_step(odeint_system(), y_, t_, h) == odeint::success;
    ++stats_.linear_solves;  // one LU factorisation per attempted step
    if (ok)
      for (std::size_t i = 0; i < x_.size(); ++i) x_[i] = s_[i] * y_[i];
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
  void set_state(const double* x) override {
    for (std::size_t i = 0; i < x_.size(); ++i) x_[i] = x[i], y_[i] = x[i] / s_[i];
  }

 private:
  Vec y_;                                  // the state integrated: x / s
  std::vector<double> x_, s_;              // x = s y, and the scales
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
  return std::make_unique<Rosenbrock4>(o);
}
}  // namespace detail

}  // namespace pumasim
