// The Newton systems of CVODE and ARKODE (SUNDIALS 6.x) on a SUNDenseMatrix,
// with the project's vector instructions: a direct linear solver by Eigen's LU
// with partial pivoting, the same factorisation as SUNDIALS' own dense solver
// (SUNLinSol_Dense: Gaussian elimination with partial pivoting, LAPACK's
// GETRF/GETRS in C), and a dense matrix whose copy and scale-add operations
// (the Newton matrix I - gamma J from the saved Jacobian at every set-up) run
// as Eigen expressions (copy, zero and c A + I with the same arithmetic
// element by element; c A + B, used with a mass matrix only, may be fused). On the
// 24-state plant the LU and its solves were the largest share of CVODE's own
// work, the copies and scale-adds a sizeable one (results/cost_breakdown.md, perf).
// Private to the SUNDIALS adapters.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

namespace pumasim::detail {

// For an n x n SUNDenseMatrix; freed with SUNLinSolFree. A matrix with a zero
// pivot fails the set-up with SUNLS_LUFACT_FAIL (recoverable, as
// SUNLinSol_Dense reports it).
SUNLinearSolver make_dense_lu(SUNContext ctx, int n);

// An n x n SUNDenseMatrix (SUNMATRIX_DENSE: SUNDIALS' difference-quotient
// Jacobian and every dense accessor still apply) whose zero, copy, scale-add
// and clone operations are replaced by Eigen ones; its clones too. Freed with
// SUNMatDestroy.
SUNMatrix make_dense_matrix(SUNContext ctx, int n);

// A serial N_Vector of length n (NVECTOR_SERIAL: N_VGetArrayPointer and every
// serial operation apply) with SUNDIALS' fused operations enabled (a linear
// combination of the Nordsieck history in one loop instead of one
// N_VScale/N_VLinearSum pass per vector) and two weighted norms replaced:
// nvwsqrsumlocal and nvwrmsnorm (N_VWrmsNorm: every error test and Newton
// convergence test of CVODE and ARKODE) sum in four independent partial
// sums, which the compiler vectorises, where the library's single running
// sum is a chain of dependent additions (a reassociation it may not make
// itself): the same sum up to rounding. The masked and vector-array norms
// (nvwrmsnormmask, nvwsqrsummasklocal, nvwrmsnormvectorarray), which CVODE
// and ARKODE call only for features pumasim does not use (constraints,
// sensitivities), stay the library's. Its clones (CVODE's and ARKODE's work
// vectors) inherit the operations. Freed with N_VDestroy.
N_Vector make_state_vector(SUNContext ctx, int n);

// The same operations on a vector that owns no data: point it at an array
// with N_VSetArrayPointer before each use (the dense output's target), so
// that no vector is allocated per output. Being reused, it makes its
// integrator's dense output one call at a time (one integrator per thread,
// as everywhere). Freed with N_VDestroy; the array is never freed by it.
N_Vector make_view_vector(SUNContext ctx, int n);

}  // namespace pumasim::detail
