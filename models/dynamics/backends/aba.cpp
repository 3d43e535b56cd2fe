#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo aba_entry() {
  return entry<Aba>(
      "Featherstone's articulated body algorithm, O(n), rotor inertia as armature; "
      "H from the CRBA");
}

}  // namespace pumasim::detail
