#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo rnea_probing_shared_entry() {
  return entry<RneaProbingShared>(
      "probing with the kinematics shared: one trigonometric pass, h + n "
      "gravity-free RNEA passes for H, then Cholesky");
}

}  // namespace pumasim::detail
