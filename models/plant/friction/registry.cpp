#include "models/plant/friction/registry.hpp"

namespace pumasim {

const char* to_string(FrictionModel m) {
  const char* name = "?";
  FrictionLaws::visit(m, [&](auto law) { name = decltype(law)::kName; });
  return name;
}

const std::vector<std::pair<std::string, FrictionModel>>& friction_model_choices() {
  static const std::vector<std::pair<std::string, FrictionModel>> choices = [] {
    std::vector<std::pair<std::string, FrictionModel>> out;
    FrictionLaws::for_each([&](auto law) { out.emplace_back(decltype(law)::kName, friction_model<decltype(law)>()); });
    return out;
  }();
  return choices;
}

bool friction_model_from_name(const std::string& name, FrictionModel* m) {
  for (const auto& [n, model] : friction_model_choices()) {
    if (n == name) return *m = model, true;
  }
  return false;
}

}  // namespace pumasim
