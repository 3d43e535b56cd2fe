// Fixed-step integrators written in the project: forward Euler, classical RK4,
// and Adams-Bashforth of orders 2-4 (the paper's method).
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
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "integrators/integrator.hpp"
#include "integrators/registry_entries.hpp"

namespace pumasim {
namespace {

class FixedStep : public Integrator {
 public:
  FixedStep(const IntegratorOptions& o, int order) : dt_(o.dt), max_steps_(o.max_steps), order_(order) {
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
    k1_.resize(m), k2_.resize(m), k3_.resize(m), k4_.resize(m), tmp_.resize(m);
    g_.resize(sys.num_roots()), g_new_.resize(sys.num_roots());
    if (!g_.empty()) sys.roots(t_, x_.data(), g_.data());
    restart_history();
    if (started_) ++stats_.restarts;
    started_ = true;
  }
  Outcome advance(double t_stop) override { return run(t_stop); }
  double time() const override { return t_; }
  const double* state() const override { return x_.data(); }

 protected:
  virtual void step(double h, bool full_step) = 0;  // x_ <- x_(t_ + h)
  virtual void restart_history() {}

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
  double t_ = 0;
  std::vector<double> x_, k1_, k2_, k3_, k4_, tmp_, g_, g_new_;

 private:
  Outcome run(double t_stop) {
    long taken = 0;
    while (t_ < t_stop) {
      double h = t_stop - t_;
      bool full = true;
      if (h > dt_ * (1 + 1e-9)) {
        h = dt_;
      } else if (h < dt_ * (1 - 1e-9)) {
        full = false;  // shortened to land on t_stop
      }
      step(h, full);
      t_ = (h == t_stop - t_) ? t_stop : t_ + h;
      ++stats_.steps;
      if (!full) restart_history();
      if (const std::string bad = non_finite_components(*sys_, t_, x_.data()); !bad.empty()) {
        return {Outcome::kFailed, -1, bad};
      }
      if (++taken > max_steps_) {
        return {Outcome::kFailed, -1,
                "too many steps (" + std::to_string(max_steps_) + ") before t = " +
                    std::to_string(t_stop) + " s; stopped at t = " + std::to_string(t_) + " s"};
      }
      if (!g_.empty()) {
        sys_->roots(t_, x_.data(), g_new_.data());
        const int k = first_crossing(g_, g_new_);
        g_ = g_new_;
        if (k >= 0) return {Outcome::kRoot, k, ""};
      }
    }
    return {};
  }

  double dt_;
  long max_steps_;
  int order_;
  bool started_ = false;
};

class Euler final : public FixedStep {
 public:
  explicit Euler(const IntegratorOptions& o) : FixedStep(o, 1) {}
  const char* name() const override { return "euler"; }

 protected:
  void step(double h, bool) override {
    f(t_, x_.data(), k1_.data());
    for (std::size_t i = 0; i < x_.size(); ++i) x_[i] += h * k1_[i];
  }
};

class Rk4 final : public FixedStep {
 public:
  explicit Rk4(const IntegratorOptions& o) : FixedStep(o, 4) {}
  const char* name() const override { return "rk4"; }

 protected:
  void step(double h, bool) override {
    f(t_, x_.data(), k1_.data());
    rk4(h, k1_.data());
  }
};

class AdamsBashforth final : public FixedStep {
 public:
  AdamsBashforth(const IntegratorOptions& o, int k) : FixedStep(o, k), k_(k) {}
  const char* name() const override { return k_ == 2 ? "ab2" : k_ == 3 ? "ab3" : "ab4"; }

 protected:
  void restart_history() override {
    count_ = 0;
    ring_.resize(static_cast<std::size_t>(k_));
    for (auto& v : ring_) v.resize(x_.size());
  }
  // ring_[(head_ - j) mod k] holds f_{n-j}.
  void step(double h, bool) override {
    const int m = static_cast<int>(x_.size());
    head_ = (head_ + 1) % k_;
    f(t_, x_.data(), ring_[head_].data());
    if (count_ < k_) ++count_;
    if (count_ < k_) {
      rk4(h, ring_[head_].data());  // bootstrap the history with RK4
      return;
    }
    static constexpr double kB2[] = {3.0 / 2, -1.0 / 2};
    static constexpr double kB3[] = {23.0 / 12, -16.0 / 12, 5.0 / 12};
    static constexpr double kB4[] = {55.0 / 24, -59.0 / 24, 37.0 / 24, -9.0 / 24};
    const double* b = k_ == 2 ? kB2 : k_ == 3 ? kB3 : kB4;
    for (int i = 0; i < m; ++i) {
      double s = 0;
      for (int j = 0; j < k_; ++j) s += b[j] * ring_[(head_ - j + k_) % k_][i];
      x_[i] += h * s;
    }
  }

 private:
  int k_;
  int head_ = 0, count_ = 0;
  std::vector<std::vector<double>> ring_;
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
