// No friction: the shaft turns freely.
#pragma once

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct NoFriction {
  static constexpr const char* kName = "none";
  static constexpr bool kNeedsAppliedTorque = false;  // the torque to resist at rest (needs h)
  static constexpr bool kStickSlipEvents = false;     // stuck/slipping modes switched by root functions
  static constexpr bool kSetValued = false;  // a set-valued Coulomb part (Fs, Fk) for time-stepping
  static constexpr FrictionKeys kKeys{};

  template <class S>
  static S torque(const FrictionParams&, const S&, const S&, SlipMode) {
    return S(0);
  }
};

}  // namespace pumasim
