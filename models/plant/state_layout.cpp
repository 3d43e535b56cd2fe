#include "models/plant/state_layout.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/invariant.hpp"

namespace pumasim {

int StateLayout::add(const std::vector<std::string>& slice_names, const std::vector<double>& slice_scale) {
  PUMASIM_DEMAND(slice_names.size() == slice_scale.size(), "StateLayout::add: one typical magnitude per name");
  const int offset = size;
  names.insert(names.end(), slice_names.begin(), slice_names.end());
  scale.insert(scale.end(), slice_scale.begin(), slice_scale.end());
  bound.insert(bound.end(), slice_names.size(), std::numeric_limits<double>::infinity());
  bound_why.insert(bound_why.end(), slice_names.size(), std::string());
  size += static_cast<int>(slice_names.size());
  return offset;
}

void StateLayout::set_bound(int k, double value, const std::string& why) {
  if (!(value > 0) || !std::isfinite(value)) return;
  bound.at(static_cast<std::size_t>(k)) = value;
  bound_why.at(static_cast<std::size_t>(k)) = why;
}

int StateLayout::index(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (names[k] == name) return static_cast<int>(k);
  }
  return -1;
}

std::vector<std::string> joint_names(const char* prefix, int n) {
  std::vector<std::string> out;
  for (int j = 0; j < n; ++j) out.push_back(prefix + std::to_string(j + 1));
  return out;
}

}  // namespace pumasim
