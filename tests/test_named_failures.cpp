// Failures named, not reported as successes (issue 31). The physical range of
// the plant's states (models/plant/physical_bounds.hpp; a diverged run was `ok`): the bounds follow the parameters by
// their closed forms (a driven joint's no-load speed V / (K Z) and current
// (V + K w_max) / (R0 + R); R x 10 divides the current's by 10), a passive
// arm's speed bound holds on an accurate run of it (energy cannot exceed
// E_avail), and a diverged run ends as a named "unstable" failure with exit
// status 1, warned of before it starts. The paper's rule, discontinuous in the
// state, is named so up front, and an adaptive method's step collapse on it is
// diagnosed as chattering. --rtol alone sets atol; absurd tolerances and a
// misspelt table are refused with the right message.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "experiments/cli.hpp"
#include "integrators/registry.hpp"
#include "models/plant/physical_bounds.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "simulation/run.hpp"
#include "tests/cli_capture.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

using testing::cli;
using testing::CliResult;

const std::string kScenes = PUMASIM_SCENES_DIR;

double full_command(const PlantConfig& pc, int j) {
  return command_voltage_range(pc.amplifier[static_cast<std::size_t>(j)],
                               controller_output_limit(pc.controller_params, j));
}

TEST(PhysicalBounds, DriveBoundsAreTheClosedForms) {
  for (const char* resistance : {"", "motor.resistance=21.0"}) {
    std::vector<std::string> sets;
    if (*resistance) sets.push_back(resistance);
    const Scene sc = load_scene(kScenes + "/paper_slow.toml", sets);
    Plant p(sc.plant);
    const StateLayout& L = p.layout();
    ASSERT_GE(L.i, 0);
    for (int j = 0; j < L.n; ++j) {
      const PlantConfig& pc = sc.plant;
      const double V = full_command(pc, j), K = pc.motor[j].torque_constant;
      const double Z = pc.robot.joints[static_cast<std::size_t>(j)].gear_ratio;
      const double R = pc.amplifier[j].output_resistance + pc.motor[j].resistance;
      ASSERT_TRUE(std::isfinite(V) && V > 0);
      EXPECT_DOUBLE_EQ(p.physical_bound(L.qd + j), V / (K * std::abs(Z)));
      EXPECT_DOUBLE_EQ(p.physical_bound(L.i + j), 2 * V / R);  // (V + K (V / K)) / R
      EXPECT_NE(p.physical_bound_why(L.i + j).find("(R0 + R)"), std::string::npos);
      EXPECT_TRUE(std::isinf(p.physical_bound(L.q + j)));  // angles: no bound
    }
  }
}

TEST(PhysicalBounds, CurrentBoundScalesWithTheResistance) {
  const Scene a = load_scene(kScenes + "/paper_slow.toml");
  Scene b = a;
  for (auto& m : b.plant.motor) m.resistance *= 10;
  for (auto& amp : b.plant.amplifier) amp.output_resistance *= 10;
  Plant pa(a.plant), pb(b.plant);
  for (int j = 0; j < pa.layout().n; ++j) {
    const int k = pa.layout().i + j;
    EXPECT_NEAR(pb.physical_bound(k) * 10, pa.physical_bound(k), 1e-12 * pa.physical_bound(k));
    EXPECT_EQ(pb.physical_bound(pb.layout().qd + j), pa.physical_bound(pa.layout().qd + j));
  }
}

// A passive arm released at rest: its speeds on an accurate run (Dormand-
// Prince at rtol 1e-9) stay within the bound, which must hold for every
// trajectory; and the bound is finite (a check that checks something).
TEST(PhysicalBounds, PassiveArmSpeedsStayWithinTheEnergyBound) {
  for (const char* scene : {"passive_arm.toml", "planar2_passive.toml"}) {
    Scene sc = load_scene(kScenes + "/" + scene);
    Plant p(sc.plant);
    const StateLayout& L = p.layout();
    for (int j = 0; j < L.n; ++j) ASSERT_TRUE(std::isfinite(p.physical_bound(L.qd + j))) << scene;
    IntegratorOptions o;
    o.rtol = 1e-9, o.atol = 1e-11;
    auto integ = find_integrator("odeint-dopri5").make(o);
    double peak = 0;
    int worst = 0;
    const RunResult r = run_plant(
        p, *integ,
        {.t_end = std::min(sc.duration, 2.0), .output_interval = 1e-3, .observe = [&](double, const double* x) {
           for (int j = 0; j < L.n; ++j) {
             if (std::abs(x[L.qd + j]) / p.physical_bound(L.qd + j) > peak) {
               peak = std::abs(x[L.qd + j]) / p.physical_bound(L.qd + j), worst = j;
             }
           }
         }});
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_GT(peak, 0.0) << scene << ": the arm moved";
    EXPECT_LE(peak, 1.0) << scene << ": qd" << worst + 1 << " past its bound";
  }
}

