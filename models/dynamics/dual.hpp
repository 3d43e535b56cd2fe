// Forward-mode dual number a + b·ε (ε² = 0) with one tangent direction.
//
// Running an algorithm with q = Dual(q, dq) gives, in every output, the exact
// directional derivative along dq: for example dH/dt = H'(q)·qd from one call
// to the mass matrix with Dual(q, qd). Used for exact Jacobians and for the
// physics identities in the tests; no truncation error, unlike differences.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "models/dynamics/scalar_traits.hpp"

namespace pumasim {

class Dual {
 public:
  Dual() = default;
  Dual(double v) : v_(v) {}  // NOLINT: implicit, as for a built-in scalar
  Dual(double v, double d) : v_(v), d_(d) {}
  double value() const { return v_; }
  double deriv() const { return d_; }

  Dual& operator+=(Dual o) { v_ += o.v_; d_ += o.d_; return *this; }
  Dual& operator-=(Dual o) { v_ -= o.v_; d_ -= o.d_; return *this; }
  Dual& operator*=(Dual o) { d_ = d_ * o.v_ + v_ * o.d_; v_ *= o.v_; return *this; }
  Dual& operator/=(Dual o) {
    const double inv = 1.0 / o.v_;
    v_ *= inv;
    d_ = (d_ - v_ * o.d_) * inv;
    return *this;
  }
  Dual operator-() const { return Dual(-v_, -d_); }
  Dual operator+() const { return *this; }

  friend Dual operator+(Dual a, Dual b) { return a += b; }
  friend Dual operator-(Dual a, Dual b) { return a -= b; }
  friend Dual operator*(Dual a, Dual b) { return a *= b; }
  friend Dual operator/(Dual a, Dual b) { return a /= b; }
  friend bool operator<(Dual a, Dual b) { return a.v_ < b.v_; }
  friend bool operator>(Dual a, Dual b) { return a.v_ > b.v_; }
  friend bool operator<=(Dual a, Dual b) { return a.v_ <= b.v_; }
  friend bool operator>=(Dual a, Dual b) { return a.v_ >= b.v_; }
  friend bool operator==(Dual a, Dual b) { return a.v_ == b.v_; }
  friend bool operator!=(Dual a, Dual b) { return a.v_ != b.v_; }

  friend Dual sin(Dual a) { return Dual(std::sin(a.v_), std::cos(a.v_) * a.d_); }
  friend Dual cos(Dual a) { return Dual(std::cos(a.v_), -std::sin(a.v_) * a.d_); }
  friend Dual sqrt(Dual a) {
    const double r = std::sqrt(a.v_);
    return Dual(r, a.d_ / (2.0 * r));
  }
  friend Dual tanh(Dual a) {
    const double th = std::tanh(a.v_);
    return Dual(th, (1.0 - th * th) * a.d_);
  }
  friend Dual exp(Dual a) {
    const double e = std::exp(a.v_);
    return Dual(e, e * a.d_);
  }
  friend Dual log(Dual a) { return Dual(std::log(a.v_), a.d_ / a.v_); }
  friend Dual abs(Dual a) { return a.v_ < 0 ? -a : a; }
  friend bool isfinite(Dual a) { return std::isfinite(a.v_) && std::isfinite(a.d_); }

 private:
  double v_ = 0.0;
  double d_ = 0.0;
};

inline double value_of(Dual x) { return x.value(); }

}  // namespace pumasim

namespace Eigen {
template <>
struct NumTraits<pumasim::Dual> : pumasim::DoubleLikeNumTraits<pumasim::Dual, 2, 3> {};
}  // namespace Eigen
