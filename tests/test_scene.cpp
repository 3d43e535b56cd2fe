// The resolved scene round trip: resolved_toml(load_scene(f)), written to a
// file and loaded again, gives the same Scene and the same resolved text, for
// every shipped scene and for a few --set overrides (models/scene/: each
// section is read and written over one table of entries).
#include <gtest/gtest.h>

#include <functional>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "models/scene/scene.hpp"
#include "tests/scene_paths.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

namespace fs = std::filesystem;

using test::scene_path;

std::vector<std::string> shipped_scenes() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(PUMASIM_SCENES_DIR)) {
    if (e.path().extension() == ".toml") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The text after the header line (which names the source file).
// The scene itself: without the header line naming the source and the footer
// naming the files read (the copy reads itself, not the original).
std::string body(const std::string& resolved) {
  const std::size_t from = resolved.find('\n'), to = resolved.find("\n# input file: ");
  return resolved.substr(from, to == std::string::npos ? std::string::npos : to - from);
}

void expect_same_drive(const PlantConfig& a, const PlantConfig& b, const std::string& what) {
  ASSERT_EQ(a.amplifier.size(), b.amplifier.size()) << what;
  for (std::size_t j = 0; j < a.amplifier.size(); ++j) {
    EXPECT_EQ(a.amplifier[j].gain, b.amplifier[j].gain) << what;
    EXPECT_EQ(a.amplifier[j].output_resistance, b.amplifier[j].output_resistance) << what;
    EXPECT_EQ(a.amplifier[j].voltage_limit, b.amplifier[j].voltage_limit) << what;
  }
  ASSERT_EQ(a.motor.size(), b.motor.size()) << what;
  for (std::size_t j = 0; j < a.motor.size(); ++j) {
    EXPECT_EQ(a.motor[j].inductance, b.motor[j].inductance) << what;
    EXPECT_EQ(a.motor[j].resistance, b.motor[j].resistance) << what;
    EXPECT_EQ(a.motor[j].torque_constant, b.motor[j].torque_constant) << what;
  }
  ASSERT_EQ(a.friction.size(), b.friction.size()) << what;
  for (std::size_t j = 0; j < a.friction.size(); ++j) {
    EXPECT_EQ(a.friction[j].model, b.friction[j].model) << what;
    EXPECT_EQ(a.friction[j].viscous, b.friction[j].viscous) << what;
    EXPECT_EQ(a.friction[j].static_torque, b.friction[j].static_torque) << what;
    EXPECT_EQ(a.friction[j].kinetic_torque, b.friction[j].kinetic_torque) << what;
    EXPECT_EQ(a.friction[j].zero_speed, b.friction[j].zero_speed) << what;
    EXPECT_EQ(a.friction[j].speed_scale, b.friction[j].speed_scale) << what;
    EXPECT_EQ(a.friction[j].stribeck_speed, b.friction[j].stribeck_speed) << what;
    EXPECT_EQ(a.friction[j].bristle_stiffness, b.friction[j].bristle_stiffness) << what;
    EXPECT_EQ(a.friction[j].bristle_damping, b.friction[j].bristle_damping) << what;
    EXPECT_EQ(a.friction[j].dahl_exponent, b.friction[j].dahl_exponent) << what;
  }
}

void expect_same_controller(const PlantConfig& a, const PlantConfig& b, const std::string& what) {
  EXPECT_EQ(a.controller, b.controller) << what;
  EXPECT_EQ(a.servo_period, b.servo_period) << what;
  EXPECT_EQ(a.setpoint_interval, b.setpoint_interval) << what;
  // Every key of the law, from its own table: a new law needs no edit here.
  ASSERT_EQ(controller_law_name(a.controller_params), controller_law_name(b.controller_params)) << what;
  ASSERT_EQ(controller_joints(a.controller_params), controller_joints(b.controller_params)) << what;
  std::visit(
      [&](const auto& pa) {
        using Params = std::decay_t<decltype(pa)>;
        const Params& pb = std::get<Params>(b.controller_params);
        for (std::size_t j = 0; j < pa.joints.size(); ++j) {
          for (const auto& k : Params::Law::keys()) {
            EXPECT_EQ(pa.joints[j].*k.member, pb.joints[j].*k.member) << what << ": " << k.key << " of joint " << j;
          }
        }
        for (const auto& k : Params::Law::text_keys()) {
          EXPECT_EQ(pa.settings.*k.member, pb.settings.*k.member) << what << ": " << k.key;
          if (k.rows) { EXPECT_EQ(pa.settings.*k.rows, pb.settings.*k.rows) << what << ": " << k.key << "'s rows"; }
        }
      },
      a.controller_params);
}

void expect_same_plant(const PlantConfig& a, const PlantConfig& b, const std::string& what) {
  EXPECT_EQ(a.robot.dof(), b.robot.dof()) << what;
  EXPECT_EQ(a.robot.name, b.robot.name) << what;
  for (int j = 0; j < a.robot.dof() && j < b.robot.dof(); ++j) {
    EXPECT_EQ(a.robot.joints[j].rotor_inertia, b.robot.joints[j].rotor_inertia) << what;
  }
  EXPECT_EQ(a.n, b.n) << what;
  EXPECT_EQ(a.q_held, b.q_held) << what;
  EXPECT_EQ(a.backend, b.backend) << what;
  EXPECT_EQ(a.drive, b.drive) << what;
  EXPECT_EQ(a.energy_ledger, b.energy_ledger) << what;
  EXPECT_EQ(a.q0, b.q0) << what;
  expect_same_drive(a, b, what);
  expect_same_controller(a, b, what);
  ASSERT_EQ(a.reference != nullptr, b.reference != nullptr) << what;
  if (a.reference) {
    EXPECT_EQ(a.reference->timing().duration(), b.reference->timing().duration()) << what;
    const double T = a.reference->timing().duration();
    ReferenceSample ra, rb;
    for (double t : {0.0, 0.3 * T, 0.71 * T, T}) {
      a.reference->eval(t, ra);
      b.reference->eval(t, rb);
      EXPECT_EQ(ra.q, rb.q) << what << " t = " << t;
      EXPECT_EQ(ra.qd, rb.qd) << what << " t = " << t;
    }
  }
}

void expect_same_reference(const ReferenceSettings& a, const ReferenceSettings& b, const std::string& what) {
  EXPECT_EQ(a.height, b.height) << what;
  EXPECT_EQ(a.start, b.start) << what;
  EXPECT_EQ(a.heading, b.heading) << what;
  ASSERT_EQ(a.segments.size(), b.segments.size()) << what;
  for (std::size_t i = 0; i < a.segments.size(); ++i) {
    EXPECT_EQ(a.segments[i].length, b.segments[i].length) << what;
    EXPECT_EQ(a.segments[i].radius, b.segments[i].radius) << what;
    EXPECT_EQ(a.segments[i].angle, b.segments[i].angle) << what;
  }
  EXPECT_EQ(a.timing, b.timing) << what;
  EXPECT_EQ(a.profile, b.profile) << what;
  EXPECT_EQ(a.max_speed, b.max_speed) << what;
  EXPECT_EQ(a.traversal_time, b.traversal_time) << what;
  EXPECT_EQ(a.blend, b.blend) << what;
  EXPECT_EQ(a.jerk_fraction, b.jerk_fraction) << what;
  EXPECT_EQ(a.interpolation, b.interpolation) << what;
  EXPECT_EQ(a.via_segments, b.via_segments) << what;
  EXPECT_EQ(a.voltage_fraction, b.voltage_fraction) << what;
  EXPECT_EQ(a.current_limit, b.current_limit) << what;
  EXPECT_EQ(a.joint_speed_limit, b.joint_speed_limit) << what;
  EXPECT_EQ(a.grid, b.grid) << what;
  EXPECT_EQ(a.config.right_arm, b.config.right_arm) << what;
  EXPECT_EQ(a.config.elbow_up, b.config.elbow_up) << what;
  EXPECT_EQ(a.config.wrist_flip, b.config.wrist_flip) << what;
  EXPECT_EQ(a.orientation, b.orientation) << what;
}

void expect_same_scene(const Scene& a, const Scene& b, const std::string& what) {
  EXPECT_EQ(a.name, b.name) << what;
  EXPECT_EQ(a.robot_spec, b.robot_spec) << what;
  EXPECT_EQ(a.rotor_inertia, b.rotor_inertia) << what;
  EXPECT_EQ(a.duration, b.duration) << what;
  EXPECT_EQ(a.output_interval, b.output_interval) << what;
  EXPECT_EQ(a.integrator.name, b.integrator.name) << what;
  EXPECT_EQ(a.integrator.dt, b.integrator.dt) << what;
  EXPECT_EQ(a.integrator.rtol, b.integrator.rtol) << what;
  EXPECT_EQ(a.integrator.atol, b.integrator.atol) << what;
  EXPECT_EQ(a.has_reference, b.has_reference) << what;
  expect_same_reference(a.reference, b.reference, what);
  expect_same_plant(a.plant, b.plant, what);
}

// Loads `scene` with `overrides`, writes its resolved text next to the other
// temporary files, loads that, and compares the scenes and their texts.
void expect_round_trip(const std::string& scene, const std::vector<std::string>& overrides) {
  std::string what = fs::path(scene).stem().string();
  for (const auto& o : overrides) what += " --set " + o;
  const Scene a = load_scene(scene, overrides);
  const std::string text = resolved_toml(a);
  static int count = 0;
  const fs::path path = testing::scratch_root() /
                        ("pumasim_resolved_" + std::to_string(::getpid()) + "_" + std::to_string(++count) + ".toml");
  std::ofstream(path) << text;
  Scene b;
  try {
    b = load_scene(path.string());
  } catch (const ConfigError& e) {
    fs::remove(path);
    FAIL() << what << ": the resolved scene does not load: " << e.what() << "\n" << text;
  }
  fs::remove(path);
  EXPECT_EQ(body(text), body(resolved_toml(b))) << what;
  expect_same_scene(a, b, what);
  // The same text read with no file (load_scene_text, what an unpickled
  // pumasim.Scene loads), as if at the scene's own path.
  const Scene c = load_scene_text(text, scene);
  EXPECT_EQ(body(text), body(resolved_toml(c))) << what << " (from its text)";
  expect_same_scene(a, c, what + " (from its text)");
}

TEST(SceneRoundTrip, EveryShippedScene) {
  const auto scenes = shipped_scenes();
  ASSERT_GE(scenes.size(), 17u);
  for (const std::string& s : scenes) expect_round_trip(s, {});
}

TEST(SceneRoundTrip, Overrides) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> sets = {
      {"paper_slow", {"integrator.rtol=1e-7", "integrator.name=\"cvode-bdf\""}},
      {"stick_slip", {"friction.model=\"tanh\"", "friction.speed_scale=0.05"}},
      {"stick_slip", {"friction.model=\"karnopp\""}},
      {"stick_slip", {"friction.model=\"stribeck\"", "friction.stribeck_speed=0.2", "friction.speed_scale=0.02"}},
      {"stick_slip",
       {"friction.model=\"lugre\"", "friction.stribeck_speed=0.1", "friction.bristle_stiffness=[100.0, 200.0, 300.0]",
        "friction.bristle_damping=0.5"}},
      {"paper_slow_viscous",  // no static_torque in the file: Dahl has no static level
       {"friction.model=\"dahl\"", "friction.kinetic_torque=0.124", "friction.bristle_stiffness=100.0",
        "friction.dahl_exponent=2.0"}},
      {"paper_slow", {"friction.model=\"karnopp\"", "friction.zero_speed=0.01"}},
      {"paper_slow", {"controller.kp=[1, 2, 3]", "amplifier.voltage_limit=30"}},
      {"paper_slow",
       {"controller.mode=\"sampled\"", "controller.servo_period=2.5e-4", "controller.setpoint_interval=1e-3"}},
      {"paper_slow", {"motor.inductance=0"}},
      {"paper_slow_6dof", {"scene.energy_ledger=true", "scene.rotor_inertia=false"}},
      {"paper_slow", {"scene.held=[0.1, -0.2, 0.3]", "scene.backend=\"aba\""}},
      {"smooth_line_quintic", {"reference.timing=\"scurve\"", "reference.blend=0.3"}},
      {"paper_slow",
       {"reference.interpolation=\"joint-quintic\"", "reference.via_segments=4", "reference.arm=\"right\""}},
      {"planning", {"planning.grid=100", "planning.current_limit=[4.0, 5.0, 6.0]", "planning.joint_speed_limit=2.0"}},
      // Angles whose degrees do not all read back simply (deg -> rad -> deg).
      {"paper_slow",
       {"reference.segments=[{line = 0.1}, {arc_radius = 0.08, turn_degrees = 13.7}, "
        "{arc_radius = 0.08, turn_degrees = -45.1}, {arc_radius = 0.08, turn_degrees = 91.3}]"}},
  };
  for (const auto& [scene, set] : sets) expect_round_trip(scene_path(scene), set);
  expect_round_trip(scene_path("passive_arm"), {"initial.pose=\"qr\""});
  expect_round_trip(scene_path("energy_long_time"), {"initial.pose=\"qs\""});
}

