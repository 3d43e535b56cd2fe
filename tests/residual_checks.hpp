// Shared check of the plant's residual form (tests/test_ida.cpp,
// tests/test_dae_current.cpp): its Newton matrix against differences of F.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "models/plant/plant.hpp"

namespace pumasim::testing {

// dF/dx + c dF/dx' at (t = 0, x, xp) against central differences of F
// (steps 1e-6 max(1, |x_k|) and 1e-6 max(1, |xp_k|)): each row within 1e-6
// of its largest entry. Returns the Newton matrix, for further checks.
inline Eigen::MatrixXd expect_newton_matrix_matches_differences(Plant& plant, const std::vector<double>& x,
                                                                const std::vector<double>& xp, double c) {
  const int m = plant.size();
  Eigen::MatrixXd N(m, m), D(m, m);
  plant.residual_newton_matrix(0.0, x.data(), c, N);
  std::vector<double> rp(m), rm(m);
  for (int k = 0; k < m; ++k) {
    const double h = 1e-6 * std::max(1.0, std::abs(x[k]));
    std::vector<double> xa = x, xb = x, fa = xp, fb = xp;
    xa[k] += h, xb[k] -= h;
    plant.residual(0.0, xa.data(), xp.data(), rp.data());
    plant.residual(0.0, xb.data(), xp.data(), rm.data());
    for (int i = 0; i < m; ++i) D(i, k) = (rp[i] - rm[i]) / (2 * h);
    const double g = 1e-6 * std::max(1.0, std::abs(xp[k]));
    fa[k] += g, fb[k] -= g;
    plant.residual(0.0, x.data(), fa.data(), rp.data());
    plant.residual(0.0, x.data(), fb.data(), rm.data());
    for (int i = 0; i < m; ++i) D(i, k) += c * (rp[i] - rm[i]) / (2 * g);
  }
  for (int i = 0; i < m; ++i) {
    const double scale = std::max(1.0, N.row(i).cwiseAbs().maxCoeff());
    EXPECT_LT((N.row(i) - D.row(i)).cwiseAbs().maxCoeff(), 1e-6 * scale) << plant.layout().names[i];
  }
  return N;
}

}  // namespace pumasim::testing
