// libFuzzer harness: an open-loop input's CSV file (controller.file), read
// as experiments/scenes/open_loop_voltage.toml reads it (read_joint_csv with
// the column "u", models/scene/joint_csv.hpp: three joints), and, when
// accepted, the plant's input table made from its rows
// (models/plant/controller/input_table.hpp, held and linear) and evaluated at
// every row and between rows: the table must take the rows the reader
// accepted (it throws std::invalid_argument otherwise) and its values must be
// finite. A ConfigError is the expected refusal of bad input (exit status
// 2); any other exception, a non-finite input from accepted rows, a crash, a
// sanitizer report or a hang is a finding.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "models/plant/controller/input_table.hpp"
#include "models/robot/strict_toml.hpp"
#include "models/scene/joint_csv.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {

constexpr int kJoints = 3;  // open_loop_voltage.toml's scene.joints

void check_finite(const pumasim::InputTable& table, double t) {
  const int k = table.resolve(t, -1, false);
  for (int j = 0; j < kJoints; ++j) {
    if (!std::isfinite(table.value(j, t, k))) {
      std::fprintf(stderr, "fuzz: accepted rows, input %d not finite at t = %.17g\n", j + 1, t);
      std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = pumasim::fuzz::input_path("input.csv");
  pumasim::fuzz::write_input(path, data, size);
  std::vector<std::vector<double>> rows;
  try {
    rows = pumasim::read_joint_csv(path, kJoints, "u");
  } catch (const pumasim::ConfigError&) {
    return 0;
  }
  for (const auto interpolation : {pumasim::InputInterpolation::kZeroOrderHold, pumasim::InputInterpolation::kLinear}) {
    const pumasim::InputTable table(rows, kJoints, interpolation);  // std::invalid_argument: a finding
    for (std::size_t k = 0; k < rows.size(); ++k) {
      check_finite(table, rows[k][0]);
      if (k + 1 < rows.size()) check_finite(table, rows[k][0] + 0.5 * (rows[k + 1][0] - rows[k][0]));
    }
  }
  return 0;
}
