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
// difference in t. Neither method locates roots: like the fixed-step
// methods they check the root functions' signs after each accepted step.
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

  IntegratorOptions opt_;
  OdeSystem* sys_ = nullptr;
  double t_ = 0, h_ = 0;

 private:
  Outcome run(double t_stop) {
    long taken = 0;
    const double span = std::max(1.0, std::abs(t_stop));
    if (h_ <= 0) h_ = std::min(1e-4, std::max(t_stop - t_, 0.0));
    while (t_ < t_stop) {
      double h = std::min(h_, t_stop - t_);
      const bool last = h >= t_stop - t_;
      const double t_before = t_;
      if (try_step(h)) {
        ++stats_.steps;
        if (last && t_ >= t_before + (t_stop - t_before) * (1 - 1e-12)) t_ = t_stop;
        if (!(last && h_ < h)) h_ = h;  // keep the controller's proposal unless shortened
        if (const std::string bad = non_finite_components(*sys_, t_, data()); !bad.empty()) {
          return {Outcome::kFailed, -1, std::string(name()) + ": " + bad};
        }
        if (!g_.empty()) {
          sys_->roots(t_, data(), g_new_.data());
          const int k = first_crossing(g_, g_new_);
          g_ = g_new_;
          if (k >= 0) return {Outcome::kRoot, k, ""};
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
  // The non-finite components, or else the fastest-changing one.
  std::string non_finite_suffix() const {
    const std::string bad = non_finite_components(*sys_, t_, data());
    if (!bad.empty()) return "; " + bad;
    const int n = sys_->size();
    std::vector<double> f(n);
    sys_->rhs(t_, data(), f.data());
    int worst = 0;
    double rate = -1;
    for (int i = 0; i < n; ++i) {
      const double r = std::abs(f[i]) / std::max(1.0, std::abs(data()[i]));
      if (r > rate || !std::isfinite(r)) rate = r, worst = i;
    }
    return "; fastest-changing component " + sys_->state_name(worst) + " = " + std::to_string(data()[worst]);
  }
  std::vector<double> g_, g_new_;
};

class Dopri5 final : public OdeintBase {
  using State = std::vector<double>;
  using Stepper = odeint::controlled_runge_kutta<odeint::runge_kutta_dopri5<State>>;

 public:
  using OdeintBase::OdeintBase;
  const char* name() const override { return "odeint-dopri5"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = true;
    c.order = 5;
    return c;
  }
  const double* state() const override { return x_.data(); }

 protected:
  void load(const double* x0, int n) override { x_.assign(x0, x0 + n); }
  void fresh_stepper() override {
    stepper_ = Stepper(odeint::default_error_checker<double, odeint::range_algebra, odeint::default_operations>(
        opt_.atol, opt_.rtol));
  }
  bool try_step(double& h) override {
    auto f = [this](const State& x, State& dx, double t) {
      dx.resize(x.size());
      sys_->rhs(t, x.data(), dx.data());
      ++stats_.rhs_evaluations;
    };
    return stepper_.try_step(f, x_, t_, h) == odeint::success;
  }
  const double* data() const override { return x_.data(); }

 private:
  State x_;
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
    c.order = 4;
    c.implicit = true;
    c.uses_jacobian = true;
    return c;
  }
  const double* state() const override { return &x_[0]; }

 protected:
  void load(const double* x0, int n) override {
    x_.resize(n);
    std::copy(x0, x0 + n, x_.begin());
    f0_.resize(n), f1_.resize(n), xt_.resize(n);
  }
  // rosenbrock4_controller is not assignable (const coefficients): rebuilt on reset.
  void fresh_stepper() override { stepper_ = std::make_unique<Stepper>(opt_.atol, opt_.rtol); }
  bool try_step(double& h) override {
    const int n = static_cast<int>(x_.size());
    auto f = [this, n](const Vec& x, Vec& dx, double t) {
      std::copy(x.begin(), x.end(), xt_.begin());
      sys_->rhs(t, xt_.data(), f1_.data());
      ++stats_.rhs_evaluations;
      dx.resize(n);
      std::copy(f1_.begin(), f1_.end(), dx.begin());
    };
    auto jac = [this, n](const Vec& x, Mat& J, double t, Vec& dfdt) {
      std::copy(x.begin(), x.end(), xt_.begin());
      sys_->jacobian(t, xt_.data(), Jd_);
      ++stats_.jacobian_evaluations;
      J.resize(n, n);
      for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) J(r, c) = Jd_(r, c);
      // Explicit time dependence by a forward difference in t.
      const double dt = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(t));
      sys_->rhs(t, xt_.data(), f0_.data());
      sys_->rhs(t + dt, xt_.data(), f1_.data());
      stats_.rhs_evaluations += 2;
      dfdt.resize(n);
      for (int r = 0; r < n; ++r) dfdt[r] = (f1_[r] - f0_[r]) / dt;
    };
    const bool ok = stepper_->try_step(std::make_pair(f, jac), x_, t_, h) == odeint::success;
    ++stats_.linear_solves;  // one LU factorisation per attempted step
    return ok;
  }
  const double* data() const override { return &x_[0]; }

 private:
  Vec x_;
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
