// The coupled stick/slip problem of k joints at rest (or at the end of a
// time step), solved as one problem instead of releasing joints one at a
// time.
//
// Given the Delassus operator W (k x k; the inverse effective inertia seen by
// the joints' friction: Z H^-1 Z restricted to them at acceleration level,
// Z S A^-1 B at the velocity level of a time step; SPD or nearly), the free
// motion b (each joint's acceleration, or end-of-step speed, without its
// friction), and per joint a static level s_j and a kinetic level k_j with
// s_j >= k_j >= 0, find the friction r (a torque, or an impulse) with
//   v = b + W r
// and for each joint one of
//   stuck:            v_j = 0, |r_j| <= s_j
//   slipping, sign σ: r_j = -σ k_j, σ v_j >= 0 (moving in direction σ, or at 0).
// A joint with may_stick = false (one whose friction was just found at its
// static level, a break-away) only slips.
//
// The solution is unique when s = k and W is symmetric positive definite
// (then r minimises 1/2 r'Wr + b'r over the box |r_j| <= k_j; a time step's W
// = Z S A^-1 B is only nearly symmetric); with s > k a joint whose holding
// torque lies between k_j and s_j may stick or slip. The choice here is a
// local one: the projected Gauss-Seidel sweep below sticks a joint whenever
// sticking is consistent given the others' current r, joint by joint in index
// order, so among several solutions its answer can depend on the joints'
// order and need not have the most stuck joints (a referee's check of random
// problems found a few such cases); the enumeration's fallback takes the
// consistent assignment with the most stuck joints (the first in the
// enumeration's order among equals). The tests check only that the answer is
// one of the enumerated solutions.
//
// Method (solve): projected Gauss-Seidel. Per joint in turn, with the others'
// r fixed: v'_j = b_j + sum_{i != j} W_ji r_i, the holding value
// r* = -v'_j / W_jj; stuck (r_j = r*) if may_stick and |r*| <= s_j, else
// slipping in σ = sign(v'_j) (r_j = -σ k_j; then |v'_j| > k_j W_jj and v_j has
// sign σ). Stopping rule: a sweep that changes no joint's mode and no r_j by
// more than 1e-10 x the problem's scale (max_j max(s_j, |b_j| / W_jj)), or
// kMaxSweeps sweeps (then not converged). The sweep's modes are then solved
// exactly (the stuck joints' r from their rows of v = 0) and checked; if they
// are not consistent (PGS did not converge, or W is far from SPD) every
// assignment is enumerated (k <= kMaxEnumerated) and the choice above taken.
// Residual: the largest violation of the conditions by the returned (r, v),
// in units of r (a speed or acceleration violation divided by W_jj), relative
// to the problem's scale.
//
// Preallocated for a capacity of joints: solve() does not allocate.
#pragma once

#include <vector>

namespace pumasim {

struct StickProblem {
  int k = 0;
  const double* W = nullptr;           // row-major k x k
  const double* b = nullptr;           // free acceleration or speed
  const double* s = nullptr;           // static levels
  const double* kin = nullptr;         // kinetic levels
  const bool* may_stick = nullptr;     // nullptr: every joint may stick
};

struct StickResult {
  int iterations = 0;      // PGS sweeps
  double residual = 0.0;   // relative violation of the returned solution
  bool converged = false;  // PGS met its stopping rule
  bool enumerated = false; // the answer came from the enumeration
  bool consistent = false; // the returned (r, modes) satisfies the conditions (within 1e-9 of the scale)
};

class StickSolver {
 public:
  static constexpr int kMaxSweeps = 500;
  static constexpr int kMaxEnumerated = 8;  // 3^8 = 6561 assignments
  explicit StickSolver(int capacity = 0) { reserve(capacity); }
  void reserve(int capacity);
  int capacity() const { return cap_; }

  // The coupled solve: r (friction) and mode (0 stuck, +1 / -1 slipping) per joint.
  StickResult solve(const StickProblem& p, double* r, int* mode);
  // Projected Gauss-Seidel alone (r and mode as it leaves them).
  StickResult pgs(const StickProblem& p, double* r, int* mode);
  // The exact r and v = b + W r of one mode assignment (stuck joints: their
  // rows of v = 0 solved by Gaussian elimination with partial pivoting); false
  // when that system is singular.
  bool solve_for_modes(const StickProblem& p, const int* mode, double* r, double* v);
  // The relative residual of (r, mode) (see above); v = b + W r recomputed.
  double residual(const StickProblem& p, const double* r, const int* mode);
  // Every consistent assignment, visit(mode, r) for each; returns their number.
  template <class Visit>
  int enumerate(const StickProblem& p, Visit&& visit);

 private:
  double scale(const StickProblem& p) const;
  bool enumerate_best(const StickProblem& p, double* r, int* mode);
  int cap_ = 0;
  std::vector<double> a_, rhs_, v_, r_try_;
  std::vector<int> mode_try_, idx_;
};

template <class Visit>
int StickSolver::enumerate(const StickProblem& p, Visit&& visit) {
  int total = 1;
  for (int j = 0; j < p.k; ++j) total *= 3;
  int count = 0;
  for (int code = 0; code < total; ++code) {
    int c = code;
    bool allowed = true;
    for (int j = 0; j < p.k; ++j, c /= 3) {
      mode_try_[j] = c % 3 == 0 ? 0 : (c % 3 == 1 ? 1 : -1);
      if (mode_try_[j] == 0 && p.may_stick && !p.may_stick[j]) allowed = false;
    }
    if (!allowed || !solve_for_modes(p, mode_try_.data(), r_try_.data(), v_.data())) continue;
    if (residual(p, r_try_.data(), mode_try_.data()) > 1e-9) continue;
    ++count;
    visit(static_cast<const int*>(mode_try_.data()), static_cast<const double*>(r_try_.data()));
  }
  return count;
}

}  // namespace pumasim
