// One joint's drive (paper sections 2-4): PIV servo card -> voltage amplifier
// -> DC motor with armature inductance -> gear and rotor -> friction on the
// motor shaft. All quantities are on the MOTOR side unless named joint-side:
// motor speed w_m = Z qd, joint torque from the drive tau = Z (K i - tau_f).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace pumasim {

// Voltage amplifier: e_a = sat(K_A u, +-V_max), in series with R0.
struct AmplifierParams {
  double gain = 1.0;               // K_A [V/V]
  double output_resistance = 0.0;  // R0 [ohm]
  double voltage_limit = 1e9;      // V_max [V]
};

// Paper eq. (2): La di/dt = K_A u - (R0 + R) i - K w_m; torque K i.
// La = 0 makes the current algebraic (the reduced model: no current state).
struct MotorParams {
  double inductance = 0.0;       // La [H]
  double resistance = 1.0;       // R [ohm]
  double torque_constant = 0.1;  // K [N m/A] = back-EMF constant [V s/rad]
};

// The friction laws (models/plant/friction/: one file each, and their
// registry): none, viscous B w_m, the paper's rule (sec. 4: at "zero" speed
// |w_m| <= zero_speed the friction balances the applied torque up to the static
// level), exact hybrid stick/slip with events, Karnopp (the paper's rule with a
// finite band), smooth tanh, and the Panda's identified sigmoid (Gaz et al. 2019).
// Which friction law a joint follows: the law's place in the plant's list
// (FrictionLaws, models/plant/friction/registry.hpp; friction_model<Law>()
// names one). The first law, and the default, is none: no friction torque
// whatever the numbers below.
struct FrictionModel {
  std::uint8_t index = 0;
  constexpr bool none() const { return index == 0; }
  friend bool operator==(FrictionModel, FrictionModel) = default;
};

struct FrictionParams {
  FrictionModel model;          // none by default
  double viscous = 0.0;         // B [N m s/rad], added in every model but none
  double static_torque = 0.0;   // Fs [N m] (paper: 0.146)
  double kinetic_torque = 0.0;  // Fk [N m] (paper: 0.124)
  double zero_speed = 1e-6;     // [rad/s]: "zero" for the paper's rule, band for Karnopp's
  double speed_scale = 1e-2;    // [rad/s]: tanh's scale
  // The sigmoid law (models/plant/friction/sigmoid.hpp; Gaz et al. 2019's phi1, phi2, phi3, motor side):
  double sigmoid_level = 0.0;   // phi1 [N m]
  double sigmoid_slope = 0.0;   // phi2 [s/rad]
  double sigmoid_offset = 0.0;  // phi3 [rad/s]
  // The smooth Stribeck law's speed scale (models/plant/friction/stribeck.hpp),
  // Simscape's default sqrt(2) x 0.1 rad/s (its break-away speed 0.1 rad/s).
  double stribeck_speed = 0.14142135623730951;  // w_St [rad/s]
  // LuGre's bristles (models/plant/friction/lugre.hpp, motor side).
  double bristle_stiffness = 0.0;  // sigma0 [N m/rad]
  double bristle_damping = 0.0;    // sigma1 [N m s/rad]
  double dahl_exponent = 1.0;      // alpha (models/plant/friction/dahl.hpp)
};

// Slip state of a joint under the hybrid model.
enum class SlipMode : std::int8_t { kStuck = 0, kPositive = 1, kNegative = -1 };

template <class S>
S sign_of(const S& x) {
  return x > S(0) ? S(1) : (x < S(0) ? S(-1) : S(0));
}

// The largest amplifier output a controller whose output is limited to
// +-output_limit can command: min(K_A u_max, V_max) [V].
inline double command_voltage_range(const AmplifierParams& A, double output_limit) {
  return std::min(A.gain * output_limit, A.voltage_limit);
}

template <class S>
S saturate(const S& x, double limit) {
  if (x > S(limit)) return S(limit);
  if (x < S(-limit)) return S(-limit);
  return x;
}

}  // namespace pumasim
