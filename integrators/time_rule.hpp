// The one rule for "the same time": two instants closer than rounding of
// times of their size, 1e-12 max(1, |a|, |b|) [s], are the same instant. A
// stop computed apart from the time reached (k * period against a sum of
// steps) lands within it; a step shorter than it would drag a step-size
// controller down to an underflow. The driver (experiments/simulation: end of
// run, outputs, events due) and the odeint steppers (a stop reached) decide
// with it; CVODE and ARKODE stop exactly at their stop time. The plant's
// sample grids (models/plant/plant.cpp, on_grid) are a different question,
// whether a time it announced is a multiple of a period, answered on the
// sample index.
#pragma once

#include <algorithm>
#include <cmath>

namespace pumasim {

inline constexpr double kSameTimeRelative = 1e-12;


// An infinite time (no next event) is the same only as itself.
inline bool same_time(double a, double b) {
  if (!std::isfinite(a) || !std::isfinite(b)) return a == b;
  return std::abs(a - b) <= kSameTimeRelative * std::max({1.0, std::abs(a), std::abs(b)});
}

// a is before b and not the same instant.
inline bool before(double a, double b) { return a < b && !same_time(a, b); }

}  // namespace pumasim
