// The tabulated reference (models/reference/reference_table.hpp) against the
// exact one (the inverse kinematics at every time, Reference::eval): on every
// segment between breakpoints, densely, every joint's q, qd and qdd as the
// controller reads them, within 1e-10 (rad, rad/s, rad/s^2); p and v within
// 1e-12 m, m/s; and exactly the exact reference where it is not tabulated.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "models/reference/reference_table.hpp"
#include "models/scene/scene.hpp"

#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

struct MaxError {
  double q = 0, qd = 0, qdd = 0, p = 0, v = 0;
};

// Largest differences over `per` equally spaced times per sub-interval span
// in each segment, ends included.
MaxError dense_check(const Reference& ref, ReferenceTable& table, int per) {
  MaxError e;
  const std::vector<double>& bp = ref.breakpoints();
  ReferenceSample exact, tab;
  for (std::size_t s = 0; s < bp.size(); ++s) {
    const double a = s == 0 ? 0.0 : bp[s - 1], b = bp[s];
    const int pts = std::max(2, static_cast<int>(std::ceil((b - a) / ReferenceTable::kSpan)) * per);
    for (int i = 0; i <= pts; ++i) {
      const double t = a + (b - a) * i / pts;
      ref.eval(t, exact, static_cast<int>(s));
      table.eval(t, tab, static_cast<int>(s), false);
      e.q = std::max(e.q, (exact.q - tab.q).cwiseAbs().maxCoeff());
      e.qd = std::max(e.qd, (exact.qd - tab.qd).cwiseAbs().maxCoeff());
      e.qdd = std::max(e.qdd, (exact.qdd - tab.qdd).cwiseAbs().maxCoeff());
      e.p = std::max(e.p, (exact.p - tab.p).cwiseAbs().maxCoeff());
      e.v = std::max(e.v, (exact.v - tab.v).cwiseAbs().maxCoeff());
    }
  }
  return e;
}

class ReferenceTableScenes : public ::testing::TestWithParam<const char*> {};

TEST_P(ReferenceTableScenes, WithinOneTenthOfANanoradianOfTheExactReference) {
  const Scene sc = load_scene(test::scene_path(GetParam()));
  ASSERT_TRUE(sc.plant.reference);
  const Reference& ref = *sc.plant.reference;
  ReferenceTable table(ref);
  const MaxError e = dense_check(ref, table, 800);  // 800 times per 2 s: 25 between two nodes
  EXPECT_LT(e.q, 1e-10);
  EXPECT_LT(e.qd, 1e-10);
  EXPECT_LT(e.qdd, 1e-10);
  EXPECT_LT(e.p, 1e-12);
  EXPECT_LT(e.v, 1e-12);
  EXPECT_GT(table.filled(), 0);
  EXPECT_EQ(table.exact_fallbacks(), 0);  // every sub-interval interpolated, none left to the exact IK
  char buf[128];
  std::snprintf(buf, sizeof buf, "q %.3g qd %.3g qdd %.3g p %.3g v %.3g; degree kept <= %d", e.q, e.qd, e.qdd, e.p,
                e.v, table.max_degree_kept());
  RecordProperty("max_errors", buf);
}

// The truncation (ReferenceTable::kChopTol) against the same table with every
// series at full degree: no component moves by more than the bound, |T_j| <= 1
// times the dropped coefficients, plus Clenshaw's rounding (a few ulps of the
// largest value); and the series do decay before the full degree, so the
// truncation is in effect.
TEST_P(ReferenceTableScenes, TruncationMovesNoComponentByMoreThanItsBound) {
  const Scene sc = load_scene(test::scene_path(GetParam()));
  const Reference& ref = *sc.plant.reference;
  ReferenceTable cut(ref), full(ref, false);
  const std::vector<double>& bp = ref.breakpoints();
  ReferenceSample a, b;
  double diff = 0, scale = 1;
  for (std::size_t s = 0; s < bp.size(); ++s) {
    const double t0 = s == 0 ? 0.0 : bp[s - 1], t1 = bp[s];
    const int pts = std::max(2, static_cast<int>(std::ceil((t1 - t0) / ReferenceTable::kSpan)) * 400);
    for (int i = 0; i <= pts; ++i) {
      const double t = t0 + (t1 - t0) * i / pts;
      cut.eval(t, a, static_cast<int>(s), false);
      full.eval(t, b, static_cast<int>(s), false);
      for (const auto& [x, y] : {std::pair{a.q, b.q}, {a.qd, b.qd}, {a.qdd, b.qdd}}) {
        diff = std::max(diff, (x - y).cwiseAbs().maxCoeff());
        scale = std::max(scale, y.cwiseAbs().maxCoeff());
      }
      for (const auto& [x, y] : {std::pair{a.p, b.p}, {a.v, b.v}}) {
        diff = std::max(diff, (x - y).cwiseAbs().maxCoeff());
        scale = std::max(scale, y.cwiseAbs().maxCoeff());
      }
    }
  }
  const double eps = std::numeric_limits<double>::epsilon();
  EXPECT_LE(diff, ReferenceTable::kChopTol + 64 * eps * scale);
  EXPECT_EQ(full.max_degree_kept(), ReferenceTable::kDegree);
  EXPECT_LT(cut.max_degree_kept(), ReferenceTable::kDegree);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ReferenceTableScenes,
                         ::testing::Values("paper_slow", "paper_slow_6dof_hybrid", "paper_slow_6dof"));

// Breakpoints stay exact: at each segment's ends the table gives that
// segment's own limit (the exact reference evaluated on the segment), and
// before the first / after the last tabulated time the exact reference.
TEST(ReferenceTable, KeepsTheSegmentsLimitsAtBreakpointsAndTheExactReferenceOutside) {
  const Scene sc = load_scene(test::scene_path("paper_slow_6dof_hybrid"));
  const Reference& ref = *sc.plant.reference;
  ReferenceTable table(ref);
  const std::vector<double>& bp = ref.breakpoints();
  ReferenceSample exact, tab;
  for (std::size_t s = 0; s + 1 < bp.size(); ++s) {
    for (int side = 0; side < 2; ++side) {  // segment s's right end, segment s + 1's left end
      const int seg = static_cast<int>(s) + side;
      ref.eval(bp[s], exact, seg);
      table.eval(bp[s], tab, seg, false);
      EXPECT_LT((exact.qdd - tab.qdd).cwiseAbs().maxCoeff(), 1e-10) << "breakpoint " << s << " side " << side;
    }
  }
  // After the last breakpoint (the hold): the exact reference, bit for bit.
  const int last = static_cast<int>(bp.size());
  ref.eval(bp.back() + 1.0, exact, last);
  table.eval(bp.back() + 1.0, tab, last, false);
  EXPECT_EQ(exact.q, tab.q);
  EXPECT_EQ(exact.qdd, tab.qdd);
  // A piece continued past its end (extend): the exact continuation.
  ref.eval(bp[0] + 1e-3, exact, 0, true);
  table.eval(bp[0] + 1e-3, tab, 0, true);
  EXPECT_EQ(exact.q, tab.q);
}

}  // namespace
}  // namespace pumasim
