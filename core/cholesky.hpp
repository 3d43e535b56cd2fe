// Cholesky<S, N>: in-place H = L L^T and solves, for the small dense SPD
// mass matrices of the dynamics back-ends (models/dynamics/), on any scalar S
// (double, the operation-counting Counted, the forward-mode Dual) and joint
// count N (fixed, or Eigen::Dynamic). Its workspace is allocated in the
// constructor and never after. Eigen only.
#pragma once

#include <cmath>
#include <type_traits>

#include <Eigen/Core>

namespace pumasim {

// In-place Cholesky factorisation H = L L^T and solve, for small dense SPD
// matrices; templated on the scalar so that its operations are counted too.
// Only H's lower triangle is read. A matrix that is not positive definite
// yields NaN (sqrt of a negative pivot), which the caller reports as a
// numerical failure; no branch, no throw.
//
// For a fixed size (n = 3, 6) the loops run row by row and unroll; for a
// dynamic size (large chains) the same operations, in the same number, run
// column by column (the gaxpy form of Golub & Van Loan, Matrix Computations,
// sec. 4.2; section quoted from memory),
// so that every inner loop reads contiguous memory and vectorises.
// How many factorisations this thread has made (every scalar and size): for
// the tests that show a computation factors no mass matrix (the plant's
// residual form, tests/test_ida.cpp). One increment per factorisation.
inline long& cholesky_factorisations() {
  thread_local long count = 0;
  return count;
}

template <class S, int N>
class Cholesky {
 public:
  explicit Cholesky(int n) : L_(n, n), inv_diag_(n) {
    L_.setZero();
    inv_diag_.setZero();
  }

  template <class M>
  void factor(const M& H) {
    ++cholesky_factorisations();
    if constexpr (N == Eigen::Dynamic) {
      factor_columns(H);
    } else {
      factor_rows(H);
    }
  }

  // x <- H^{-1} x
  template <class V>
  void solve_in_place(V&& x) const {
    if constexpr (N == Eigen::Dynamic) {
      solve_columns(x);
    } else {
      solve_rows(x);
    }
  }

  // X <- H^{-1} X for a matrix X (each column a right-hand side), and
  // X <- X H^{-1} (each row one), for the derivatives' many right-hand sides:
  // the same substitutions as solve_in_place, a whole row (or column) of X at
  // a time (on large matrices, Eigen's blocked triangular solves).
  template <class M>
  void solve_columns_in_place(M&& X) const {
    const int n = static_cast<int>(L_.rows());
    if constexpr (std::is_same_v<S, double>) {
      // Eigen's blocked solves win on large matrices, lose on small ones
      // (overhead); their work buffers are on the stack up to
      // EIGEN_STACK_ALLOCATION_LIMIT (128 KB): no heap below about n = 128.
      if (n > 12) {
        const auto L = L_.template triangularView<Eigen::Lower>();
        L.solveInPlace(X);
        L.transpose().solveInPlace(X);
        return;
      }
    }
    for (int j = 0; j < n; ++j) {  // L Y = X
      X.row(j) *= inv_diag_[j];
      for (int i = j + 1; i < n; ++i) X.row(i) -= L_(i, j) * X.row(j);
    }
    for (int i = n - 1; i >= 0; --i) {  // L^T Z = Y
      for (int k = i + 1; k < n; ++k) X.row(i) -= L_(k, i) * X.row(k);
      X.row(i) *= inv_diag_[i];
    }
  }
  // Hinv <- H^{-1} (both triangles), for the derivatives' many right-hand
  // sides: one product with H^{-1} (a matrix product, Eigen's blocked GEMM)
  // costs less than two triangular solves per right-hand side (Eigen's
  // blocked triangular solves reach a fraction of GEMM's speed at n = 24 to
  // 48). H^{-1} = L^{-T} L^{-1} = Y Y^T with Y = L^{-T} upper triangular,
  // built column by column from L^T Y = I: Y(i, i) = 1 / L(i, i) and
  //   Y(0:i, i) = Y(0:i, 0:i) c,   c = -L(i, 0:i)^T / L(i, i),
  // one matrix-vector product on the finished top-left block (its zeros
  // below the diagonal included: twice the n^3 / 6 multiply-adds, but one
  // vectorised product instead of i short updates, half the time at
  // n = 48), then Y Y^T. Y and c are the caller's workspace (n x n, n).
  // double only.
  template <class M, class W, class V>
  void inverse(M&& Hinv, W&& Y, V&& c) const {
    static_assert(std::is_same_v<S, double>, "Cholesky::inverse is for double");
    const int n = static_cast<int>(L_.rows());
    Y.setZero();
    for (int i = 0; i < n; ++i) {
      if (i > 0) {
        c.head(i) = L_.row(i).head(i).transpose() * (-inv_diag_[i]);
        Y.col(i).head(i).noalias() = Y.topLeftCorner(i, i) * c.head(i);
      }
      Y(i, i) = inv_diag_[i];
    }
    Hinv.noalias() = Y * Y.transpose();
  }

