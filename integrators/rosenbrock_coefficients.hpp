// Coefficient sets for odeint's rosenbrock4 stepper, which steps any
// six-stage, stiffly accurate Rosenbrock method of Hairer's RODAS form (Hairer &
// Wanner II, Sec. IV.7, (7.25); stages 5 and 6 at t + h, the embedded solution
// the fifth stage's point, the solution the sixth's): odeint reads the members
// gamma, d_i (= gamma_i, multiplying h df/dt), c_i (= alpha_i), a_ij, c_ij
// and the dense-output d2j, d3j by name.
//
// - ConsistentRosenbrockCoefficients: Hairer's RODAS table as Boost 1.74 ships
//   it, with d1..d4 recomputed (see integrators/odeint.cpp for the defect:
//   d4 = +0.0362).
// - Rodas4PCoefficients: Steinebach's RODASP (Rodas4P), built so that neither
//   the method nor its embedded one loses order on the Prothero-Robinson
//   problem (G. Steinebach, "Order-reduction of ROW-methods for DAEs and method
//   of lines applications", Preprint 1741, TH Darmstadt, 1995); the table is
//   METH = 3 of Hairer's rodas.f. Figures read from the transcription in
//   SciML/OrdinaryDiffEq.jl, src/tableaus/rosenbrock_tableaus.jl
//   (Rodas4PTableau); tests/test_rosenbrock_tables.cpp checks them against the
//   order conditions, so a misread digit fails a test.
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

// Steinebach's RODASP (Rodas4P): order 4, embedded order 3, both stiffly
// accurate; d_i as published (tests check them against gamma_i = sum_j gamma_ij).
template <class Value>
struct Rodas4PCoefficients {
  // The orders odeint's stepper reports (order()); clang instantiates these
  // members of rosenbrock4 with the class, GCC only where they are used.
  static const unsigned short stepper_order = 4;
  static const unsigned short error_order = 3;
  const Value gamma = 0.25;
  const Value d1 = 0.25, d2 = -0.5, d3 = -0.023504, d4 = -0.0362;
  const Value c2 = 0.75, c3 = 0.21, c4 = 0.63;
  const Value c21 = -12.0;
  const Value a21 = 3.0;
  const Value c31 = -8.791795173947035, c32 = -2.207865586973518;
  const Value a31 = 1.831036793486759, a32 = 0.4955183967433795;
  const Value c41 = 10.81793056857153, c42 = 6.780270611428266, c43 = 19.53485944642410;
  const Value a41 = 2.304376582692669, a42 = -0.05249275245743001, a43 = -1.176798761832782;
  const Value c51 = 34.19095006749676, c52 = 15.49671153725963, c53 = 54.74760875964130, c54 = 14.16005392148534;
  const Value a51 = -7.170454962423024, a52 = -4.741636671481785, a53 = -16.31002631330971, a54 = -1.062004044111401;
  const Value c61 = 34.62605830930532, c62 = 15.30084976114473, c63 = 56.99955578662667, c64 = 18.40807009793095,
              c65 = -5.714285714285717;
  const Value d21 = 25.09876703708589, d22 = 11.62013104361867, d23 = 28.49148307714626, d24 = -5.664021568594133,
              d25 = 0.0;
  const Value d31 = 1.638054557396973, d32 = -0.7373619806678748, d33 = 8.477918219238990, d34 = 15.99253148779520,
              d35 = -1.882352941176471;
};

}  // namespace pumasim
