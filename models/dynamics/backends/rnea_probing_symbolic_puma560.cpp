#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo rnea_probing_symbolic_puma560_entry() {
  return entry<RneaProbingSymbolicPuma560>(
      "the same probing with puma560.toml's numbers folded into the unrolled RNEA "
      "(3 joints: wrist held at zero); other parameters are refused");
}

}  // namespace pumasim::detail
