// Forward-mode dual number with N tangent directions: a + sum_k b_k eps_k
// (eps_k eps_l = 0). One pass of an algorithm on DualN<N> gives the
// derivatives of every output along N directions at once, where the
// one-tangent Dual (dual.hpp) needs N passes that each recompute the values.
// N is fixed at compile time, so the tangent loops have a constant trip count
// and vectorise; unused tangents stay zero. Used for the exact Jacobians
// (dynamics_derivatives.hpp, Plant::jacobian_exact).
#pragma once

#include <array>
#include <cmath>

#include <Eigen/Core>

#include "models/dynamics/scalar_traits.hpp"

// The tangent loops are the whole cost of a pass: inlined always (GCC left
// operator* out of line once a second DualN<N> was instantiated, which
// doubled the time of a pass).
#if defined(__GNUC__)
#define PUMASIM_DUALN_INLINE inline __attribute__((always_inline))
#else
#define PUMASIM_DUALN_INLINE inline
#endif

namespace pumasim {

template <int N>
class DualN {
 public:
  static constexpr int kTangents = N;
  DualN() { d_.fill(0.0); }
  DualN(double v) : v_(v) { d_.fill(0.0); }  // NOLINT: implicit, as for a built-in scalar
  // v with tangent 1 in direction k (none if k is outside [0, N)).
  DualN(double v, int k) { seed(v, k); }
  // In place: value v, tangent 1 in direction k (none if k is outside
  // [0, N)), the others 0 (a seed without a temporary).
  PUMASIM_DUALN_INLINE void seed(double v, int k) {
    v_ = v;
    d_.fill(0.0);
    if (k >= 0 && k < N) d_[static_cast<std::size_t>(k)] = 1.0;
  }
  double value() const { return v_; }
  double deriv(int k) const { return d_[static_cast<std::size_t>(k)]; }
  double& deriv(int k) { return d_[static_cast<std::size_t>(k)]; }
  const double* derivs() const { return d_.data(); }
  double* derivs() { return d_.data(); }

  PUMASIM_DUALN_INLINE DualN& operator+=(const DualN& o) {
    v_ += o.v_;
    for (int k = 0; k < N; ++k) d_[k] += o.d_[k];
    return *this;
  }
  PUMASIM_DUALN_INLINE DualN& operator-=(const DualN& o) {
    v_ -= o.v_;
    for (int k = 0; k < N; ++k) d_[k] -= o.d_[k];
    return *this;
  }
  PUMASIM_DUALN_INLINE DualN& operator*=(const DualN& o) {
    for (int k = 0; k < N; ++k) d_[k] = d_[k] * o.v_ + v_ * o.d_[k];
    v_ *= o.v_;
    return *this;
  }
  PUMASIM_DUALN_INLINE DualN& operator/=(const DualN& o) {
    const double inv = 1.0 / o.v_;
    v_ *= inv;
    for (int k = 0; k < N; ++k) d_[k] = (d_[k] - v_ * o.d_[k]) * inv;
    return *this;
  }
  PUMASIM_DUALN_INLINE DualN operator-() const { return scaled(-1.0, 0.0, -1.0); }
  PUMASIM_DUALN_INLINE DualN operator+() const { return *this; }

  friend PUMASIM_DUALN_INLINE DualN operator+(DualN a, const DualN& b) { return a += b; }
  friend PUMASIM_DUALN_INLINE DualN operator-(DualN a, const DualN& b) { return a -= b; }
  friend PUMASIM_DUALN_INLINE DualN operator*(DualN a, const DualN& b) { return a *= b; }
  friend PUMASIM_DUALN_INLINE DualN operator/(DualN a, const DualN& b) { return a /= b; }
  friend PUMASIM_DUALN_INLINE bool operator<(const DualN& a, const DualN& b) { return a.v_ < b.v_; }
  friend PUMASIM_DUALN_INLINE bool operator>(const DualN& a, const DualN& b) { return a.v_ > b.v_; }
  friend PUMASIM_DUALN_INLINE bool operator<=(const DualN& a, const DualN& b) { return a.v_ <= b.v_; }
  friend PUMASIM_DUALN_INLINE bool operator>=(const DualN& a, const DualN& b) { return a.v_ >= b.v_; }
  friend PUMASIM_DUALN_INLINE bool operator==(const DualN& a, const DualN& b) { return a.v_ == b.v_; }
  friend PUMASIM_DUALN_INLINE bool operator!=(const DualN& a, const DualN& b) { return a.v_ != b.v_; }

  // f(a) with f(a.v) = fv and f'(a.v) = df.
  friend PUMASIM_DUALN_INLINE DualN sin(const DualN& a) { return a.scaled(0.0, std::sin(a.v_), std::cos(a.v_)); }
  friend PUMASIM_DUALN_INLINE DualN cos(const DualN& a) { return a.scaled(0.0, std::cos(a.v_), -std::sin(a.v_)); }
  friend PUMASIM_DUALN_INLINE DualN sqrt(const DualN& a) {
    const double r = std::sqrt(a.v_);
    return a.scaled(0.0, r, 1.0 / (2.0 * r));
  }
  friend PUMASIM_DUALN_INLINE DualN tanh(const DualN& a) {
    const double th = std::tanh(a.v_);
    return a.scaled(0.0, th, 1.0 - th * th);
  }
  friend PUMASIM_DUALN_INLINE DualN exp(const DualN& a) {
    const double e = std::exp(a.v_);
    return a.scaled(0.0, e, e);
  }
  friend PUMASIM_DUALN_INLINE DualN log(const DualN& a) { return a.scaled(0.0, std::log(a.v_), 1.0 / a.v_); }
  friend PUMASIM_DUALN_INLINE DualN abs(const DualN& a) { return a.v_ < 0 ? -a : a; }
  friend PUMASIM_DUALN_INLINE bool isfinite(const DualN& a) {
    bool ok = std::isfinite(a.v_);
    for (int k = 0; k < N; ++k) ok = ok && std::isfinite(a.d_[k]);
    return ok;
  }

 private:
  // (cv v + fv, df d): the value replaced or scaled, the tangents scaled.
  PUMASIM_DUALN_INLINE DualN scaled(double cv, double fv, double df) const {
    DualN r(cv * v_ + fv);
    for (int k = 0; k < N; ++k) r.d_[k] = df * d_[k];
    return r;
  }
  double v_ = 0.0;
  std::array<double, N> d_;
};

template <int N>
double value_of(const DualN<N>& x) {
  return x.value();
}

}  // namespace pumasim

namespace Eigen {
template <int N>
struct NumTraits<pumasim::DualN<N>> : pumasim::DoubleLikeNumTraits<pumasim::DualN<N>, N + 1, 2 * N + 1> {};
}  // namespace Eigen
