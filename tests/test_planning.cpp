// Trajectory planning: the timing laws, the time-optimal planner, joint-space
// interpolation through via-points, and the path's distance function.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/cli.hpp"
#include "models/scene/scene.hpp"
#include "models/reference/time_optimal.hpp"
#include "models/reference/timing.hpp"
#include "models/reference/trajectory.hpp"

#include "tests/scene_paths.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

using test::scene_path;

// s(0) = 0, s(T) = L, at rest at both ends; s and sd continuous; sd and sdd
// the derivatives of s and sd (central differences, away from the pieces'
// joints where sdd may jump).
void expect_consistent(const Timing& tm, double L, double T) {
  double s, sd, sdd;
  tm.eval(0.0, s, sd, sdd);
  EXPECT_EQ(s, 0.0) << tm.kind();
  EXPECT_NEAR(sd, 0.0, 1e-12) << tm.kind();
  tm.eval(T, s, sd, sdd);
  EXPECT_NEAR(s, L, 1e-12 * L) << tm.kind();
  EXPECT_NEAR(sd, 0.0, 1e-9) << tm.kind();
  EXPECT_NEAR(tm.duration(), T, 1e-12 * T) << tm.kind();
  const double h = 1e-6 * T;
  double worst_jump = 0, worst_d1 = 0, worst_d2 = 0;
  for (int k = 1; k < 997; ++k) {
    const double t = T * k / 997.0;
    double s0, v0, a0, s1, v1, a1, sm, vm, am;
    tm.eval(t - h, sm, vm, am);
    tm.eval(t, s0, v0, a0);
    tm.eval(t + h, s1, v1, a1);
    worst_jump = std::max(worst_jump, std::abs(s1 - sm) / (2 * h) - std::abs(v0));  // no jump in s
    worst_d1 = std::max(worst_d1, std::abs((s1 - sm) / (2 * h) - v0));
    if (std::abs(a1 - am) < 1e-6 * (1 + std::abs(a0))) {  // sdd smooth here
      worst_d2 = std::max(worst_d2, std::abs((v1 - vm) / (2 * h) - a0));
    }
  }
  const double v_scale = L / T, a_scale = L / (T * T);
  EXPECT_LT(worst_jump, 1e-6 * v_scale) << tm.kind();
  EXPECT_LT(worst_d1, 1e-6 * v_scale) << tm.kind();
  EXPECT_LT(worst_d2, 1e-5 * a_scale) << tm.kind();
}

// Closed forms: the trapezoid and the S-curve cruise at L / (T (1 - blend))
// (a symmetric acceleration phase covers half its duration times the cruise
// speed); the quintic peaks at 15 L / (8 T) at T / 2.
TEST(Timing, LawsReachTheEndAtRestWithTheirClosedFormPeakSpeeds) {
  const double L = 1.3, T = 4.0;
  const std::vector<Eigen::Vector2d> paper{{0.0, 0.0}, {0.08, 1.0}, {0.3, 1.0}, {0.4, 0.5},
                                           {0.55, 0.8}, {0.75, 0.8}, {0.9, 0.3}, {1.0, 0.0}};
  const Timing table = Timing::table_with_duration(paper, L, T);
  const Timing trap = Timing::trapezoid(L, T, 0.2);
  const Timing scurve = Timing::scurve(L, T, 0.25, 0.3);
  const Timing quintic = Timing::quintic(L, T);
  for (const Timing* tm : {&table, &trap, &scurve, &quintic}) expect_consistent(*tm, L, T);
  EXPECT_NEAR(trap.peak_speed(), L / (T * 0.8), 1e-12);
  EXPECT_NEAR(scurve.peak_speed(), L / (T * 0.75), 1e-12);
  double s, sd, sdd;
  quintic.eval(T / 2, s, sd, sdd);
  EXPECT_NEAR(sd, 15 * L / (8 * T), 1e-12);
  EXPECT_NEAR(s, L / 2, 1e-12);
  // The S-curve's acceleration is continuous: at most jerk * dt apart.
  double prev = 0, worst = 0;
  for (int k = 1; k <= 10000; ++k) {
    scurve.eval(T * k / 10000.0, s, sd, sdd);
    worst = std::max(worst, std::abs(sdd - prev));
    prev = sdd;
  }
  const double A = scurve.peak_speed() / (0.25 * T * 0.7), J = A / (0.3 * 0.25 * T);
  EXPECT_LT(worst, 1.0001 * J * T / 10000);
  // time_at inverts s(t).
  for (const Timing* tm : {&table, &trap, &scurve, &quintic}) {
    tm->eval(0.37 * T, s, sd, sdd);
    EXPECT_NEAR(tm->time_at(s), 0.37 * T, 1e-9 * T) << tm->kind();
  }
}

