#include "models/plant/state_layout.hpp"

#include <stdexcept>

namespace pumasim {

int StateLayout::add(const std::vector<std::string>& slice_names, const std::vector<double>& slice_scale) {
  if (slice_names.size() != slice_scale.size()) throw std::logic_error("StateLayout::add: one scale per name");
  const int offset = size;
  names.insert(names.end(), slice_names.begin(), slice_names.end());
  scale.insert(scale.end(), slice_scale.begin(), slice_scale.end());
  size += static_cast<int>(slice_names.size());
  return offset;
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
