// Eigen's NumTraits for the project's own scalars (Counted, Dual): real,
// signed, non-integer types with double's precision, passed by value.
#pragma once

#include <Eigen/Core>

namespace pumasim {

template <class T, int kAddCost, int kMulCost>
struct DoubleLikeNumTraits : Eigen::NumTraits<double> {
  using Real = T;
  using NonInteger = T;
  using Literal = T;
  using Nested = T;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = kAddCost,
    MulCost = kMulCost
  };
};

}  // namespace pumasim
