// An open-loop input: no feedback, the command read from a CSV file of rows
// t, u1 ... un (controller.file, relative to the scene file; the scene reads
// it), interpolated between rows (input_table.hpp: zero-order hold or linear,
// held after the last row). What u is (controller.input):
//   "voltage"  the amplifier's input voltage [V], in the place of the DAC's
//              output of the other laws: the drive follows (e_a = sat(K_A u,
//              +-V_max), then the motor), so the scene has the drive;
//   "torque"   the joints' torques [N m], link side (after the gear), acting
//              on the links directly: the scene has no drive, and friction
//              (motor side, as always) opposes them as Z tau_f.
// output_limit clamps |u| in the input's unit (default: no clamp; the
// amplifier's voltage_limit still applies to a voltage). The rows are time
// events of the continuous timing (the plant stops there); the sampled timing
// samples the interpolated input every servo period and holds it, as a DAC.
// It has no memory and holds nothing: with the drive, the currents start in
// equilibrium with the first output at rest (the plant, initial_state).
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "models/plant/controller/input_table.hpp"
#include "models/plant/controller/law.hpp"
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct OpenLoopParams {
  double output_limit = std::numeric_limits<double>::infinity();  // |u| <= this, [V] or [N m]
};

struct OpenLoopSettings {
  std::string input;          // "voltage" | "torque"
  std::string interpolation;  // "zoh" | "linear"
  std::string file;           // the CSV file (an absolute path once read)
  std::vector<std::vector<double>> rows;  // its rows t, u1 ... un
};

class OpenLoopController {
 public:
  static constexpr std::string_view kName = "open_loop";
  using Params = OpenLoopParams;
  using Settings = OpenLoopSettings;
  static constexpr bool kHasInput = true;

  static const std::vector<ControllerKey<OpenLoopParams>>& keys() {
    static const std::vector<ControllerKey<OpenLoopParams>> k = {
        {"output_limit", &OpenLoopParams::output_limit, Bounds::positive_or_infinity(),
         "[V] or [N m] (the input's unit): |u| clamped; default inf, none"},
    };
    return k;
  }
  static const std::vector<ControllerTextKey<OpenLoopSettings>>& text_keys() {
    static const std::vector<ControllerTextKey<OpenLoopSettings>> k = {
        {"input", &OpenLoopSettings::input, {"voltage", "torque"},
         "voltage: the amplifier's input [V] (with the drive) | torque: joint torques [N m] (no drive)", true},
        {"interpolation", &OpenLoopSettings::interpolation, {"zoh", "linear"},
         "between rows: zoh (zero-order hold) | linear; after the last row its values hold", true},
        {"file", &OpenLoopSettings::file, {}, "a CSV file of rows t, u1 ... un (relative to the scene)", true,
         &OpenLoopSettings::rows, "u"},
    };
    return k;
  }
  static ControllerCommand command(const OpenLoopSettings& s) {
    return s.input == "torque" ? ControllerCommand::kTorque : ControllerCommand::kVoltage;
  }
  static double input_end(const OpenLoopSettings& s) {
    return s.rows.empty() ? std::numeric_limits<double>::infinity() : s.rows.back()[0];
  }
  static double output_limit(const OpenLoopParams& p) { return p.output_limit; }

  OpenLoopController(ControllerMode mode, const std::vector<OpenLoopParams>& params, const OpenLoopSettings& s,
                     const ControllerContext&)
      : mode_(mode),
        p_(params),
        table_(s.rows, static_cast<int>(params.size()),
               s.interpolation == "linear" ? InputInterpolation::kLinear : InputInterpolation::kZeroOrderHold) {}

  void declare(StateLayout&) const {}

  template <class S>
  void output(const ControllerClock& c, const ReferenceSample&, const S*, const StateLayout&,
              PlantWorkspace<S>& w) const {
    const int k = table_.resolve(c.t, c.piece, c.extend);
    for (int j = 0; j < static_cast<int>(p_.size()); ++j) {
      w.u[j] = S(saturate(table_.value(j, c.t, k), p_[static_cast<std::size_t>(j)].output_limit));
    }
  }

  template <class S>
  void rates(const ReferenceSample&, const S*, const StateLayout&, const PlantWorkspace<S>&, S*) const {}

  int discrete_size() const { return 0; }
  void sample(const ControllerClock& c, const ReferenceSample& r, const double* x, const StateLayout& L,
              PlantWorkspace<double>& w, ControllerDiscreteState& d) const {
    output(c, r, x, L, w);
    for (std::size_t j = 0; j < p_.size(); ++j) d.u_held[j] = w.u[static_cast<int>(j)];
  }

  void hold(int, double, double*, const StateLayout&, ControllerDiscreteState&) const {}

  // Continuous: the rows are where u jumps or kinks. Sampled: u changes only
  // at the samples (the plant's own events).
  double next_time_event(double t) const {
    return mode_ == ControllerMode::kContinuous ? table_.next_breakpoint(t) : std::numeric_limits<double>::infinity();
  }
  int piece_after(double t) const { return table_.piece_after(t); }

 private:
  const ControllerMode mode_;
  const std::vector<OpenLoopParams> p_;
  const InputTable table_;
};

}  // namespace pumasim
