// SceneTemplate (models/scene/scene.hpp): a load through a template is
// load_scene's load (the same resolved scene, the same inputs, the same
// errors) for every shipped scene, with and without overrides; what it
// shares (the robot, the reference and its table) is shared only between
// loads whose reference inputs are equal. And the cheaper pieces the
// ensemble's rows use: Reference::point is eval's point bit for bit, and the
// drive signals without the dynamics satisfy the motor's own equations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "models/plant/plant.hpp"
#include "models/reference/reference_table.hpp"
#include "models/scene/scene.hpp"
#include "simulation/run.hpp"
#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

using test::scene_path;

std::vector<std::string> shipped_scene_files() {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(PUMASIM_SCENES_DIR)) {
    if (e.path().extension() == ".toml") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// What a load gives that a user can see: the resolved scene (every value,
// and the footer naming every input file with its hash), and the inputs.
void expect_same_load(const Scene& a, const Scene& b, const std::string& what) {
  EXPECT_EQ(resolved_toml(a), resolved_toml(b)) << what;
  EXPECT_TRUE(a.inputs == b.inputs) << what;
  EXPECT_EQ(a.sources, b.sources) << what;
  EXPECT_EQ(a.duration, b.duration) << what;
}

std::string config_error_of(const std::function<void()>& load) {
  try {
    load();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneTemplate, EveryShippedSceneLoadsAsLoadSceneDoes) {
  const std::vector<std::string> files = shipped_scene_files();
  ASSERT_GE(files.size(), 20u);
  for (const std::string& f : files) {
    const SceneTemplate t(f);
    const Scene plain = load_scene(f);
    expect_same_load(t.load(), plain, f + ", first load");
    expect_same_load(t.load(), plain, f + ", second load (what was shared)");
  }
}

TEST(SceneTemplate, OverridesAndSetsAsLoadScene) {
  const std::string f = scene_path("paper_slow_viscous");
  const SceneTemplate t(f);
  const std::vector<std::vector<std::string>> cases = {
      {"motor.resistance=2.5"},       {"amplifier.gain=3.5", "motor.inductance=0.003"},
      {"reference.max_speed=0.05"},   {"scene.rotor_inertia=false"},
      {"scene.held=[0.1, 0.0, 0.0]"}, {"scene.joints=6", "scene.held=[]", "amplifier.gain=4.0"},
  };
  for (const auto& sets : cases) {
    std::string what = f;
    for (const std::string& s : sets) what += " " + s;
    std::string plain_error, template_error;
    std::optional<Scene> plain, through;
    try {
      plain = load_scene(f, sets);
    } catch (const ConfigError& e) {
      plain_error = e.what();
    }
    try {
      through = t.load(sets);
    } catch (const ConfigError& e) {
      template_error = e.what();
    }
    EXPECT_EQ(template_error, plain_error) << what;
    if (plain && through) expect_same_load(*through, *plain, what);
  }
  // The template's own sets come before each load's overrides, as load_scene's list.
  const SceneTemplate with_sets(f, {"motor.resistance=3.0"});
  expect_same_load(with_sets.load({"amplifier.gain=3.0"}),
                   load_scene(f, {"motor.resistance=3.0", "amplifier.gain=3.0"}), "sets then overrides");
}

TEST(SceneTemplate, ErrorsAsLoadSceneAndNothingKeptOfAFailure) {
  const std::string f = scene_path("paper_slow_viscous");
  const SceneTemplate t(f);
  for (const std::vector<std::string>& bad : std::vector<std::vector<std::string>>{
           {"motor.resistanc=1.0"}, {"motor.resistance=-1.0"}, {"reference.height=5.0"}, {"scene.robot=\"nope\""}}) {
    const std::string plain = config_error_of([&] { load_scene(f, bad); });
    EXPECT_NE(plain, "(no error)") << bad[0];
    EXPECT_EQ(config_error_of([&] { t.load(bad); }), plain) << bad[0];
    EXPECT_EQ(config_error_of([&] { t.load(bad); }), plain) << bad[0] << ", again";
  }
  expect_same_load(t.load(), load_scene(f), "after the failures");
  EXPECT_THROW(SceneTemplate(scene_path("no_such_scene")), ConfigError);
}

// A load reads a copy of the document parsed once, whose values have lost
// their source lines (toml++ copies none): a refusal that names a line of
// the file (here scene.held's, too long for one joint fewer) must still
// name it, as load_scene does, and so must the check of the integrator's
// name made after the load (load_checked_scene), for a name set in the file.
TEST(SceneTemplate, ARefusalNamesTheFilesLine) {
  const std::string f = scene_path("paper_slow_viscous");
  const SceneTemplate t(f);
  const std::string plain = config_error_of([&] { load_scene(f, {"scene.joints=2"}); });
  EXPECT_NE(plain.find(f + ":"), std::string::npos) << plain;  // file:line
  EXPECT_EQ(config_error_of([&] { t.load({"scene.joints=2"}); }), plain);

  std::ifstream in(f);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string was = "name = \"ab2\"";
  ASSERT_NE(text.find(was), std::string::npos);
  text.replace(text.find(was), was.size(), "name = \"no-such-method\"");
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "pumasim_template_line";
  std::filesystem::create_directories(dir);
  const std::string g = (dir / "unknown_method.toml").string();  // scene.robot is a name: read from anywhere
  std::ofstream(g) << text;
  const SceneTemplate u(g);
  const std::string expected = config_error_of([&] { load_checked_scene(g, {}); });
  EXPECT_NE(expected.find(g + ":"), std::string::npos) << expected;
  EXPECT_EQ(config_error_of([&] { load_checked_scene(u, {}); }), expected);
  std::filesystem::remove_all(dir);
}

TEST(SceneTemplate, SharesTheReferenceOnlyBetweenEqualInputs) {
  const std::string f = scene_path("paper_slow_viscous");
  const SceneTemplate t(f);
  const Scene a = t.load(), drive = t.load({"motor.resistance=2.5", "amplifier.gain=3.0"});
  ASSERT_TRUE(a.plant.reference && a.plant.reference_table);
  EXPECT_EQ(drive.plant.reference.get(), a.plant.reference.get());
  EXPECT_EQ(drive.plant.reference_table.get(), a.plant.reference_table.get());
  EXPECT_EQ(&a.plant.reference_table->reference(), a.plant.reference.get());
  // The table given is the one the plant model uses.
  const Plant p(a.plant);
  EXPECT_EQ(p.model().reference_table(), a.plant.reference_table.get());
  // Half the peak speed: the table timing's duration doubles (a law in s/L
  // and t v_max / L; Timing::table), so the reference was built again.
  const Scene slow = t.load({"reference.max_speed=0.05"});
  EXPECT_NE(slow.plant.reference.get(), a.plant.reference.get());
  EXPECT_NEAR(slow.duration, 2 * a.duration, 1e-9 * a.duration);
  const Scene held = t.load({"scene.held=[0.3, 0.0, 0.0]"});
  EXPECT_NE(held.plant.reference.get(), a.plant.reference.get());
  // More distinct references than kept: each load still has its own, right one.
  for (int k = 0; k < static_cast<int>(SceneTemplate::kShared) + 3; ++k) {
    const double v = 0.06 + 0.002 * k;
    const Scene s = t.load({"reference.max_speed=" + std::to_string(v)});
    expect_same_load(s, load_scene(f, {"reference.max_speed=" + std::to_string(v)}), "max_speed " + std::to_string(v));
  }
}

TEST(SceneTemplate, TimeOptimalTimingIsNotShared) {
  const std::string f = scene_path("planning");
  const SceneTemplate t(f);
  const Scene a = t.load(), b = t.load();
  EXPECT_NE(a.plant.reference.get(), b.plant.reference.get());  // its planner reads the drive
  expect_same_load(b, load_scene(f), f);
}

// Reference::point(t) against eval(t).p: a Cartesian path's point without
// the IK, a joint-space reference through the full evaluation; equal bits.
TEST(ReferencePoint, IsEvalsPointBitForBit) {
  for (const std::string name : {"paper_slow_viscous", "paper_fast_6dof", "joint_space_csv", "stanford_tracking"}) {
    const Scene sc = load_scene(scene_path(name));
    ASSERT_TRUE(sc.plant.reference) << name;
    const Reference& ref = *sc.plant.reference;
    ReferenceSample a = ref.sample(), b = ref.sample();
    const double T = ref.timing().duration();
    for (int k = 0; k <= 400; ++k) {
      const double t = T * k / 400.0;
      ref.eval(t, a);
      const Eigen::Vector3d p = ref.point(t, b);
      EXPECT_TRUE(p == a.p) << name << " at t = " << t << ": " << p.transpose() << " vs " << a.p.transpose();
    }
  }
}

// The drive signals without the friction and the dynamics: with the reduced
// motor (La = 0) the current is algebraic, i = (e_a - K w_m) / (R0 + R) with
// w_m = r qd, and e_a = sat(K_A u, V_max) (the motor's and the amplifier's
// equations, experiments/scenes/README.md), at a state away from the start.
TEST(DriveSignals, SatisfyTheAmplifierAndMotorEquations) {
  const Scene sc = load_scene(scene_path("paper_slow_viscous"), {"motor.inductance=0.0"});
  Plant p(sc.plant);
  const StateLayout& L = p.layout();
  std::vector<double> x(static_cast<std::size_t>(p.size()));
  p.initial_state(x.data());
  for (int j = 0; j < L.n; ++j) x[L.q + j] += 0.01 * (j + 1), x[L.qd + j] = 0.3 - 0.2 * j;
  std::vector<DriveSignals> d(static_cast<std::size_t>(L.n));
  p.drive_signals(0.7, x.data(), d.data());
  for (int j = 0; j < L.n; ++j) {
    const AmplifierParams& A = sc.plant.amplifier[j];
    const MotorParams& M = sc.plant.motor[j];
    const double ea = std::clamp(A.gain * d[j].u, -A.voltage_limit, A.voltage_limit);
    const double wm = sc.plant.robot.joints[j].gear_ratio * x[L.qd + j];
    EXPECT_NEAR(d[j].ea, ea, 1e-12 * A.voltage_limit) << "joint " << j + 1;
    EXPECT_NEAR(d[j].i, (ea - M.torque_constant * wm) / (A.output_resistance + M.resistance),
                1e-12 * (1 + std::abs(d[j].i)))
        << "joint " << j + 1;
    EXPECT_NE(d[j].u, 0.0) << "joint " << j + 1;  // the state is off the reference: the law acts
  }
}

}  // namespace
}  // namespace pumasim
