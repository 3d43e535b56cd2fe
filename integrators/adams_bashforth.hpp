// The explicit Adams-Bashforth k-step weights, k = 2..4 (Hairer, Norsett &
// Wanner I, sec. III.1, Table 1.1): x_{n+1} = x_n + h sum_j b_j f_{n-j},
// j = 0..k-1. The one table for the integrators and their stability regions.
#pragma once

#include <array>
#include <stdexcept>

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

}  // namespace pumasim