// The phase-plane passes under box limits |sdd| <= a, sd <= v: the minimum
// time is the closed form L / v + v / a (or 2 sqrt(L / a) when the speed
// limit is never reached), to within the grid's spacing.
TEST(TimeOptimal, BoxLimitsGiveTheClosedFormMinimumTime) {
  const double a = 2.0, v = 0.5;
  for (double L : {1.0, 0.05}) {
    const double exact = L >= v * v / a ? L / v + v / a : 2 * std::sqrt(L / a);
    for (int N : {100, 1000, 10000}) {
      std::vector<double> s(N + 1);
      for (int k = 0; k <= N; ++k) s[k] = L * k / N;
      const PhasePlaneResult r = time_optimal_grid(
          s, [&](int, double x) { return x <= v * v ? AccelerationBounds{-a, a} : AccelerationBounds{1, 0}; }, 1e4);
      const double T = Timing::phase_plane(r.s, r.sd).duration();
      const double err = std::abs(T - exact) / exact;
      EXPECT_GE(T, exact * (1 - 1e-12)) << "L " << L << " N " << N;  // nothing beats the optimum
      EXPECT_LT(err, 5.0 / N) << "L " << L << " N " << N;
    }
  }
}

// The planner on the planning scene (the paper's path and drives): checked
// against its own limits on a grid 10 times finer than its own (the stated
// tolerance: 1 % of the voltage limit); a uniformly 1 % faster timing
// violates a limit; and the fastest feasible trapezoid found by a simple
// search (bisection on T for each blend) is slower.
class PlannerOnTheScene : public ::testing::Test {
 protected:
  void SetUp() override {
    sc_ = load_scene(scene_path("planning"));
    setup_ = time_optimal_setup(sc_.plant, sc_.plant.n, sc_.reference);
    L_ = setup_.unit->path().length();
    const int fine = 10 * sc_.reference.grid;
    for (int k = 0; k <= fine; ++k) s_.push_back(L_ * k / fine);
    dyn_ = setup_.planner->path_dynamics(*setup_.unit, s_);
  }
  // The largest |demand| / limit over the fine grid for a timing scaled in speed by k.
  double worst_ratio(const Timing& tm, double k = 1.0, std::string* where = nullptr) const {
    double worst = 0;
    const DriveLimits& lim = setup_.planner->limits();
    for (std::size_t i = 0; i < s_.size(); ++i) {
      double s, sd, sdd;
      tm.eval(tm.time_at(s_[i]), s, sd, sdd);
      for (int j = 0; j < sc_.plant.n; ++j) {
        double volts, amps;
        setup_.planner->drive_demand(dyn_, static_cast<int>(i), j, k * sd, k * k * sdd, volts, amps);
        if (std::abs(volts) / lim.voltage[j] > worst) {
          worst = std::abs(volts) / lim.voltage[j];
          if (where) *where = "joint " + std::to_string(j + 1) + " at s = " + std::to_string(s_[i]) + " m";
        }
      }
    }
    return worst;
  }
  Scene sc_;
  PlanningSetup setup_;
  double L_ = 0;
  std::vector<double> s_;
  PathDynamics dyn_;
};

TEST_F(PlannerOnTheScene, RespectsTheLimitsAndNothingFasterIsFeasible) {
  const Timing& opt = sc_.plant.reference->timing();
  ASSERT_EQ(opt.kind(), "time-optimal");
  const double T = opt.duration();
  std::string where;
  EXPECT_LE(worst_ratio(opt, 1.0, &where), 1.01) << where;
  EXPECT_GT(worst_ratio(opt, 1.01), 1.01);  // 1 % faster: beyond the tolerance somewhere
  for (double blend : {0.05, 0.1, 0.2, 0.3, 0.4, 0.5}) {
    double lo = 0.5 * T, hi = 20 * T;  // lo infeasible (checked), hi feasible
    ASSERT_GT(worst_ratio(Timing::trapezoid(L_, lo, blend)), 1.0) << blend;
    ASSERT_LE(worst_ratio(Timing::trapezoid(L_, hi, blend)), 1.0) << blend;
    for (int it = 0; it < 30; ++it) {
      const double mid = 0.5 * (lo + hi);
      (worst_ratio(Timing::trapezoid(L_, mid, blend)) <= 1.0 ? hi : lo) = mid;
    }
    EXPECT_GT(hi, T) << "a trapezoid with blend " << blend << " in " << hi << " s beats the optimum " << T << " s";
  }
}

