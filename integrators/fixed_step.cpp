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
// Dense output (outputs between steps, where the driver does not stop):
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
#include "integrators/fixed_step.hpp"
#include "integrators/integrator.hpp"

namespace pumasim {
namespace {

using detail::FixedStep;

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
    // poly_[j][p]: coefficient of th^(p+1) in beta_j(th) = int_0^th l_j(s) ds;
    // beta_j(1) are the Adams-Bashforth coefficients.
    const auto basis = adams_lagrange_basis(k_);
    for (int j = 0; j < k_; ++j) {
      for (int p = 0; p < k_; ++p) poly_[j][p] = basis[j][p] / static_cast<double>(p + 1);
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
    const History f = history();
    for (int i = 0; i < m; ++i) {
      double s = 0;
      for (int j = 0; j < k_; ++j) s += b[j] * f[j][i];
      x_[i] += w * s;
    }
  }
  // x(t0 + th h) = x0 + h out, with the history dt apart: out = (g / h) sum
  // beta_j(th h / g) f_{n-j}, g the history's spacing (h itself on a full step).
  void extension(double th, double* out) const override {
    if (bootstrap_) return rk4_extension(th, ring_[head_].data(), out);
    const double* b = coefficients(th * h_ / grid_);
    const double w = grid_ / h_;
    const History f = history();
    for (std::size_t i = 0; i < x_.size(); ++i) {
      double s = 0;
      for (int j = 0; j < k_; ++j) s += b[j] * f[j][i];
      out[i] = w * s;
    }
  }

 private:
  // f at the last k_ grid points, newest first (the ring's order resolved
  // once per step, not per component).
  using History = std::array<const double*, 4>;
  History history() const {
    History f{};
    for (int j = 0; j < k_; ++j) f[j] = ring_[(head_ - j + k_) % k_].data();
    return f;
  }
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
