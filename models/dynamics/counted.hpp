// Operation-counting scalar: a double that counts the arithmetic done on it.
//
// Running a dynamics algorithm templated on its scalar with `Counted` gives the
// number of multiplies, additions (subtractions included), divisions, square
// roots and transcendental calls (sin, cos) of one call -- the figures the paper
// quotes for its Lagrange step (425 multiplies and 369 additions for n = 6).
// Negation, comparison and copies are not counted. Counts are per thread.
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

#include "models/dynamics/scalar_traits.hpp"

namespace pumasim {

struct OpCounts {
  std::int64_t mul = 0;   // multiplications
  std::int64_t add = 0;   // additions and subtractions
  std::int64_t div = 0;   // divisions
  std::int64_t sqrt = 0;  // square roots
  std::int64_t trig = 0;  // sin, cos and other transcendental calls
};

inline OpCounts& op_counts() {
  thread_local OpCounts counts;
  return counts;
}

class Counted {
 public:
  Counted() = default;
  Counted(double v) : v_(v) {}  // NOLINT: implicit, as for a built-in scalar
  double value() const { return v_; }

  Counted& operator+=(Counted o) { ++op_counts().add; v_ += o.v_; return *this; }
  Counted& operator-=(Counted o) { ++op_counts().add; v_ -= o.v_; return *this; }
  Counted& operator*=(Counted o) { ++op_counts().mul; v_ *= o.v_; return *this; }
  Counted& operator/=(Counted o) { ++op_counts().div; v_ /= o.v_; return *this; }
  Counted operator-() const { return Counted(-v_); }
  Counted operator+() const { return *this; }

  friend Counted operator+(Counted a, Counted b) { return a += b; }
  friend Counted operator-(Counted a, Counted b) { return a -= b; }
  friend Counted operator*(Counted a, Counted b) { return a *= b; }
  friend Counted operator/(Counted a, Counted b) { return a /= b; }
  friend bool operator<(Counted a, Counted b) { return a.v_ < b.v_; }
  friend bool operator>(Counted a, Counted b) { return a.v_ > b.v_; }
  friend bool operator<=(Counted a, Counted b) { return a.v_ <= b.v_; }
  friend bool operator>=(Counted a, Counted b) { return a.v_ >= b.v_; }
  friend bool operator==(Counted a, Counted b) { return a.v_ == b.v_; }
  friend bool operator!=(Counted a, Counted b) { return a.v_ != b.v_; }

  friend Counted sin(Counted a) { ++op_counts().trig; return Counted(std::sin(a.v_)); }
  friend Counted cos(Counted a) { ++op_counts().trig; return Counted(std::cos(a.v_)); }
  friend Counted tanh(Counted a) { ++op_counts().trig; return Counted(std::tanh(a.v_)); }
  friend Counted sqrt(Counted a) { ++op_counts().sqrt; return Counted(std::sqrt(a.v_)); }
  friend Counted abs(Counted a) { return Counted(std::abs(a.v_)); }
  friend bool isfinite(Counted a) { return std::isfinite(a.v_); }

 private:
  double v_ = 0.0;
};

inline double value_of(double x) { return x; }
inline double value_of(Counted x) { return x.value(); }

}  // namespace pumasim

namespace Eigen {
template <>
struct NumTraits<pumasim::Counted> : pumasim::DoubleLikeNumTraits<pumasim::Counted, 1, 1> {};
}  // namespace Eigen