  template <class M>
  void solve_rows_in_place(M&& X) const {
    const int n = static_cast<int>(L_.rows());
    for (int j = 0; j < n; ++j) {  // Z L^T = X
      for (int k = 0; k < j; ++k) X.col(j) -= L_(j, k) * X.col(k);
      X.col(j) *= inv_diag_[j];
    }
    for (int j = n - 1; j >= 0; --j) {  // Y L = Z
      for (int k = j + 1; k < n; ++k) X.col(j) -= L_(k, j) * X.col(k);
      X.col(j) *= inv_diag_[j];
    }
  }

 private:
  template <class M>
  void factor_rows(const M& H) {
    using std::sqrt;
    const int n = static_cast<int>(L_.rows());
    for (int j = 0; j < n; ++j) {
      S d = H(j, j);
      for (int k = 0; k < j; ++k) d -= L_(j, k) * L_(j, k);
      L_(j, j) = sqrt(d);
      inv_diag_[j] = S(1) / L_(j, j);
      for (int i = j + 1; i < n; ++i) {
        S v = H(i, j);
        for (int k = 0; k < j; ++k) v -= L_(i, k) * L_(j, k);
        L_(i, j) = v * inv_diag_[j];
      }
    }
  }

  template <class V>
  void solve_rows(V& x) const {
    const int n = static_cast<int>(L_.rows());
    for (int i = 0; i < n; ++i) {
      S v = x[i];
      for (int k = 0; k < i; ++k) v -= L_(i, k) * x[k];
      x[i] = v * inv_diag_[i];
    }
    for (int i = n - 1; i >= 0; --i) {
      S v = x[i];
      for (int k = i + 1; k < n; ++k) v -= L_(k, i) * x[k];
      x[i] = v * inv_diag_[i];
    }
  }

  // Column j of L from column j of H less L(j:n, 0:j) L(j, 0:j)^T.
  template <class M>
  void factor_columns(const M& H) {
    using std::sqrt;
    const int n = static_cast<int>(L_.rows());
    for (int j = 0; j < n; ++j) {
      const int m = n - j;
      auto col = L_.col(j).segment(j, m);
      col = H.col(j).segment(j, m);
      if (j > 0) col.noalias() -= L_.block(j, 0, m, j).lazyProduct(L_.row(j).head(j).transpose());
      L_(j, j) = sqrt(L_(j, j));
      inv_diag_[j] = S(1) / L_(j, j);
      col.tail(m - 1) *= inv_diag_[j];
    }
  }

  // L y = x by columns (each solved entry removed from the ones below), then
  // L^T x = y by contiguous dot products.
  template <class V>
  void solve_columns(V& x) const {
    const int n = static_cast<int>(L_.rows());
    for (int i = 0; i < n; ++i) {
      const S xi = x[i] * inv_diag_[i];
      x[i] = xi;
      const int m = n - i - 1;
      if (m > 0) x.segment(i + 1, m) -= xi * L_.col(i).tail(m);
    }
    for (int i = n - 1; i >= 0; --i) {
      const int m = n - i - 1;
      S v = x[i];
      if (m > 0) v -= L_.col(i).tail(m).dot(x.segment(i + 1, m));
      x[i] = v * inv_diag_[i];
    }
  }

 private:
  Eigen::Matrix<S, N, N> L_;
  Eigen::Matrix<S, N, 1> inv_diag_;
};

}  // namespace pumasim
