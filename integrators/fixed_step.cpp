// Fixed-step integrators written in the project: forward Euler, classical RK4,
// and Adams-Bashforth of orders 2-4 (the paper's integrator family; it does not give the order).
//
// Adams-Bashforth history: the first k-1 steps after every (re)start are
// taken with RK4, whose derivatives seed the history; a reset (after a
// controller sample, a set-point update, a friction event) drops the history
// and starts it again, because the right-hand side jumps there. A step that
// must be shortened to land on a stop that is not on the step grid also
// restarts the history (AB's coefficients assume equal steps).
//
// Roots: fixed-step methods do not locate them; after each step they compare
// the signs of the root functions and report the first that changed, at the
// step's end ("the friction rule applied per step").
// Dense output (outputs between steps; the driver no longer stops at them):
// each method's own continuous extension over the last step, which costs no
// right-hand side: forward Euler the straight line (order 1); RK4 the
// extension from its four stages, b1 = th - 3/2 th^2 + 2/3 th^3,
// b2 = b3 = th^2 - 2/3 th^3, b4 = -1/2 th^2 + 2/3 th^3 (order 3; Hairer,
// Norsett & Wanner I, Sec. II.6); Adams-Bashforth k the integral over
// [t_n, t_n + th h] of the same polynomial through f_n ... f_{n-k+1} that the
// step integrates over the whole step (order k; th = 1 gives the step).
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "integrators/adams_bashforth.hpp"
#include "integrators/integrator.hpp"
#include "integrators/registry_entries.hpp"

namespace pumasim {
namespace {

class FixedStep : public Integrator {
 public:
  FixedStep(const IntegratorOptions& o, int order) : Integrator(o.max_steps), dt_(o.dt), order_(order) {
    if (!(o.dt > 0)) throw std::invalid_argument("fixed-step integrator: expected dt > 0");
  }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.order = order_;
    return c;
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    sys_ = &sys;
    const int m = sys.size();
    t_ = t0;
    x_.assign(x0, x0 + m);
    k1_.resize(m), k2_.resize(m), k3_.resize(m), k4_.resize(m), tmp_.resize(m), x0_ = x_;
    t0_ = t0, h_ = 0;
    g_.resize(sys.num_roots()), g_new_.resize(sys.num_roots());
    if (!g_.empty()) sys.roots(t_, x_.data(), g_.data());
    restart_history();
    if (started_) ++stats_.restarts;
    started_ = true;
  }
  double time() const override { return t_; }
  const double* state() const override { return x_.data(); }
  double step_start() const override { return t0_; }
  void dense_state(double t, double* x) override {
    const int m = static_cast<int>(x_.size());
    if (h_ == 0 || t >= t_) {
      std::copy(x_.begin(), x_.end(), x);
      return;
    }
    const double th = std::clamp((t - t0_) / h_, 0.0, 1.0);
    extension(th, x);
    for (int i = 0; i < m; ++i) x[i] = x0_[i] + h_ * x[i];
  }

 protected:
  virtual void advance_step(double h, bool full_step) = 0;  // x_ <- x_(t_ + h)
  double dt() const { return dt_; }
  virtual void restart_history() {}
  // Over the last step (from x0_ at t0_, size h_): sum_j b_j(th) k_j into
  // out, so that x(t0_ + th h_) = x0_ + h_ out.
  virtual void extension(double th, double* out) const = 0;
  void rk4_extension(double th, const double* f0, double* out) const {
    const double th2 = th * th, th3 = th2 * th;
    const double b1 = th - 1.5 * th2 + th3 * 2 / 3, b23 = th2 - th3 * 2 / 3, b4 = -0.5 * th2 + th3 * 2 / 3;
    for (std::size_t i = 0; i < x_.size(); ++i) out[i] = b1 * f0[i] + b23 * (k2_[i] + k3_[i]) + b4 * k4_[i];
  }

