// The drive's index-1 DAE: with La = 0 and motor.current = "algebraic" the
// currents stay in the state as algebraic unknowns i_motor with
//   0 = e_a - (R0 + R) i - K w_m,   w_m = Z qd,
// the limit La -> 0 of the current states' La di/dt = e_a - (R0 + R) i - K w_m,
// and IDA integrates the plant's residual form with them (IDASetId,
// IDACalcIC at each start). Checked:
//  - F's algebraic rows are the balance's residual, -(e_a - (R0 + R) i - K Z qd),
//    with e_a from the drive signals (a closed form), and read no x';
//  - the Newton matrix dF/dx + c dF/dx' agrees with central differences of F
//    on every row, the algebraic ones included;
//  - IDA completes the plant's start (currents holding gravity at rest,
//    millivolts off the balance) to a consistent one, and every other
//    method's reset leaves an ODE's start alone;
//  - at every output of a run the current satisfies the balance, and the
//    joint states agree with the reduced ODE's (currents eliminated) from a
//    reference run;
//  - hybrid friction's break-aways under a sampled controller come at the
//    reduced ODE's ticks (the plant settles the currents before the modes);
//  - the full model tends to the DAE as La -> 0 at the rate O(La) (Tikhonov's
//    theorem: Kokotovic, Khalil and O'Reilly, "Singular Perturbation Methods
//    in Control", 1986, ch. 1);
//  - the ODE methods, the stiffness analysis and the sensitivities refuse it,
//    naming the key, and the key with La > 0 is refused by the scene reader.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/errors.hpp"
#include "experiments/stiffness.hpp"
#include "integrators/registry.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "simulation/run.hpp"
#include "simulation/sensitivity.hpp"
#include "tests/integrator_helpers.hpp"
#include "tests/residual_checks.hpp"
#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

using test::scene_path;

const std::vector<std::string> kAlgebraic = {"motor.inductance=0", "motor.current=\"algebraic\""};

Scene dae_scene() { return load_scene(scene_path("paper_slow_viscous"), kAlgebraic); }

// e_a - (R0 + R) i - K Z qd [V] for joint j at x (e_a from the drive signals).
double balance(Plant& plant, const Scene& sc, double t, const double* x, int j) {
  const StateLayout& l = plant.layout();
  std::vector<DriveSignals> s(static_cast<std::size_t>(l.n));
  plant.drive_signals(t, x, s.data());
  const MotorBlock& m = plant.model().motor();
  const double Z = sc.plant.robot.joints[static_cast<std::size_t>(j)].gear_ratio;
  return s[static_cast<std::size_t>(j)].ea - m.loop_resistance(j) * x[l.i + j] -
         m.params(j).torque_constant * Z * x[l.qd + j];
}

// x(0) moved off rest (speeds and currents perturbed, so that the balance
// does not hold), f there.
// The balance as a current error [A]: i - (e_a - K Z qd) / (R0 + R), per
// unit of the current's scale (its absolute tolerance's).
double balance_error(Plant& plant, const Scene& sc, double t, const double* x, int j) {
  const StateLayout& l = plant.layout();
  return std::abs(balance(plant, sc, t, x, j)) / plant.model().motor().loop_resistance(j) /
         plant.tolerance_scale(l.i + j);
}

struct DaePoint {
  std::vector<double> x, f;
};
DaePoint off_rest(Plant& plant) {
  DaePoint p;
  const int m = plant.size();
  p.x.resize(m), p.f.resize(m);
  plant.initial_state(p.x.data());
  const StateLayout& l = plant.layout();
  for (int j = 0; j < l.n; ++j) p.x[l.qd + j] += 0.05 * (j + 1), p.x[l.i + j] += 0.3 * (j + 1);
  plant.rhs(0.0, p.x.data(), p.f.data());
  return p;
}

TEST(DaeCurrent, AlgebraicRowsAreTheVoltageBalanceAndReadNoDerivative) {
  const Scene sc = dae_scene();
  Plant plant(sc.plant);
  const StateLayout& l = plant.layout();
  ASSERT_GE(l.i, 0) << "no current slice";
  const DaePoint p = off_rest(plant);
  const int m = plant.size();
  std::vector<double> r(m), r2(m), xp = p.f;
  plant.residual(0.0, p.x.data(), xp.data(), r.data());
  for (int j = 0; j < l.n; ++j) {
    const double b = balance(plant, sc, 0.0, p.x.data(), j);
    EXPECT_GT(std::abs(b), 0.1) << "the point does not move the balance off 0";
    EXPECT_NEAR(r[l.i + j], -b, 1e-12 * std::max(1.0, std::abs(b))) << "joint " << j + 1;
    xp[l.i + j] += 7.0;  // the current's x' is in no row
  }
  plant.residual(0.0, p.x.data(), xp.data(), r2.data());
  for (int i = 0; i < m; ++i) EXPECT_EQ(r2[i], r[i]) << l.names[i];
}

