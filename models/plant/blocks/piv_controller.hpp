// The PIV&F servo card block (drive.hpp, PivParams: the Compumotor 6000-series
// law). One law, two timings:
//   continuous  the card as an analogue law: u(t) from (t, x); the integral of
//               the position error is a state (slice z_piv1..n, typical
//               magnitude its full range integral_limit / |Ki|);
//   sampled     the card as it runs: every servo_period the law is evaluated
//               and its output held; the integral is discrete state.
// Both keep |Ki z| within integral_limit: the sampled integral is clamped at
// each sample, the continuous one stops integrating at the bound (the clamp's
// continuous-time form).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

enum class ControllerMode { kNone, kContinuous, kSampled };

// The law: u = sat(Kp e + Ki z - Kv w + Kvff w_ref + Kaff a_ref + offset, +-u_max),
// motor-side quantities (Z the gear ratio): e = Z (q_ref - q), w = Z qd.
template <class S>
S piv_law(const PivParams& P, double Z, const S& e, const S& z, const S& qd, double qd_ref, double qdd_ref) {
  const S v = S(P.kp) * e + S(P.ki) * z - S(P.kv * Z) * qd + S(P.kvff * Z * qd_ref) + S(P.kaff * Z * qdd_ref) +
              S(P.offset);
  return saturate(v, P.output_limit);
}

// Motor-side position error Z (q_ref - q).
template <class S>
S piv_error(double Z, double q_ref, const S& q) {
  return S(Z) * (S(q_ref) - q);
}

// The integral's bound: |Ki z| <= integral_limit.
inline double piv_integral_bound(const PivParams& P) { return P.integral_limit / std::abs(P.ki); }

// The sampled integral after a sample: clamped to the bound (unbounded if Ki = 0).
inline double piv_clamp_integral(const PivParams& P, double z) {
  if (P.ki == 0) return z;
  const double lim = piv_integral_bound(P);
  return std::clamp(z, -lim, lim);
}

// The continuous integral's rate: e, or 0 while at the bound and pushed past it.
template <class S>
S piv_integral_rate(const PivParams& P, const S& z, const S& e) {
  const S iz = S(P.ki) * z;
  const S ie = S(P.ki) * e;
  const bool windup = (iz >= S(P.integral_limit) && ie > S(0)) || (iz <= S(-P.integral_limit) && ie < S(0));
  return windup ? S(0) : e;
}

// The controller's discrete state: the sampled card's held output and integral.
struct PivDiscreteState {
  std::vector<double> u_held, integral;
};

class PivController {
 public:
  PivController(ControllerMode mode, const std::vector<PivParams>& params, std::vector<double> gear_ratio,
                double servo_period)
      : mode_(mode), p_(params), Z_(std::move(gear_ratio)), period_(servo_period) {}
  ControllerMode mode() const { return mode_; }
  const PivParams& params(int j) const { return p_[static_cast<std::size_t>(j)]; }
  int joints() const { return static_cast<int>(Z_.size()); }

  void declare(StateLayout& L) const {
    if (mode_ != ControllerMode::kContinuous) return;
    std::vector<double> scale(Z_.size(), 1.0);
    for (int j = 0; j < joints(); ++j) {
      if (params(j).ki != 0) scale[static_cast<std::size_t>(j)] = piv_integral_bound(params(j));
    }
    L.z = L.add(joint_names("z_piv", joints()), scale);
  }

  // The continuous card's output w.u from the reference r and the state
  // (w.q, w.qd, the integrals at x + offset).
  template <class S>
  void continuous_output(const ReferenceSample& r, const S* x, int offset, PlantWorkspace<S>& w) const {
    for (int j = 0; j < joints(); ++j) {
      const double Z = Z_[static_cast<std::size_t>(j)];
      w.u[j] = piv_law(params(j), Z, piv_error(Z, r.q[j], w.q[j]), x[offset + j], w.qd[j], r.qd[j], r.qdd[j]);
    }
  }

  // The sampled card's held output (0 without a controller).
  template <class S>
  void held_output(const PivDiscreteState& d, PlantWorkspace<S>& w) const {
    for (int j = 0; j < joints(); ++j) {
      w.u[j] = mode_ == ControllerMode::kSampled ? S(d.u_held[static_cast<std::size_t>(j)]) : S(0);
    }
  }

  // The continuous integrals' rates.
  template <class S>
  void integral_rates(const ReferenceSample& r, const S* x, int offset, const PlantWorkspace<S>& w, S* xdot) const {
    for (int j = 0; j < joints(); ++j) {
      const S e = piv_error(Z_[static_cast<std::size_t>(j)], r.q[j], w.q[j]);
      xdot[offset + j] = piv_integral_rate(params(j), x[offset + j], e);
    }
  }

  // A sample of the sampled card at state x (angles and speeds at q_off, qd_off).
  void sample(const ReferenceSample& r, const double* x, int q_off, int qd_off, PivDiscreteState& d) const {
    for (int j = 0; j < joints(); ++j) {
      const std::size_t k = static_cast<std::size_t>(j);
      const double Z = Z_[k];
      const double e = piv_error(Z, r.q[j], x[q_off + j]);
      d.integral[k] = piv_clamp_integral(params(j), d.integral[k] + e * period_);
      d.u_held[k] = piv_law(params(j), Z, e, d.integral[k], x[qd_off + j], r.qd[j], r.qdd[j]);
    }
  }

  // The integral that holds output u at zero error and speed (0 if Ki = 0).
  double holding_integral(int j, double u) const {
    const PivParams& P = params(j);
    return P.ki != 0 ? piv_clamp_integral(P, (u - P.offset) / P.ki) : 0.0;
  }

 private:
  const ControllerMode mode_;
  const std::vector<PivParams> p_;
  const std::vector<double> Z_;
  const double period_;
};

}  // namespace pumasim
