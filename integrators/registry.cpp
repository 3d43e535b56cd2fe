#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/registry.hpp"
#include "integrators/integrator.hpp"
#include "integrators/registry.hpp"
#include "integrators/stability.hpp"

namespace pumasim {

void OdeSystem::jacobian(double t, const double* x, Eigen::MatrixXd& J) {
  const int m = size();
  J.resize(m, m);
  std::vector<double> x1(x, x + m), f0(m), f1(m);
  rhs(t, x, f0.data());
  for (int k = 0; k < m; ++k) {
    const double h = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(x[k]));
    x1[k] = x[k] + h;
    rhs(t, x1.data(), f1.data());
    x1[k] = x[k];
    for (int r = 0; r < m; ++r) J(r, k) = (f1[r] - f0[r]) / h;
  }
}

SetValuedSolve OdeSystem::solve_set_valued(int, const double*, const double*, const double*, const double*, double*) {
  throw std::logic_error("this system has no set-valued friction solve");
}

Outcome Integrator::advance_to(double t) {
  const auto start = std::chrono::steady_clock::now();
  Outcome out;
  for (long taken = 0; time() < t && out.status == Outcome::kReached; ++taken) {
    if (taken >= max_steps_per_call_) {
      out = {Outcome::kFailed, -1,
             std::string(name()) + ": too many steps (" + std::to_string(max_steps_per_call_) + ") before t = " +
                 std::to_string(t) + " s; stopped at t = " + std::to_string(time()) + " s"};
      break;
    }
    out = step(t);
  }
  stats_.wall_time += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

Outcome Integrator::step_toward(double t_stop) {
  const auto start = std::chrono::steady_clock::now();
  Outcome out = step(t_stop);
  stats_.wall_time += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

int first_crossing(const std::vector<double>& g_old, const std::vector<double>& g_new) {
  for (std::size_t k = 0; k < g_old.size(); ++k) {
    if (crossed(g_old[k], g_new[k])) return static_cast<int>(k);
  }
  return -1;
}

std::string non_finite_components(const OdeSystem& sys, double t, const double* x) {
  std::string bad;
  int count = 0;
  for (int i = 0; i < sys.size(); ++i) {
    if (std::isfinite(x[i])) continue;
    if (count++ < 4) {
      if (!bad.empty()) bad.append(", ");
      bad.append(sys.state_name(i)).append(" = ").append(std::to_string(x[i]));
    }
  }
  if (bad.empty()) return "";
  if (count > 4) bad += " and " + std::to_string(count - 4) + " more";
  return "non-finite state at t = " + std::to_string(t) + " s: " + bad;
}

std::string fastest_component(OdeSystem& sys, double t, const double* x) {
  const int n = sys.size();
  std::vector<double> f(static_cast<std::size_t>(n));
  sys.rhs(t, x, f.data());
  int worst = 0;
  double rate = -1;
  for (int i = 0; i < n; ++i) {
    const double r = std::abs(f[i]) / std::max(1.0, std::abs(x[i]));
    if (r > rate || !std::isfinite(r)) rate = r, worst = i;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, " (|f| / max(1, |x|) = %.3g 1/s)", rate);
  return sys.state_name(worst) + " = " + std::to_string(x[worst]) + buf;
}

// Each row's factory, defined in the integrator's own file (the only other
// file a new integrator touches: scripts/check_extension.py adds one in a
// scratch copy of the tree with no other edit).
namespace detail {
std::unique_ptr<Integrator> make_euler(const IntegratorOptions&);
std::unique_ptr<Integrator> make_rk4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ab2(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ab3(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ab4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_ab2(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_ab3(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_ab4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_rk4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_arkode_erk(const IntegratorOptions&);
std::unique_ptr<Integrator> make_arkode_dirk(const IntegratorOptions&);
std::unique_ptr<Integrator> make_arkode_imex(const IntegratorOptions&);
std::unique_ptr<Integrator> make_cvode_bdf(const IntegratorOptions&);
std::unique_ptr<Integrator> make_cvode_adams(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ida(const IntegratorOptions&);
std::unique_ptr<Integrator> make_moreau_jean(const IntegratorOptions&);
std::unique_ptr<Integrator> make_moreau_jean_075(const IntegratorOptions&);
std::unique_ptr<Integrator> make_odeint_dopri5(const IntegratorOptions&);
std::unique_ptr<Integrator> make_odeint_rosenbrock4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_odeint_rodas4p(const IntegratorOptions&);
std::unique_ptr<Integrator> make_radau5(const IntegratorOptions&);
std::unique_ptr<Integrator> make_symplectic_midpoint(const IntegratorOptions&);
}  // namespace detail

namespace {

// Sorted by name (checked below). Orders and stability intervals: Hairer,
// Norsett & Wanner I (Euler, RK4: real intervals 2 and 2.7853; Adams-
// Bashforth k = 2, 3, 4: 1, 6/11, 3/10, Sec. III.3); Dormand & Prince 1980
// (DOPRI5: order 5, real interval about 3.3); Hairer & Wanner II, Sec. IV.7
// (RODAS-type rosenbrock4: order 4, dense output order 3); the SUNDIALS 6.4
// manuals (CVODE BDF 1-5 / Adams 1-12; ARKODE's order-4 tables, whose dense
// output is ARKODE's Hermite interpolant, degree 3 by default).
// std::to_array counts the rows: a new row (and its factory's declaration
// above) is the only edit here.
constexpr auto kIntegrators = std::to_array<IntegratorInfo>({
    {
        .name = "ab2",
        .summary = "Adams-Bashforth, order 2, fixed step (RK4 start)",
        .make = &detail::make_ab2,
        .kind = IntegratorKind::kFixedStep,
        .order = 2,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 1.0,
        .stable_at = &stable_ab2,
        .dense_order = 2,
        .starter_steps = 1,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "ab3",
        .summary = "Adams-Bashforth, order 3, fixed step (RK4 start)",
        .make = &detail::make_ab3,
        .kind = IntegratorKind::kFixedStep,
        .order = 3,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 6.0 / 11,
        .stable_at = &stable_ab3,
        .dense_order = 3,
        .starter_steps = 2,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "ab4",
        .summary = "Adams-Bashforth, order 4, fixed step (RK4 start)",
        .make = &detail::make_ab4,
        .kind = IntegratorKind::kFixedStep,
        .order = 4,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 0.3,
        .stable_at = &stable_ab4,
        .dense_order = 4,
        .starter_steps = 3,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "arkode-dirk",
        .summary = "SUNDIALS ARKODE, diagonally implicit RK (ARK4(3)6L[2]SA's implicit table, order 4), Newton, dense; "
                   "adaptive",
        .make = &detail::make_arkode_dirk,
        .kind = IntegratorKind::kAdaptive,
        .order = 4,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = true,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "arkode-erk",
        .summary = "SUNDIALS ARKODE, explicit RK (order 4); adaptive",
        .make = &detail::make_arkode_erk,
        .kind = IntegratorKind::kAdaptive,
        .order = 4,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "arkode-imex",
        .summary = "SUNDIALS ARKODE, additive IMEX RK (order 4): the system's stiff part implicit; adaptive",
        .make = &detail::make_arkode_imex,
        .kind = IntegratorKind::kAdaptive,
        .order = 4,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "cvode-adams",
        .summary = "SUNDIALS CVODE, Adams-Moulton 1-12, Newton, dense; adaptive",
        .make = &detail::make_cvode_adams,
        .kind = IntegratorKind::kAdaptive,
        .order = 12,
        .variable_order = true,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 12,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = true,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "cvode-bdf",
        .summary = "SUNDIALS CVODE, BDF 1-5, Newton, dense; adaptive",
        .make = &detail::make_cvode_bdf,
        .kind = IntegratorKind::kAdaptive,
        .order = 5,
        .variable_order = true,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 5,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = true,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    // The exponential methods' stability interval is their explicit parent's,
    // for the eigenvalues of N's Jacobian: the linear part (the system's
    // linear_diagonal) is integrated exactly, stable for any lambda <= 0.
    {
        .name = "etd-ab2",
        .summary = "exponential Adams-Bashforth, order 2: the system's diagonal linear part (the armature) exact, the "
                   "rest AB2; fixed step (etd-rk4 start)",
        .make = &detail::make_etd_ab2,
        .kind = IntegratorKind::kFixedStep,
        .order = 2,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 1.0,
        .dense_order = 2,
        .starter_steps = 1,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "etd-ab3",
        .summary = "exponential Adams-Bashforth, order 3: the diagonal linear part exact, the rest AB3; fixed step "
                   "(etd-rk4 start)",
        .make = &detail::make_etd_ab3,
        .kind = IntegratorKind::kFixedStep,
        .order = 3,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 6.0 / 11,
        .dense_order = 3,
        .starter_steps = 2,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "etd-ab4",
        .summary = "exponential Adams-Bashforth, order 4: the diagonal linear part exact, the rest AB4; fixed step "
                   "(etd-rk4 start)",
        .make = &detail::make_etd_ab4,
        .kind = IntegratorKind::kFixedStep,
        .order = 4,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 0.3,
        .dense_order = 4,
        .starter_steps = 3,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "etd-rk4",
        .summary = "Cox-Matthews exponential RK, order 4: the diagonal linear part exact (RK4 without one); fixed step",
        .make = &detail::make_etd_rk4,
        .kind = IntegratorKind::kFixedStep,
        .order = 4,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 4,
        .real_stability = 2.785293563405282,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    {
        .name = "euler",
        .summary = "forward Euler, fixed step",
        .make = &detail::make_euler,
        .kind = IntegratorKind::kFixedStep,
        .order = 1,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 1,
        .real_stability = 2.0,
        .stable_at = &stable_euler,
        .dense_order = 1,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    // IDA: the same BDF family as cvode-bdf, on the system's implicit form.
    {
        .name = "ida",
        .summary = "SUNDIALS IDA, variable-order BDF 1-5 on the implicit form F(t, x, x') = 0 (the plant's: inverse "
                   "dynamics M qdd + h - tau on the speeds' rows, no factorisation of M in the residual), Newton with "
                   "a dense LU, roots; adaptive",
        .make = &detail::make_ida,
        .kind = IntegratorKind::kAdaptive,
        .order = 5,
        .variable_order = true,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 5,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = true,
        .finds_roots = true,
        .set_valued_friction = false,
        .residual_form = true,
    },
    // Moreau-Jean: linearly implicit theta = 1, stable on the whole negative
    // real axis (real_stability: infinity); one f_smooth per step (a
    // difference Jacobian's m + 1 more are counted when the system has no exact one).
    {
        .name = "moreau-jean",
        .summary =
            "Moreau-Jean time-stepping: linearly implicit theta-method (theta = 1) on the state, set-valued "
            "Coulomb friction (hybrid, paper, karnopp laws' Fs, Fk) as impulses from one coupled stick/slip solve per "
            "step; no events; order 1, fixed step",
        .make = &detail::make_moreau_jean,
        .kind = IntegratorKind::kFixedStep,
        .order = 1,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 1,
        .real_stability = std::numeric_limits<double>::infinity(),
        .dense_order = 1,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = true,
    },
    {
        .name = "moreau-jean-075",
        .summary = "moreau-jean with theta = 3/4: less numerical damping, A-stable; order 1, fixed step",
        .make = &detail::make_moreau_jean_075,
        .kind = IntegratorKind::kFixedStep,
        .order = 1,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 1,
        .real_stability = std::numeric_limits<double>::infinity(),
        .dense_order = 1,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = true,
    },
    {
        .name = "odeint-dopri5",
        .summary = "Boost.Odeint Dormand-Prince 5(4), adaptive, explicit",
        .make = &detail::make_odeint_dopri5,
        .kind = IntegratorKind::kAdaptive,
        .order = 5,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 4,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "odeint-rodas4p",
        .summary = "Boost.Odeint's Rosenbrock stepper with Steinebach's Rodas4P table (order 4, built against order "
                   "reduction), adaptive, linearly implicit, the system's Jacobian",
        .make = &detail::make_odeint_rodas4p,
        .kind = IntegratorKind::kAdaptive,
        .order = 4,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = false,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "odeint-rosenbrock4",
        .summary =
            "Boost.Odeint's rosenbrock4 stepper with Hairer's RODAS table (Boost's default, d4 repaired: -0.0362; "
            "order 4, loses order on stiff time-dependent forcing: prefer odeint-rodas4p), adaptive, linearly "
            "implicit, the system's Jacobian",
        .make = &detail::make_odeint_rosenbrock4,
        .kind = IntegratorKind::kAdaptive,
        .order = 4,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = false,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "radau5",
        .summary = "Radau IIA of order 5 after Hairer & Wanner's RADAU5: simplified Newton on the real and complex "
                   "transformed systems, embedded order-3 error estimate, Gustafsson's predictive step control, "
                   "collocation dense output; adaptive",
        .make = &detail::make_radau5,
        .kind = IntegratorKind::kAdaptive,
        .order = 5,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = 0.0,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = true,
        .exact_jacobian = true,
        .jacobian_choice = false,
        .finds_roots = true,
        .set_valued_friction = false,
    },
    {
        .name = "rk4",
        .summary = "classical Runge-Kutta, order 4, fixed step",
        .make = &detail::make_rk4,
        .kind = IntegratorKind::kFixedStep,
        .order = 4,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 4,
        .real_stability = 2.785293563405282,
        .stable_at = &stable_rk4,
        .dense_order = 3,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    },
    // The implicit midpoint rule in (q, p): A-stable (|R(z)| = 1 on the
    // imaginary axis), its nonlinear equations solved by fixed-point
    // iteration (no Jacobian), a varying number of force evaluations per step.
    {
        .name = "symplectic-midpoint",
        .summary =
            "implicit midpoint rule in canonical coordinates (q, p = M(q) qd), iterated to round-off: symplectic and "
            "symmetric, order 2, fixed step; lossless, unforced arms only (no controller, no friction)",
        .make = &detail::make_symplectic_midpoint,
        .kind = IntegratorKind::kFixedStep,
        .order = 2,
        .variable_order = false,
        .implicit = true,
        .rhs_per_step = 0,
        .real_stability = std::numeric_limits<double>::infinity(),
        .dense_order = 2,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
        .conservative_only = true,
    },
});

}  // namespace

static_assert(entries_sorted_unique(kIntegrators), "the integrator registry must be sorted by name, each name once");

std::span<const IntegratorInfo> integrators() { return kIntegrators; }

std::string integrator_names() { return entry_names(integrators()); }

const IntegratorInfo& find_integrator(std::string_view name) { return find_entry(integrators(), name, "integrator"); }

}  // namespace pumasim
