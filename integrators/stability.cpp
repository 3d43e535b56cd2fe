#include "integrators/stability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "integrators/adams_bashforth.hpp"
#include "integrators/registry.hpp"

namespace pumasim {
namespace {

using C = std::complex<double>;

// Adams-Bashforth k: zeta^k - zeta^(k-1) - z sum_j b_j zeta^(k-1-j), the
// coefficients b_j of the explicit k-step formula.
bool ab_stable(int k, C z) {
  const double* c = adams_bashforth_weights(k);
  // Monic polynomial p(zeta) = zeta^k + a_{k-1} zeta^{k-1} + ... + a_0.
  std::vector<C> a(static_cast<std::size_t>(k));  // a[i]: coefficient of zeta^i
  a[static_cast<std::size_t>(k - 1)] = -1.0 - z * c[0];
  for (int j = 1; j < k; ++j) a[static_cast<std::size_t>(k - 1 - j)] = -z * c[j];
  Eigen::MatrixXcd M = Eigen::MatrixXcd::Zero(k, k);  // companion matrix
  for (int i = 1; i < k; ++i) M(i, i - 1) = 1.0;
  for (int i = 0; i < k; ++i) M(i, k - 1) = -a[static_cast<std::size_t>(i)];
  const Eigen::VectorXcd roots = Eigen::ComplexEigenSolver<Eigen::MatrixXcd>(M, false).eigenvalues();
  for (int i = 0; i < k; ++i) {
    if (std::abs(roots[i]) > 1.0 + 1e-9) return false;
  }
  return true;
}

}  // namespace

bool stable_euler(C z) { return std::abs(1.0 + z) <= 1.0 + 1e-12; }
bool stable_rk4(C z) { return std::abs(1.0 + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0) <= 1.0 + 1e-12; }
bool stable_ab2(C z) { return ab_stable(2, z); }
bool stable_ab3(C z) { return ab_stable(3, z); }
bool stable_ab4(C z) { return ab_stable(4, z); }

std::optional<bool> in_stability_region(std::string_view method, C z) {
  for (const IntegratorInfo& i : integrators()) {
    if (i.name == method) return i.stable_at ? std::optional<bool>(i.stable_at(z)) : std::nullopt;
  }
  return std::nullopt;
}

std::optional<double> max_stable_step(std::string_view method, const std::vector<C>& eigenvalues) {
  if (!in_stability_region(method, C(0.0))) return std::nullopt;
  double h_max = std::numeric_limits<double>::infinity();
  for (const C& lambda : eigenvalues) {
    const double r = std::abs(lambda);
    if (r == 0.0) continue;
    const C dir = lambda / r;
    // |z| along the ray: a scan in steps of 0.01 to the first exit (these
    // regions are connected near the origin and lie inside |z| < 3), then
    // bisection. A ray that does not leave within |z| = 4 limits nothing.
    double lo = 0.0, hi = -1.0;
    for (double s = 0.01; s <= 4.0; s += 0.01) {
      if (!*in_stability_region(method, s * dir)) {
        hi = s;
        break;
      }
      lo = s;
    }
    if (hi < 0) continue;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (*in_stability_region(method, mid * dir) ? lo : hi) = mid;
    }
    h_max = std::min(h_max, lo / r);
  }
  return h_max;
}

}  // namespace pumasim