// Current and joint-speed limits (set in [planning]) hold along the planned
// timing on the finer grid, within the same 1 %, and make it slower.
TEST(PlannerLimits, CurrentAndSpeedLimitsHoldAndCostTime) {
  const Scene free = load_scene(scene_path("planning"));
  const Scene sc = load_scene(scene_path("planning"), {"planning.current_limit=4.0", "planning.joint_speed_limit=0.8"});
  const Timing& tm = sc.plant.reference->timing();
  EXPECT_GT(tm.duration(), free.plant.reference->timing().duration());
  const PlanningSetup setup = time_optimal_setup(sc.plant, sc.plant.n, sc.reference);
  const double L = setup.unit->path().length();
  std::vector<double> s;
  for (int k = 0; k <= 10 * sc.reference.grid; ++k) s.push_back(L * k / (10 * sc.reference.grid));
  const PathDynamics d = setup.planner->path_dynamics(*setup.unit, s);
  double worst_i = 0, worst_w = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    double ss, sd, sdd;
    tm.eval(tm.time_at(s[i]), ss, sd, sdd);
    for (int j = 0; j < sc.plant.n; ++j) {
      double volts, amps;
      setup.planner->drive_demand(d, static_cast<int>(i), j, sd, sdd, volts, amps);
      worst_i = std::max(worst_i, std::abs(amps) / 4.0);
      worst_w = std::max(worst_w, std::abs(d.dq[i][j]) * sd / 0.8);
    }
  }
  EXPECT_LE(worst_i, 1.01);
  EXPECT_LE(worst_w, 1.01);
  EXPECT_GT(std::max(worst_i, worst_w), 0.99);  // one of them binds somewhere
}

// Joint-space interpolation: through the via-points exactly (the Cartesian
// reference's angles there), off the path between them by an amount that
// falls as the via-points get denser -- faster for the quintic, whose pieces
// also match the reference's rates.
TEST(JointSpace, PassesThroughTheViaPointsAndConvergesToThePath) {
  const Scene sc = load_scene(scene_path("planning"), {"reference.timing=\"quintic\"", "reference.traversal_time=6.0"});
  const Reference& cart = *sc.plant.reference;
  const Path& path = cart.path();
  auto deviation = [&](Interpolation ip, int M, double* via_error) {
    const Reference ref(sc.plant.robot, sc.plant.n, sc.plant.q_held, sc.reference.config, sc.reference.orientation,
                        path, cart.timing(), ip, M);
    double worst = 0;
    *via_error = 0;
    ReferenceSample a, b;
    for (int k = 0; k <= M; ++k) {
      const double t = cart.timing().time_at(path.length() * k / M);
      ref.eval(t, a);
      cart.eval(t, b);
      *via_error = std::max(*via_error, (a.q - b.q).cwiseAbs().maxCoeff());
    }
    for (int k = 0; k <= 4000; ++k) {
      ref.eval(cart.timing().duration() * k / 4000, a);
      worst = std::max(worst, path.distance(a.p));
    }
    return worst;
  };
  for (Interpolation ip : {Interpolation::kJointCubic, Interpolation::kJointQuintic}) {
    double previous = 1.0;
    for (int M : {8, 16, 32}) {
      double via_error;
      const double d = deviation(ip, M, &via_error);
      EXPECT_LT(via_error, 1e-6) << M;  // time_at is exact to ~1e-15 T; the joints then agree to ~1e-9
      EXPECT_LT(d, previous / 3) << "interpolation " << static_cast<int>(ip) << " M " << M;
      previous = d;
    }
  }
}

