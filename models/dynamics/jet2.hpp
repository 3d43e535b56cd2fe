// A Taylor jet of order 2 along one direction: x(s) = v + d1 s + d2 s^2 / 2,
// carried through +, -, *, /, sin and cos by the product and chain rules.
//
// Running a kinematic pass with q = Jet2(q, qd, qdd) gives, in every output
// y(q(t)), y, dy/dt and d2y/dt2 exactly (no truncation error): for a
// redundant arm's reference (models/reference/numerical_ik.hpp) the
// Jacobian's second derivative along the motion, which the rates of a
// null-space rule need. Dual (dual.hpp) is the order-1 case.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "models/dynamics/scalar_traits.hpp"

namespace pumasim {

class Jet2 {
 public:
  Jet2() = default;
  Jet2(double v) : v_(v) {}  // NOLINT: implicit, as for a built-in scalar
  Jet2(double v, double d1, double d2) : v_(v), d1_(d1), d2_(d2) {}
  double value() const { return v_; }
  double d1() const { return d1_; }  // dy/ds at s = 0
  double d2() const { return d2_; }  // d2y/ds2 at s = 0

  Jet2& operator+=(Jet2 o) { v_ += o.v_, d1_ += o.d1_, d2_ += o.d2_; return *this; }
  Jet2& operator-=(Jet2 o) { v_ -= o.v_, d1_ -= o.d1_, d2_ -= o.d2_; return *this; }
  Jet2& operator*=(Jet2 o) {
    d2_ = d2_ * o.v_ + 2 * d1_ * o.d1_ + v_ * o.d2_;
    d1_ = d1_ * o.v_ + v_ * o.d1_;
    v_ *= o.v_;
    return *this;
  }
  Jet2& operator/=(Jet2 o) {  // c = a / b: c' = (a' - c b') / b, c'' = (a'' - 2 c' b' - c b'') / b
    const double inv = 1.0 / o.v_;
    v_ *= inv;
    const double c1 = (d1_ - v_ * o.d1_) * inv;
    d2_ = (d2_ - 2 * c1 * o.d1_ - v_ * o.d2_) * inv;
    d1_ = c1;
    return *this;
  }
  Jet2 operator-() const { return Jet2(-v_, -d1_, -d2_); }
  Jet2 operator+() const { return *this; }

  friend Jet2 operator+(Jet2 a, Jet2 b) { return a += b; }
  friend Jet2 operator-(Jet2 a, Jet2 b) { return a -= b; }
  friend Jet2 operator*(Jet2 a, Jet2 b) { return a *= b; }
  friend Jet2 operator/(Jet2 a, Jet2 b) { return a /= b; }
  friend bool operator<(Jet2 a, Jet2 b) { return a.v_ < b.v_; }
  friend bool operator>(Jet2 a, Jet2 b) { return a.v_ > b.v_; }
  friend bool operator<=(Jet2 a, Jet2 b) { return a.v_ <= b.v_; }
  friend bool operator>=(Jet2 a, Jet2 b) { return a.v_ >= b.v_; }
  friend bool operator==(Jet2 a, Jet2 b) { return a.v_ == b.v_; }
  friend bool operator!=(Jet2 a, Jet2 b) { return a.v_ != b.v_; }

  // (sin a)' = cos a a', (sin a)'' = -sin a a'^2 + cos a a''; cos likewise.
  friend Jet2 sin(Jet2 a) {
    const double s = std::sin(a.v_), c = std::cos(a.v_);
    return Jet2(s, c * a.d1_, -s * a.d1_ * a.d1_ + c * a.d2_);
  }
  friend Jet2 cos(Jet2 a) {
    const double s = std::sin(a.v_), c = std::cos(a.v_);
    return Jet2(c, -s * a.d1_, -c * a.d1_ * a.d1_ - s * a.d2_);
  }
  friend Jet2 abs(Jet2 a) { return a.v_ < 0 ? -a : a; }
  friend bool isfinite(Jet2 a) { return std::isfinite(a.v_) && std::isfinite(a.d1_) && std::isfinite(a.d2_); }

 private:
  double v_ = 0.0, d1_ = 0.0, d2_ = 0.0;
};

inline double value_of(Jet2 x) { return x.value(); }

}  // namespace pumasim

namespace Eigen {
template <>
struct NumTraits<pumasim::Jet2> : pumasim::DoubleLikeNumTraits<pumasim::Jet2, 3, 6> {};
}  // namespace Eigen
