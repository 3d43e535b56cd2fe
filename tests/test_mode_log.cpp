// The friction mode log (simulation/mode_log.hpp, events.csv) on
// one joint under a known input, against closed forms.
// The PUMA's first joint alone (vertical axis: no gravity torque; alone, its
// inertia J = H11 is constant, so h = 0 and the applied torque is the input
// reflected to the motor, u / Z), a torque input u(t) interpolated linearly
// through (0, 0), (T1, U), (2 T1, 0), then 0; Coulomb friction Fs, Fk and
// no viscous term. At rest the joint sticks until u / Z reaches Fs:
//   t_b = Z Fs T1 / U;
// then it slips forward, J qd' = u - Z Fk, until the impulse of u after t_b,
// I = U T1 - U t_b^2 / (2 T1) (the triangle's area less the part before t_b),
// equals Z Fk (t - t_b): if that is after 2 T1 (u = 0 there), the speed
// returns to zero at
//   t_s = t_b + I / (Z Fk),
// where it sticks for good (|u / Z| = 0 < Fs). Neither time depends on J.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "models/scene/scene.hpp"
#include "simulation/mode_log.hpp"
#include "simulation/scene_run.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

namespace fs = std::filesystem;

constexpr double kFs = 0.146, kFk = 0.124, kT1 = 0.02;  // [N m] motor side (the paper's levels), [s]
const std::string kLevels = "static_torque = 0.146\nkinetic_torque = 0.124\n";

// The scene (written to a fresh folder) with the [friction] section's keys
// `friction`; U = 2 Z Fs (Z < 0 here: u / Z rises from 0 to 2 Fs).
std::string scene_file(const std::string& friction) {
  const fs::path d = testing::scratch_root() /
                     ("pumasim_mode_log_" + std::to_string(::getpid()) + "_" +
                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::create_directories(d);
  const double Z = -62.6111;  // the PUMA's joint 1 gear ratio (models/robots/puma560.toml); checked below
  char csv[160];
  std::snprintf(csv, sizeof csv, "t,u1\n0,0\n%.17g,%.17g\n%.17g,0\n", kT1, 2 * Z * kFs, 2 * kT1);
  std::ofstream(d / "input.csv") << csv;
  std::ofstream(d / "scene.toml")
      << "[scene]\nname = \"mode_log_test\"\nrobot = \"puma560\"\njoints = 1\n"
         "held = [-0.6, 0.9, 0.1, 0.4, 0.2]\nduration = 0.08\noutput_interval = 0.01\n"
         "\n[controller]\nlaw = \"open_loop\"\nmode = \"continuous\"\ninput = \"torque\"\n"
         "interpolation = \"linear\"\nfile = \"input.csv\"\n\n[initial]\nq = [0.3]\n\n[friction]\n"
      << friction;
  return (d / "scene.toml").string();
}

struct Event {
  double t;
  int joint;
  std::string mode;
};

std::vector<Event> parse(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t,joint,mode,applied_torque,static_torque");
  std::vector<Event> out;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::string t, j, m;
    std::getline(row, t, ',');
    std::getline(row, j, ',');
    std::getline(row, m, ',');
    out.push_back({std::stod(t), std::stoi(j), m});
  }
  return out;
}

SceneRun run(const Scene& sc, const std::string& integrator, double output_interval) {
  Scene s = sc;
  s.integrator.name = integrator;
  s.output_interval = output_interval;
  RunControls rc;
  rc.options.dt = 1e-6;
  rc.options.rtol = 1e-10;
  rc.options.atol = 1e-13;
  SceneRun r = simulate_scene(s, rc);
  EXPECT_TRUE(r.result.ok) << r.result.failure;
  return r;
}

// Closed-form break-away and stick times for U = 2 Z Fs (t_b = T1 / 2).
void closed_form(double& t_b, double& t_s) {
  const double U_over_Z = 2 * kFs;
  t_b = kFs * kT1 / U_over_Z;
  const double I_over_Z = U_over_Z * kT1 - U_over_Z * t_b * t_b / (2 * kT1);
  t_s = t_b + I_over_Z / kFk;
  ASSERT_GT(t_s, 2 * kT1);  // the stick comes after the input ended, as the closed form assumes
}

// The hybrid model's events: at t = 0 stuck, slip + at t_b, stuck at t_s,
// located by CVODE's root finding (rtol 1e-10: the times to well under 1e-6 s).
TEST(ModeLog, HybridEventsAtTheClosedFormTimes) {
  const Scene sc = load_scene(scene_file(kLevels + "model = \"hybrid\"\n"));
  ASSERT_EQ(sc.plant.robot.joints[0].gear_ratio, -62.6111);
  double t_b = 0, t_s = 0;
  closed_form(t_b, t_s);
  const std::vector<Event> e = parse(run(sc, "cvode-bdf", 0.01).events_csv);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].t, 0.0);
  EXPECT_EQ(e[0].mode, "stick");
  EXPECT_EQ(e[1].mode, "slip+");
  EXPECT_NEAR(e[1].t, t_b, 1e-6);
  EXPECT_EQ(e[2].mode, "stick");
  EXPECT_NEAR(e[2].t, t_s, 1e-6);
  for (const Event& x : e) EXPECT_EQ(x.joint, 1);
}

// The paper's rule (no modes of its own) with RK4 at 1 us: the accepted steps
// classified. Break-away at the end of the first step past t_b (the stick
// branch no longer holds: |u / Z| > Fs); stuck from where |w_m| falls to
// kStickSpeed, at most kStickSpeed / (Z^2 Fk / J) before t_s (the speed
// falls at the constant rate Z^2 Fk / J motor side), and at most a step
// after. The same events whatever the output grid.
TEST(ModeLog, ClassifiedStepsAtTheClosedFormTimesWhateverTheOutputGrid) {
  const Scene sc = load_scene(scene_file(kLevels + "model = \"paper\"\n"));
  double t_b = 0, t_s = 0;
  closed_form(t_b, t_s);
  const double dt = 1e-6, Z = sc.plant.robot.joints[0].gear_ratio;  // Z^2: its sign does not matter
  const SceneRun r = run(sc, "rk4", 0.01);
  const std::vector<Event> e = parse(r.events_csv);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].mode, "stick");
  EXPECT_EQ(e[1].mode, "slip+");
  EXPECT_GE(e[1].t, t_b);
  EXPECT_LE(e[1].t, t_b + dt * 1.000001);
  EXPECT_EQ(e[2].mode, "stick");
  // J from the deceleration the run shows is not needed: bound it by the
  // arm's joint-1 inertia range, rotor included (J >= Jm Z^2 > 0.5 kg m^2).
  const double lead = kStickSpeed * 10.0 / (Z * Z * kFk);  // J <= 10 kg m^2
  EXPECT_GE(e[2].t, t_s - lead - dt);
  EXPECT_LE(e[2].t, t_s + dt * 1.000001);
  EXPECT_EQ(run(sc, "rk4", 0.0013).events_csv, r.events_csv);
}

// No Coulomb levels (viscous friction only): no modes, no events.csv.
TEST(ModeLog, NothingWithoutFrictionModes) {
  const Scene sc = load_scene(scene_file("model = \"viscous\"\nviscous = 1e-3\n"));
  const SceneRun r = run(sc, "rk4", 0.01);
  EXPECT_EQ(r.events_csv, "");
  EXPECT_EQ(r.mode_changes, 0);
}

}  // namespace
}  // namespace pumasim
