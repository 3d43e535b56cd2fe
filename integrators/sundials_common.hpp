// Private to the SUNDIALS adapters (CVODE, ARKODE): what both need to say
// about a failure.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include <nvector/nvector_serial.h>

#include "integrators/integrator.hpp"

namespace pumasim::detail {

// "; largest weighted local errors: qd2 (3.1), i_motor2 (0.8), q2 (0.01)"
inline std::string largest_weighted_errors(const OdeSystem& sys, N_Vector ele, N_Vector w) {
  const int n = static_cast<int>(N_VGetLength_Serial(ele));
  const double* e = N_VGetArrayPointer(ele);
  const double* ww = N_VGetArrayPointer(w);
  std::vector<int> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(),
            [&](int a, int b) { return std::abs(e[a] * ww[a]) > std::abs(e[b] * ww[b]); });
  std::string msg = "; largest weighted local errors:";
  for (int k = 0; k < std::min(3, n); ++k) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", std::abs(e[idx[k]] * ww[idx[k]]));
    msg.append(" ").append(sys.state_name(idx[k])).append(" (").append(buf).append(")");
  }
  return msg;
}

}  // namespace pumasim::detail
