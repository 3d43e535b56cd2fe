// An open-loop input in time: rows t_0 = 0 < t_1 < ... < t_{m-1}, each with
// one value per simulated joint (read from a file by the scene), and between
// rows either a zero-order hold (row k's values on [t_k, t_{k+1})) or the
// straight line from row k to row k + 1. After the last row its values hold.
// Piece k is [t_k, t_{k+1}] (k < m - 1) and the last piece [t_{m-1}, inf), so
// the rows t_1 ... t_{m-1} are where the input jumps (hold) or kinks (line):
// the plant stops the integrators there (time events), and each piece is
// evaluated from inside: a step that ends at a row sees the left limit, the
// next one the right limit. Evaluating on the piece a step lies in (the hint
// the plant keeps since the last time event) costs O(1); a time outside it
// finds its piece by bisection, O(log m). Nothing allocates after construction.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/time_rule.hpp"

namespace pumasim {

enum class InputInterpolation { kZeroOrderHold, kLinear };

class InputTable {
 public:
  InputTable() = default;
  // rows: t, then n values; at least two rows, t from 0 strictly increasing
  // (the scene checks them, naming the file's line; std::invalid_argument here).
  InputTable(const std::vector<std::vector<double>>& rows, int n, InputInterpolation interpolation)
      : n_(n), interp_(interpolation) {
    if (rows.size() < 2) throw std::invalid_argument("plant: an open-loop input needs at least two rows");
    for (const std::vector<double>& r : rows) {
      if (r.size() != static_cast<std::size_t>(n + 1)) {
        throw std::invalid_argument("plant: an open-loop input's rows are t, then " + std::to_string(n) +
                                    " values (one per simulated joint)");
      }
      if (!t_.empty() && !(r[0] > t_.back())) throw std::invalid_argument("plant: open-loop input times must increase");
      t_.push_back(r[0]);
      v_.insert(v_.end(), r.begin() + 1, r.end());
    }
    if (t_[0] != 0.0) throw std::invalid_argument("plant: an open-loop input starts at t = 0");
    tol_ = time_tolerance(t_.back());  // core/time_rule.hpp
  }

  int pieces() const { return static_cast<int>(t_.size()); }
  double end() const { return t_.back(); }  // the last row's time [s]

  // The first row time strictly after t (+inf if none).
  double next_breakpoint(double t) const {
    const auto it = std::upper_bound(t_.begin(), t_.end(), t);
    return it == t_.end() ? std::numeric_limits<double>::infinity() : *it;
  }

  // The piece a step starting at t lies in: the number of rows after the
  // first whose time is <= t (to rounding).
  int piece_after(double t) const {
    return static_cast<int>(std::upper_bound(t_.begin() + 1, t_.end(), t + tol_) - (t_.begin() + 1));
  }

  // The piece to evaluate t on: `hint` when t lies in it (to rounding) or
  // `extend` (its formula continued past its ends), else the piece holding t.
  int resolve(double t, int hint, bool extend) const {
    const int m = pieces();
    if (hint >= 0 && hint < m &&
        (extend || (t >= t_[static_cast<std::size_t>(hint)] - tol_ &&
                    (hint == m - 1 || t <= t_[static_cast<std::size_t>(hint) + 1] + tol_)))) {
      return hint;
    }
    return piece_after(t);
  }

  // Joint j's value at t by piece k's formula.
  double value(int j, double t, int k) const {
    const std::size_t a = static_cast<std::size_t>(k) * static_cast<std::size_t>(n_) + static_cast<std::size_t>(j);
    if (interp_ == InputInterpolation::kZeroOrderHold || k == pieces() - 1) return v_[a];
    const std::size_t b = a + static_cast<std::size_t>(n_);
    const double t0 = t_[static_cast<std::size_t>(k)], t1 = t_[static_cast<std::size_t>(k) + 1];
    return v_[a] + (v_[b] - v_[a]) * ((t - t0) / (t1 - t0));
  }

 private:
  int n_ = 0;
  InputInterpolation interp_ = InputInterpolation::kZeroOrderHold;
  std::vector<double> t_;  // row times [s]
  std::vector<double> v_;  // row k's values at v_[k n .. k n + n - 1]
  double tol_ = 0.0;       // [s] rounding of a time at a row
};

}  // namespace pumasim
