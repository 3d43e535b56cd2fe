// Viscous friction on the motor shaft: B w_m.
#pragma once

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct ViscousFriction {
  static constexpr const char* kName = "viscous";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{true, false, false, false};

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S&, SlipMode) {
    return S(f.viscous) * w;
  }
};

}  // namespace pumasim
