// The plant's implicit form F(t, x, x') = 0 (PlantModel::residual) and IDA
// on it (integrators/sundials_ida.cpp):
//  - F vanishes at the ODE's own derivative, x' = f(t, x), to rounding;
//  - F is affine in x' with the slope the form claims: the identity on every
//    row but the speeds', H(q) there (inverse dynamics is linear in qdd), the
//    identity on a joint the hybrid model holds;
//  - it factors no mass matrix: the Cholesky factorisations this thread made
//    (core/cholesky.hpp's counter) do not change over residual calls, where
//    one right-hand side adds one;
//  - its Newton matrix dF/dx + c dF/dx' agrees with central differences of F;
//  - IDA through the driver on the 6-joint hybrid scene finds the stick/slip
//    mode changes of a reference run, at its times, and ends within 100 rtol
//    of it;
//  - the paper's rule is refused, with the reason, before the run and by
//    the integrator.
// The conformance suites (tests/test_conformance.cpp) run IDA on
// Prothero-Robinson (F = x' - f) and on the smooth plant (this form).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/cholesky.hpp"
#include "integrators/registry.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "simulation/run.hpp"
#include "tests/residual_checks.hpp"
#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

using test::scene_path;

struct ResidualPoint {
  std::vector<double> x, f, r;
};

// x(0) of the scene, moved off rest (speeds and the currents' equilibrium
// perturbed) so that every term of F is at work; f there, and F(0, x, f).
ResidualPoint point_of(Plant& plant) {
  ResidualPoint p;
  const int m = plant.size();
  p.x.resize(m), p.f.resize(m), p.r.resize(m);
  plant.initial_state(p.x.data());
  const StateLayout& l = plant.layout();
  for (int j = 0; j < l.n; ++j) {
    p.x[l.qd + j] += 0.05 * (j + 1);
    if (l.i >= 0) p.x[l.i + j] += 0.01 * (j + 1);
  }
  plant.rhs(0.0, p.x.data(), p.f.data());
  plant.residual(0.0, p.x.data(), p.f.data(), p.r.data());
  return p;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double e : v) m = std::max(m, std::abs(e));
  return m;
}

// F(t, x, f(t, x)) = 0: the speeds' rows H f_qd + h - tau to rounding
// relative to the joint torques' size, the others exactly as f's own
// arithmetic (1e-12 of the largest rate, to allow a reordering).
TEST(ImplicitForm, VanishesAtTheOdesDerivative) {
  for (const char* name : {"paper_slow_viscous", "paper_slow_6dof_hybrid", "smooth_line_quintic"}) {
    SCOPED_TRACE(name);
    Plant plant(load_scene(scene_path(name)).plant);
    const ResidualPoint p = point_of(plant);
    const StateLayout& l = plant.layout();
    std::vector<double> speeds, others;
    for (int i = 0; i < plant.size(); ++i) {
      (i >= l.qd && i < l.qd + l.n ? speeds : others).push_back(p.r[i]);
    }
    EXPECT_LT(max_abs(speeds), 1e-10 * std::max(1.0, max_abs(p.f)));
    EXPECT_LE(max_abs(others), 1e-12 * max_abs(p.f));
  }
}

// F(x, f + d) - F(x, f) = D d with D the identity but on the free joints'
// speed rows, where it is H(q) (every column), and on a held joint's, where it
// is the identity too.
TEST(ImplicitForm, IsAffineInTheDerivativeWithTheMassMatrixOnTheSpeeds) {
  for (const char* name : {"paper_slow_viscous", "paper_slow_6dof_hybrid"}) {
    SCOPED_TRACE(name);
    Plant plant(load_scene(scene_path(name)).plant);
    const ResidualPoint p = point_of(plant);
    const StateLayout& l = plant.layout();
    const int m = plant.size(), n = l.n;
    std::vector<double> d(m), xp(m), r(m);
    for (int i = 0; i < m; ++i) d[i] = 0.3 * std::sin(1.7 * i + 0.2), xp[i] = p.f[i] + d[i];
    plant.residual(0.0, p.x.data(), xp.data(), r.data());
    Eigen::MatrixXd H(n, n);
    plant.mass_matrix(p.x.data() + l.q, H);
    int held = 0;
    for (int i = 0; i < m; ++i) {
      double expected = d[i];
      const int j = i - l.qd;
      const bool speed = j >= 0 && j < n;
      if (speed && plant.slip_mode(j) == SlipMode::kStuck && plant.joint_has_modes(j) && plant.has_mode_events()) {
        ++held;
      } else if (speed) {
        expected = 0;
        for (int k = 0; k < n; ++k) expected += H(j, k) * d[l.qd + k];
      }
      EXPECT_NEAR(r[i] - p.r[i], expected, 1e-9 * std::max(1.0, std::abs(expected))) << plant.layout().names[i];
    }
    if (std::string(name) == "paper_slow_6dof_hybrid") EXPECT_GT(held, 0) << "no joint held at the start";
  }
}

