// The Franka Emika Panda's identified friction law (Gaz, Cognetti, Oliva,
// Robuffo Giordano and De Luca, "Dynamic Identification of the Franka Emika
// Panda Robot With Retrieval of Feasible Parameters Using Penalty-Based
// Optimization", IEEE RA-L 4(4), 2019, sec. IV, the friction model):
//
//   tau_f(w) = phi1 / (1 + exp(-phi2 (w + phi3))) - phi1 / (1 + exp(-phi2 phi3)) + B w
//
// a sigmoid, shifted so that tau_f(0) = 0, plus the scene's viscous B w_m.
// With phi1, phi2 >= 0 it increases with w and is 0 at rest: it opposes
// the motion at every speed, and has no stuck state (smooth, no event).
// Written with 1 / (1 + exp(-x)) = (1 + tanh(x / 2)) / 2, which neither
// overflows for a large |x| nor needs an exp of the plant's scalar types:
//
//   tau_f(w) = (phi1 / 2) (tanh(phi2 (w + phi3) / 2) - tanh(phi2 phi3 / 2)) + B w.
//
// On the motor shaft, as every law here: a joint-side law (phi1 [N m],
// phi2 [s/rad], phi3 [rad/s], as the paper identifies them) behind a gear
// Z acts as the motor-side law phi1 / |Z|, phi2 / |Z|, Z phi3 (the joint
// torque Z tau_f at motor speed Z qd); the slope at rest, phi1 phi2 / 4
// sech^2(phi2 phi3 / 2), is the stiffness a study varies.
#pragma once

#include <cmath>

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct SigmoidFriction {
  static constexpr const char* kName = "sigmoid";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{.viscous = true, .sigmoid = true};

  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S&, SlipMode) {
    using std::tanh;
    const double half = 0.5 * f.sigmoid_slope;
    return S(0.5 * f.sigmoid_level) * (tanh(S(half) * (w + S(f.sigmoid_offset))) - S(std::tanh(half * f.sigmoid_offset))) +
           S(f.viscous) * w;
  }
};

}  // namespace pumasim
