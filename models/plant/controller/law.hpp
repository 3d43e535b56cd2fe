// What every controller law shares (the laws: this folder, one file each; the
// list: registry.hpp). A controller reads the reference and the measured
// joint state and commands the amplifier (u, the DAC's voltage). One law, two
// timings (ControllerMode):
//   continuous  u(t) from (t, x); the law's own memory (the PIV integral) is
//               a slice of the state, which the law declares;
//   sampled     the law is evaluated every servo period and its output held;
//               its memory is discrete state (ControllerDiscreteState).
//
// A law is a class with
//   kName                               its name in scene files ([controller] law)
//   Params                              its parameters for one joint
//   keys()                              the [controller] keys it reads: one per
//                                       Params member, with bounds and meaning
//   Law(mode, params, context)          per-joint parameters, the plant around it
//   declare(layout)                     its continuous slice (names, magnitudes)
//   output<S>(ref, x, layout, w)        continuous: w.u from the reference and w.q, w.qd
//   rates<S>(ref, x, layout, w, xdot)   continuous: its slice's derivatives
//   discrete_size()                     sampled: its memory's size
//   sample(ref, x, layout, w, d)        sampled: d.u_held and d.memory after a sample
//                                       (w: the plant's scratch and model, in double)
//   hold(j, u, x, layout, d)            at rest on the reference: the memory that
//                                       makes joint j's output u (gravity held)
//   output_limit(params)                |u| <= this [V] (the DAC's range)
// Its parameters are const; the plant dispatches on the law once per
// evaluation (std::visit), never per joint.
#pragma once

#include <string_view>
#include <vector>

#include "models/robot/drive.hpp"
#include "models/robot/bounds.hpp"

namespace pumasim {

enum class ControllerMode { kNone, kContinuous, kSampled };

// The sampled controller's discrete state: the held output (one per joint)
// and the law's memory (discrete_size() numbers).
struct ControllerDiscreteState {
  std::vector<double> u_held, memory;
};

// What a law may read of the plant around it, per simulated joint (the drive's
// parameters are empty without a drive; a controller needs one).
struct ControllerContext {
  std::vector<double> gear_ratio;
  double servo_period = 0.0;  // [s], sampled
  std::vector<AmplifierParams> amplifier;
  std::vector<MotorParams> motor;
};

// One [controller] key of a law: a number per joint (or one for all), read
// into a member of its Params within bounds.
template <class Params>
struct ControllerKey {
  std::string_view key;
  double Params::*member;
  Bounds bounds;
  std::string_view meaning;  // unit and role, one line
  bool required = false;
};

}  // namespace pumasim