// The residual factors no mass matrix; one right-hand side factors one (the
// counter sees the back-end's factorisation: the instrument works).
TEST(ImplicitForm, FactorsNoMassMatrix) {
  for (const char* name : {"paper_slow_viscous", "paper_slow_6dof_hybrid"}) {
    SCOPED_TRACE(name);
    Plant plant(load_scene(scene_path(name)).plant);
    ResidualPoint p = point_of(plant);
    const long before = cholesky_factorisations();
    for (int k = 0; k < 100; ++k) plant.residual(1e-3 * k, p.x.data(), p.f.data(), p.r.data());
    EXPECT_EQ(cholesky_factorisations(), before);
    plant.rhs(0.0, p.x.data(), p.f.data());
    EXPECT_GE(cholesky_factorisations(), before + 1);
  }
}

// dF/dx + c dF/dx' at (x, f(x)) against central differences of F (steps
// 1e-6 max(1, |x_i|)): within 1e-6 of the largest entry of its row. At the
// consistent point the matrix is exact by construction; off it (x' != f) it
// misses (dH/dq)(x'_qd - f_qd) in the speeds' rows, which this test does
// not see (Newton's iteration only needs an approximation).
TEST(ImplicitForm, NewtonMatrixAgreesWithDifferencesOfTheResidual) {
  for (const char* name : {"paper_slow_viscous", "paper_slow_6dof_hybrid"}) {
    SCOPED_TRACE(name);
    Plant plant(load_scene(scene_path(name)).plant);
    const ResidualPoint p = point_of(plant);
    testing::expect_newton_matrix_matches_differences(plant, p.x, p.f, 250.0);
  }
}

struct DriverRun {
  std::vector<double> x;  // at the end, per unit of each state's scale
  std::vector<ModeChange> changes;
  IntegratorStats stats;
  bool ok = false;
};

DriverRun run_hybrid(const std::string& method, double rtol, double atol, double t_end) {
  Plant plant(load_scene(scene_path("paper_slow_6dof_hybrid")).plant);
  IntegratorOptions o;
  o.rtol = rtol, o.atol = atol;
  auto integ = make_integrator(method, o);
  DriverRun d;
  const RunResult r =
      run_plant(plant, *integ, {.t_end = t_end, .output_interval = t_end, .observe = [&](double, const double* s) {
                                  d.x.assign(s, s + plant.size());
                                }});
  d.ok = r.ok;
  d.stats = integ->stats();
  d.changes = plant.mode_changes();
  for (std::size_t i = 0; i < d.x.size(); ++i) d.x[i] /= plant.tolerance_scale(static_cast<int>(i));
  return d;
}

// IDA on the implicit form with the hybrid model's events, at rtol 1e-8
// over 3 s, against a reference run (CVODE's BDF on the ODE at rtol 1e-12):
// the same stick/slip mode changes, joint by joint and in order, each at a
// time within 1e-6 s of the reference's (located to the root finder's
// tolerance, with the state's error of about rtol shifting the crossing),
// and the end state within 100 rtol of the reference per unit of each
// state's scale (the conformance suite's bound), with its Jacobian reused
// over Newton set-ups.
TEST(ImplicitForm, IdaFindsTheHybridEventsOfTheReference) {
  const double rtol = 1e-8;
  const DriverRun ida = run_hybrid("ida", rtol, 1e-3 * rtol, 3.0), ref = run_hybrid("cvode-bdf", 1e-12, 1e-15, 3.0);
  ASSERT_TRUE(ida.ok);
  ASSERT_TRUE(ref.ok);
  ASSERT_GT(ref.changes.size(), 6u);  // the start's modes and at least one change after
  ASSERT_EQ(ida.changes.size(), ref.changes.size());
  double worst_t = 0;
  for (std::size_t k = 0; k < ref.changes.size(); ++k) {
    EXPECT_EQ(ida.changes[k].joint, ref.changes[k].joint) << "change " << k;
    EXPECT_EQ(ida.changes[k].mode, ref.changes[k].mode) << "change " << k;
    worst_t = std::max(worst_t, std::abs(ida.changes[k].t - ref.changes[k].t));
  }
  EXPECT_LT(worst_t, 1e-6);
  double worst = 0;
  for (std::size_t i = 0; i < ida.x.size(); ++i) worst = std::max(worst, std::abs(ida.x[i] - ref.x[i]));
  EXPECT_LT(worst, 100 * rtol);
  // With the Jacobian kept over set-ups (sundials_ida.cpp), fewer Jacobians
  // than Newton set-ups.
  EXPECT_LT(ida.stats.jacobian_evaluations, ida.stats.linear_solves);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3e s, %.3e", worst_t, worst);
  RecordProperty("event_time_and_end_state_differences", buf);
}

// The paper's rule has no residual form: refused before the run, naming the
// joint and the law, and by the integrator on the plant.
TEST(ImplicitForm, ThePapersRuleIsRefusedWithItsReason) {
  const Scene sc = load_scene(scene_path("paper_slow"));
  RunOptions a;
  a.integrator = "ida";
  try {
    plan_run(sc, a);
    ADD_FAILURE() << "ida accepted the paper's rule";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 1's friction law (friction.model = \"paper\") switches at rest"),
              std::string::npos)
        << e.what();
  }
  Plant plant(sc.plant);
  PlantSystem sys(plant);
  std::vector<double> x(static_cast<std::size_t>(plant.size()));
  plant.initial_state(x.data());
  IntegratorOptions o;
  auto integ = make_integrator("ida", o);
  EXPECT_THROW(integ->reset(sys, 0.0, x.data()), std::invalid_argument);
}

}  // namespace
}  // namespace pumasim
