// Exact hybrid stick/slip. A stuck joint stays stuck (qd = qdd = 0) while the
// torque it must resist is within the static level; its friction is then the
// constraint force, which the rigid body computes
// (RigidBodyBlock::constrained_accelerations).
// A slipping joint feels Fk against its slip direction plus B w_m. The
// switches are events: a slipping joint's speed reaching zero, a stuck
// joint's applied torque reaching Fs (Plant::roots, on_root, settle_modes);
// it needs an integrator that finds roots.
#pragma once

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct HybridFriction {
  static constexpr const char* kName = "hybrid";
  static constexpr bool kNeedsAppliedTorque = true;
  static constexpr bool kStickSlipEvents = true;
  static constexpr bool kSetValued = true;
  static constexpr FrictionKeys kKeys{true, true, false, false};

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S& applied, SlipMode mode) {
    if (mode == SlipMode::kStuck) return applied;  // the constraint force
    return S(f.kinetic_torque) * S(static_cast<double>(static_cast<int>(mode))) + S(f.viscous) * w;
  }
};

}  // namespace pumasim
