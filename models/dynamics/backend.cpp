#include "models/dynamics/backend.hpp"

#include <algorithm>
#include <atomic>
#include <array>
#include <stdexcept>


namespace pumasim {
namespace detail {
// One file each in models/dynamics/backends/.
BackendInfo aba_entry();
BackendInfo crba_entry();
BackendInfo crba_symbolic_entry();
BackendInfo crba_symbolic_puma560_entry();
BackendInfo crba_world_entry();
BackendInfo lagrange_euler_entry();
BackendInfo lagrange_symbolic_entry();
BackendInfo lagrange_symbolic_puma560_entry();
BackendInfo rnea_probing_entry();
BackendInfo rnea_probing_shared_entry();
BackendInfo rnea_probing_symbolic_entry();
BackendInfo rnea_probing_symbolic_puma560_entry();
}  // namespace detail

namespace {

// Sorted by name (checked below). A new back-end is one file in
// models/dynamics/backends/ and one line here.
const std::array<BackendInfo, 12>& registry() {
  static const std::array<BackendInfo, 12> table{{
      detail::aba_entry(),
      detail::crba_entry(),
      detail::crba_symbolic_entry(),
      detail::crba_symbolic_puma560_entry(),
      detail::crba_world_entry(),
      detail::lagrange_euler_entry(),
      detail::lagrange_symbolic_entry(),
      detail::lagrange_symbolic_puma560_entry(),
      detail::rnea_probing_entry(),
      detail::rnea_probing_shared_entry(),
      detail::rnea_probing_symbolic_entry(),
      detail::rnea_probing_symbolic_puma560_entry(),
  }};
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