// The plant puts algebraic currents on the balance itself wherever events
// change what they depend on (PlantModel::settle_currents): its start keeps
// it to rounding. Currents moved off it (0.3 A) are completed by IDA's reset
// (IDACalcIC) to within 10 rtol of each current's scale (the Newton bound of
// the run test below), the differential states x(0) untouched.
TEST(DaeCurrent, TheStartIsConsistentAndIdaCompletesAnInconsistentOne) {
  const Scene sc = dae_scene();
  Plant plant(sc.plant);
  PlantSystem sys(plant);
  std::vector<double> x(static_cast<std::size_t>(plant.size()));
  plant.initial_state(x.data());
  const StateLayout& l = plant.layout();
  for (int j = 0; j < l.n; ++j) EXPECT_LT(balance_error(plant, sc, 0.0, x.data(), j), 1e-14) << "joint " << j + 1;
  for (int j = 0; j < l.n; ++j) x[l.i + j] += 0.3;
  IntegratorOptions o;
  o.rtol = 1e-8, o.atol = 1e-11;
  auto integ = make_integrator("ida", o);
  integ->reset(sys, 0.0, x.data());
  const double* s = integ->state();
  double missed = 0, kept = 0;
  for (int j = 0; j < l.n; ++j) {
    missed = std::max(missed, balance_error(plant, sc, 0.0, x.data(), j));
    kept = std::max(kept, balance_error(plant, sc, 0.0, s, j));
  }
  EXPECT_GT(missed, 1e-3) << "the moved currents keep the balance: this test sees nothing";
  EXPECT_LT(kept, 10 * o.rtol);
  for (int i = 0; i < plant.size(); ++i) {
    if (!plant.model().algebraic_state(i)) EXPECT_EQ(s[i], x[static_cast<std::size_t>(i)]) << l.names[i];
  }
}

// Every other method's reset leaves an ODE's start as given, bit for bit
// (the driver reports integrator.state() after a reset, for a DAE's sake).
TEST(DaeCurrent, ResetLeavesAnOdesStartAlone) {
  Plant plant(load_scene(scene_path("paper_slow_viscous")).plant);
  PlantSystem sys(plant);
  std::vector<double> x(static_cast<std::size_t>(plant.size()));
  plant.initial_state(x.data());
  for (const std::string& name : testing::integrator_names()) {
    IntegratorOptions o;
    o.dt = 5e-4, o.rtol = 1e-6, o.atol = 1e-9;
    auto integ = make_integrator(name, o);
    integ->reset(sys, 0.0, x.data());
    EXPECT_TRUE(std::equal(x.begin(), x.end(), integ->state())) << name;
  }
}

// As tests/test_ida.cpp's check of the ODE's form (tests/residual_checks.hpp): central differences of F
// (steps 1e-6 max(1, |x_i|)) within 1e-6 of the largest entry of each row.
TEST(DaeCurrent, NewtonMatrixAgreesWithDifferencesOfTheResidual) {
  Plant plant(dae_scene().plant);
  const DaePoint p = off_rest(plant);
  const Eigen::MatrixXd N = testing::expect_newton_matrix_matches_differences(plant, p.x, p.f, 250.0);
  const StateLayout& l = plant.layout();
  EXPECT_EQ(N(l.i, l.i), plant.model().motor().loop_resistance(0)) << "dF/di = R0 + R, no c";
}

struct Rows {
  std::vector<double> t;
  std::vector<std::vector<double>> x;  // the output rows' states
  double worst_balance = 0;            // max balance_error, over joints and rows
  IntegratorStats stats;
  bool ok = false;
};

