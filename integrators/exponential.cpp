// Exponential integrators for a system with a constant diagonal linear part,
// f(t, x) = diag(lambda) x + N(t, x) (OdeSystem::linear_diagonal): the linear
// decay is integrated exactly, N by an explicit formula. On the plant the
// linear part is the armature's -(R0 + R)/La, so the electrical state is
// advanced exactly over each step for the N (voltage, back-EMF) the formula
// assumes, and the mechanics by the explicit method: the partitioned scheme a
// fixed-step simulation of a motor-driven arm may use.
//
// etd-ab2..4: exponential Adams-Bashforth of order k (Cox & Matthews, J.
//   Comput. Phys. 176 (2002) 430-455, sec. 2.1; Hochbruck & Ostermann, Acta
//   Numerica 19 (2010) 209-286, sec. 2.5): x_{n+1} = e^{z} x_n + h sum_j
//   w_j(z) N_{n-j}, w_j(z) = int_0^1 e^{z (1 - s)} l_j(s) ds, z = lambda h,
//   l_j the Adams-Bashforth Lagrange basis through N_n ... N_{n-k+1}. With
//   lambda = 0, w_j = beta_j: the component is advanced by AB-k itself.
// etd-rk4: Cox & Matthews' ETDRK4 (their eq. (26)-(29)); with lambda = 0 it is
//   the classical RK4. It also starts the etd-ab history after every restart
//   (as RK4 starts AB-k), so the start is stable at any lambda.
// Dense output: the same integrals over [0, th] (the step's N polynomial: the
// AB-k one, or ETDRK4's quadratic through N(x_n), the mean of its two
// midpoint stages and N at its last stage, which with lambda = 0 is RK4's
// continuous extension of order 3).
//
// The integrals I_p(th, z) = int_0^th e^{z (th - s)} s^p ds, p = 0..3, come
// from a series for |z th| < 2 and by parts otherwise (both forms exact; the
// recursion only amplifies rounding by p! / |z th|^p < 1 where it is used),
// so that no phi-function cancels for small z and none overflows for z << 0.
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "integrators/adams_bashforth.hpp"
#include "integrators/fixed_step.hpp"

namespace pumasim {
namespace {

using detail::FixedStep;
using Moments = std::array<double, 4>;

// I_p(th, z) for p = 0..3.
Moments exp_moments(double th, double z) {
  Moments I{};
  const double zt = z * th;
  if (std::abs(zt) < 2.0) {
    // I_p = th^(p+1) sum_m (z th)^m p! / (m + p + 1)!
    double thp = th;
    for (int p = 0; p < 4; ++p, thp *= th) {
      double term = 1.0 / (p + 1), sum = 0.0;
      for (int m = 0; m < 40 && term != 0.0; ++m) {
        sum += term;
        term *= zt / (m + p + 2);
      }
      I[static_cast<std::size_t>(p)] = thp * sum;
    }
    return I;
  }
  I[0] = std::expm1(zt) / z;
  double thp = 1.0;
  for (int p = 1; p < 4; ++p) {
    thp *= th;
    I[static_cast<std::size_t>(p)] = (p * I[static_cast<std::size_t>(p - 1)] - thp) / z;
  }
  return I;
}

// int_0^th e^{z (th - s)} sum_p c[p] s^p ds
double weight(const std::array<double, 4>& c, const Moments& I) {
  return c[0] * I[0] + c[1] * I[1] + c[2] * I[2] + c[3] * I[3];
}

// ETDRK4's N polynomial through s = 0, 1/2, 1 (Lagrange basis, powers of s).
constexpr std::array<std::array<double, 4>, 3> kQuadratic{{
    {1.0, -3.0, 2.0, 0.0},   // at s = 0: N(x_n)
    {0.0, 4.0, -4.0, 0.0},   // at s = 1/2: (N(a) + N(b)) / 2
    {0.0, -1.0, 2.0, 0.0},   // at s = 1: N(c)
}};

class Exponential : public FixedStep {
 public:
  Exponential(const IntegratorOptions& o, int order) : FixedStep(o, order) {}
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    lambda_.resize(static_cast<std::size_t>(sys.size()));
    sys.linear_diagonal(lambda_.data());
    for (double l : lambda_) {
      if (!(l <= 0.0) || !std::isfinite(l)) {
        throw std::invalid_argument("exponential integrator: the system's linear part must be finite and <= 0");
      }
    }
    const std::size_t m = lambda_.size();
    na_.resize(m), nb_.resize(m), nc_.resize(m), n0_.resize(m), a_.resize(m);
    rk_step_ = 0;
    FixedStep::reset(sys, t0, x0);
  }