// Distance to the path: points pushed off it sideways by d (less than the
// arcs' radius) and up by h are sqrt(d^2 + h^2) away.
TEST(PathDistance, OffsetPointsAreTheirOffsetAway) {
  const Path path({0.4, -0.25}, 0.0, -0.15, {{0.2, 0, 0}, {0, 0.08, M_PI}, {0.2, 0, 0}, {0, 0.05, -M_PI / 2}});
  for (int k = 0; k <= 200; ++k) {
    Eigen::Vector3d p, dp, ddp;
    path.eval(path.length() * k / 200, p, dp, ddp);
    EXPECT_NEAR(path.distance(p), 0.0, 1e-12);
    const Eigen::Vector3d normal(-dp.y(), dp.x(), 0.0);
    for (double d : {-0.01, 0.02}) {
      const Eigen::Vector3d off = p + d * normal + Eigen::Vector3d(0, 0, 0.003);
      // Near the joints of pieces another piece may be nearer: never farther.
      EXPECT_LE(path.distance(off), std::hypot(d, 0.003) + 1e-12);
      const double sk = path.length() * k / 200;
      bool inside = sk > 0.03 && sk < path.length() - 0.03;
      for (double joint : {0.2, 0.2 + 0.08 * M_PI, 0.4 + 0.08 * M_PI}) inside &= std::abs(sk - joint) > 0.03;
      if (inside) {
        EXPECT_NEAR(path.distance(off), std::hypot(d, 0.003), 1e-12) << k;
      }
    }
  }
}

// The hint (the piece to measure first) changes the work, never the
// distance: for every hint, out of range included, the same double as
// without one, and the piece it reports is at that distance.
TEST(PathDistance, TheHintChangesNothingButTheWork) {
  const Path path({0.4, -0.25}, 0.0, -0.15, {{0.2, 0, 0}, {0, 0.08, M_PI}, {0.2, 0, 0}, {0, 0.05, -M_PI / 2}});
  std::mt19937_64 g(35);
  std::uniform_real_distribution<double> x(0.2, 0.9), y(-0.5, 0.3), z(-0.3, 0.0);
  for (int k = 0; k < 500; ++k) {
    const Eigen::Vector3d p(x(g), y(g), z(g));
    const double plain = path.distance(p);
    for (int hint : {-3, 0, 1, 2, 3, 4, 99}) {
      int nearest = hint;
      EXPECT_EQ(path.distance(p, &nearest), plain) << k << " hint " << hint;
      ASSERT_GE(nearest, 0);
      ASSERT_LT(nearest, 4);
      int again = nearest;  // measured first, it is still the nearest
      EXPECT_EQ(path.distance(p, &again), plain);
      EXPECT_EQ(again, nearest);
    }
  }
}

// `pumasim run` reports the path deviation and the drive's peaks: at every
// output the distance to the path is at most the distance to the reference
// point (which lies on the path), and no amplifier voltage exceeds its limit.
TEST(RunReport, DeviationBelowTrackingErrorAndVoltagesWithinTheLimit) {
  const auto dir = testing::scratch_root() / "pumasim_planning_run";
  std::ostringstream out, err;
  ASSERT_EQ(run_cli({"run", scene_path("planning"), "--set", "reference.timing=\"quintic\"", "--set",
                     "reference.traversal_time=2.0", "--out", dir.string()},
                    out, err),
            0)
      << err.str();
  std::ifstream csv(dir / "trajectory.csv");
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> head;
  for (std::stringstream ss(line); std::getline(ss, line, ',');) head.push_back(line.substr(0, line.find(" [")));
  const auto col = [&](const std::string& h) { return std::find(head.begin(), head.end(), h) - head.begin(); };
  const auto e = col("path_error"), d = col("path_deviation"), v = col("e_a2");
  ASSERT_LT(d, static_cast<long>(head.size()));
  ASSERT_LT(v, static_cast<long>(head.size()));
  int rows = 0;
  double peak = 0;
  while (std::getline(csv, line)) {
    std::vector<double> x;
    for (std::stringstream ss(line); std::getline(ss, line, ',');) x.push_back(std::stod(line));
    EXPECT_LE(x[d], x[e] + 1e-9) << "row " << rows;
    EXPECT_LE(std::abs(x[v]), 40.0) << "row " << rows;
    peak = std::max(peak, std::abs(x[v]));
    ++rows;
  }
  EXPECT_GT(rows, 100);
  EXPECT_GT(peak, 0.0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pumasim
