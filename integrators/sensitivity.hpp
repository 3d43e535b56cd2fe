// Forward parameter sensitivities s_k = dx/dp_k of x' = f(t, x; p) by SUNDIALS
// CVODES (BDF, Newton with a dense direct solver, the staggered corrector --
// the sensitivities corrected after the state, with the same Newton matrix --
// and the sensitivities in the error test): along x,
//     s_k' = J(t, x) s_k + df/dp_k(t, x),   s_k(t0) = dx0/dp_k
// (Hindmarsh et al., "SUNDIALS: Suite of nonlinear and differential/algebraic
// equation solvers", ACM TOMS 31(3), 2005; the CVODES guide, sec. 2.6), with
// J the system's Jacobian (its exact one where it has it) and df/dp the
// system's own. Only continuous systems: one with root functions (events
// that switch the right-hand side, where the sensitivities jump by the
// saltation matrix, Hiskens & Pai, IEEE TCAS-I 47(2), 2000) is refused, and
// so is a run where the system's jump_at says f jumps in x (a clamp
// engaging). The system's stops (time events, where f may kink or jump in
// t) restart the method with x and s as they are: s is continuous across a
// stop at a time tau that does not depend on p (the jump condition
// s+ = s- - (f+ - f-) dtau/dp has dtau/dp = 0). The outputs are
// interpolated (CV_NORMAL past them), so that they do not cap the steps
// (the staggered corrector and the interpolated outputs were chosen by
// measurement: see the commit that made them).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "integrators/integrator.hpp"

namespace pumasim {

class SensitivitySystem : public OdeSystem {
 public:
  virtual int parameters() const = 0;
  virtual std::string parameter_name(int k) const { return "p" + std::to_string(k + 1); }
  // |p_k|, or a typical magnitude: CVODES scales s_k's absolute tolerance by it.
  virtual double parameter_scale(int /*k*/) const { return 1.0; }
  // df/dp (size() x parameters(), column-major) at (t, x).
  virtual void parameter_derivatives(double t, const double* x, double* dfdp) = 0;
  // dx0/dp (size() x parameters(), column-major); zero by default.
  virtual void initial_sensitivities(double* s0) const;
  // The next time after t where f kinks or changes (infinity: none), and
  // what the system does there; the state must not jump (sensitivity_run
  // refuses a jump: it would need its jump condition).
  virtual double next_stop(double /*t*/) const;
  virtual void on_stop(double /*t*/, double* /*x*/) {}
  // Why f jumps in x at (t, x), a converged state (a clamp engaging: the
  // sensitivities would jump); "" when it does not. The run fails with it.
  virtual std::string jump_at(double /*t*/, const double* /*x*/) const { return {}; }
};

struct SensitivityOptions {
  double rtol = 1e-6;
  double atol = 1e-8;          // times tolerance_scale(i); s_k's, divided by parameter_scale(k)
  long max_steps = 5'000'000;  // in all; beyond it, a reported failure
};

struct SensitivityRun {
  bool ok = true;
  std::string failure;             // what, when (a refused system, CVODES' flag)
  std::vector<double> t;           // the output times reached
  std::vector<Eigen::VectorXd> x;  // the state at each
  std::vector<Eigen::MatrixXd> s;  // dx/dp at each (size() x parameters())
  IntegratorStats stats;           // steps, f (without the sensitivities' own), Jacobians
  long sensitivity_rhs = 0;        // calls of the sensitivities' right-hand side (all p at once)
  long sensitivity_jacobians = 0;  // the system's Jacobians those calls made (one per (t, x))
  long sensitivity_error_test_failures = 0;
  double wall_time = 0;  // [s]
};

// The run from (t0, x0) through the increasing `outputs` (each > t0).
SensitivityRun sensitivity_run(SensitivitySystem& sys, double t0, const double* x0, const std::vector<double>& outputs,
                               const SensitivityOptions& options);

}  // namespace pumasim
