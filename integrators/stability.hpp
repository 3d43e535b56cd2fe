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

// Is z = h lambda in the method's (closed) region of absolute stability?
// Runge-Kutta: |R(z)| <= 1 with R the stability polynomial (Euler 1 + z,
// RK4 the degree-4 Taylor polynomial). Adams-Bashforth k: every root of
// rho(zeta) - z sigma(zeta) in the closed unit disc. nullopt for a method with
// no such table here (the adaptive ones).
std::optional<bool> in_stability_region(std::string_view method, std::complex<double> z);

// The largest h such that h lambda stays in the region for every lambda of
// `eigenvalues` (each ray from the origin to its first exit; lambda = 0
// imposes nothing; pass decaying modes only: a growing one, Re lambda > 0,
// leaves every region at once); +inf if none limits it, nullopt as above.
std::optional<double> max_stable_step(std::string_view method, const std::vector<std::complex<double>>& eigenvalues);

}  // namespace pumasim
