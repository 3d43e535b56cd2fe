// libFuzzer harness: a scene file, loaded as `pumasim check` and `pumasim run`
// load it (load_checked_scene: the scene, its robot by name from
// models/robots/, the plant's consistency checks, the integrator's name). A
// ConfigError is the expected refusal of bad input (exit status 2); any other
// exception, a crash, a sanitizer report or a hang is a finding.
#include <cstdint>

#include "simulation/run.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = pumasim::fuzz::input_path("scene.toml");
  pumasim::fuzz::write_input(path, data, size);
  try {
    pumasim::load_checked_scene(path, {});
  } catch (const pumasim::ConfigError&) {
  }
  return 0;
}
