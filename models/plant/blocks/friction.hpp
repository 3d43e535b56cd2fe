// Friction block: one law per joint from the registry (models/plant/friction/),
// on the motor shaft. A law with an internal state (LuGre's bristles) gets
// the slice z_fric1..n of the state; the hybrid law's stuck/slipping modes
// are discrete state (FrictionModes), switched by the plant's root
// functions.
#pragma once

#include <cmath>
#include <vector>

#include "models/plant/friction/registry.hpp"
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"

namespace pumasim {

using FrictionModes = std::vector<SlipMode>;

class FrictionBlock {
 public:
  explicit FrictionBlock(const std::vector<FrictionParams>& params) : p_(params) {
    for (const auto& f : p_) {
      needs_applied_ |= pumasim::needs_applied_torque(f.model);
      // With Fs = Fk = 0 the stick/slip law is its viscous part alone (a stuck
      // joint would need an applied torque of exactly 0): no modes, no events.
      // Events there chattered: a joint released at zero speed whose
      // acceleration, through H, points against its slip direction re-sticks
      // at once, and CVODE's steps collapsed just after t = 0 until its budget
      // ran out (measured: commit a3d5b8c).
      joint_events_.push_back(has_stick_slip_events(f.model) && (f.static_torque > 0 || f.kinetic_torque > 0));
      events_ |= joint_events_.back();
      law_set_valued_.push_back(is_set_valued(f.model));
      joint_set_valued_.push_back(law_set_valued_.back() && (f.static_torque > 0 || f.kinetic_torque > 0));
      joint_state_.push_back(friction_states(f.model) > 0);
      state_ |= joint_state_.back();
    }
  }
  // The slice z_fric1..n when some joint's law has a state (every joint
  // gets one; a law without a state leaves its component at 0).
  void declare(StateLayout& L) const {
    if (!state_) return;
    std::vector<double> scale;  // the bound, the deflection the law tends to at speed
    for (const auto& f : p_) {
      const double b = friction_state_bound(f);
      scale.push_back(std::isfinite(b) ? b : 1.0);
    }
    L.zf = L.add(joint_names("z_fric", static_cast<int>(p_.size())), scale);
    for (std::size_t j = 0; j < p_.size(); ++j) {
      L.set_bound(L.zf + static_cast<int>(j), friction_state_bound(p_[j]), friction_state_bound_why(p_[j]));
    }
  }
  bool has_state() const { return state_; }
  bool has_state(int j) const { return joint_state_[static_cast<std::size_t>(j)]; }
  // A stateful law's torque at (w_m, z), and dz/dt into zdot.
  template <class S>
  S state_torque(int j, const S& wm, const S& z, S& zdot) const {
    zdot = friction_rate(params(j), wm, z);
    return friction_state_torque(params(j), wm, z, zdot);
  }
  const FrictionParams& params(int j) const { return p_[static_cast<std::size_t>(j)]; }
  // Some joint's law reads the torque it must resist at rest (so f needs h).
  bool needs_applied_torque() const { return needs_applied_; }
  // Some joint's law has stuck/slipping modes switched at root functions.
  bool has_events() const { return events_; }
  bool has_events(int j) const { return joint_events_[static_cast<std::size_t>(j)]; }
  // Joint j is held by its friction (the rigid body then constrains it).
  bool stuck(int j, const FrictionModes& modes) const {
    return has_events(j) && modes[static_cast<std::size_t>(j)] == SlipMode::kStuck;
  }

  // Joint j's law has a set-valued Coulomb part with a level > 0 (what
  // time-stepping solves as impulses; its B w_m stays in smooth_torque).
  bool set_valued(int j) const { return joint_set_valued_[static_cast<std::size_t>(j)]; }
  // The smooth part of the friction torque: B w_m for the laws with a
  // set-valued part (hybrid, paper, karnopp), the whole torque of the others.
  template <class S>
  S smooth_torque(int j, const S& wm) const {
    if (law_set_valued_[static_cast<std::size_t>(j)]) return S(params(j).viscous) * wm;
    return friction_torque(params(j), wm, S(0), SlipMode::kPositive);
  }

  template <class S>
  S torque(int j, const S& wm, const S& applied, const FrictionModes& modes) const {
    return friction_torque(params(j), wm, applied, modes[static_cast<std::size_t>(j)]);
  }

 private:
  const std::vector<FrictionParams> p_;
  std::vector<bool> joint_events_;  // per joint: its law has stick/slip events
  std::vector<bool> law_set_valued_, joint_set_valued_;  // per joint: the law's, and with a level > 0
  std::vector<bool> joint_state_;                        // per joint: its law has a state
  bool state_ = false;
  bool needs_applied_ = false;
  bool events_ = false;
};

}  // namespace pumasim
