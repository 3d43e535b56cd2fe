// Shared helpers for the integrator tests: the registry's names, fixed-step options.
#pragma once

#include <string>
#include <vector>

#include "integrators/registry.hpp"

namespace pumasim::testing {

// Every registered integrator's name, in the registry's order.
inline std::vector<std::string> integrator_names() {
  std::vector<std::string> v;
  for (const auto& i : integrators()) v.emplace_back(i.name);
  return v;
}

// Options for a fixed step dt (the rest at their defaults).
inline IntegratorOptions fixed_step(double dt) {
  IntegratorOptions o;
  o.dt = dt;
  return o;
}

}  // namespace pumasim::testing
