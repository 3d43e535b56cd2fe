// libFuzzer harness: a robot file (load_robot_file). A ConfigError is the
// expected refusal of bad input (main() turns it into exit status 2); any
// other exception, a crash, a sanitizer report or a hang is a finding.
#include <cstdint>

#include "models/robot/robot_file.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = pumasim::fuzz::input_path("robot.toml");
  pumasim::fuzz::write_input(path, data, size);
  try {
    pumasim::load_robot_file(path);
  } catch (const pumasim::ConfigError&) {
  }
  return 0;
}
