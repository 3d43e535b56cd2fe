// libFuzzer harness: a joint-space reference's CSV file (reference.joints),
// read as experiments/scenes/joint_space_csv.toml reads it (read_joint_csv,
// models/scene/joint_csv.hpp: three joints), and, when accepted, the splines
// a scene makes through its rows (JointCurve, cubic and quintic, as
// joint_curve_of in models/scene/scene.cpp) evaluated at every row and
// between rows: q, dq/dt and d2q/dt2 must be finite there. A ConfigError
// from the reader, or the curve's std::invalid_argument when its spline is
// not finite (which the scene's loading turns into a ConfigError naming the
// file), is the expected refusal of bad input (exit status 2); any other
// exception, a non-finite curve that was accepted, a crash, a sanitizer
// report or a hang is a finding. (The whole scene is not loaded per input: its reference's trace,
// 4000 forward kinematics, made it about 80 inputs a second, a hundredth of
// this; the scene harness covers the scene's keys.)
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/reference/joint_curve.hpp"
#include "models/robot/strict_toml.hpp"
#include "models/scene/joint_csv.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {

constexpr int kJoints = 3;  // joint_space_csv.toml's scene.joints

void check_finite(const pumasim::JointCurve& c, double x) {
  Eigen::VectorXd q(kJoints), dq(kJoints), ddq(kJoints);
  c.eval(x, q, dq, ddq);
  if (!q.allFinite() || !dq.allFinite() || !ddq.allFinite()) {
    std::fprintf(stderr, "fuzz: accepted rows, a %s spline not finite at t = %.17g\n",
                 c.kind() == pumasim::JointCurve::Kind::kCubic ? "cubic" : "quintic", x);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = pumasim::fuzz::input_path("reference.csv");
  pumasim::fuzz::write_input(path, data, size);
  std::vector<std::vector<double>> rows;
  try {
    rows = pumasim::read_joint_csv(path, kJoints);
  } catch (const pumasim::ConfigError&) {
    return 0;
  }
  std::vector<double> knots;
  std::vector<Eigen::VectorXd> points;
  for (const auto& row : rows) {
    knots.push_back(row[0]);
    Eigen::VectorXd q = Eigen::VectorXd::Zero(kJoints);
    for (int j = 0; j < kJoints; ++j) q[j] = row[static_cast<std::size_t>(j + 1)];
    points.push_back(q);
  }
  for (const auto kind : {pumasim::JointCurve::Kind::kCubic, pumasim::JointCurve::Kind::kQuintic}) {
    std::optional<pumasim::JointCurve> built;
    try {
      built.emplace(knots, points, kJoints, kind);
    } catch (const std::invalid_argument& e) {
      // Only the curve's own finiteness refusal; its other checks (two
      // points, increasing knots, the first at 0) are the reader's promise.
      if (std::string(e.what()).find("is not finite") == std::string::npos) {
        std::fprintf(stderr, "fuzz: accepted rows refused by the curve: %s\n", e.what());
        std::abort();
      }
      continue;
    }
    const pumasim::JointCurve& c = *built;
    for (std::size_t k = 0; k < knots.size(); ++k) {
      check_finite(c, knots[k]);
      if (k + 1 < knots.size()) check_finite(c, knots[k] + 0.5 * (knots[k + 1] - knots[k]));
    }
  }
  return 0;
}