 protected:
  // N(t, x) = f(t, x) - lambda x into n.
  void nonlinear(double t, const double* x, double* n) {
    f(t, x, n);
    for (std::size_t i = 0; i < lambda_.size(); ++i) n[i] -= lambda_[i] * x[i];
  }
  // One ETDRK4 step of size h from (t_, x_), n0_ = N(t_, x_) already computed.
  void etdrk4(double h) {
    if (h != rk_step_) cache_rk_weights(h);
    const std::size_t m = x_.size();
    const auto stage = [&](std::size_t i) { return rk_[i * 6 + 1]; };  // h I_0(1/2, z)
    for (std::size_t i = 0; i < m; ++i) a_[i] = rk_[i * 6] * x_[i] + stage(i) * n0_[i];
    nonlinear(t_ + 0.5 * h, a_.data(), na_.data());
    for (std::size_t i = 0; i < m; ++i) tmp_[i] = rk_[i * 6] * x_[i] + stage(i) * na_[i];  // b
    nonlinear(t_ + 0.5 * h, tmp_.data(), nb_.data());
    for (std::size_t i = 0; i < m; ++i) tmp_[i] = rk_[i * 6] * a_[i] + stage(i) * (2.0 * nb_[i] - n0_[i]);  // c
    nonlinear(t_ + h, tmp_.data(), nc_.data());
    for (std::size_t i = 0; i < m; ++i) {
      const double* w = &rk_[i * 6 + 2];
      x_[i] = w[0] * x_[i] + w[1] * n0_[i] + w[2] * 0.5 * (na_[i] + nb_[i]) + w[3] * nc_[i];
    }
  }
  // Per component, for step size h: e^{z/2}, h I_0(1/2, z), e^z and h times
  // the three weights of the quadratic N polynomial over [0, 1].
  void cache_rk_weights(double h) {
    rk_.resize(x_.size() * 6);
    for (std::size_t i = 0; i < x_.size(); ++i) {
      const double z = lambda_[i] * h;
      const Moments half = exp_moments(0.5, z), whole = exp_moments(1.0, z);
      double* w = &rk_[i * 6];
      w[0] = std::exp(0.5 * z), w[1] = h * half[0], w[2] = std::exp(z);
      for (std::size_t q = 0; q < 3; ++q) w[3 + q] = h * weight(kQuadratic[q], whole);
    }
    rk_step_ = h;
  }
  // ETDRK4's value at t0_ + th h of component i, from x0 (the step's start).
  double quadratic_extension(std::size_t i, double th, double h, double x0) const {
    const Moments I = exp_moments(th, lambda_[i] * h);
    return std::exp(lambda_[i] * h * th) * x0 +
           h * (weight(kQuadratic[0], I) * n0_[i] + weight(kQuadratic[1], I) * 0.5 * (na_[i] + nb_[i]) +
                weight(kQuadratic[2], I) * nc_[i]);
  }
  // FixedStep's extension is an increment over x0_ in units of h_; the
  // exponential ones are not linear in x0, so dense_state is overridden.
  void extension(double, double*) const override {}

  std::vector<double> lambda_, n0_, na_, nb_, nc_, a_;
  std::vector<double> rk_;  // cache_rk_weights
  double rk_step_ = 0;
};

class EtdRk4 final : public Exponential {
 public:
  explicit EtdRk4(const IntegratorOptions& o) : Exponential(o, 4) {}
  const char* name() const override { return "etd-rk4"; }
  void dense_state(double t, double* x) override {
    if (h_ == 0 || t >= t_) return std::copy(x_.begin(), x_.end(), x), void();
    const double th = std::clamp((t - t0_) / h_, 0.0, 1.0);
    for (std::size_t i = 0; i < x_.size(); ++i) x[i] = quadratic_extension(i, th, h_, x0_[i]);
  }

