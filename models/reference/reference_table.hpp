// The reference tabulated per smooth piece: within each segment between two
// breakpoints (Reference::breakpoints), sub-intervals of at most kSpan
// seconds, each with a Chebyshev interpolant of degree kDegree (values at the
// Chebyshev extreme points, Trefethen, Approximation Theory and Approximation
// Practice, 2013, ch. 2-3) of every component the plant reads: q, qd, qdd of
// the n simulated joints, p and v (3n + 6 components, in blocks of kBlock:
// the PUMA's 6 joints fill one block, 3 joints one block with padding). Each component is interpolated from the
// exact reference's own value (qd and qdd are not differences of q), so
// their errors are of the same size. The nodes are evaluated on the
// segment's own formula (Reference::eval with the segment and extend), so
// the breakpoints stay exact: a sub-interval never straddles one.
//
// A sub-interval is filled the first time a time inside it is asked for
// (the storage is allocated once, at construction: lookups never allocate).
// Lookups are const and thread-safe: the table is one of the immutable parts
// that plant models share (models/plant/plant_model.hpp), so that threads
// evaluating f on one model share it. A sub-interval is filled under a lock,
// once, and published by its state (release/acquire); a filled one is read
// without a lock. Its coefficients depend only on the reference, so which
// thread fills it, and when, changes no value.
// Where the interpolant has not converged -- the magnitude of its last two
// Chebyshev coefficients, which bounds the error of a smooth function's
// interpolant to about that size (Trefethen 2013, ch. 8), above kTailTol
// in any component -- the sub-interval is marked and the exact reference
// is used there. Times outside the tabulated range (before 0, after the last
// breakpoint, a piece continued past its ends) use the exact reference too.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "models/reference/trajectory.hpp"

namespace pumasim {

class ReferenceTable {
 public:
  static constexpr int kDegree = 32;         // Chebyshev degree per sub-interval
  static constexpr double kSpan = 2.0;       // [s] longest sub-interval
  static constexpr double kTailTol = 1e-12;  // convergence test on the last two coefficients
  // Truncation: each sub-interval's series keeps degrees 0..d, d the
  // smallest with sum_{j > d} max_i |c_ij| <= kChopTol (the tail dropped).
  // As |T_j(x)| <= 1 on the interval, the cut changes no component by more
  // than kChopTol: an absolute bound in each component's own unit (rad,
  // rad/s, rad/s^2, m, m/s), far below the interpolant's error bound
  // (kTailTol). A smooth piece's series decays well before kDegree, and
  // Clenshaw's recurrence, a dependency chain as long as the degree, is the
  // table's whole cost per lookup.
  static constexpr double kChopTol = 1e-14;
  // Components per block: Clenshaw's recurrence runs on a block at once
  // (fixed-size vectors, no allocation).
  static constexpr int kBlock = 24;
  // The most blocks a table holds, over all its sub-intervals (for the PUMA,
  // 65,536 s of reference at kSpan; about 200 MB of coefficients): a longer
  // reference is not tabulated (the plant then evaluates it exactly), so that
  // a derived duration (a speed of 1e-9 m/s) allocates nothing before the
  // run's own bounds are checked.
  static constexpr double kMaxBlocks = 32768;
  // How many sub-intervals ref's table would have, and how many blocks,
  // counted without allocating (doubles: they may exceed any integer type).
  static double sub_intervals(const Reference& ref);
  static double blocks(const Reference& ref) { return sub_intervals(ref) * blocks_per_sample(ref); }
  static int blocks_per_sample(const Reference& ref) {
    return (3 * ref.simulated_joints() + 6 + kBlock - 1) / kBlock;
  }

  // Whether a reference is tabulated: a Cartesian path followed through its
  // inverse kinematics, of at most kMaxBlocks blocks.
  static bool tabulates(const Reference& ref) {
    return ref.has_path() && ref.interpolation() == Interpolation::kCartesian && blocks(ref) <= kMaxBlocks;
  }
  // The reference must outlive the table. Allocates all storage. truncate:
  // cut each series as above (false: every series keeps kDegree; for tests).
  explicit ReferenceTable(const Reference& ref, bool truncate = true);

  // As Reference::eval(t, out, segment, extend), from the interpolant where
  // there is one. Allocation-free; thread-safe.
  void eval(double t, ReferenceSample& out, int segment, bool extend) const;

  // How many sub-intervals were filled / fell back to the exact reference,
  // and the largest degree kept after truncation (for tests).
  int filled() const;
  int exact_fallbacks() const;
  int max_degree_kept() const;
  const Reference& reference() const { return ref_; }

 private:
  using Coefs = Eigen::Matrix<double, Eigen::Dynamic, kDegree + 1>;  // blocks_ x kBlock rows
  struct Sub {
    double a = 0, b = 0;
    int degree = kDegree;  // kept after truncation (written by fill, before its state)
  };
  enum State : char { kEmpty, kTable, kExact };
  // Sub-interval k's state, filling it first if it is empty.
  State state(int segment, int k) const;
  void fill(int segment, int k) const;  // under fill_lock_
  void pack(const ReferenceSample& s, double* c) const;
  // Block b's values v into out's components.
  void unpack(int b, const Eigen::Matrix<double, kBlock, 1>& v, ReferenceSample& out) const;

  const Reference& ref_;
  bool truncate_;
  int n_;       // simulated joints
  int blocks_;  // blocks per sample
  std::vector<int> first_;   // per segment: index of its first sub-interval; one past the end at the back
  // The lazily filled part: written only by fill(), under fill_lock_.
  mutable std::vector<Sub> subs_;
  mutable std::vector<Coefs> coefs_;  // per sub-interval
  mutable std::unique_ptr<std::atomic<State>[]> state_;  // per sub-interval; published last
  mutable std::mutex fill_lock_;
  mutable ReferenceSample fill_sample_;  // fill's scratch (under fill_lock_)
  mutable Eigen::MatrixXd fill_values_;  // the values at the nodes
  mutable int filled_ = 0, fallbacks_ = 0, max_degree_kept_ = 0;
};

}  // namespace pumasim
