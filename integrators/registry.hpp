// The integrator registry: one sorted name -> factory table.
#pragma once

#include <complex>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "integrators/integrator.hpp"

namespace pumasim {

// What a method is, as the conformance tests and the experiments read it:
// adding an integrator is its file plus one registry line, and the typed
// tests take their expectations from here (a method whose entry lacks what a
// test needs fails that test).
enum class IntegratorKind { kFixedStep, kAdaptive };

struct IntegratorInfo {
  const char* name;
  const char* summary;
  std::unique_ptr<Integrator> (*make)(const IntegratorOptions& options);
  IntegratorKind kind;
  int order;                 // convergence order (variable-order methods: the highest they use)
  bool variable_order;       // CVODE's BDF 1-5 and Adams 1-12
  bool implicit;
  int rhs_per_step;          // right-hand sides per step (fixed-step methods; 0: varies)
  double real_stability;     // explicit methods: the stability interval on the negative real axis,
                             // h lambda in [-real_stability, 0] (closed forms); 0: implicit, or not one number
  // Explicit fixed-step methods: is z = h lambda in the (closed) region of
  // absolute stability (y' = lambda y stays bounded)? nullptr: no region here
  // (adaptive, implicit and exponential methods). stability.hpp's
  // max_stable_step reads it (scanning |z| up to 4: a region reaching
  // further reads as no limit); a test checks it against real_stability.
  // Left out of a row it is nullptr, and the method drops out of the
  // stiffness diagnosis and the stability test.
  bool (*stable_at)(std::complex<double> z);
  int dense_order;           // order of the dense output (continuous extension) over a step
  int starter_steps;         // multistep methods: steps of the RK4 (etd-ab: ETDRK4) starter after every (re)start (k - 1)
  // What IntegratorCapabilities says of an instance (integrator.hpp), known
  // without building one (capabilities_of; a test checks that they agree).
  bool uses_jacobian;        // a Newton or Rosenbrock method: uses a Jacobian
  bool exact_jacobian;       // the system's (OdeSystem::jacobian); else its own differences (arkode-imex)
  bool jacobian_choice;      // either, as IntegratorOptions::exact_jacobian says (cvode-*, arkode-dirk)
  bool finds_roots;          // locates the system's roots; the fixed-step methods check signs per step
  bool set_valued_friction;  // Coulomb friction as impulses of a coupled solve in each step, no events
                             // (moreau-jean; OdeSystem::solve_set_valued); the others locate stick/slip events
  // Integrates only a lossless, unforced mechanical system
  // (OdeSystem::conservative_mechanics: symplectic-midpoint) and refuses any
  // other; the registry-wide tests on general ODEs and driven scenes leave it
  // out (tests/integrator_helpers.hpp), its own tests cover it.
  bool conservative_only = false;
  // Integrates the system's implicit form (OdeSystem::implicit_form: ida),
  // F = x' - f where it has none, and refuses a system that refuses one.
  bool residual_form = false;
};

// The capabilities of the entry's instances.
inline IntegratorCapabilities capabilities_of(const IntegratorInfo& i) {
  return IntegratorCapabilities{.adaptive = i.kind == IntegratorKind::kAdaptive,
                                .order = i.order,
                                .implicit = i.implicit,
                                .uses_jacobian = i.uses_jacobian,
                                .exact_jacobian = i.exact_jacobian,
                                .jacobian_choice = i.jacobian_choice,
                                .finds_roots = i.finds_roots,
                                .set_valued_friction = i.set_valued_friction};
}

// All integrators, sorted by name.
std::span<const IntegratorInfo> integrators();
// The entry called `name`; std::invalid_argument listing the valid names otherwise.
const IntegratorInfo& find_integrator(std::string_view name);
std::string integrator_names();
inline std::unique_ptr<Integrator> make_integrator(std::string_view name, const IntegratorOptions& o) {
  return find_integrator(name).make(o);
}

}  // namespace pumasim
