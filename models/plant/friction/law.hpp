// What a friction law reads from the scene's [friction] section, besides its
// name: the keys that mean something for it (the others are unknown keys in a
// scene that chooses it) and its default "zero speed" band. Each law (this
// folder) declares one.
#pragma once

namespace pumasim {

struct FrictionKeys {
  bool viscous = false;      // viscous: B [N m s/rad]
  bool levels = false;       // static_torque Fs, kinetic_torque Fk [N m]
  bool zero_speed = false;   // zero_speed: the "zero" speed or band [rad/s]
  bool speed_scale = false;  // speed_scale: tanh(w / speed_scale) [rad/s]
  double default_zero_speed = 1e-6;  // [rad/s], when zero_speed is read
  bool sigmoid = false;      // sigmoid_level, sigmoid_slope, sigmoid_offset [N m, s/rad, rad/s] (sigmoid.hpp)
  bool stribeck_speed = false;  // stribeck_speed: the Stribeck speed scale w_St [rad/s] (stribeck.hpp, lugre.hpp)
  bool bristles = false;        // bristle_damping sigma1 [N m s/rad] (lugre.hpp)
  bool stiffness = false;       // bristle_stiffness sigma0 [N m/rad] (lugre.hpp, dahl.hpp)
  bool kinetic_only = false;    // of the levels, kinetic_torque alone: no static level (dahl.hpp)
  bool dahl = false;            // dahl_exponent alpha (dahl.hpp)
};

}  // namespace pumasim
