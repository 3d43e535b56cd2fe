#include "experiments/stiffness.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "core/time_rule.hpp"
#include "integrators/registry.hpp"
#include "integrators/stability.hpp"
#include "models/dynamics/backend.hpp"
#include "simulation/run.hpp"

namespace pumasim {
namespace {

struct Run {
  bool ok = false;
  std::vector<double> final_state;
};

// A run of the scene through the front door (simulation/run.hpp), with
// `integrator` at its scene settings or at step dt, over [0, t_end], `at`
// seeing each output with the run's plant.
Run run_scene(const Scene& sc, const std::string& integrator, std::optional<double> dt, double t_end, double interval,
              const OutputSink& at) {
  RunRequest request;
  request.scene = &sc;
  request.options = {.integrator = integrator,
                     .dt = dt,
                     .t_end = t_end,
                     .output_interval = interval,
                     .max_steps = 20'000'000,
                     .max_wall = 0};
  Run r;
  RunSinks sinks;
  sinks.output = [&](Plant& plant, double t, const double* x) {
    if (at) at(plant, t, x);
    r.final_state.assign(x, x + plant.size());
  };
  const RunRecord rec = run(request, sinks);
  r.ok = rec.run.result.ok && !before(rec.run.result.t_final, t_end, t_end);  // core/time_rule.hpp
  return r;
}

// The mode k of J = V diag(lam) V^-1 (L = V^-1: rows are left eigenvectors):
// its eigenvalue and the state with the largest participation factor.
ModeInfo describe_mode(const Plant& p, int k, const Eigen::VectorXcd& lam, const Eigen::MatrixXcd& V,
                       const Eigen::MatrixXcd& L) {
  ModeInfo m;
  m.re = lam[k].real(), m.im = lam[k].imag();
  int best = 0;
  double pmax = -1;
  for (int i = 0; i < lam.size(); ++i) {
    const double pf = std::abs(L(k, i) * V(i, k));
    if (pf > pmax) pmax = pf, best = i;
  }
  m.state = p.layout().names[static_cast<std::size_t>(best)];
  return m;
}

// The spectrum of the Jacobian J at t: its figures, and every eigenvalue
// appended to `all`.
StiffnessSample spectrum_sample(const Plant& p, double t, const Eigen::MatrixXd& J,
                                std::vector<std::complex<double>>& all) {
  Eigen::EigenSolver<Eigen::MatrixXd> es(J, true);
  const Eigen::VectorXcd lam = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();
  const Eigen::MatrixXcd L = V.inverse();  // rows: left eigenvectors
  StiffnessSample s;
  s.t = t;
  double fast = -1, slow = std::numeric_limits<double>::infinity();
  int i_fast = -1, i_slow = -1;
  for (int k = 0; k < lam.size(); ++k) {
    all.push_back(lam[k]);
    s.spectral_radius = std::max(s.spectral_radius, std::abs(lam[k]));
    if (lam[k].real() > 0) ++s.unstable_modes;
  }
  // Decaying modes: Re lambda below -1e-9 of the spectral radius (the PIV
  // integrators' near-zero modes and rounding excluded).
  for (int k = 0; k < lam.size(); ++k) {
    const double a = -lam[k].real();
    if (a <= 1e-9 * s.spectral_radius) continue;
    if (a > fast) fast = a, i_fast = k;
    if (a < slow) slow = a, i_slow = k;
  }
  if (i_fast >= 0) {
    s.fastest = describe_mode(p, i_fast, lam, V, L);
    s.slowest = describe_mode(p, i_slow, lam, V, L);
    s.stiffness_ratio = fast / slow;
  }
  return s;
}

// Stable at dt: the run over [0, t_end] succeeds and ends within 10 %
// (relative, per state, floor 1) of the reference run's final state.
bool stable_at(const Scene& sc, const char* name, double dt, double t_end, const Run& ref) {
  const Run r = run_scene(sc, name, dt, t_end, t_end, nullptr);
  if (!r.ok || r.final_state.size() != ref.final_state.size()) return false;
  for (std::size_t i = 0; i < r.final_state.size(); ++i) {
    const double d = std::abs(r.final_state[i] - ref.final_state[i]);
    if (!(d <= 0.1 * std::max(1.0, std::abs(ref.final_state[i])))) return false;
  }
  return true;
}

// The largest stable step of b.integrator on the scene: bracketed on a log
// scale around the prediction, then bisected (geometric).
void measure_step(const Scene& sc, double t_end, const Run& ref, StepBound& b) {
  const char* name = b.integrator.c_str();
  double lo = b.predicted / 8, hi = b.predicted * 8;
  if (!stable_at(sc, name, lo, t_end, ref)) {
    b.note = "unstable at predicted/8";
  } else if (stable_at(sc, name, hi, t_end, ref)) {
    b.measured = hi;
    b.note = "stable at predicted*8 (a lower bound)";
  } else {
    for (int it = 0; it < 14; ++it) {
      const double mid = std::sqrt(lo * hi);
      (stable_at(sc, name, mid, t_end, ref) ? lo : hi) = mid;
    }
    b.measured = lo;
  }
}

}  // namespace

StiffnessReport analyse_stiffness(const Scene& sc, double t_end, int samples, bool bisect) {
  if (samples < 1) throw std::invalid_argument("stiffness: expected at least one sample");
  // An index-1 DAE's current rows hold residuals: df/dx's eigenvalues would be no ODE's.
  if (const std::string why = why_no_ode_form(sc.plant); !why.empty()) throw std::invalid_argument("stiffness: " + why);
  StiffnessReport rep;
  std::vector<std::complex<double>> all;
  Eigen::MatrixXd J;
  const Run ref =
      run_scene(sc, sc.integrator.name, std::nullopt, t_end, t_end / samples, [&](Plant& p, double t, const double* x) {
        p.jacobian_exact(t, x, J);
        rep.samples.push_back(spectrum_sample(p, t, J, all));
      });
  if (!ref.ok) throw std::runtime_error("stiffness: the scene's own run (" + sc.integrator.name + ") failed");
  std::vector<std::complex<double>> decaying;
  for (const auto& l : all) {
    if (l.real() < 0) decaying.push_back(l);
  }
  // Every method with a stability region in its registry entry, by order
  // then name (euler, ab2, ab3, ab4, rk4 today).
  std::vector<const IntegratorInfo*> explicit_methods;
  for (const IntegratorInfo& i : integrators()) {
    if (i.stable_at) explicit_methods.push_back(&i);
  }
  std::stable_sort(explicit_methods.begin(), explicit_methods.end(), [](const auto* a, const auto* b) {
    return a->order != b->order ? a->order < b->order : std::string_view(a->name) < std::string_view(b->name);
  });
  for (const IntegratorInfo* m : explicit_methods) {
    const char* name = m->name;
    StepBound b;
    b.integrator = name;
    b.predicted = *max_stable_step(name, decaying);
    if (bisect && std::isfinite(b.predicted)) measure_step(sc, t_end, ref, b);
    rep.steps.push_back(b);
  }
  return rep;
}

ConditioningReport analyse_conditioning(const Scene& sc, int samples) {
  if (!sc.plant.reference) throw std::invalid_argument("conditioning: the scene has no [reference] to follow");
  if (samples < 1) throw std::invalid_argument("conditioning: expected at least one sample");
  const PlantConfig& pc = sc.plant;
  const int n = pc.n;
  const RobotModel sim = simulated_robot(pc.robot, n, pc.q_held);
  ConditioningReport rep;
  std::vector<std::unique_ptr<DynamicsBackend>> bs;
  for (const BackendInfo& b : backends()) {
    if (!b.why_unsupported(sim).empty()) continue;
    rep.backends.emplace_back(b.name);
    bs.push_back(b.make(sim));
  }
  auto crba = find_backend("crba").make(sim);
  Eigen::VectorXd q(n), qd(n), qdd(n), tau(n), out(n);
  Eigen::MatrixXd H(n, n);
  ReferenceSample r;
  const double T = pc.reference->timing().duration();
  for (int k = 0; k <= samples; ++k) {
    ConditioningSample s;
    s.t = T * k / samples;
    pc.reference->eval(s.t, r);
    q = r.q.head(n), qd = r.qd.head(n), qdd = r.qdd.head(n);
    s.q.assign(q.data(), q.data() + n);
    crba->mass_matrix(q, H);
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H, Eigen::EigenvaluesOnly).eigenvalues();
    s.min_eig_H = ev.minCoeff();
    s.cond_H = ev.maxCoeff() / ev.minCoeff();
    crba->inverse_dynamics(q, qd, qdd, tau);
    const double scale = std::max(qdd.lpNorm<Eigen::Infinity>(), 1.0);  // at rest qdd = 0: floor 1 rad/s^2
    for (auto& b : bs) {
      b->forward_dynamics(q, qd, tau, out);
      s.qdd_error.push_back((out - qdd).lpNorm<Eigen::Infinity>() / scale);
    }
    rep.samples.push_back(std::move(s));
  }
  return rep;
}

