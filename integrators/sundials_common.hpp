// Private to the SUNDIALS adapters (CVODE, ARKODE): what both need to say
// about a failure.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
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

// The absolute tolerances atol * sys.tolerance_scale(i), handed to `set`
// (CVodeSVtolerances, ARKStepSVtolerances: both keep a copy); its flag.
template <class Set>
int set_absolute_tolerances(const OdeSystem& sys, double atol, SUNContext ctx, Set set) {
  N_Vector v = N_VNew_Serial(sys.size(), ctx);
  double* a = N_VGetArrayPointer(v);
  for (int i = 0; i < sys.size(); ++i) a[i] = atol * sys.tolerance_scale(i);
  const int flag = set(v);
  N_VDestroy(v);
  return flag;
}

// The index of the first root function SUNDIALS reports as found.
// A flag's name from CVodeGetReturnFlagName / ARKStepGetReturnFlagName, which
// return a malloc'd string that the caller frees (SUNDIALS 6; LeakSanitizer
// found it left).
inline std::string flag_name(char* name) {
  std::string s = name ? name : "?";
  std::free(name);
  return s;
}

// "<method> failed with flag F (NAME) at t = T s: <SUNDIALS' message>;
// largest weighted local errors: ...; non-finite ...": a failed step's report,
// from the integrator's local error estimates and weights (its
// Get*EstLocalErrors / Get*ErrWeights) at mem; flag_name_malloced from its
// Get*ReturnFlagName (freed here).
using GetVector = int (*)(void*, N_Vector);
inline std::string failure_message(const char* method, int flag, char* flag_name_malloced, double t,
                                   const std::string& error, const OdeSystem& sys, void* mem, N_Vector y,
                                   GetVector local_errors, GetVector weights) {
  std::string msg = std::string(method) + " failed with flag " + std::to_string(flag) + " (" +
                    flag_name(flag_name_malloced) + ") at t = " + std::to_string(t) + " s";
  if (!error.empty()) msg += ": " + error;
  N_Vector ele = N_VClone(y), w = N_VClone(y);
  if (local_errors(mem, ele) == 0 && weights(mem, w) == 0) msg += largest_weighted_errors(sys, ele, w);
  N_VDestroy(ele);
  N_VDestroy(w);
  const std::string bad = non_finite_components(sys, t, N_VGetArrayPointer(y));
  if (!bad.empty()) msg.append("; ").append(bad);
  return msg;
}

inline int first_root_found(const std::vector<int>& rootsfound) {
  return static_cast<int>(std::find_if(rootsfound.begin(), rootsfound.end(), [](int r) { return r != 0; }) -
                          rootsfound.begin());
}

// SUNDIALS counts from its last (re)initialisation: add what `now` counted
// since `base` to `total`, across restarts. The caller zeroes `base` at every
// re-initialisation (inferring it from a falling step count missed every
// interval longer than the one before, and under-counted runs with events).
inline void accumulate_since_reinit(IntegratorStats& total, IntegratorStats& base,
                                    const IntegratorStats& now) {
  total.steps += now.steps - base.steps;
  total.rhs_evaluations += now.rhs_evaluations - base.rhs_evaluations;
  total.jacobian_evaluations += now.jacobian_evaluations - base.jacobian_evaluations;
  total.linear_solves += now.linear_solves - base.linear_solves;
  total.rejected_steps += now.rejected_steps - base.rejected_steps;
  total.nonlinear_iterations += now.nonlinear_iterations - base.nonlinear_iterations;
  base = now;
}

inline void check_flag(int flag, const char* module, const char* what) {
  if (flag < 0) {
    throw std::runtime_error(std::string(module) + ": " + what + " failed with flag " + std::to_string(flag));
  }
}

// Both integrators' interpolant is valid over their last internal step
// [tcur - hu, tcur]: its start, from their GetCurrentTime and GetLastStep.
using GetReal = int (*)(void*, sunrealtype*);
inline double last_step_start(void* mem, double t_reached, GetReal current_time, GetReal last_step) {
  double tcur = t_reached, hu = 0;
  current_time(mem, &tcur);
  last_step(mem, &hu);
  return std::min(t_reached, tcur - hu);
}

// The state at t into x: the current state at or past the time reached,
// else SUNDIALS' interpolant (CVodeGetDky / ARKStepGetDky, derivative 0)
// written through `view`, a vector without data of y's length
// (make_view_vector), pointed at x for the call.
using GetDky = int (*)(void*, sunrealtype, int, N_Vector);
inline void interpolated_state(void* mem, GetDky get_dky, double t, double t_reached, N_Vector y, N_Vector view,
                               double* x, const char* module, const char* what) {
  const sunindextype n = N_VGetLength_Serial(y);
  if (t >= t_reached) {
    std::copy(N_VGetArrayPointer(y), N_VGetArrayPointer(y) + n, x);
    return;
  }
  N_VSetArrayPointer(x, view);
  const int flag = get_dky(mem, t, 0, view);
  N_VSetArrayPointer(nullptr, view);
  check_flag(flag, module, what);
}

}  // namespace pumasim::detail
