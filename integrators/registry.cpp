#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "integrators/integrator.hpp"
#include "integrators/registry.hpp"
#include "integrators/registry_entries.hpp"

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

namespace {

// Sorted by name (checked below). Orders and stability intervals: Hairer,
// Norsett & Wanner I (Euler, RK4: real intervals 2 and 2.7853; Adams-
// Bashforth k = 2, 3, 4: 1, 6/11, 3/10, Sec. III.3); Dormand & Prince 1980
// (DOPRI5: order 5, real interval about 3.3); Hairer & Wanner II, Sec. IV.7
// (RODAS-type rosenbrock4: order 4, dense output order 3); the SUNDIALS 6.4
// manuals (CVODE BDF 1-5 / Adams 1-12; ARKODE's order-4 tables, whose dense
// output is ARKODE's Hermite interpolant, degree 3 by default).
constexpr auto F = IntegratorKind::kFixedStep;
constexpr auto A = IntegratorKind::kAdaptive;
constexpr std::array<IntegratorInfo, 19> kIntegrators{{
    {"ab2", "Adams-Bashforth, order 2, fixed step (RK4 start)", &detail::make_ab2, F, 2, false, false, 1, 1.0, 2, 1},
    {"ab3", "Adams-Bashforth, order 3, fixed step (RK4 start)", &detail::make_ab3, F, 3, false, false, 1, 6.0 / 11, 3, 2},
    {"ab4", "Adams-Bashforth, order 4, fixed step (RK4 start)", &detail::make_ab4, F, 4, false, false, 1, 0.3, 4, 3},
    {"arkode-dirk", "SUNDIALS ARKODE, diagonally implicit RK (ARK4(3)6L[2]SA's implicit table, order 4), Newton, dense; adaptive",
     &detail::make_arkode_dirk, A, 4, false, true, 0, 0.0, 3, 0},
    {"arkode-erk", "SUNDIALS ARKODE, explicit RK (order 4); adaptive", &detail::make_arkode_erk, A, 4, false, false, 0,
     0.0, 3, 0},
    {"arkode-imex", "SUNDIALS ARKODE, additive IMEX RK (order 4): the system's stiff part implicit; adaptive",
     &detail::make_arkode_imex, A, 4, false, true, 0, 0.0, 3, 0},
    {"cvode-adams", "SUNDIALS CVODE, Adams-Moulton 1-12, Newton, dense; adaptive", &detail::make_cvode_adams, A, 12,
     true, true, 0, 0.0, 12, 0},
    {"cvode-bdf", "SUNDIALS CVODE, BDF 1-5, Newton, dense; adaptive", &detail::make_cvode_bdf, A, 5, true, true, 0,
     0.0, 5, 0},
    // The exponential methods' stability interval is their explicit parent's,
    // for the eigenvalues of N's Jacobian: the linear part (the system's
    // linear_diagonal) is integrated exactly, stable for any lambda <= 0.
    {"etd-ab2", "exponential Adams-Bashforth, order 2: the system's diagonal linear part (the armature) exact, the "
     "rest AB2; fixed step (etd-rk4 start)", &detail::make_etd_ab2, F, 2, false, false, 1, 1.0, 2, 1},
    {"etd-ab3", "exponential Adams-Bashforth, order 3: the diagonal linear part exact, the rest AB3; fixed step "
     "(etd-rk4 start)", &detail::make_etd_ab3, F, 3, false, false, 1, 6.0 / 11, 3, 2},
    {"etd-ab4", "exponential Adams-Bashforth, order 4: the diagonal linear part exact, the rest AB4; fixed step "
     "(etd-rk4 start)", &detail::make_etd_ab4, F, 4, false, false, 1, 0.3, 4, 3},
    {"etd-rk4", "Cox-Matthews exponential RK, order 4: the diagonal linear part exact (RK4 without one); fixed step",
     &detail::make_etd_rk4, F, 4, false, false, 4, 2.785293563405282, 3, 0},
    {"euler", "forward Euler, fixed step", &detail::make_euler, F, 1, false, false, 1, 2.0, 1, 0},
    // Moreau-Jean: linearly implicit theta = 1, stable on the whole negative
    // real axis (real_stability: infinity); one f_smooth per step (a
    // difference Jacobian's m + 1 more are counted when the system has no exact one).
    {"moreau-jean", "Moreau-Jean time-stepping: linearly implicit theta-method (theta = 1) on the state, set-valued "
     "Coulomb friction (hybrid, paper, karnopp laws' Fs, Fk) as impulses from one coupled stick/slip solve per "
     "step; no events; order 1, fixed step", &detail::make_moreau_jean, F, 1, false, true, 1,
     std::numeric_limits<double>::infinity(), 1, 0},
    {"moreau-jean-075", "moreau-jean with theta = 3/4: less numerical damping, A-stable; order 1, fixed step",
     &detail::make_moreau_jean_075, F, 1, false, true, 1, std::numeric_limits<double>::infinity(), 1, 0},
    {"odeint-dopri5", "Boost.Odeint Dormand-Prince 5(4), adaptive, explicit", &detail::make_odeint_dopri5, A, 5,
     false, false, 0, 0.0, 4, 0},
    {"odeint-rodas4p",
     "Boost.Odeint's Rosenbrock stepper with Steinebach's Rodas4P table (order 4, built against order reduction), "
     "adaptive, linearly implicit, the system's Jacobian",
     &detail::make_odeint_rodas4p, A, 4, false, true, 0, 0.0, 3, 0},
    {"odeint-rosenbrock4",
     "Boost.Odeint's rosenbrock4 stepper with Hairer's RODAS table (Boost's default, d4 repaired: -0.0362; order "
     "4, loses order on stiff time-dependent forcing: prefer odeint-rodas4p), adaptive, linearly implicit, the "
     "system's Jacobian",
     &detail::make_odeint_rosenbrock4, A, 4, false, true, 0, 0.0, 3, 0},
    {"rk4", "classical Runge-Kutta, order 4, fixed step", &detail::make_rk4, F, 4, false, false, 4, 2.785293563405282,
     3, 0},
}};

}  // namespace

std::span<const IntegratorInfo> integrators() {
  static const bool sorted = std::is_sorted(kIntegrators.begin(), kIntegrators.end(), [](auto& a, auto& b) {
    return std::string_view(a.name) < std::string_view(b.name);
  });
  if (!sorted) throw std::logic_error("integrator registry is not sorted by name");
  return kIntegrators;
}

std::string integrator_names() {
  std::string s;
  for (const auto& i : integrators()) {
    if (!s.empty()) s.append(", ");
    s.append(i.name);
  }
  return s;
}

const IntegratorInfo& find_integrator(std::string_view name) {
  const auto all = integrators();
  const auto it = std::lower_bound(all.begin(), all.end(), name,
                                   [](const auto& i, auto key) { return std::string_view(i.name) < key; });
  if (it == all.end() || std::string_view(it->name) != name) {
    throw std::invalid_argument("unknown integrator '" + std::string(name) + "'; expected one of: " +
                                integrator_names());
  }
  return *it;
}

}  // namespace pumasim
