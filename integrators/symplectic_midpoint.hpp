// The implicit midpoint rule in canonical coordinates (q, p = M(q) qd), for
// a lossless, unforced mechanical system (ConservativeMechanics): one step
// of size h from z0 = (q0, p0) is the z1 = (q1, p1) with
//   q1 = q0 + h M(qm)^-1 pm,   p1 = p0 + h dL/dq(qm, M(qm)^-1 pm),
//   (qm, pm) = ((q0 + q1) / 2, (p0 + p1) / 2),
// the midpoint rule on Hamilton's equations. It is symplectic (Feng Kang
// 1985; Hairer, Lubich & Wanner, "Geometric Numerical Integration", 2nd ed.
// 2006, Theorem VI.3.5: the one-step map's Jacobian P satisfies
// P' J P = J), symmetric (the step with -h from z1 gives z0 back) and of
// order 2; by backward error analysis its energy error then stays bounded,
// O(h^2), over exponentially long times instead of drifting (ibid.,
// Theorem IX.8.1). All of that holds in (q, p), not in (q, qd): the
// integrator keeps p from step to step and forms qd = M^-1 p only for the
// state it reports.
//
// The nonlinear equations are solved by fixed-point iteration, carried to
// round-off: it stops when an update is zero or no smaller than the one
// before once updates are at rounding level (ibid., Sec. VIII.6.1), so that
// the map is the exact midpoint map up to rounding (a loose tolerance would
// spoil both symplecticity and symmetry). An iteration that stops
// contracting before that is a reported failure (a smaller dt).
#pragma once

#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "integrators/integrator.hpp"

namespace pumasim {

// Scratch for midpoint_step on a system of n degrees of freedom.
struct MidpointScratch {
  explicit MidpointScratch(int n) : M(n, n), llt(n), qm(n), pm(n), vm(n), g(n), q_next(n), p_next(n) {}
  Eigen::MatrixXd M;
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::VectorXd qm, pm, vm, g, q_next, p_next;
};

struct MidpointSolve {
  int iterations = 0;  // of the fixed-point map (one M, one Cholesky, one dL/dq each)
  bool converged = false;
  double update = 0;    // the last update's relative size
  std::string failure;  // when not converged: what happened
};

// One step of size h (either sign) from (q0, p0); (q1, p1) hold the first
// guess on entry and the step's end on return. At most max_iterations
// fixed-point iterations. Allocation-free.
MidpointSolve midpoint_step(ConservativeMechanics& m, double h, const double* q0, const double* p0, double* q1,
                            double* p1, MidpointScratch& s, int max_iterations = 200);

// p = M(q) qd and its inverse qd = M(q)^-1 p.
void midpoint_momentum(ConservativeMechanics& m, const double* q, const double* qd, double* p, MidpointScratch& s);
bool midpoint_velocity(ConservativeMechanics& m, const double* q, const double* p, double* qd, MidpointScratch& s);

}  // namespace pumasim