// A scene whose robot is a URDF file (models/robots/puma560.urdf, the pose
// qr from its side file): its resolved scene, with the path made absolute,
// loads back to the same scene.
TEST(SceneRoundTrip, UrdfRobot) {
  const std::string urdf = std::string(PUMASIM_SCENES_DIR) + "/../../models/robots/puma560.urdf";
  expect_round_trip(scene_path("passive_arm"), {"scene.robot=\"" + urdf + "\"", "initial.pose=\"qr\""});
}

// The time-optimal scene plans without limits by default: its resolved
// [planning] says inf, which must load back (the scene README's "inf: none").
TEST(SceneRoundTrip, UnlimitedPlanningLoadsBack) {
  const Scene a = load_scene(scene_path("planning"));
  EXPECT_TRUE(std::isinf(a.reference.current_limit[0]));
  expect_round_trip(scene_path("planning"), {});
}

// The Stribeck law's break-away torque is its peak: one below the Coulomb
// level on some joint is refused, naming the key, the joint and both levels;
// and the law needs its Stribeck speed.
TEST(SceneEntries, StribeckNeedsItsPeakAboveCoulomb) {
  const std::vector<std::string> stribeck = {"friction.model=\"stribeck\"", "friction.stribeck_speed=0.14"};
  std::vector<std::string> low = stribeck;
  low.push_back("friction.static_torque=[0.146, 0.1, 0.146]");
  try {
    load_scene(scene_path("stick_slip"), low);
    ADD_FAILURE() << "a break-away torque below the Coulomb level loaded";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("friction.static_torque"), std::string::npos) << m;
    EXPECT_NE(m.find("joint 2: static_torque 0.1 N m below kinetic_torque 0.124 N m"), std::string::npos) << m;
  }
  EXPECT_THROW(load_scene(scene_path("stick_slip"), {"friction.model=\"stribeck\""}), ConfigError);  // no w_St
  // LuGre divides by its levels' G(w): a zero level is refused, naming it.
  try {
    load_scene(scene_path("stick_slip"),
               {"friction.model=\"lugre\"", "friction.stribeck_speed=0.1", "friction.bristle_stiffness=100.0",
                "friction.bristle_damping=0.6", "friction.kinetic_torque=0.0"});
    ADD_FAILURE() << "a LuGre law with Fk = 0 loaded";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("friction.kinetic_torque"), std::string::npos) << e.what();
  }
  const Scene ok = load_scene(scene_path("stick_slip"), stribeck);
  for (const FrictionParams& f : ok.plant.friction) EXPECT_EQ(f.stribeck_speed, 0.14);
}

