#include "models/dynamics/backend_impl.hpp"

namespace pumasim::detail {

BackendInfo lagrange_euler_entry() {
  return entry<LagrangeEuler>(
      "textbook Lagrange-Euler with 4x4 matrices (Uicker / Fu-Gonzalez-Lee), "
      "O(n^4) + Cholesky");
}

}  // namespace pumasim::detail
