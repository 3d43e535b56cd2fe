// The PIV&F servo card (the Compumotor 6000-series law): a controller law
// (law.hpp). The integral of the position error is its memory: a state in the
// continuous timing (slice z_piv1..n, typical magnitude its full range
// integral_limit / |Ki|), discrete state in the sampled one. Both keep
// |Ki z| within integral_limit: the sampled integral is clamped at each
// sample, the continuous one stops integrating at the bound (the clamp's
// continuous-time form).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "models/plant/controller/law.hpp"
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

// The law of the Compumotor 6000-series servo cards (models/robots/puma560_sources.md,
// sec. 7, from the 6250 user guide, ch. 4): P and I on the position error, V on
// the measured velocity (feedback, not error), velocity and acceleration
// feed-forward, an integral windup limit, output saturation at +-10 V:
//   u = sat(Kp e + Ki z - Kv w + Kvff w_ref + Kaff a_ref + offset, +-u_max)
// with e = Z (q_ref - q), w = Z qd, w_ref = Z qd_ref, a_ref = Z qdd_ref and z
// the integral of e, clamped so |Ki z| <= integral_limit. The gains act on
// MOTOR-side angles, as the card reads the motor encoders; so one gain sign
// serves every joint whatever the sign of its gear ratio.
struct PivParams {
  double kp = 0.0;              // [V/rad], motor side
  double ki = 0.0;              // [V/(rad s)]
  double kv = 0.0;              // [V s/rad]
  double kvff = 0.0;            // [V s/rad]
  double kaff = 0.0;            // [V s^2/rad]
  double integral_limit = 10.0; // [V], limit of |Ki z|
  double output_limit = 10.0;   // [V], DAC range
  double offset = 0.0;          // [V], SOFFS
};

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

class PivController : public WithoutSettings {
 public:
  static constexpr std::string_view kName = "piv";
  using Params = PivParams;
  static const std::vector<ControllerKey<PivParams>>& keys() {
    static const std::vector<ControllerKey<PivParams>> k = {
        {"kp", &PivParams::kp, Bounds::any(), "[V/rad] motor side", true},
        {"ki", &PivParams::ki, Bounds::any(), "[V/(rad s)]"},
        {"kv", &PivParams::kv, Bounds::any(), "[V s/rad] on the measured speed"},
        {"kvff", &PivParams::kvff, Bounds::any(), "[V s/rad] speed feed-forward"},
        {"kaff", &PivParams::kaff, Bounds::any(), "[V s^2/rad] acceleration feed-forward"},
        {"integral_limit", &PivParams::integral_limit, Bounds::positive(), "[V] limit of |Ki z|"},
        {"output_limit", &PivParams::output_limit, Bounds::positive(), "[V] DAC range"},
        {"offset", &PivParams::offset, Bounds::any(), "[V] SOFFS"},
    };
    return k;
  }

  PivController(ControllerMode mode, const std::vector<PivParams>& params, const NoSettings&,
                const ControllerContext& context)
      : mode_(mode), p_(params), Z_(context.gear_ratio), period_(context.servo_period) {}
  const PivParams& params(int j) const { return p_[static_cast<std::size_t>(j)]; }
  int joints() const { return static_cast<int>(Z_.size()); }
  static double output_limit(const PivParams& p) { return p.output_limit; }

  void declare(StateLayout& L) const {
    if (mode_ != ControllerMode::kContinuous) return;
    std::vector<double> scale(Z_.size(), 1.0);
    for (int j = 0; j < joints(); ++j) {
      if (params(j).ki != 0) scale[static_cast<std::size_t>(j)] = piv_integral_bound(params(j));
    }
    L.z = L.add(joint_names("z_piv", joints()), scale);
  }

  // Continuous: w.u from the reference and the state (w.q, w.qd, the integrals in slice L.z).
  template <class S>
  void output(const ControllerClock&, const ReferenceSample& r, const S* x, const StateLayout& L,
              PlantWorkspace<S>& w) const {
    for (int j = 0; j < joints(); ++j) {
      const double Z = Z_[static_cast<std::size_t>(j)];
      w.u[j] = piv_law(params(j), Z, piv_error(Z, r.q[j], w.q[j]), x[L.z + j], w.qd[j], r.qd[j], r.qdd[j]);
    }
  }

  // Continuous: the integrals' rates.
  template <class S>
  void rates(const ReferenceSample& r, const S* x, const StateLayout& L, const PlantWorkspace<S>& w, S* xdot) const {
    for (int j = 0; j < joints(); ++j) {
      const S e = piv_error(Z_[static_cast<std::size_t>(j)], r.q[j], w.q[j]);
      xdot[L.z + j] = piv_integral_rate(params(j), x[L.z + j], e);
    }
  }

  // Sampled: the memory is the integral of each joint.
  int discrete_size() const { return joints(); }
  void sample(const ControllerClock&, const ReferenceSample& r, const double* x, const StateLayout& L,
              PlantWorkspace<double>&, ControllerDiscreteState& d) const {
    for (int j = 0; j < joints(); ++j) {
      const std::size_t k = static_cast<std::size_t>(j);
      const double Z = Z_[k];
      const double e = piv_error(Z, r.q[j], x[L.q + j]);
      d.memory[k] = piv_clamp_integral(params(j), d.memory[k] + e * period_);
      d.u_held[k] = piv_law(params(j), Z, e, d.memory[k], x[L.qd + j], r.qd[j], r.qdd[j]);
    }
  }

  // At rest on the reference (e = 0, qd = 0, no feed-forward): the integral
  // that makes the output u (0 if Ki = 0), in both timings.
  void hold(int j, double u, double* x, const StateLayout& L, ControllerDiscreteState& d) const {
    const PivParams& P = params(j);
    const double I = P.ki != 0 ? piv_clamp_integral(P, (u - P.offset) / P.ki) : 0.0;
    if (L.z >= 0) x[L.z + j] = I;
    d.memory[static_cast<std::size_t>(j)] = I;
  }

 private:
  const ControllerMode mode_;
  const std::vector<PivParams> p_;
  const std::vector<double> Z_;
  const double period_;
};

}  // namespace pumasim
