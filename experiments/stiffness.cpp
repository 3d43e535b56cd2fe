#include "experiments/stiffness.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "integrators/driver.hpp"
#include "integrators/registry.hpp"
#include "integrators/stability.hpp"

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

}  // namespace pumasim
