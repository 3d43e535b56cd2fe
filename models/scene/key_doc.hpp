// One scene key as the reference shows it: `pumasim keys` prints these, and
// scripts/gen_reference.py writes docs/reference/scene-keys.md from them.
#pragma once

#include <string>
#include <vector>

namespace pumasim {

struct SceneKeyDoc {
  std::string section;  // "friction"
  std::string key;      // "static_torque"
  std::string need;     // "required", "optional" or "if set" (optional, written only when given)
  std::string what;     // the value, as a message says it: "a number >= 0, one per joint (an array) or one for all"
  std::string meaning;  // the entry's one line: unit and role
  std::string applies;  // when the key means something ("model = \"paper\" or ..."); empty: always
};

// Every entry of every section's table, in the order a scene is read.
std::vector<SceneKeyDoc> scene_key_docs();

}  // namespace pumasim
