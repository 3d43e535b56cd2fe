#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo lagrange_symbolic_puma560_entry() {
  return entry<LagrangeSymbolicPuma560>(
      "the same closed form with puma560.toml's numbers folded in "
      "(3 joints: wrist held at zero); other parameters are refused");
}

}  // namespace pumasim::detail
