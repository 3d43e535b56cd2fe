#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo rnea_probing_entry() {
  return entry<RneaProbing>(
      "the paper's method: n + 2 inverse-dynamics (RNEA) calls build g, h and "
      "H, then Cholesky");
}

}  // namespace pumasim::detail
