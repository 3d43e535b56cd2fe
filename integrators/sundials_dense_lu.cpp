#include "integrators/sundials_dense_lu.hpp"

#include <cmath>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>

#include <Eigen/Dense>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace pumasim::detail {
namespace {

static_assert(std::is_same_v<realtype, double>, "SUNDIALS built with realtype double (Debian's)");

struct DenseLu {
  explicit DenseLu(int n) : n(n), lu(n), tmp(n) {}
  int n;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  Eigen::VectorXd tmp;  // for x and b in one vector
  sunindextype last_flag = SUNLS_SUCCESS;
};

DenseLu& content(SUNLinearSolver S) { return *static_cast<DenseLu*>(S->content); }

SUNLinearSolver_Type get_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID get_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int initialize(SUNLinearSolver S) {
  content(S).last_flag = SUNLS_SUCCESS;
  return SUNLS_SUCCESS;
}

int newton_lu_setup(SUNLinearSolver S, SUNMatrix A) {
  DenseLu& c = content(S);
  if (SUNDenseMatrix_Rows(A) != c.n || SUNDenseMatrix_Columns(A) != c.n) {
    return static_cast<int>(c.last_flag = SUNLS_ILL_INPUT);
  }
  c.lu.compute(Eigen::Map<const Eigen::MatrixXd>(SUNDenseMatrix_Data(A), c.n, c.n));
  // A zero pivot: singular (SUNLinSol_Dense reports the column; any positive
  // value is recoverable for the integrators).
  const auto pivots = c.lu.matrixLU().diagonal();
  for (int k = 0; k < c.n; ++k) {
    if (pivots[k] == 0.0) return static_cast<int>(c.last_flag = SUNLS_LUFACT_FAIL);
  }
  return static_cast<int>(c.last_flag = SUNLS_SUCCESS);
}

int newton_lu_solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  DenseLu& c = content(S);
  Eigen::Map<Eigen::VectorXd> xm(N_VGetArrayPointer(x), c.n);
  const Eigen::Map<const Eigen::VectorXd> bm(N_VGetArrayPointer(b), c.n);
  if (xm.data() == bm.data()) {
    c.tmp = bm;
    xm = c.lu.solve(c.tmp);
  } else {
    xm = c.lu.solve(bm);
  }
  return static_cast<int>(c.last_flag = SUNLS_SUCCESS);
}

sunindextype last_flag(SUNLinearSolver S) { return content(S).last_flag; }

int free_solver(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  delete static_cast<DenseLu*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

// The matrix operations on SUNDenseMatrix's column-major storage.
Eigen::Map<Eigen::MatrixXd> as_eigen(SUNMatrix A) {
  return {SUNDenseMatrix_Data(A), static_cast<Eigen::Index>(SUNDenseMatrix_Rows(A)),
          static_cast<Eigen::Index>(SUNDenseMatrix_Columns(A))};
}
bool same_shape(SUNMatrix A, SUNMatrix B) {
  return SUNMatGetID(B) == SUNMATRIX_DENSE && SUNDenseMatrix_Rows(A) == SUNDenseMatrix_Rows(B) &&
         SUNDenseMatrix_Columns(A) == SUNDenseMatrix_Columns(B);
}
int newton_matrix_zero(SUNMatrix A) {
  as_eigen(A).setZero();
  return SUNMAT_SUCCESS;
}
int newton_matrix_copy(SUNMatrix A, SUNMatrix B) {  // B = A
  if (!same_shape(A, B)) return SUNMAT_ILL_INPUT;
  as_eigen(B) = as_eigen(A);
  return SUNMAT_SUCCESS;
}
int newton_matrix_scale_add(realtype c, SUNMatrix A, SUNMatrix B) {  // A = c A + B
  if (!same_shape(A, B)) return SUNMAT_ILL_INPUT;
  auto a = as_eigen(A);
  a = c * a + as_eigen(B);
  return SUNMAT_SUCCESS;
}
int newton_matrix_scale_add_identity(realtype c, SUNMatrix A) {  // A = c A + I
  auto a = as_eigen(A);
  a *= c;
  a.diagonal().array() += 1.0;
  return SUNMAT_SUCCESS;
}
void install_matrix_ops(SUNMatrix A);
SUNMatrix newton_matrix_clone(SUNMatrix A) {
  SUNMatrix B = SUNMatClone_Dense(A);
  if (B) install_matrix_ops(B);
  return B;
}
void install_matrix_ops(SUNMatrix A) {
  A->ops->zero = newton_matrix_zero;
  A->ops->copy = newton_matrix_copy;
  A->ops->scaleadd = newton_matrix_scale_add;
  A->ops->scaleaddi = newton_matrix_scale_add_identity;
  A->ops->clone = newton_matrix_clone;
}

// sum_i (x_i w_i)^2 in four partial sums (see the header).
realtype weighted_square_sum(N_Vector x, N_Vector w) {
  const sunindextype n = NV_LENGTH_S(x);
  const realtype* a = NV_DATA_S(x);
  const realtype* b = NV_DATA_S(w);
  realtype s[4] = {0, 0, 0, 0};
  sunindextype i = 0;
  for (; i + 4 <= n; i += 4) {
    for (int k = 0; k < 4; ++k) {
      const realtype p = a[i + k] * b[i + k];
      s[k] += p * p;
    }
  }
  for (; i < n; ++i) {
    const realtype p = a[i] * b[i];
    s[0] += p * p;
  }
  return (s[0] + s[1]) + (s[2] + s[3]);
}
realtype weighted_rms_norm(N_Vector x, N_Vector w) {
  return std::sqrt(weighted_square_sum(x, w) / static_cast<realtype>(NV_LENGTH_S(x)));
}

N_Vector with_state_ops(N_Vector v) {
  if (!v) throw std::bad_alloc();
  if (N_VEnableFusedOps_Serial(v, SUNTRUE) != 0) {
    N_VDestroy(v);
    throw std::runtime_error("N_VEnableFusedOps_Serial failed");
  }
  v->ops->nvwsqrsumlocal = weighted_square_sum;
  v->ops->nvwrmsnorm = weighted_rms_norm;
  return v;
}
}  // namespace

N_Vector make_state_vector(SUNContext ctx, int n) { return with_state_ops(N_VNew_Serial(n, ctx)); }

N_Vector make_view_vector(SUNContext ctx, int n) { return with_state_ops(N_VMake_Serial(n, nullptr, ctx)); }

SUNMatrix make_dense_matrix(SUNContext ctx, int n) {
  SUNMatrix A = SUNDenseMatrix(n, n, ctx);
  if (!A) throw std::bad_alloc();
  install_matrix_ops(A);
  return A;
}

SUNLinearSolver make_dense_lu(SUNContext ctx, int n) {
  auto c = std::make_unique<DenseLu>(n);
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (!S) throw std::bad_alloc();
  S->ops->gettype = get_type;
  S->ops->getid = get_id;
  S->ops->initialize = initialize;
  S->ops->setup = newton_lu_setup;
  S->ops->solve = newton_lu_solve;
  S->ops->lastflag = last_flag;
  S->ops->free = free_solver;
  S->content = c.release();
  return S;
}

}  // namespace pumasim::detail
