// The one rule for "the same time": two instants of a run closer than
// 1e-12 max(1, |horizon|) [s] are the same instant, the horizon being the
// largest time in play (the driver: the run's end; a stepper: its stop). A
// stop computed apart from the time reached (k * period or k * output
// interval against a sum of fixed steps, whose rounding grows with the number
// of steps) lands within it; a step shorter than it would drag a step-size
// controller down to an underflow. The driver (simulation: end of
// run, outputs, events due) and the odeint steppers (a stop reached) decide
// with it; CVODE and ARKODE stop exactly at their stop time. The models use
// its width where they place a time among their own breakpoints: an
// open-loop input's rows (models/plant/controller/input_table.hpp), the
// reference's breakpoints (models/reference/trajectory.cpp) and its table's
// segment ends (models/reference/reference_table.cpp). (A step meant to
// end at the stop snaps to it when it lands within 1e-12 of its own length,
// odeint.cpp: a rounding of the step, not a comparison of two instants.) The plant's
// sample grids (models/plant/plant_model.cpp, on_grid) are a different question,
// whether a time it announced is a multiple of a period, answered on the
// sample index.
#pragma once

#include <algorithm>
#include <cmath>

namespace pumasim {

inline constexpr double kSameTimeRelative = 1e-12;

// The width of one instant in a run whose times reach `horizon` [s].
inline double time_tolerance(double horizon) { return kSameTimeRelative * std::max(1.0, std::abs(horizon)); }

// a is before b and not the same instant (an infinite b, no next event, is
// after every finite a).
inline bool before(double a, double b, double horizon) { return a < b - time_tolerance(horizon); }

inline bool same_time(double a, double b, double horizon) {
  if (!std::isfinite(a) || !std::isfinite(b)) return a == b;
  return std::abs(a - b) <= time_tolerance(horizon);
}

}  // namespace pumasim
