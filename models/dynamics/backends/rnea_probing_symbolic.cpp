#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo rnea_probing_symbolic_entry() {
  return entry<RneaProbingSymbolic>(
      "the paper's probing on an RNEA unrolled with SymPy for the PUMA 560's "
      "structure (3 or 6 joints; parameters at run time): n + 2 calls, then Cholesky");
}

}  // namespace pumasim::detail
