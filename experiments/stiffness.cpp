#include "experiments/stiffness.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "experiments/simulation/driver.hpp"
#include "integrators/registry.hpp"
#include "integrators/stability.hpp"
#include "models/dynamics/backend.hpp"

namespace pumasim {
namespace {

struct Run {
  bool ok = false;
  std::vector<double> final_state;
};

Run run_scene(const Scene& sc, const std::string& integrator, const IntegratorOptions& o, double t_end,
              double interval, const std::function<void(Plant&, double, const double*)>& at) {
  Plant plant(sc.plant);
  auto integ = make_integrator(integrator, o);
  Run r;
  const RunResult res = run_plant(plant, *integ, t_end, interval, [&](double t, const double* x) {
    if (at) at(plant, t, x);
    r.final_state.assign(x, x + plant.size());
  }, 20'000'000);
  r.ok = res.ok && res.t_final >= t_end * (1 - 1e-12);
  return r;
}

}  // namespace

StiffnessReport analyse_stiffness(const Scene& sc, double t_end, int samples, bool bisect) {
  if (samples < 1) throw std::invalid_argument("stiffness: expected at least one sample");
  StiffnessReport rep;
  std::vector<std::complex<double>> all;
  IntegratorOptions ref_opt;
  ref_opt.dt = sc.integrator.dt, ref_opt.rtol = sc.integrator.rtol, ref_opt.atol = sc.integrator.atol;
  Eigen::MatrixXd J;
  const Run ref = run_scene(sc, sc.integrator.name, ref_opt, t_end, t_end / samples, [&](Plant& p, double t,
                                                                                         const double* x) {
    p.jacobian_exact(t, x, J);
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
    auto describe = [&](int k) {
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
    };
    if (i_fast >= 0) {
      s.fastest = describe(i_fast);
      s.slowest = describe(i_slow);
      s.stiffness_ratio = fast / slow;
    }
    rep.samples.push_back(s);
  });
  if (!ref.ok) throw std::runtime_error("stiffness: the scene's own run (" + sc.integrator.name + ") failed");
  std::vector<std::complex<double>> decaying;
  for (const auto& l : all) {
    if (l.real() < 0) decaying.push_back(l);
  }
  for (const char* name : {"euler", "ab2", "ab3", "ab4", "rk4"}) {
    StepBound b;
    b.integrator = name;
    b.predicted = *max_stable_step(name, decaying);
    if (bisect && std::isfinite(b.predicted)) {
      auto stable = [&](double dt) {
        IntegratorOptions o;
        o.dt = dt;
        const Run r = run_scene(sc, name, o, t_end, t_end, nullptr);
        if (!r.ok || r.final_state.size() != ref.final_state.size()) return false;
        for (std::size_t i = 0; i < r.final_state.size(); ++i) {
          const double d = std::abs(r.final_state[i] - ref.final_state[i]);
          if (!(d <= 0.1 * std::max(1.0, std::abs(ref.final_state[i])))) return false;
        }
        return true;
      };
      // Bracket on a log scale around the prediction, then bisect (geometric).
      double lo = b.predicted / 8, hi = b.predicted * 8;
      if (!stable(lo)) {
        b.note = "unstable at predicted/8";
      } else if (stable(hi)) {
        b.measured = hi;
        b.note = "stable at predicted*8 (a lower bound)";
      } else {
        for (int it = 0; it < 14; ++it) {
          const double mid = std::sqrt(lo * hi);
          (stable(mid) ? lo : hi) = mid;
        }
        b.measured = lo;
      }
    }
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

}  // namespace pumasim
