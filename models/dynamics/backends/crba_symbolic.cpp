#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo crba_symbolic_entry() {
  return entry<CrbaSymbolic>(
      "CRBA for H and RNEA for h, unrolled with SymPy for the PUMA 560's structure "
      "(3 or 6 joints; parameters at run time) + Cholesky");
}

}  // namespace pumasim::detail
