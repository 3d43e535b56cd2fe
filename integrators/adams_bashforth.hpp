// The explicit Adams-Bashforth k-step weights, k = 2..4 (Hairer, Norsett &
// Wanner I, sec. III.1, Table 1.1): x_{n+1} = x_n + h sum_j b_j f_{n-j},
// j = 0..k-1. The one table for the integrators and their stability regions.
#pragma once

#include <array>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace pumasim {

inline constexpr std::array<std::array<double, 4>, 3> kAdamsBashforthWeights = {{
    {3.0 / 2, -1.0 / 2, 0.0, 0.0},
    {23.0 / 12, -16.0 / 12, 5.0 / 12, 0.0},
    {55.0 / 24, -59.0 / 24, 37.0 / 24, -9.0 / 24},
}};

// b_0..b_{k-1} of the k-step method.
inline const double* adams_bashforth_weights(int k) {
  if (k < 2 || k > 4) throw std::invalid_argument("Adams-Bashforth: k must be 2, 3 or 4");
  return kAdamsBashforthWeights[static_cast<std::size_t>(k - 2)].data();
}

// The Lagrange basis of the k-step methods in powers of s: l_j(s) =
// sum_p basis[j][p] s^p, l_j(-m) = [j == m] on the nodes s = 0, -1, ..., -(k-1)
// (f_{n-j} sits at s = -j, in units of the history's spacing). Integrated
// over [0, th] they are the Adams-Bashforth weights beta_j(th); against
// e^{z (th - s)} the exponential ones (exponential.cpp).
inline std::array<std::array<double, 4>, 4> adams_lagrange_basis(int k) {
  std::array<std::array<double, 4>, 4> basis{};
  for (int j = 0; j < k; ++j) {
    std::vector<double> c{1.0};
    for (int m = 0; m < k; ++m) {
      if (m == j) continue;
      std::vector<double> next(c.size() + 1, 0.0);  // c * (s + m) / (m - j)
      for (std::size_t p = 0; p < c.size(); ++p) {
        next[p] += c[p] * m / (m - j);
        next[p + 1] += c[p] / (m - j);
      }
      c = next;
    }
    for (std::size_t p = 0; p < c.size(); ++p) basis[static_cast<std::size_t>(j)][p] = c[p];
  }
  return basis;
}

}  // namespace pumasim
