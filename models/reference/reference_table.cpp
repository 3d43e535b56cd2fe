#include "models/reference/reference_table.hpp"

#include "core/time_rule.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace pumasim {

double ReferenceTable::sub_intervals(const Reference& ref) {
  const std::vector<double>& bp = ref.breakpoints();
  double total = 0;
  for (std::size_t s = 0; s < bp.size(); ++s) {
    const double a = s == 0 ? 0.0 : bp[s - 1], b = bp[s];
    total += std::max(1.0, std::ceil((b - a) / kSpan));
  }
  return total;
}

ReferenceTable::ReferenceTable(const Reference& ref, bool truncate)
    : ref_(ref), truncate_(truncate), n_(ref.simulated_joints()), blocks_(blocks_per_sample(ref)) {
  if (!(blocks(ref) <= kMaxBlocks)) {
    throw std::invalid_argument("reference table: expected at most " + std::to_string(static_cast<long>(kMaxBlocks)) +
                                " blocks (ReferenceTable::blocks: check before making one)");
  }
  const std::vector<double>& bp = ref.breakpoints();
  // Segment s is [bp[s-1], bp[s]] (bp[-1] = 0); the one after the last
  // breakpoint (the hold at the end) is not tabulated.
  for (std::size_t s = 0; s < bp.size(); ++s) {
    first_.push_back(static_cast<int>(subs_.size()));
    const double a = s == 0 ? 0.0 : bp[s - 1], b = bp[s];
    const int k = std::max(1, static_cast<int>(std::ceil((b - a) / kSpan)));
    for (int i = 0; i < k; ++i) {
      Sub sub;
      sub.a = a + (b - a) * i / k;
      sub.b = i + 1 == k ? b : a + (b - a) * (i + 1) / k;
      subs_.push_back(sub);
    }
  }
  first_.push_back(static_cast<int>(subs_.size()));
  coefs_.assign(subs_.size(), Coefs::Zero(blocks_ * kBlock, kDegree + 1));
  fill_sample_ = ref.sample();
  fill_values_ = Eigen::MatrixXd::Zero(blocks_ * kBlock, kDegree + 1);
  state_ = std::make_unique<std::atomic<State>[]>(subs_.size());
  for (std::size_t k = 0; k < subs_.size(); ++k) state_[k].store(kEmpty, std::memory_order_relaxed);
}

int ReferenceTable::filled() const {
  const std::lock_guard<std::mutex> lock(fill_lock_);
  return filled_;
}
int ReferenceTable::exact_fallbacks() const {
  const std::lock_guard<std::mutex> lock(fill_lock_);
  return fallbacks_;
}
int ReferenceTable::max_degree_kept() const {
  const std::lock_guard<std::mutex> lock(fill_lock_);
  return max_degree_kept_;
}

ReferenceTable::State ReferenceTable::state(int segment, int k) const {
  std::atomic<State>& s = state_[static_cast<std::size_t>(k)];
  const State seen = s.load(std::memory_order_acquire);
  if (seen != kEmpty) return seen;
  const std::lock_guard<std::mutex> lock(fill_lock_);
  if (s.load(std::memory_order_relaxed) == kEmpty) fill(segment, k);  // another thread may have filled it
  return s.load(std::memory_order_relaxed);
}

// Components: q (n), qd (n), qdd (n), p (3), v (3), then zeros to the block's end.
void ReferenceTable::pack(const ReferenceSample& s, double* c) const {
  const int n = n_;
  for (int j = 0; j < n; ++j) c[j] = s.q[j], c[n + j] = s.qd[j], c[2 * n + j] = s.qdd[j];
  for (int i = 0; i < 3; ++i) c[3 * n + i] = s.p[i], c[3 * n + 3 + i] = s.v[i];
}

void ReferenceTable::unpack(int b, const Eigen::Matrix<double, kBlock, 1>& v, ReferenceSample& out) const {
  const int n = n_, lo = b * kBlock, hi = lo + kBlock;
  // The part of [from, from + len) in this block, written to dst.
  const auto take = [&](int from, int len, double* dst) {
    for (int c = std::max(from, lo); c < std::min(from + len, hi); ++c) dst[c - from] = v[c - lo];
  };
  take(0, n, out.q.data());
  take(n, n, out.qd.data());
  take(2 * n, n, out.qdd.data());
  take(3 * n, 3, out.p.data());
  take(3 * n + 3, 3, out.v.data());
}

