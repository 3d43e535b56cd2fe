#include "models/dynamics/backend.hpp"

#include <algorithm>
#include <atomic>
#include <array>
#include <stdexcept>

#include "backend_registry.inc"  // generated: the back-ends this build has (PUMASIM_BACKENDS)

namespace pumasim {
namespace {

// Sorted by name (checked below). A new back-end is one file in
// models/dynamics/backends/ and its name in models/dynamics/CMakeLists.txt.
const detail::BackendTable& registry() {
  static const detail::BackendTable table = detail::make_backend_table();
  return table;
}

bool registry_sorted() {
  return std::is_sorted(registry().begin(), registry().end(), [](const auto& a, const auto& b) {
    return std::string_view(a.name) < std::string_view(b.name);
  });
}

}  // namespace

std::span<const BackendInfo> backends() {
  static const bool sorted = registry_sorted();
  if (!sorted) throw std::logic_error("backend registry is not sorted by name");
  return registry();
}

namespace {
std::atomic<long> built_count{0};
}  // namespace

long backends_built() { return built_count.load(std::memory_order_relaxed); }

void detail::count_backend_built() { built_count.fetch_add(1, std::memory_order_relaxed); }

std::string backend_names() {
  std::string s;
  for (const auto& b : backends()) {
    if (!s.empty()) s += ", ";
    s += b.name;
  }
  return s;
}

const BackendInfo& find_backend(std::string_view name) {
  const auto all = backends();
  const auto it = std::lower_bound(all.begin(), all.end(), name, [](const auto& b, auto key) {
    return std::string_view(b.name) < key;
  });
  if (it == all.end() || std::string_view(it->name) != name) {
    throw std::invalid_argument("unknown dynamics back-end '" + std::string(name) +
                                "'; expected one of: " + backend_names());
  }
  return *it;
}

}  // namespace pumasim
