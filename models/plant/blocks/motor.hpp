// DC motor block (paper eq. 2): La di/dt = e_a - (R0 + R) i - K w_m, torque
// K i, w_m = Z qd the motor speed. With La > 0 for every joint the currents
// are states (slice i_motor1..n, typical magnitude the stall current at full
// command); with La = 0 for every joint the current is algebraic: eliminated
// (the reduced model), i = (e_a - K w_m) / (R0 + R), or kept as an algebraic
// unknown (the same slice), its row the residual 0 = e_a - (R0 + R) i - K w_m
// (the drive's index-1 DAE, for the residual form).
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

class MotorBlock {
 public:
  MotorBlock(const std::vector<MotorParams>& motor, const std::vector<AmplifierParams>& amplifier,
             bool algebraic = false)
      : m_(motor), a_(amplifier) {
    const auto inductive = [](const MotorParams& m) { return m.inductance > 0; };
    const bool any = std::any_of(m_.begin(), m_.end(), inductive);
    if (any && !std::all_of(m_.begin(), m_.end(), inductive)) {
      throw std::invalid_argument("plant: armature inductance must be > 0 for every joint or 0 for "
                                  "every joint (the reduced model)");
    }
    electrical_ = any;
    if (algebraic && (any || m_.empty())) {
      throw std::invalid_argument("plant: algebraic currents need La = 0 for every joint");
    }
    algebraic_ = algebraic;
  }
  bool has_current_state() const { return electrical_ || algebraic_; }
  // The current slice holds algebraic unknowns (La = 0), not states with a rate.
  bool algebraic() const { return algebraic_; }
  const MotorParams& params(int j) const { return m_[static_cast<std::size_t>(j)]; }
  // R0 + R [ohm]
  double loop_resistance(int j) const { return a_[static_cast<std::size_t>(j)].output_resistance + params(j).resistance; }

  // The current slice, when the currents are states. full_command[j]: the
  // largest voltage the controller can command (the stall current's scale).
  void declare(StateLayout& L, const std::vector<double>& full_command) const {
    if (!has_current_state()) return;
    const int n = static_cast<int>(m_.size());
    std::vector<double> scale(static_cast<std::size_t>(n), 1.0);
    for (int j = 0; j < n; ++j) {
      const double v = full_command[static_cast<std::size_t>(j)], r = loop_resistance(j);
      if (v > 0 && r > 0 && std::isfinite(v / r)) scale[static_cast<std::size_t>(j)] = v / r;
    }
    L.i = L.add(joint_names("i_motor", n), scale);
  }

  // Joint j's current (from the state, its derivative written to xdot;
  // from the state, the algebraic row's residual e_a - (R0 + R) i - K w_m
  // written to xdot; or eliminated) for amplifier output ea at motor speed wm.
  template <class S>
  S current(int j, const S& ea, const S& wm, const S* x, S* xdot, int offset) const {
    const MotorParams& M = params(j);
    const S R = S(loop_resistance(j));
    if (offset >= 0) {
      const S i = x[offset + j];
      const S v = ea - R * i - S(M.torque_constant) * wm;
      xdot[offset + j] = algebraic_ ? v : v / S(M.inductance);
      return i;
    }
    return (ea - S(M.torque_constant) * wm) / R;
  }

  // The current that holds joint torque g at rest [A].
  double holding_current(int j, double g, double gear_ratio) const {
    return g / (gear_ratio * params(j).torque_constant);
  }

 private:
  const std::vector<MotorParams> m_;
  const std::vector<AmplifierParams> a_;
  bool electrical_ = false;
  bool algebraic_ = false;
};

}  // namespace pumasim
