// Private: the base of the fixed-step integrators (fixed_step.cpp, and the
// exponential ones in exponential.cpp): the step grid, a step shortened to
// land on a stop, the non-finite check, the root sign checks per step, the
// dense output from each method's continuous extension, and RK4's stages.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "integrators/integrator.hpp"

namespace pumasim::detail {

class FixedStep : public Integrator {
 public:
  FixedStep(const IntegratorOptions& o, int order)
      : Integrator(o.max_steps), dt_(o.dt), order_(order), keep_history_(o.keep_history) {
    if (!(o.dt > 0)) throw std::invalid_argument("fixed-step integrator: expected dt > 0");
  }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.order = order_;
    return c;
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    if (keep_history_ && started_ && sys_ == &sys && t0 == t_ && static_cast<int>(x_.size()) == sys.size()) {
      x_.assign(x0, x0 + sys.size());  // the event may have changed the state
      if (!g_.empty()) sys.roots(t_, x_.data(), g_.data());
      return;
    }
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
  // Set by advance_step when the step failed (what, when): the step then
  // reports it, with the state at the step's start.
  std::string step_failure_;
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
    if (!step_failure_.empty()) {  // the method's own (an implicit solve that did not converge)
      std::string m;
      m.swap(step_failure_);
      x_ = x0_;
      return {Outcome::kFailed, -1, m};
    }
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
  bool keep_history_;
  bool started_ = false;
};

}  // namespace pumasim::detail