 protected:
  void advance_step(double h, bool) override {
    nonlinear(t_, x_.data(), n0_.data());
    etdrk4(h);
  }
};

class EtdAdamsBashforth final : public Exponential {
 public:
  EtdAdamsBashforth(const IntegratorOptions& o, int k)
      : Exponential(o, k), k_(k), basis_(adams_lagrange_basis(k)) {}
  const char* name() const override { return k_ == 2 ? "etd-ab2" : k_ == 3 ? "etd-ab3" : "etd-ab4"; }
  void dense_state(double t, double* x) override {
    if (h_ == 0 || t >= t_) return std::copy(x_.begin(), x_.end(), x), void();
    const double th = std::clamp((t - t0_) / h_, 0.0, 1.0);
    for (std::size_t i = 0; i < x_.size(); ++i) {
      x[i] = bootstrap_ ? quadratic_extension(i, th, h_, x0_[i]) : multistep(i, th * h_ / grid_, x0_[i]);
    }
  }

 protected:
  void restart_history() override {
    count_ = 0;
    ring_.resize(static_cast<std::size_t>(k_));
    for (auto& v : ring_) v.resize(x_.size());
    cached_spacing_ = 0;
  }
  // ring_[(head_ - j) mod k] holds N_{n-j}.
  void advance_step(double h, bool full) override {
    head_ = (head_ + 1) % k_;
    double* n = ring_[static_cast<std::size_t>(head_)].data();
    nonlinear(t_, x_.data(), n);
    if (count_ < k_) ++count_;
    bootstrap_ = count_ < k_;
    if (bootstrap_) {
      std::copy(n, n + x_.size(), n0_.begin());
      etdrk4(h);
      return;
    }
    // A shortened step integrates the history's polynomial (points dt apart)
    // over [0, h / dt] of its spacing, as AdamsBashforth does.
    grid_ = full ? h : dt();
    if (full && cached_spacing_ != h) cache_full_step_weights(h);
    for (std::size_t i = 0; i < x_.size(); ++i) {
      x_[i] = full ? full_step(i) : multistep(i, h / grid_, x_[i]);
    }
  }

 private:
  // Component i at th (in units of the spacing grid_) from x0.
  double multistep(std::size_t i, double th, double x0) const {
    const double z = lambda_[i] * grid_;
    const Moments I = exp_moments(th, z);
    double s = 0;
    for (int j = 0; j < k_; ++j) s += weight(basis_[static_cast<std::size_t>(j)], I) * history(j, i);
    return std::exp(z * th) * x0 + grid_ * s;
  }
  double full_step(std::size_t i) const {
    const double* w = &weights_[i * 5];
    double s = 0;
    for (int j = 0; j < k_; ++j) s += w[j + 1] * history(j, i);
    return w[0] * x_[i] + grid_ * s;
  }
  // The full step's e^z and w_j(z) per component: computed once per step size.
  void cache_full_step_weights(double h) {
    weights_.resize(x_.size() * 5);
    for (std::size_t i = 0; i < x_.size(); ++i) {
      const double z = lambda_[i] * h;
      const Moments I = exp_moments(1.0, z);
      weights_[i * 5] = std::exp(z);
      for (int j = 0; j < k_; ++j) weights_[i * 5 + 1 + j] = weight(basis_[static_cast<std::size_t>(j)], I);
    }
    cached_spacing_ = h;
  }
  double history(int j, std::size_t i) const { return ring_[static_cast<std::size_t>((head_ - j + k_) % k_)][i]; }

  int k_;
  std::array<std::array<double, 4>, 4> basis_;
  int head_ = 0, count_ = 0;
  bool bootstrap_ = true;  // the last step was an ETDRK4 start-up step
  double grid_ = 1;         // the history's spacing over the last step
  double cached_spacing_ = 0;
  std::vector<double> weights_;  // per component: e^z, w_0 .. w_{k-1}
  std::vector<std::vector<double>> ring_;
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_etd_rk4(const IntegratorOptions& o) { return std::make_unique<EtdRk4>(o); }
std::unique_ptr<Integrator> make_etd_ab2(const IntegratorOptions& o) {
  return std::make_unique<EtdAdamsBashforth>(o, 2);
}
std::unique_ptr<Integrator> make_etd_ab3(const IntegratorOptions& o) {
  return std::make_unique<EtdAdamsBashforth>(o, 3);
}
std::unique_ptr<Integrator> make_etd_ab4(const IntegratorOptions& o) {
  return std::make_unique<EtdAdamsBashforth>(o, 4);
}
}  // namespace detail

}  // namespace pumasim
