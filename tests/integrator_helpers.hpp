// Shared helpers for the integrator tests: the registry's names, fixed-step options.
#pragma once

#include <string>
#include <vector>

#include "integrators/registry.hpp"

namespace pumasim::testing {

// The registered integrators for general ODEs, in the registry's order:
// all but those that integrate only a conservative mechanical system
// (IntegratorInfo::conservative_only), which refuse the test problems and
// the driven scenes the registry-wide suites run; tests/test_symplectic.cpp
// covers those.
inline std::vector<std::string> integrator_names() {
  std::vector<std::string> v;
  for (const auto& i : integrators())
    if (!i.conservative_only) v.emplace_back(i.name);
  return v;
}

// Options for a fixed step dt (the rest at their defaults).
inline IntegratorOptions fixed_step(double dt) {
  IntegratorOptions o;
  o.dt = dt;
  return o;
}

}  // namespace pumasim::testing
