#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo crba_world_entry() {
  return entry<CrbaWorld>(
      "composite rigid body algorithm in the world frame (H_ij = S_i^T Ic_j S_j, "
      "no transform per ancestor) for H + one RNEA pass for h + Cholesky");
}

}  // namespace pumasim::detail
