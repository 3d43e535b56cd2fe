// The friction modes of a run (stick, slip +, slip -) as events, written to
// the run folder as events.csv (t, joint, mode, the applied torque and Fs):
//   - the hybrid model: its own mode changes (Plant::mode_changes), exactly
//     where its root functions put them;
//   - the laws without modes (the paper's rule, Karnopp, tanh, and any
//     integrator that treats friction its own way): a classification of each
//     ACCEPTED step of the integrator (Plant::classify_modes: stuck when
//     |w_m| <= kStickSpeed and, for a law with a stick branch, that branch
//     holds the joint), never of the output rows, so the sequence does not
//     depend on the output grid. A change counts only when the new mode holds
//     for at least kMinModeDuration (over the accepted steps that follow);
//     it is dated at the end of the first step classified so. A candidate still
//     shorter than that when the run ends is dropped.
// The comparison with a reference (experiments/mode_sequence.py) applies the
// same minimum duration to the hybrid model's events.
#pragma once

#include <string>
#include <vector>

#include "models/plant/plant.hpp"

namespace pumasim {

inline constexpr double kStickSpeed = 1e-3;       // [rad/s] motor side: Karnopp's band in stick_slip.toml
inline constexpr double kMinModeDuration = 1e-3;  // [s]: shorter stick or slip intervals are not modes

// Follows a run's accepted steps and keeps the mode changes that last.
class ModeClassifier {
 public:
  // speed_only: stuck when |w_m| <= stick_speed alone (the integrator solved
  // the friction law itself: moreau-jean); the applied torque is then NaN.
  ModeClassifier(Plant& plant, double stick_speed = kStickSpeed, double min_duration = kMinModeDuration,
                 bool speed_only = false);
  // The state at the end of an accepted step (or the initial state at t = 0).
  void step(double t, const double* x);
  const std::vector<ModeChange>& changes() const { return changes_; }
  // Counts an accepted step (any friction law, the hybrid one too): its
  // length and the joint speeds' signs.
  void count(double t, const double* x);
  // Over the accepted steps counted: the joint speeds' sign changes (summed
  // over the joints; a zero speed is no sign), and the shortest step [s].
  long speed_sign_changes() const { return sign_changes_; }
  double shortest_step() const { return shortest_; }

 private:
  Plant& plant_;
  double stick_speed_, min_duration_;
  bool speed_only_;
  std::vector<SlipMode> now_;  // this step's classification
  std::vector<double> applied_;
  struct Joint {
    int confirmed = 2;   // the mode in force (as int; 2: none yet)
    int candidate = 2;   // a different mode seen since `since`
    double since = 0;    // [s]
    double applied = 0;  // [N m] at the candidate's first step
  };
  std::vector<Joint> joints_;
  std::vector<ModeChange> changes_;
  std::vector<int> sign_;  // per joint: the last nonzero speed's sign (0: none yet)
  long sign_changes_ = 0;
  double last_t_ = -1, shortest_ = 0;
};

// events.csv: "t,joint,mode,applied_torque,static_torque", joint 1-based,
// mode stick, slip+ or slip-, torques [N m] motor side, full precision;
// only the joints with modes (Plant::joint_has_modes).
std::string events_csv(const Plant& plant, const std::vector<ModeChange>& changes);

}  // namespace pumasim
