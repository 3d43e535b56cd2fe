// Linear stability of the fixed-step explicit methods: whether h lambda lies
// in a method's stability region (y' = lambda y stays bounded), and the
// largest step that keeps every eigenvalue of a Jacobian inside it -- the
// bound a stiffness diagnosis sets beside the step found by experiment.
#pragma once

#include <complex>
#include <optional>
#include <string_view>
#include <vector>

namespace pumasim {

// The regions of absolute stability of the fixed-step explicit methods, the
// registry entries' stable_at (integrators/registry.hpp): is z = h lambda in
// the closed region? Runge-Kutta: |R(z)| <= 1 with R the stability
// polynomial (Euler 1 + z, RK4 the degree-4 Taylor polynomial).
// Adams-Bashforth k: every root of rho(zeta) - z sigma(zeta) in the closed
// unit disc.
bool stable_euler(std::complex<double> z);
bool stable_rk4(std::complex<double> z);
bool stable_ab2(std::complex<double> z);
bool stable_ab3(std::complex<double> z);
bool stable_ab4(std::complex<double> z);

// The registry entry `method`'s region: nullopt for a method with none (the
// adaptive, implicit and exponential ones) or a name not in the registry.
std::optional<bool> in_stability_region(std::string_view method, std::complex<double> z);

// The largest h such that h lambda stays in the region for every lambda of
// `eigenvalues` (each ray from the origin to its first exit; lambda = 0
// imposes nothing; pass decaying modes only: a growing one, Re lambda > 0,
// leaves every region at once); +inf if none limits it, nullopt as above.
std::optional<double> max_stable_step(std::string_view method, const std::vector<std::complex<double>>& eigenvalues);

}  // namespace pumasim
