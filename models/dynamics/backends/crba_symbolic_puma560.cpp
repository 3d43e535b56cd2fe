#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo crba_symbolic_puma560_entry() {
  return entry<CrbaSymbolicPuma560>(
      "the same unrolled CRBA and RNEA with puma560.toml's numbers folded in "
      "(3 joints: wrist held at zero); other parameters are refused");
}

}  // namespace pumasim::detail