  void f(double t, const double* x, double* dx) {
    sys_->rhs(t, x, dx);
    ++stats_.rhs_evaluations;
  }
  void rk4(double h, const double* f0) {  // f0 = f(t_, x_) already computed
    const int m = static_cast<int>(x_.size());
    for (int i = 0; i < m; ++i) tmp_[i] = x_[i] + 0.5 * h * f0[i];
    f(t_ + 0.5 * h, tmp_.data(), k2_.data());
    for (int i = 0; i < m; ++i) tmp_[i] = x_[i] + 0.5 * h * k2_[i];
    f(t_ + 0.5 * h, tmp_.data(), k3_.data());
    for (int i = 0; i < m; ++i) tmp_[i] = x_[i] + h * k3_[i];
    f(t_ + h, tmp_.data(), k4_.data());
    for (int i = 0; i < m; ++i) x_[i] += h / 6 * (f0[i] + 2 * k2_[i] + 2 * k3_[i] + k4_[i]);
  }

  OdeSystem* sys_ = nullptr;
  double t_ = 0, t0_ = 0, h_ = 0;  // now; the last step's start and size
  std::vector<double> x_, x0_, k1_, k2_, k3_, k4_, tmp_, g_, g_new_;

  Outcome step(double t_stop) override {
    double h = t_stop - t_;
    bool full = true;
    if (h > dt_ * (1 + 1e-9)) {
      h = dt_;
    } else if (h < dt_ * (1 - 1e-9)) {
      full = false;  // shortened to land on t_stop
    }
    t0_ = t_, h_ = h;
    x0_ = x_;
    advance_step(h, full);
    t_ = (h == t_stop - t_) ? t_stop : t_ + h;
    ++stats_.steps;
    if (!full) restart_history();
    if (const std::string bad = non_finite_components(*sys_, t_, x_.data()); !bad.empty()) {
      return {Outcome::kFailed, -1, bad};
    }
    if (!g_.empty()) {
      sys_->roots(t_, x_.data(), g_new_.data());
      const int k = first_crossing(g_, g_new_);
      g_ = g_new_;
      if (k >= 0) return {Outcome::kRoot, k, ""};
    }
    return {};
  }

 private:
  double dt_;
  int order_;
  bool started_ = false;
};

class Euler final : public FixedStep {
 public:
  explicit Euler(const IntegratorOptions& o) : FixedStep(o, 1) {}
  const char* name() const override { return "euler"; }

 protected:
  void advance_step(double h, bool) override {
    f(t_, x_.data(), k1_.data());
    for (std::size_t i = 0; i < x_.size(); ++i) x_[i] += h * k1_[i];
  }
  void extension(double th, double* out) const override {
    for (std::size_t i = 0; i < x_.size(); ++i) out[i] = th * k1_[i];
  }
};

class Rk4 final : public FixedStep {
 public:
  explicit Rk4(const IntegratorOptions& o) : FixedStep(o, 4) {}
  const char* name() const override { return "rk4"; }

 protected:
  void advance_step(double h, bool) override {
    f(t_, x_.data(), k1_.data());
    rk4(h, k1_.data());
  }
  void extension(double th, double* out) const override { rk4_extension(th, k1_.data(), out); }
};

class AdamsBashforth final : public FixedStep {
 public:
  AdamsBashforth(const IntegratorOptions& o, int k) : FixedStep(o, k), k_(k) {
    // poly_[j][p]: coefficient of th^(p+1) in beta_j(th) = int_0^th l_j(s) ds,
    // l_j the Lagrange basis polynomial on the nodes s = 0, -1, ..., -(k-1)
    // (f_{n-j} at s = -j); beta_j(1) are the Adams-Bashforth coefficients.
    for (int j = 0; j < k_; ++j) {
      std::vector<double> c{1.0};  // l_j's coefficients in powers of s
      for (int m = 0; m < k_; ++m) {
        if (m == j) continue;
        std::vector<double> next(c.size() + 1, 0.0);  // c * (s + m) / (m - j)
        for (std::size_t p = 0; p < c.size(); ++p) {
          next[p] += c[p] * m / (m - j);
          next[p + 1] += c[p] / (m - j);
        }
        c = next;
      }
      for (std::size_t p = 0; p < c.size(); ++p) poly_[j][p] = c[p] / static_cast<double>(p + 1);
    }
  }
  const char* name() const override { return k_ == 2 ? "ab2" : k_ == 3 ? "ab3" : "ab4"; }

