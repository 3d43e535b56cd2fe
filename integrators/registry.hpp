// The integrator registry: one sorted name -> factory table.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "integrators/integrator.hpp"

namespace pumasim {

struct IntegratorInfo {
  const char* name;
  const char* summary;
  std::unique_ptr<Integrator> (*make)(const IntegratorOptions& options);
};

// All integrators, sorted by name.
std::span<const IntegratorInfo> integrators();
// The entry called `name`; std::invalid_argument listing the valid names otherwise.
const IntegratorInfo& find_integrator(std::string_view name);
std::string integrator_names();
inline std::unique_ptr<Integrator> make_integrator(std::string_view name, const IntegratorOptions& o) {
  return find_integrator(name).make(o);
}

}  // namespace pumasim
