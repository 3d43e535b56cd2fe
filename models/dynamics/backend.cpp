#include "models/dynamics/backend.hpp"

#include <atomic>
#include <span>
#include <string>

#include "core/invariant.hpp"
#include "core/registry.hpp"
#include "models/dynamics/built_backends.hpp"  // generated: the back-ends this build has (PUMASIM_BACKENDS)

namespace pumasim {

// Sorted by name: the generated list is, at compile time (built_backends.hpp).
// A new back-end is its entry file in models/dynamics/backends/ (found by
// the build's glob), with its algorithm beside it.
std::span<const BackendInfo> backends() {
  static const auto table = [] {
    auto t = detail::make_backend_table();
    for (std::size_t k = 0; k < t.size(); ++k) {
      PUMASIM_DEMAND(t[k].name == kBuiltBackendNames[k],
                     "back-end entry " + std::string(kBuiltBackendNames[k]) + "_entry() is named '" + t[k].name +
                         "' (its algorithm template's kName)");
    }
    return t;
  }();
  return table;
}

namespace {
std::atomic<long> built_count{0};
}  // namespace

long backends_built() { return built_count.load(std::memory_order_relaxed); }

void detail::count_backend_built() { built_count.fetch_add(1, std::memory_order_relaxed); }

std::string backend_names() { return entry_names(backends()); }

const BackendInfo& find_backend(std::string_view name) { return find_entry(backends(), name, "dynamics back-end"); }

}  // namespace pumasim
