#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo crba_entry() {
  return entry<Crba>(
      "composite rigid body algorithm for H + one RNEA pass for h + Cholesky");
}

}  // namespace pumasim::detail
