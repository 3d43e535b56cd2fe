// What every controller law shares (the laws: this folder, one file each; the
// list: registry.hpp). A controller reads the reference and the measured
// joint state and commands the amplifier (u, the DAC's voltage), or, for an
// open-loop torque input without a drive, the joints (u, their torques). One
// law, two timings (ControllerMode):
//   continuous  u(t) from (t, x); the law's own memory (the PIV integral) is
//               a slice of the state, which the law declares;
//   sampled     the law is evaluated every servo period and its output held;
//               its memory is discrete state (ControllerDiscreteState).
//
// A law is a class with
//   kName                               its name in scene files ([controller] law)
//   Params                              its parameters for one joint
//   keys()                              the [controller] keys it reads into Params: one
//                                       per member, a number per joint, with bounds and meaning
//   Settings, text_keys()               its settings for all joints and the [controller]
//                                       keys that read them (a name from a list, or a
//                                       file of rows); NoSettings and none for a law
//                                       that derives from WithoutSettings
//   command(settings)                   what u is: a voltage to the drive, or joint torques
//   Law(mode, params, settings, context)  per-joint parameters, settings, the plant around it
//   declare(layout)                     its continuous slice (names, magnitudes)
//   output<S>(clock, ref, x, layout, w)  continuous: w.u from the reference and w.q, w.qd
//   rates<S>(ref, x, layout, w, xdot)   continuous: its slice's derivatives
//   discrete_size()                     sampled: its memory's size
//   sample(clock, ref, x, layout, w, d)  sampled: d.u_held and d.memory after a sample
//                                       (w: the plant's scratch and model, in double)
//   hold(j, u, x, layout, d)            at rest on the reference: the memory that
//                                       makes joint j's output u (gravity held)
//   kHasInput                           whether its output depends on t by itself (an
//                                       open-loop input, given as rows in time)
//   next_time_event(t), piece_after(t)  where that input jumps or kinks (its rows; +inf:
//                                       nowhere), and the piece a step from t lies in
//   input_end(settings)                 the input's last row's time (+inf: no input)
//   output_limit(params)                |u| <= this (the DAC's range [V])
// Its parameters are const; the plant dispatches on the law once per
// evaluation (std::visit), never per joint.
#pragma once

#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "models/robot/drive.hpp"
#include "models/robot/bounds.hpp"

namespace pumasim {

enum class ControllerMode { kNone, kContinuous, kSampled };

// What a law's output u is: the amplifier's input voltage (the drive follows),
// or the joints' torques (no drive: they act on the links directly).
enum class ControllerCommand { kVoltage, kTorque };

// The sampled controller's discrete state: the held output (one per joint),
// the law's memory (discrete_size() numbers), and the piece of the law's own
// input since the last time event (piece_after; 0 for a law without one).
struct ControllerDiscreteState {
  std::vector<double> u_held, memory;
  int piece = 0;
};

// When a law is evaluated: the time, the piece of its own input a step lies in
// (ControllerDiscreteState::piece), and whether that piece is continued past
// its ends (for differences in t that must not see a jump or a kink).
struct ControllerClock {
  double t = 0.0;
  int piece = 0;
  bool extend = false;
};

// What a law may read of the plant around it, per simulated joint (the drive's
// parameters are empty without a drive).
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

// One [controller] key of a law's Settings (one value for all joints), read
// into a string member: one of `allowed` (its default is the member's
// initialiser); or, with `rows`, a file: a CSV file relative to the scene
// file, its path made absolute in `member` and its rows (a header line, then
// t, v1 ... vn for the n simulated joints, t from 0 strictly increasing;
// models/scene/joint_csv.hpp) read into `rows`, `column` naming the values.
template <class Settings>
struct ControllerTextKey {
  std::string_view key;
  std::string Settings::*member;
  std::vector<std::string> allowed;
  std::string_view meaning;  // unit and role, one line
  bool required = false;
  std::vector<std::vector<double>> Settings::*rows = nullptr;
  std::string_view column = {};  // a file's values: "u" for u1 ... un
};

// A law without settings derives from this.
struct NoSettings {};
struct WithoutSettings {
  using Settings = NoSettings;
  static const std::vector<ControllerTextKey<NoSettings>>& text_keys() {
    static const std::vector<ControllerTextKey<NoSettings>> none;
    return none;
  }
  static ControllerCommand command(const NoSettings&) { return ControllerCommand::kVoltage; }
  // No input of its own: no time events, one piece.
  static constexpr bool kHasInput = false;
  static double next_time_event(double) { return std::numeric_limits<double>::infinity(); }
  static int piece_after(double) { return 0; }
  static double input_end(const NoSettings&) { return std::numeric_limits<double>::infinity(); }
};

}  // namespace pumasim
