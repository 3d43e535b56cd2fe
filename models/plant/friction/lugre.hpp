// LuGre friction (Canudas de Wit, Olsson, Astrom and Lischinsky, "A new
// model for control of systems with friction", IEEE TAC 40(3), 1995, eqs.
// (2)-(4)): the bristles' mean deflection z [rad, on the motor shaft] is a
// state,
//
//   dz/dt = w - sigma0 |w| z / G(w),   G(w) = Fk + (Fs - Fk) exp(-(w / vs)^2),
//   tau_f = sigma0 z + sigma1 dz/dt + B w
//
// (the paper's sigma0 g(v) is G here; its sigma2 is the scene's viscous B).
// sigma0 (bristle_stiffness [N m/rad]) and sigma1 (bristle_damping
// [N m s/rad]); Fs, Fk the static and Coulomb levels; vs the Stribeck speed
// (stribeck_speed). At a constant speed z settles at sgn(w) G(w) / sigma0,
// so that the steady-state friction is the Stribeck curve
// sgn(w) G(w) + B w (the paper's eq. (5)). Near rest it is a spring and a
// damper: a stuck joint's small motion obeys, on the motor shaft,
// J_m s^2 + (sigma1 + B) s + sigma0 = 0 (the bristle mode; J_m the inertia
// the shaft sees). |z| <= Fs / sigma0 holds for all time when it holds at
// the start (the paper's Property 1; z(0) = 0 here), the state's physical
// bound.
#pragma once

#include <algorithm>
#include <cmath>

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct LuGreFriction {
  static constexpr const char* kName = "lugre";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{
      .viscous = true, .levels = true, .stribeck_speed = true, .bristles = true, .stiffness = true};
  static constexpr int kStates = 1;  // z, the bristles' deflection
  static constexpr const char* kStateBoundWhy =
      "max(Fs, Fk) / sigma0 (LuGre's bristles: Canudas de Wit et al. 1995, property 1)";

  template <class S>
  static S level(const FrictionParams& f, const S& w) {  // G(w) [N m]
    using std::exp;
    const S x = w / S(f.stribeck_speed);
    return S(f.kinetic_torque) + S(f.static_torque - f.kinetic_torque) * exp(-(x * x));
  }
  template <class S>
  static S rate(const FrictionParams& f, const S& w, const S& z) {  // dz/dt [rad/s]
    using std::abs;
    return w - S(f.bristle_stiffness) * abs(w) * z / level(f, w);
  }
  template <class S>
  static S state_torque(const FrictionParams& f, const S& w, const S& z, const S& zdot) {
    return S(f.bristle_stiffness) * z + S(f.bristle_damping) * zdot + S(f.viscous) * w;
  }
  // Without its state: the steady-state curve sgn(w) G(w) + B w (0 at rest).
  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S&, SlipMode) {
    return sign_of(w) * level(f, w) + S(f.viscous) * w;
  }
  static double state_bound(const FrictionParams& f) {  // Property 1: |z| <= Fs / sigma0
    return f.bristle_stiffness > 0 ? std::max(f.static_torque, f.kinetic_torque) / f.bristle_stiffness : HUGE_VAL;
  }
};

}  // namespace pumasim
