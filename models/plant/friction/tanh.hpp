// Smooth Coulomb friction: Fk tanh(w_m / speed_scale) + B w_m. A small
// speed_scale makes the ODE stiff.
#pragma once

#include <cmath>

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct TanhFriction {
  static constexpr const char* kName = "tanh";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{true, true, false, true};

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S&, SlipMode) {
    using std::tanh;
    return S(f.kinetic_torque) * tanh(w / S(f.speed_scale)) + S(f.viscous) * w;
  }
};

}  // namespace pumasim