// `sets` on paper_slow_viscous over [0, t_end] by `method`, outputs every
// 0.01 s at step ends (the run stops there, so no output is interpolated).
Rows run_scene_rows(const std::vector<std::string>& sets, const std::string& method, double rtol, double t_end) {
  const Scene sc = load_scene(scene_path("paper_slow_viscous"), sets);
  Plant plant(sc.plant);
  IntegratorOptions o;
  o.rtol = rtol, o.atol = 1e-3 * rtol;
  auto integ = make_integrator(method, o);
  Rows rows;
  const bool dae = sc.plant.algebraic_current;
  const RunResult r = run_plant(plant, *integ,
                                {.t_end = t_end,
                                 .output_interval = 0.01,
                                 .observe =
                                     [&](double t, const double* x) {
                                       rows.t.push_back(t);
                                       rows.x.emplace_back(x, x + plant.size());
                                       for (int j = 0; dae && j < plant.layout().n; ++j) {
                                         rows.worst_balance =
                                             std::max(rows.worst_balance, balance_error(plant, sc, t, x, j));
                                       }
                                     },
                                 .stops = Stops::kEventsAndOutputs});
  rows.ok = r.ok;
  rows.stats = integ->stats();
  return rows;
}

// IDA on the DAE at rtol 1e-8 against the reduced ODE (the same model with
// the currents eliminated) by CVODE's BDF at rtol 1e-12, over 4 s: every
// output's joint states within 100 rtol per unit of each state's scale (the
// conformance suite's bound), and at every output the balance within 10 rtol
// of the current's scale: IDA's Newton iteration stops when its correction's
// weighted RMS norm is below 0.33 (weights rtol |x| + atol scale), so the
// algebraic row, linear in i, is left within about 0.33 sqrt(12) = 1.2 of a
// weight, a weight being at most about rtol of the current's scale (|i|
// stays below the stall current, the scale).
TEST(DaeCurrent, IdaMatchesTheReducedOdeAndKeepsTheBalance) {
  const double rtol = 1e-8;
  const Rows dae = run_scene_rows(kAlgebraic, "ida", rtol, 4.0);
  const Rows ref = run_scene_rows({"motor.inductance=0"}, "cvode-bdf", 1e-12, 4.0);
  ASSERT_TRUE(dae.ok);
  ASSERT_TRUE(ref.ok);
  ASSERT_EQ(dae.t.size(), ref.t.size());
  const Scene sc = dae_scene(), red = load_scene(scene_path("paper_slow_viscous"), {"motor.inductance=0"});
  Plant pd(sc.plant), pr(red.plant);
  double worst = 0;
  for (std::size_t k = 0; k < ref.t.size(); ++k) {
    ASSERT_EQ(dae.t[k], ref.t[k]);
    for (int i = 0; i < pr.size(); ++i) {  // the reduced state's names, found in the DAE's
      const std::string& name = pr.layout().names[static_cast<std::size_t>(i)];
      const auto at = std::find(pd.layout().names.begin(), pd.layout().names.end(), name) - pd.layout().names.begin();
      ASSERT_LT(at, pd.size()) << name;
      worst = std::max(worst, std::abs(dae.x[k][static_cast<std::size_t>(at)] - ref.x[k][static_cast<std::size_t>(i)]) /
                                  pr.tolerance_scale(i));
    }
  }
  EXPECT_LT(worst, 100 * rtol);
  EXPECT_LT(dae.worst_balance, 10 * rtol);
  char buf[96];
  std::snprintf(buf, sizeof buf, "states %.3e, balance %.3e (per unit of scale), %ld steps", worst, dae.worst_balance,
                dae.stats.steps);
  RecordProperty("differences", buf);
}