// The reproducer: ab4 at 0.5 ms on the 6-joint hybrid scene diverged
// to a motor current of millions of amperes and was `ok`.
TEST(PhysicalBounds, ADivergedRunIsANamedUnstableFailure) {
  std::ostringstream out, err;
  const int status = run_cli({"run", kScenes + "/paper_slow_6dof_hybrid.toml", "--integrator", "ab4", "--dt", "5e-4",
                              "--out", (testing::scratch_root() / "pumasim_unstable_run").string(), "--force", "--quiet"},
                             out, err);
  EXPECT_EQ(status, kExitInternal) << err.str();
  const auto stats = nlohmann::json::parse(out.str());
  EXPECT_FALSE(stats["ok"].get<bool>());
  EXPECT_EQ(stats["failure_kind"], "unstable");
  const std::string why = stats["failure"];
  EXPECT_NE(why.find("unstable at t = "), std::string::npos) << why;
  EXPECT_NE(why.find("times its physical bound"), std::string::npos) << why;
  EXPECT_LT(stats["t_reached"].get<double>(), stats["t_end"].get<double>());
  // Warned of before it started: 0.5 ms is outside AB4's region at t = 0.
  EXPECT_NE(err.str().find("exceeds the largest stable step"), std::string::npos) << err.str();
}

// A stable run gets no warning and no failure.
TEST(PhysicalBounds, TheShippedPaperRunIsNeitherWarnedNorFlagged) {
  const Scene sc = load_checked_scene(kScenes + "/paper_slow.toml", {});
  const RunPlan plan = plan_run(sc, {.t_end = 2.0});
  EXPECT_EQ(stability_warning(plan.scene, plan.controls), "");
  RunRequest req;
  req.scene = &sc;
  req.options.t_end = 2.0;
  const RunRecord done = run(req);
  EXPECT_TRUE(done.run.result.ok) << done.run.result.failure;
}

}  // namespace
}  // namespace pumasim

