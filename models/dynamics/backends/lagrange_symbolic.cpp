#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo lagrange_symbolic_entry() {
  return entry<LagrangeSymbolic>(
      "closed-form Lagrange model generated with SymPy for the PUMA 560's "
      "structure (3 or 6 joints; parameters at run time) + Cholesky");
}

}  // namespace pumasim::detail