namespace {

std::string full(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// A text field: quoted (quotes doubled) when it holds a comma, a quote or a line break.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

double time_constant(const ModeInfo& m) { return m.re != 0 ? -1 / m.re : 0.0; }

}  // namespace

std::string stiffness_samples_csv(const StiffnessReport& rep) {
  std::ostringstream o;
  o << "t [s],spectral_radius [1/s],stiffness_ratio [-],fastest_tau [s],fastest_re [1/s],fastest_im [1/s],"
       "fastest_state,slowest_tau [s],slowest_re [1/s],slowest_im [1/s],slowest_state,unstable_modes [-]\n";
  for (const StiffnessSample& s : rep.samples) {
    o << full(s.t) << ',' << full(s.spectral_radius) << ',' << full(s.stiffness_ratio);
    for (const ModeInfo* m : {&s.fastest, &s.slowest}) {
      o << ',' << full(time_constant(*m)) << ',' << full(m->re) << ',' << full(m->im) << ',' << field(m->state);
    }
    o << ',' << s.unstable_modes << '\n';
  }
  return o.str();
}

std::string step_bounds_csv(const StiffnessReport& rep) {
  std::ostringstream o;
  o << "integrator,predicted_step [s],measured_step [s],note\n";
  for (const StepBound& b : rep.steps) {
    o << field(b.integrator) << ',' << full(b.predicted) << ',' << full(b.measured) << ',' << field(b.note) << '\n';
  }
  return o.str();
}

std::string conditioning_csv(const ConditioningReport& rep) {
  std::ostringstream o;
  o << "t [s]";
  const std::size_t n = rep.samples.empty() ? 0 : rep.samples.front().q.size();
  for (std::size_t j = 0; j < n; ++j) o << ",q" << j + 1 << " [rad]";
  o << ",cond_H [-],min_eig_H [kg m^2]";
  for (const auto& b : rep.backends) o << ",qdd_error_" << field(b) << " [-]";
  o << '\n';
  for (const ConditioningSample& s : rep.samples) {
    o << full(s.t);
    for (double v : s.q) o << ',' << full(v);
    o << ',' << full(s.cond_H) << ',' << full(s.min_eig_H);
    for (double e : s.qdd_error) o << ',' << full(e);
    o << '\n';
  }
  return o.str();
}

}  // namespace pumasim
