// Smooth Stribeck friction, without a state: a break-away peak at low speed
// falling to the Coulomb level, plus viscous friction. The form is
// Simscape's Rotational Friction block (MathWorks, Simscape Foundation
// Library, "Rotational Friction", after Armstrong and Canudas de Wit,
// "Friction Modeling and Compensation", The Control Handbook, CRC 1995):
//
//   tau_f(w) = sqrt(2 e) (Fs - Fk) exp(-(w / w_St)^2) (w / w_St)
//              + Fk tanh(w / w_C) + B w
//
// with Fs the break-away torque (static_torque), Fk the Coulomb level
// (kinetic_torque), w_St the Stribeck speed (stribeck_speed), w_C the
// Coulomb speed scale (speed_scale) and B the viscous coefficient. The
// Stribeck term sqrt(2 e) x exp(-x^2) peaks at x = 1/sqrt(2) with the value
// 1, so that at w = w_St / sqrt(2) (Simscape's break-away speed w_brk) the
// law is Fs + B w_brk up to Fk (1 - tanh(w_brk / w_C)). Simscape ties the
// scales to w_brk (w_St = sqrt(2) w_brk, w_C = w_brk / 10); here both are
// keys, so that a study can move one. Odd in w and, with Fs >= Fk (the
// scene reader requires it), tau_f(w) w >= 0: it dissipates at every speed.
// Its slope at rest, sqrt(2 e) (Fs - Fk) / w_St + Fk / w_C + B, is the
// stiffness it brings.
#pragma once

#include <cmath>

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct StribeckFriction {
  static constexpr const char* kName = "stribeck";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{.viscous = true, .levels = true, .speed_scale = true, .stribeck_speed = true};

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S&, SlipMode) {
    using std::exp;
    using std::tanh;
    const S x = w / S(f.stribeck_speed);
    return S(std::sqrt(2.0 * M_E) * (f.static_torque - f.kinetic_torque)) * exp(-(x * x)) * x +
           S(f.kinetic_torque) * tanh(w / S(f.speed_scale)) + S(f.viscous) * w;
  }
};

}  // namespace pumasim