// The full model at La = 1e-5 and 1e-6 H (tau_e = La / (R0 + R) down to
// 0.5 us), by CVODE's BDF at rtol 1e-11, against the DAE (IDA at 1e-10) over
// 2 s: the joint angles' largest difference falls tenfold with La (a first-
// order rate: between 5 and 20), and stays far above the runs' own errors
// (the DAE against the reduced ODE is 100 times closer than the La = 1e-6 run,
// which the test above bounds at 100 rtol per scale).
TEST(DaeCurrent, TheInductiveModelTendsToTheDaeAtRateLa) {
  const Rows dae = run_scene_rows(kAlgebraic, "ida", 1e-10, 2.0);
  ASSERT_TRUE(dae.ok);
  double gap[2] = {0, 0};
  const double la[2] = {1e-5, 1e-6};
  const Scene sc = dae_scene();
  Plant pd(sc.plant);
  for (int r = 0; r < 2; ++r) {
    char set[64];
    std::snprintf(set, sizeof set, "motor.inductance=%g", la[r]);
    const Rows full = run_scene_rows({set}, "cvode-bdf", 1e-11, 2.0);
    ASSERT_TRUE(full.ok);
    ASSERT_EQ(full.t.size(), dae.t.size());
    for (std::size_t k = 0; k < dae.t.size(); ++k) {
      for (int j = 0; j < pd.layout().n; ++j) {
        const auto q = static_cast<std::size_t>(pd.layout().q + j);  // q leads both layouts
        gap[r] = std::max(gap[r], std::abs(full.x[k][q] - dae.x[k][q]));
      }
    }
  }
  const double ratio = gap[0] / gap[1];
  EXPECT_GT(ratio, 5.0);
  EXPECT_LT(ratio, 20.0);
  EXPECT_GT(gap[1], 1e-12) << "the La = 1e-6 run is no further from the DAE than the runs' own errors";
  char buf[96];
  std::snprintf(buf, sizeof buf, "max |dq| %.3e rad (1e-5 H), %.3e rad (1e-6 H), ratio %.2f", gap[0], gap[1], ratio);
  RecordProperty("gaps", buf);
}

// stick_slip (hybrid friction with events) under a sampled controller
// (5 ms ticks: each new output moves algebraic currents at once, which may
// push a stuck joint past its break-away torque at the tick), La = 0, over
// 6 s: IDA on the DAE at rtol 1e-8 makes the mode changes of the reduced ODE
// by CVODE's BDF at rtol 1e-12 -- the same joints, modes and order, each at a
// time within 1e-6 s (the hybrid scene's bound in tests/test_ida.cpp), so
// break-aways at the same ticks (a break-away decided from the currents
// before the tick came a tick, 5 ms, late).
TEST(DaeCurrent, SampledBreakAwaysComeAtTheReducedOdesTicks) {
  const std::vector<std::string> sampled = {"controller.mode=\"sampled\"", "controller.servo_period=0.005"};
  const auto changes = [&](std::vector<std::string> sets, const char* method, double rtol) {
    sets.insert(sets.end(), sampled.begin(), sampled.end());
    Plant plant(load_scene(scene_path("stick_slip"), sets).plant);
    IntegratorOptions o;
    o.rtol = rtol, o.atol = 1e-3 * rtol;
    auto integ = make_integrator(method, o);
    const RunResult r = run_plant(plant, *integ, {.t_end = 6.0, .output_interval = 6.0});
    EXPECT_TRUE(r.ok) << method << ": " << r.failure;
    return plant.mode_changes();
  };
  const std::vector<ModeChange> dae = changes(kAlgebraic, "ida", 1e-8);
  const std::vector<ModeChange> ref = changes({"motor.inductance=0"}, "cvode-bdf", 1e-12);
  ASSERT_GT(ref.size(), 6u);  // the start's modes and changes after
  ASSERT_EQ(dae.size(), ref.size());
  double worst_t = 0;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    EXPECT_EQ(dae[k].joint, ref[k].joint) << "change " << k;
    EXPECT_EQ(dae[k].mode, ref[k].mode) << "change " << k;
    worst_t = std::max(worst_t, std::abs(dae[k].t - ref[k].t));
  }
  EXPECT_LT(worst_t, 1e-6);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%zu changes, times within %.3e s", ref.size(), worst_t);
  RecordProperty("mode_changes", buf);
}

TEST(DaeCurrent, OdeMethodsAnalysesAndTheKeyWithInductanceRefuseIt) {
  const Scene sc = dae_scene();
  for (const char* method : {"cvode-bdf", "rk4", "radau5"}) {
    RunOptions a;
    a.integrator = method;
    try {
      plan_run(sc, a);
      ADD_FAILURE() << method << " accepted the DAE";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("motor.current = \"algebraic\""), std::string::npos) << e.what();
    }
  }
  RunOptions ida;
  ida.integrator = "ida";
  EXPECT_NO_THROW(plan_run(sc, ida));
  EXPECT_THROW(analyse_stiffness(sc, 1.0, 4, false), std::invalid_argument);
  EXPECT_NE(sensitivity_refusal(sc).find("motor.current"), std::string::npos);
  try {
    load_scene(scene_path("paper_slow_viscous"), {"motor.current=\"algebraic\""});  // La = 2 mH
    ADD_FAILURE() << "motor.current accepted with La > 0";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("motor.current applies only when every inductance = 0"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace pumasim