// Per-joint arrays are checked against the simulated joints, and the robot's
// size against the 6-vectors, before anything is written.
TEST(SceneEntries, PerJointLengthsAreChecked) {
  for (const std::string& set : {std::string("controller.kp=[1, 2]"), std::string("friction.viscous=[1, 2, 3, 4]"),
                                 std::string("scene.held=[0.0]"), std::string("planning.grid=10")}) {
    EXPECT_THROW(load_scene(scene_path("paper_slow"), {set}), ConfigError) << set;
  }
  const Scene one = load_scene(scene_path("paper_slow"), {"controller.kp=5"});
  for (const PivParams& p : law_params<PivController>(one.plant)) EXPECT_EQ(p.kp, 5.0);
}

// The reference's conditions (scene_key_docs, docs/reference/scene-keys.md)
// against the laws' own declarations: a friction key applies exactly under
// the laws whose kKeys say they read it (law.hpp), and a controller law's
// keys exactly under that law, each listed once.
TEST(SceneKeyDocs, ConditionsFollowTheLawsDeclarations) {
  const std::vector<SceneKeyDoc> docs = scene_key_docs();
  const auto applies = [&](const std::string& section, const std::string& key) {
    std::vector<std::string> found;
    for (const SceneKeyDoc& d : docs) {
      if (d.section == section && d.key == key) found.push_back(d.applies);
    }
    EXPECT_EQ(found.size(), 1u) << section << "." << key;
    return found.empty() ? std::string() : found[0];
  };
  const auto laws_where = [](const std::function<bool(const FrictionKeys&)>& reads) {
    std::string r;
    FrictionLaws::for_each([&](auto law) {
      if (reads(decltype(law)::kKeys))
        r += (r.empty() ? "" : " or ") + ("\"" + std::string(decltype(law)::kName) + "\"");
    });
    return "model = " + r;
  };
  const auto laws_reading = [&](bool FrictionKeys::*flag) {
    return laws_where([flag](const FrictionKeys& k) { return k.*flag; });
  };
  EXPECT_EQ(applies("friction", "viscous"), laws_reading(&FrictionKeys::viscous));
  EXPECT_EQ(applies("friction", "static_torque"),
            laws_where([](const FrictionKeys& k) { return k.levels && !k.kinetic_only; }));
  EXPECT_EQ(applies("friction", "kinetic_torque"), laws_reading(&FrictionKeys::levels));
  EXPECT_EQ(applies("friction", "zero_speed"), laws_reading(&FrictionKeys::zero_speed));
  EXPECT_EQ(applies("friction", "speed_scale"), laws_reading(&FrictionKeys::speed_scale));
  EXPECT_EQ(applies("friction", "sigmoid_level"), laws_reading(&FrictionKeys::sigmoid));
  EXPECT_EQ(applies("friction", "stribeck_speed"), laws_reading(&FrictionKeys::stribeck_speed));
  EXPECT_EQ(applies("friction", "bristle_stiffness"), laws_reading(&FrictionKeys::stiffness));
  EXPECT_EQ(applies("friction", "dahl_exponent"), laws_reading(&FrictionKeys::dahl));
  EXPECT_EQ(applies("friction", "bristle_damping"), laws_reading(&FrictionKeys::bristles));
  EXPECT_EQ(applies("friction", "model"), "");
  ControllerLaws::for_each([&](auto tag) {
    using Law = typename decltype(tag)::Law;
    const std::string under = "law = \"" + std::string(Law::kName) + "\"";
    for (const auto& k : Law::keys()) {
      bool seen = false;
      for (const SceneKeyDoc& d : docs) {
        if (d.section == "controller" && d.key == k.key && d.applies == under) seen = true;
      }
      EXPECT_TRUE(seen) << k.key << " under " << under;
    }
  });
  EXPECT_EQ(applies("controller", "servo_period"), "mode = \"sampled\"");
}

// Every key that a shipped scene uses is in the reference, in its section:
// the reference lists what the reader reads.
TEST(SceneKeyDocs, EveryShippedSceneKeyIsListed) {
  const std::vector<SceneKeyDoc> docs = scene_key_docs();
  for (const std::string& file : shipped_scenes()) {
    const toml::table doc = parse_toml_file(file);
    for (const auto& [section_key, node] : doc) {
      const std::string section(section_key.str());  // a copy: clang 14 cannot capture a binding (P1091)
      ASSERT_TRUE(node.is_table()) << file << ": " << section;
      for (const auto& entry : *node.as_table()) {
        const std::string key(entry.first.str());
        const bool listed = std::any_of(docs.begin(), docs.end(),
                                        [&](const SceneKeyDoc& d) { return d.section == section && d.key == key; });
        EXPECT_TRUE(listed) << file << ": " << section << "." << key;
      }
    }
  }
}

}  // namespace
}  // namespace pumasim
