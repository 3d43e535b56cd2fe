// The shipped scenes' folder, as the build passes it to the tests.
#pragma once

#include <string>

#ifndef PUMASIM_SCENES_DIR
#error "PUMASIM_SCENES_DIR must be defined by the build"
#endif

namespace pumasim::test {

// experiments/scenes/<name>.toml
inline std::string scene_path(const std::string& name) {
  return std::string(PUMASIM_SCENES_DIR) + "/" + name + ".toml";
}

}  // namespace pumasim::test
