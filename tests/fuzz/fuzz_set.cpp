// libFuzzer harness: `--set key=value` overrides (apply_overrides and the
// checks of the scene they change). The input's first line names a shipped
// scene (experiments/scenes/<name>.toml; another first line: the input is
// skipped), each further line is one --set argument, as
// `pumasim run SCENE --set LINE...` passes them to load_checked_scene. A
// ConfigError is the expected refusal (exit status 2); any other exception, a
// crash, a sanitizer report or a hang is a finding.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "simulation/run.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  const std::string& name = lines.front();
  if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos) return 0;
  const std::string scene = std::string(PUMASIM_SCENES_DIR) + "/" + name + ".toml";
  std::error_code ec;  // a name too long for the file system is no shipped scene either
  if (!std::filesystem::is_regular_file(scene, ec)) return 0;
  try {
    pumasim::load_checked_scene(scene, std::vector<std::string>(lines.begin() + 1, lines.end()));
  } catch (const pumasim::ConfigError&) {
  }
  return 0;
}