// The values at the Chebyshev extreme points x_k = cos(pi k / N) and the
// coefficients of the interpolant sum_j c_j T_j(x) (Trefethen 2013, ch. 3:
// c_j = (2 / N) sum_k'' f_k cos(pi j k / N), the end terms halved, c_0 and
// c_N halved too).
void ReferenceTable::fill(int segment, int k) const {
  Sub& sub = subs_[static_cast<std::size_t>(k)];
  constexpr int N = kDegree;
  Eigen::MatrixXd& f = fill_values_;
  ReferenceSample& s = fill_sample_;
  const double mid = 0.5 * (sub.a + sub.b), half = 0.5 * (sub.b - sub.a);
  for (int i = 0; i <= N; ++i) {
    const double t = i == 0 ? sub.b : i == N ? sub.a : mid + half * std::cos(std::numbers::pi * i / N);
    ref_.eval(t, s, segment, true);
    pack(s, f.col(i).data());
  }
  Coefs& c = coefs_[static_cast<std::size_t>(k)];
  for (int j = 0; j <= N; ++j) {
    c.col(j) = 0.5 * (f.col(0) + (j % 2 ? -1.0 : 1.0) * f.col(N));
    for (int i = 1; i < N; ++i) c.col(j) += std::cos(std::numbers::pi * ((j * i) % (2 * N)) / N) * f.col(i);
    c.col(j) *= (j == 0 || j == N ? 1.0 : 2.0) / N;
  }
  const double tail = (c.col(N - 1).cwiseAbs() + c.col(N).cwiseAbs()).maxCoeff();
  const State filled = tail <= kTailTol ? kTable : kExact;
  ++filled_;
  if (filled == kExact) {
    ++fallbacks_;
    state_[static_cast<std::size_t>(k)].store(kExact, std::memory_order_release);
    return;
  }
  double dropped = 0;  // sum over j >= d of the largest |c_j|: degree d is kept once it passes kChopTol
  int d = N;
  for (; d > 0 && truncate_; --d) {
    dropped += c.col(d).cwiseAbs().maxCoeff();
    if (dropped > kChopTol) break;
  }
  sub.degree = d;
  max_degree_kept_ = std::max(max_degree_kept_, d);
  state_[static_cast<std::size_t>(k)].store(kTable, std::memory_order_release);  // the sub-interval published
}

void ReferenceTable::eval(double t, ReferenceSample& out, int segment, bool extend) const {
  if (!ref_.fits(out)) out = ref_.sample();  // allocates once
  const int m = static_cast<int>(first_.size()) - 1;  // tabulated segments
  if (segment < 0 || segment >= m) return ref_.eval(t, out, segment, extend);
  const int k0 = first_[static_cast<std::size_t>(segment)], k1 = first_[static_cast<std::size_t>(segment) + 1];
  const double a = subs_[static_cast<std::size_t>(k0)].a, b = subs_[static_cast<std::size_t>(k1) - 1].b;
  const double tol = time_tolerance(b);  // Reference's rounding of a segment's ends (core/time_rule.hpp)
  if (!(t >= a - tol && t <= b + tol)) return ref_.eval(t, out, segment, extend);
  const int k = std::clamp(k0 + static_cast<int>((t - a) / (b - a) * (k1 - k0)), k0, k1 - 1);
  if (state(segment, k) == kExact) return ref_.eval(t, out, segment, extend);
  const Sub& sub = subs_[static_cast<std::size_t>(k)];
  // Clenshaw's recurrence for all components at once.
  const Coefs& c = coefs_[static_cast<std::size_t>(k)];
  const double x = (2 * t - sub.a - sub.b) / (sub.b - sub.a);
  using Col = Eigen::Matrix<double, kBlock, 1>;
  for (int blk = 0; blk < blocks_; ++blk) {
    const int r0 = blk * kBlock;
    Col b1 = Col::Zero(), b2 = Col::Zero();
    for (int j = sub.degree; j >= 1; --j) {
      const Col b0 = c.template block<kBlock, 1>(r0, j) + 2 * x * b1 - b2;
      b2 = b1;
      b1 = b0;
    }
    unpack(blk, c.template block<kBlock, 1>(r0, 0) + x * b1 - b2, out);
  }
}

}  // namespace pumasim