 protected:
  void restart_history() override {
    count_ = 0;
    ring_.resize(static_cast<std::size_t>(k_));
    for (auto& v : ring_) v.resize(x_.size());
  }
  // ring_[(head_ - j) mod k] holds f_{n-j}.
  void advance_step(double h, bool full) override {
    const int m = static_cast<int>(x_.size());
    head_ = (head_ + 1) % k_;
    f(t_, x_.data(), ring_[head_].data());
    if (count_ < k_) ++count_;
    bootstrap_ = count_ < k_;
    if (bootstrap_) {
      rk4(h, ring_[head_].data());  // bootstrap the history with RK4
      return;
    }
    // A step shortened to land on a stop (h < dt) integrates the same
    // polynomial through the history, whose points are dt apart, over [0, h]:
    // dt * beta_j(h / dt), not h times the full step's weights (that is an
    // O(dt^2) local error at every stop, which held AB3 and AB4 to order 2).
    grid_ = full ? h : dt();
    const double* b = full ? adams_bashforth_weights(k_) : coefficients(h / grid_);
    const double w = full ? h : grid_;
    for (int i = 0; i < m; ++i) {
      double s = 0;
      for (int j = 0; j < k_; ++j) s += b[j] * ring_[(head_ - j + k_) % k_][i];
      x_[i] += w * s;
    }
  }
  // x(t0 + th h) = x0 + h out, with the history dt apart: out = (g / h) sum
  // beta_j(th h / g) f_{n-j}, g the history's spacing (h itself on a full step).
  void extension(double th, double* out) const override {
    if (bootstrap_) return rk4_extension(th, ring_[head_].data(), out);
    const double* b = coefficients(th * h_ / grid_);
    const double w = grid_ / h_;
    for (std::size_t i = 0; i < x_.size(); ++i) {
      double s = 0;
      for (int j = 0; j < k_; ++j) s += b[j] * ring_[(head_ - j + k_) % k_][i];
      out[i] = w * s;
    }
  }

 private:
  // beta_j(th), j = 0..k-1; at th = 1 the step's coefficients above (a test
  // checks it).
  const double* coefficients(double th) const {
    for (int j = 0; j < k_; ++j) {
      double v = 0, p = th;
      for (int d = 0; d < k_; ++d, p *= th) v += poly_[j][d] * p;
      beta_[j] = v;
    }
    return beta_.data();
  }

  int k_;
  int head_ = 0, count_ = 0;
  bool bootstrap_ = true;  // the last step was an RK4 start-up step
  double grid_ = 1;         // the history's spacing over the last step
  std::vector<std::vector<double>> ring_;
  std::array<std::array<double, 4>, 4> poly_{};
  mutable std::array<double, 4> beta_{};
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_euler(const IntegratorOptions& o) { return std::make_unique<Euler>(o); }
std::unique_ptr<Integrator> make_rk4(const IntegratorOptions& o) { return std::make_unique<Rk4>(o); }
std::unique_ptr<Integrator> make_ab2(const IntegratorOptions& o) { return std::make_unique<AdamsBashforth>(o, 2); }
std::unique_ptr<Integrator> make_ab3(const IntegratorOptions& o) { return std::make_unique<AdamsBashforth>(o, 3); }
std::unique_ptr<Integrator> make_ab4(const IntegratorOptions& o) { return std::make_unique<AdamsBashforth>(o, 4); }
}  // namespace detail

}  // namespace pumasim
