// A joint-space reference's points from a CSV file (scene key
// reference.joints): a header line naming the columns, then one row per
// point "t, q1, ..., qn" (t [s], angles [rad] of the scene's n simulated
// joints), comma-separated; blank lines are skipped. The first t is 0, the
// times increase by at least kMinRowStep and at most kMaxRowStep, every
// value is a finite number, no step's jump has a slope or curvature that
// overflows, and there are at least two rows. (A spline through rows that
// pass can still overflow where neighbouring steps couple: the curve checks
// itself, JointCurve::check_finite, and the scene reports it.) Anything else is a ConfigError naming the file, the line
// and, for a value, the column (1-based, with its header name). The same
// format holds an open-loop input's rows "t, u1, ..., un" (controller.file;
// `column` names the values in messages).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace pumasim {

// The shortest time between two rows [s]: a microsecond, below any servo
// period; closer rows (1e-300 s apart) made the curve's coefficients overflow
// or an integrator's stop time fall below its resolution.
inline constexpr double kMinRowStep = 1e-6;
// The longest time between two rows [s]: 1e75 s, far past any reference; the
// quintic spline's knot equations hold terms in the step's fourth power and
// its inverse, and the fourth power overflows past about 1.2e77 s (rows
// 1e110 s apart made the spline not finite; fuzz_joint_csv).
inline constexpr double kMaxRowStep = 1e75;

// Each row: t, then n angles.
std::vector<std::vector<double>> read_joint_csv(const std::string& path, int n, std::string_view column = "q");

// The same checks on rows given otherwise (reference.via_points); `where`
// prefixes the messages, which name the row (1-based).
void check_joint_rows(const std::vector<std::vector<double>>& rows, int n, const std::string& where,
                      std::string_view column = "q");

}  // namespace pumasim
