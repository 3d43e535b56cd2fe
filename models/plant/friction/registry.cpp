#include "models/plant/friction/registry.hpp"

namespace pumasim {

const char* to_string(FrictionModel m) {
  const char* name = "?";
  FrictionLaws::visit(m, [&](auto law) { name = decltype(law)::kName; });
  return name;
}

bool friction_model_from_name(const std::string& name, FrictionModel* m) {
  bool found = false;
  FrictionLaws::for_each([&](auto law) {
    if (!found && name == decltype(law)::kName) *m = decltype(law)::kModel, found = true;
  });
  return found;
}

}  // namespace pumasim