namespace pumasim {
namespace {

// The paper's rule is discontinuous in the state: `check` says so, and `run`
// warns before an adaptive method starts on it, naming what to use instead.
TEST(NamedFailures, ThePapersRuleIsNamedDiscontinuousUpFront) {
  const CliResult c = cli({"check", kScenes + "/paper_slow.toml"});
  ASSERT_EQ(c.status, kExitOk) << c.err;
  EXPECT_NE(c.out.find("# note: friction.model = \"paper\" is discontinuous in the state"), std::string::npos);
  EXPECT_NE(c.out.find("moreau-jean"), std::string::npos);
  const CliResult smooth = cli({"check", kScenes + "/passive_arm.toml"});
  EXPECT_EQ(smooth.out.find("# note:"), std::string::npos) << smooth.out;
  const CliResult r = cli({"run", kScenes + "/paper_slow.toml", "--integrator", "cvode-bdf", "--rtol", "1e-6", "--t-end",
                     "0.05", "--out", (testing::scratch_root() / "pumasim_paper_bdf").string(), "--force", "--quiet"});
  EXPECT_NE(r.err.find("warning: cvode-bdf is adaptive and friction.model = \"paper\" is discontinuous"),
            std::string::npos)
      << r.err;
}

// An adaptive method grinding on the rule ends at its step budget with the
// chattering named (the joint, its sign changes), not with "more steps".
TEST(NamedFailures, AStepCollapseOnTheRuleIsDiagnosedAsChattering) {
  const CliResult r = cli({"run", kScenes + "/paper_slow.toml", "--integrator", "cvode-bdf", "--rtol", "1e-6",
                     "--max-steps", "20000", "--out", (testing::scratch_root() / "pumasim_chatter").string(), "--force", "--quiet"});
  EXPECT_EQ(r.status, kExitInternal) << r.err;
  const auto stats = nlohmann::json::parse(r.out);
  const std::string why = stats["failure"];
  EXPECT_EQ(stats["failure_kind"], "budget");
  EXPECT_NE(why.find("chattering at a friction switching surface: qd"), std::string::npos) << why;
  EXPECT_NE(why.find("rejected steps"), std::string::npos) << why;
  EXPECT_EQ(why.find("more steps: pumasim run --max-steps"), std::string::npos) << why;
}

// --rtol alone: atol = 1e-3 rtol (per unit of each state's scale), printed;
// absurd tolerances refused with the range.
TEST(NamedFailures, RtolAloneSetsAtolAndAbsurdTolerancesAreRefused) {
  const CliResult r = cli({"run", kScenes + "/passive_arm.toml", "--integrator", "cvode-bdf", "--rtol", "1e-10", "--t-end",
                     "0.01", "--out", (testing::scratch_root() / "pumasim_rtol_alone").string(), "--force"});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  const auto stats = nlohmann::json::parse(r.out);
  EXPECT_DOUBLE_EQ(stats["rtol"].get<double>(), 1e-10);
  EXPECT_DOUBLE_EQ(stats["atol"].get<double>(), 1e-13);
  EXPECT_NE(r.err.find("rtol 1e-10, atol 1e-13"), std::string::npos) << r.err;
  for (const char* bad : {"0.9", "1e-20"}) {
    const CliResult b = cli({"run", kScenes + "/passive_arm.toml", "--integrator", "cvode-bdf", "--rtol", bad});
    EXPECT_EQ(b.status, kExitBadInput) << bad;
    EXPECT_NE(b.err.find("--rtol: expected a number in [1e-14, 0.1]"), std::string::npos) << b.err;
  }
  const CliResult s = cli({"check", kScenes + "/passive_arm.toml", "--set", "integrator.rtol=0.9"});
  EXPECT_EQ(s.status, kExitBadInput) << s.err;
  EXPECT_NE(s.err.find("integrator.rtol"), std::string::npos) << s.err;
}

// A misspelt table is named as unknown first, not as the missing half of the drive.
TEST(NamedFailures, AMisspeltTableIsNamedUnknown) {
  const std::string dir = (testing::scratch_root() / "pumasim_misspelt").string();
  std::filesystem::create_directories(dir);
  std::ifstream in(kScenes + "/paper_slow.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const auto at = s.find("[motor]");
  ASSERT_NE(at, std::string::npos);
  s.replace(at, 7, "[motors]");
  const std::string file = dir + "/scene.toml";
  std::ofstream(file) << s;
  const CliResult c = cli({"check", file});
  EXPECT_EQ(c.status, kExitBadInput);
  EXPECT_NE(c.err.find("unknown key 'motors'"), std::string::npos) << c.err;
  EXPECT_EQ(c.err.find("both [amplifier] and [motor]"), std::string::npos) << c.err;
}

}  // namespace
}  // namespace pumasim

namespace pumasim {
namespace {

// Sizes bounded before they are spent (issue 32): each case is refused at
// once with exit status 2, naming what bounded it, instead of allocating
// gigabytes (a derived duration, a file without end) or looping in place.
TEST(Bounded, SizesAreRefusedBeforeTheyAreSpent) {
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"check", "/dev/zero"}, "expected an input file of at most 16 MiB"},
      {{"check", kScenes + "/paper_slow.toml", "--set", "reference.max_speed=1e-9"}, "the reference's duration"},
      {{"check", kScenes + "/planning.toml", "--set", "friction.viscous=0x7fffffff"}, "output rows over"},
      {{"run", kScenes + "/sampled_control.toml", "--set", "controller.mode=\"sampled\"", "--set",
        "controller.servo_period=1e-30", "--max-steps", "0"},
       "controller.servo_period: expected a period that advances the time"},
  };
  for (const Case& c : cases) {
    std::ostringstream out, err;
    EXPECT_EQ(run_cli(c.args, out, err), kExitBadInput) << c.args[1] << ": " << err.str();
    EXPECT_NE(err.str().find(c.says), std::string::npos) << err.str();
  }
  // An earlier end time rescues the run: the bound is on the rows a run holds.
  std::ostringstream out, err;
  EXPECT_EQ(run_cli({"run", kScenes + "/paper_slow.toml", "--set", "reference.max_speed=1e-9", "--t-end", "0.05",
                     "--out", (testing::scratch_root() / "pumasim_slow_reference").string(), "--force", "--quiet"},
                    out, err),
            kExitOk)
      << err.str();
}

// A scene's rtol without atol: atol = 1e-3 rtol, as --rtol alone sets it.
TEST(Bounded, SceneRtolAloneSetsAtol) {
  EXPECT_DOUBLE_EQ(load_scene(kScenes + "/passive_arm.toml", {"integrator.rtol=1e-10"}).integrator.atol, 1e-13);
  EXPECT_DOUBLE_EQ(load_scene(kScenes + "/passive_arm.toml", {"integrator.rtol=1e-10", "integrator.atol=1e-9"})
                       .integrator.atol,
                   1e-9);
}

}  // namespace
}  // namespace pumasim
