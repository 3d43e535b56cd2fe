// libFuzzer harness: a URDF file and its side file (load_robot on a ".urdf"
// path, as a scene's robot key loads one: the pre-scan, urdfdom and TinyXML,
// the chain's checks, the side file read strictly). The input is the URDF,
// then, when the input holds it, the line kSideFileMarker and the side file
// (<file>.urdf.toml; none without the marker). A ConfigError is the expected
// refusal of bad input (exit status 2); any other exception, a crash, a
// sanitizer report or a hang is a finding.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "models/robot/robot_file.hpp"
#include "models/robot/urdf_file.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {
// Where the URDF ends and the side file starts (scripts/fuzz_seeds.py writes
// the seeds so).
constexpr std::string_view kSideFileMarker = "\n==== side file ====\n";
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = pumasim::fuzz::input_path("robot.urdf");
  static const std::string side = pumasim::urdf_side_file(path);
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const std::size_t cut = input.find(kSideFileMarker);
  const std::string_view urdf = input.substr(0, cut);
  pumasim::fuzz::write_input(path, data, urdf.size());
  if (cut == std::string_view::npos) {
    std::filesystem::remove(side);
  } else {
    const std::size_t from = cut + kSideFileMarker.size();
    pumasim::fuzz::write_input(side, data + from, size - from);
  }
  try {
    pumasim::load_robot(path);
  } catch (const pumasim::ConfigError&) {
  }
  return 0;
}
