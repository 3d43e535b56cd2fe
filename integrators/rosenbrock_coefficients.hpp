// odeint's rosenbrock4 coefficient set made consistent (see integrators/odeint.cpp
// for the defect in Boost 1.74's default_rosenbrock_coefficients: d4 = +0.0362).
#pragma once

#include <boost/numeric/odeint/stepper/rosenbrock4.hpp>

namespace pumasim {

// odeint's rosenbrock4 table with d_i = gamma_i = sum_j gamma_ij recomputed
// from the table's own transformed coefficients (see integrators/odeint.cpp):
// s = Gamma 1 solves (I/gamma - C) s = 1, C strictly lower triangular (c_ij),
// i.e. s_i = gamma (1 + sum_{j<i} c_ij s_j). The members shadow the base's.
template <class Value>
struct ConsistentRosenbrockCoefficients : boost::numeric::odeint::default_rosenbrock_coefficients<Value> {
  using Base = boost::numeric::odeint::default_rosenbrock_coefficients<Value>;
  ConsistentRosenbrockCoefficients()
      : d1(row_sum(0)), d2(row_sum(1)), d3(row_sum(2)), d4(row_sum(3)) {}
  Value row_sum(int i) const {
    const Base& b = *this;
    const Value c[4][3] = {{0, 0, 0}, {b.c21, 0, 0}, {b.c31, b.c32, 0}, {b.c41, b.c42, b.c43}};
    Value s[4];
    for (int r = 0; r <= i; ++r) {
      Value acc = 1;
      for (int j = 0; j < r; ++j) acc += c[r][j] * s[j];
      s[r] = b.gamma * acc;
    }
    return s[i];
  }
  const Value d1, d2, d3, d4;
};

}  // namespace pumasim
