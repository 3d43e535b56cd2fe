// The paper's rule (sec. 4) and Karnopp's model (1985): one law, two readings
// of the "zero speed" band.
//
// At "zero" speed, |w_m| <= zero_speed, the friction balances the applied
// torque (the torque it must resist at rest) up to the static level Fs; else
// it is the kinetic level Fk against the motion, plus B w_m. The paper's
// LabVIEW test was ABS(V) = 0, which floating-point speed almost never meets:
// its zero_speed is tiny by default. Karnopp's band is finite.
#pragma once

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

template <class S>
S stick_band_torque(const FrictionParams& f, const S& w, const S& tau_applied) {
  const S aw = w < S(0) ? S(-w) : w;
  if (aw <= S(f.zero_speed)) {
    const S Fs(f.static_torque);
    if (tau_applied > Fs) return Fs;
    if (tau_applied < S(-Fs)) return -Fs;
    return tau_applied;  // sticks: friction balances the applied torque
  }
  return S(f.kinetic_torque) * sign_of(w) + S(f.viscous) * w;
}

struct PaperRuleFriction {
  static constexpr const char* kName = "paper";
  static constexpr bool kNeedsAppliedTorque = true;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = true;
  static constexpr FrictionKeys kKeys{true, true, true, false, 1e-6};  // ABS(V) = 0, nearly

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S& applied, SlipMode) {
    return stick_band_torque(f, w, applied);
  }
};

struct KarnoppFriction {
  static constexpr const char* kName = "karnopp";
  static constexpr bool kNeedsAppliedTorque = true;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = true;
  static constexpr FrictionKeys kKeys{true, true, true, false, 1e-3};  // a finite band

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S& applied, SlipMode) {
    return stick_band_torque(f, w, applied);
  }
};

}  // namespace pumasim
