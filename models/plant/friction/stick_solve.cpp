#include "models/plant/friction/stick_solve.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pumasim {

void StickSolver::reserve(int capacity) {
  if (capacity <= cap_) return;
  cap_ = capacity;
  const auto c = static_cast<std::size_t>(capacity);
  a_.resize(c * c), rhs_.resize(c), v_.resize(c), r_try_.resize(c), mode_try_.resize(c), idx_.resize(c);
}

double StickSolver::scale(const StickProblem& p) const {
  double sc = 0.0;
  for (int j = 0; j < p.k; ++j) {
    const double wjj = p.W[j * p.k + j];
    sc = std::max({sc, std::max(p.s[j], p.kin[j]), wjj > 0 ? std::abs(p.b[j]) / wjj : 0.0});
  }
  return sc > 0 ? sc : 1.0;
}

// Relative violation, in units of r: a stuck joint's |v_j| / W_jj and its
// |r_j| beyond s_j; a slipping joint's r_j off -σ k_j and its speed against σ.
double StickSolver::residual(const StickProblem& p, const double* r, const int* mode) {
  double worst = 0.0;
  for (int j = 0; j < p.k; ++j) {
    double v = p.b[j];
    for (int i = 0; i < p.k; ++i) v += p.W[j * p.k + i] * r[i];
    const double wjj = p.W[j * p.k + j] > 0 ? p.W[j * p.k + j] : 1.0;
    double e = 0.0;
    if (mode[j] == 0) {
      e = std::max(std::abs(v) / wjj, std::abs(r[j]) - std::max(p.s[j], p.kin[j]));
      if (p.may_stick && !p.may_stick[j]) e = std::max(e, 1.0 * scale(p));  // not an option
    } else {
      e = std::max(std::abs(r[j] + mode[j] * p.kin[j]), std::max(0.0, -mode[j] * v) / wjj);
    }
    worst = std::max(worst, e);
  }
  return worst / scale(p);
}

bool StickSolver::solve_for_modes(const StickProblem& p, const int* mode, double* r, double* v) {
  const int k = p.k;
  int m = 0;  // stuck joints, in idx_
  for (int j = 0; j < k; ++j) {
    if (mode[j] == 0) idx_[m++] = j;
    r[j] = mode[j] == 0 ? 0.0 : -mode[j] * p.kin[j];
  }
  // Rows of the stuck joints: W_SS r_S = -(b_S + W_SL r_L), into a_ | rhs_.
  for (int a = 0; a < m; ++a) {
    const int j = idx_[a];
    double sum = p.b[j];
    for (int i = 0; i < k; ++i) sum += p.W[j * k + i] * r[i];  // r_S = 0 so far
    rhs_[a] = -sum;
    for (int c = 0; c < m; ++c) a_[a * m + c] = p.W[j * k + idx_[c]];
  }
  for (int c = 0; c < m; ++c) {  // Gaussian elimination, partial pivoting
    int piv = c;
    for (int a = c + 1; a < m; ++a) {
      if (std::abs(a_[a * m + c]) > std::abs(a_[piv * m + c])) piv = a;
    }
    if (!(std::abs(a_[piv * m + c]) > 0)) return false;
    if (piv != c) {
      for (int q = 0; q < m; ++q) std::swap(a_[c * m + q], a_[piv * m + q]);
      std::swap(rhs_[c], rhs_[piv]);
    }
    for (int a = c + 1; a < m; ++a) {
      const double f = a_[a * m + c] / a_[c * m + c];
      for (int q = c; q < m; ++q) a_[a * m + q] -= f * a_[c * m + q];
      rhs_[a] -= f * rhs_[c];
    }
  }
  for (int c = m - 1; c >= 0; --c) {
    double sum = rhs_[c];
    for (int q = c + 1; q < m; ++q) sum -= a_[c * m + q] * r[idx_[q]];
    r[idx_[c]] = sum / a_[c * m + c];
  }
  for (int j = 0; j < k; ++j) {
    v[j] = p.b[j];
    for (int i = 0; i < k; ++i) v[j] += p.W[j * k + i] * r[i];
  }
  return true;
}

StickResult StickSolver::pgs(const StickProblem& p, double* r, int* mode) {
  StickResult res;
  const int k = p.k;
  const double tol = 1e-10 * scale(p);
  for (int j = 0; j < k; ++j) r[j] = 0.0, mode[j] = 0;
  for (res.iterations = 1; res.iterations <= kMaxSweeps; ++res.iterations) {
    bool changed = false;
    for (int j = 0; j < k; ++j) {
      const double wjj = p.W[j * k + j];
      if (!(wjj > 0)) throw std::invalid_argument("stick solve: expected a positive diagonal of W");
      double vp = p.b[j];
      for (int i = 0; i < k; ++i) vp += i == j ? 0.0 : p.W[j * k + i] * r[i];
      const double hold = -vp / wjj;
      const bool can_stick = !p.may_stick || p.may_stick[j];
      const double s = std::max(p.s[j], p.kin[j]);
      int m = 0;
      double rj = hold;
      if (!(can_stick && std::abs(hold) <= s) && (std::abs(hold) >= p.kin[j] || can_stick)) {
        m = vp >= 0 ? 1 : -1;
        rj = -m * p.kin[j];
      }
      changed = changed || m != mode[j] || std::abs(rj - r[j]) > tol;
      r[j] = rj, mode[j] = m;
    }
    if (!changed) {
      res.converged = true;
      break;
    }
  }
  res.iterations = std::min(res.iterations, kMaxSweeps);
  return res;
}

// The fallback: the consistent assignment with the most stuck joints (the
// first in enumeration order among equals).
bool StickSolver::enumerate_best(const StickProblem& p, double* r, int* mode) {
  int best_stuck = -1;
  enumerate(p, [&](const int* m, const double* rr) {
    int stuck = 0;
    for (int j = 0; j < p.k; ++j) stuck += m[j] == 0;
    if (stuck <= best_stuck) return;
    best_stuck = stuck;
    std::copy(m, m + p.k, mode);
    std::copy(rr, rr + p.k, r);
  });
  return best_stuck >= 0;
}

StickResult StickSolver::solve(const StickProblem& p, double* r, int* mode) {
  if (p.k > cap_) throw std::invalid_argument("stick solve: more joints than the solver's capacity");
  StickResult res = pgs(p, r, mode);
  if (p.k == 0) {
    res.consistent = true;
    return res;
  }
  // The sweep's modes solved exactly; its own r if that system is singular.
  if (solve_for_modes(p, mode, r_try_.data(), v_.data()) && residual(p, r_try_.data(), mode) <= 1e-9) {
    std::copy(r_try_.begin(), r_try_.begin() + p.k, r);
  } else if (p.k <= kMaxEnumerated) {
    res.enumerated = enumerate_best(p, r, mode);
  }
  res.residual = residual(p, r, mode);
  res.consistent = res.residual <= 1e-9;
  return res;
}

}  // namespace pumasim
