#include "models/scene/scene.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <sstream>

#include "core/invariant.hpp"
#include "models/dynamics/backend.hpp"
#include "models/reference/reference_table.hpp"
#include "models/reference/time_optimal.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/toml_writer.hpp"
#include "models/robot/urdf_file.hpp"
#include "models/scene/entries.hpp"
#include "models/scene/joint_csv.hpp"

// Each section of a scene file is one table of entries (entries.hpp), read by
// read_<section> and written by write_<section> over that table. The order of
// a table is the order of reading: an entry's `applies` and `then` look only
// at the entries above it.

namespace pumasim {

// What a SceneTemplate's loads share: each robot model as loaded, with the
// files its load read, and the references built, each with its key.
struct SceneTemplate::Shared {
  struct Robot {
    std::string spec;  // scene.robot, a path made absolute
    RobotModel model;
    std::vector<InputFile> files;
  };
  struct ReferenceKey {  // everything make_reference reads
    std::string robot_spec;
    std::vector<InputFile> robot_files;  // by content: a robot loaded again when many are shared
    bool rotor_inertia = true;
    int n = 0;
    Eigen::VectorXd q_held;
    ReferenceSettings settings;
    bool operator==(const ReferenceKey& o) const {
      return robot_spec == o.robot_spec && robot_files == o.robot_files && rotor_inertia == o.rotor_inertia &&
             n == o.n && q_held.size() == o.q_held.size() && q_held == o.q_held && settings == o.settings;
    }
  };
  std::mutex mutex;
  std::vector<Robot> robots;
  struct Tabulated {  // a reference and its table (which refers to it), built once
    std::shared_ptr<const Reference> reference;
    std::shared_ptr<const ReferenceTable> table;  // nullptr: not tabulated (ReferenceTable::tabulates)
  };
  std::vector<std::pair<ReferenceKey, Tabulated>> references;
  // The file parsed once, with the template's sets applied: each load reads
  // a copy (a twentieth of a parse's cost), whose values have lost their
  // source lines (toml++ copies none), so a load the reader refuses is read
  // again from the text, for the message's line (SceneTemplate::load).
  toml::table doc;

  // The robot of `spec`, loaded by the first load that asks (under the lock:
  // the others wait for it rather than read it again); its files recorded
  // in the asking load's record either way.
  Robot robot(const std::string& spec) {
    const std::lock_guard<std::mutex> lock(mutex);
    for (const Robot& r : robots) {
      if (r.spec != spec) continue;
      for (const InputFile& f : r.files) record_input_file(f);
      return r;
    }
    Robot r{spec, {}, {}};
    {
      const InputRecord record;  // nested: the files reach the load's record too
      r.model = load_robot(spec);
      r.files = record.files();
    }
    if (robots.size() < kShared) robots.push_back(r);
    return r;
  }

  template <class Make>
  Tabulated reference(const ReferenceKey& key, const Make& make) {
    std::unique_lock<std::mutex> lock(mutex);
    for (const auto& [k, ref] : references) {
      if (k == key) return ref;
    }
    if (references.size() >= kShared) {
      lock.unlock();
      return {make(), nullptr};
    }
    Tabulated t{make(), nullptr};  // a failure throws, and nothing is kept
    if (ReferenceTable::tabulates(*t.reference)) {
      struct Held {  // the table keeps its reference alive
        std::shared_ptr<const Reference> reference;
        ReferenceTable table;
        explicit Held(std::shared_ptr<const Reference> r) : reference(std::move(r)), table(*reference) {}
      };
      const auto held = std::make_shared<const Held>(t.reference);
      t.table = std::shared_ptr<const ReferenceTable>(held, &held->table);
    }
    references.emplace_back(key, t);
    return t;
  }
};

namespace {

// The SceneTemplate load running on this thread (none: a plain load): what
// it shares, and the files of the robot it took.
struct TemplateLoad {
  SceneTemplate::Shared* shared = nullptr;
  std::vector<InputFile> robot_files;
};
thread_local TemplateLoad* template_load = nullptr;

using scene_io::Codec;
using scene_io::Entry;
using scene_io::Need;
using scene_io::read_entries;
using scene_io::write_entries;

const Bounds kAny = Bounds::any();
const Bounds kPositive = Bounds::positive();
const Bounds kNonNegative = Bounds::non_negative();
const Bounds kJointAngle{-4 * M_PI, 4 * M_PI};  // [rad] held joints, initial pose
const Bounds kRampShare{0.0, 0.5, true};        // (0, 0.5]: blend, jerk_fraction

// ---------------------------------------------------------------- [scene]

// The name becomes a folder name (runs/<name>/): a plain one only.
void check_name(StrictTable& t, Scene& sc) {
  const std::string& s = sc.name;
  const bool plain = !s.empty() && s.size() <= 100 && s != "." && s != ".." &&
                     std::all_of(s.begin(), s.end(), [](char c) {
                       return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
                     });
  if (!plain) {
    t.fail("name", "a plain name of at most 100 letters, digits, '_', '-' and '.' (not '.' or '..')",
           "\"" + s + "\"");
  }
}

// Loads the robot file and sizes the held pose from it (every size of the
// scene follows the robot: any number of joints). A file path (relative to the scene's
// folder) is resolved to an absolute one, which the resolved scene keeps, so
// that it loads from any working directory; a shipped robot's name stays a name.
void load_robot_of(StrictTable& t, Scene& sc) {
  if (is_robot_path(sc.robot_spec)) {
    namespace fs = std::filesystem;
    const fs::path p(sc.robot_spec);
    sc.robot_spec = fs::absolute(p.is_absolute() ? p : fs::path(sc.file).parent_path() / p).lexically_normal().string();
  }
  try {
    if (template_load) {
      SceneTemplate::Shared::Robot r = template_load->shared->robot(sc.robot_spec);
      sc.plant.robot = std::move(r.model);
      template_load->robot_files = std::move(r.files);
    } else {
      sc.plant.robot = load_robot(sc.robot_spec);
    }
  } catch (const ConfigError& e) {
    throw ConfigError(t.where("robot") + e.what());
  }
  sc.plant.q_held = Eigen::VectorXd::Zero(sc.plant.robot.dof());
}

void apply_rotor_inertia(StrictTable&, Scene& sc) {
  if (!sc.rotor_inertia) sc.plant.robot = without_rotor_inertia(sc.plant.robot);
}

// joints: a whole number in [1, the robot's joint count]; the joints beyond
// it are held (locked at `held`, their links riding on link n).
Codec<Scene> joints_codec() {
  return {[](StrictTable& t, std::string_view key, Scene& sc, int) {
            const int dof = sc.plant.robot.dof();
            const double x = t.number(key, {1.0, static_cast<double>(dof)});
            if (x != std::floor(x)) t.fail(key, "an integer in [1, " + std::to_string(dof) + "]", std::to_string(x));
            const int n = static_cast<int>(x);
            sc.plant.n = n;
          },
          [](toml::table& out, std::string_view key, const Scene& sc, int) { out.insert(key, sc.plant.n); },
          nullptr,
          "a whole number in [1, the robot's joint count]",
          {}};
}

// held: the angles of joints n+1..dof, the tail of q_held (dof entries,
// sized when the robot is read; n <= dof is checked at joints).
int held_count(const Scene& sc, int) { return sc.plant.robot.dof() - sc.plant.n; }
std::vector<double> get_held(const Scene& sc, int) {
  const int n = sc.plant.n;
  return {sc.plant.q_held.data() + n, sc.plant.q_held.data() + sc.plant.robot.dof()};
}
void set_held(Scene& sc, const std::vector<double>& v) {
  const int n = sc.plant.n;
  PUMASIM_DEMAND(n + static_cast<int>(v.size()) <= sc.plant.q_held.size(), "held: beyond the held vector");
  for (std::size_t k = 0; k < v.size(); ++k) sc.plant.q_held[n + static_cast<int>(k)] = v[k];
}

void check_backend(StrictTable& t, Scene& sc) {
  const PlantConfig& pc = sc.plant;
  try {
    const BackendInfo& b = find_backend(pc.backend);
    const RobotModel sim = simulated_robot(pc.robot, pc.n, pc.q_held);
    if (const std::string why = b.why_unsupported(sim); !why.empty()) {
      t.fail("backend", "a back-end that supports this robot", why);
    }
  } catch (const std::invalid_argument&) {
    t.fail("backend", "one of: " + backend_names(), "\"" + pc.backend + "\"");
  }
}

const std::vector<Entry<Scene>> kSceneEntries = {
    {"name", scene_io::text(PUMASIM_AT(s.name)), "the run's name, also its folder runs/<name>/", Need::kRequired,
     {}, check_name},
    {"robot", scene_io::text(PUMASIM_AT(s.robot_spec)), "a shipped robot name, or a file relative to the scene",
     Need::kRequired, {}, load_robot_of},
    {"rotor_inertia", scene_io::flag(PUMASIM_AT(s.rotor_inertia)), "false: the robot's rotor inertias removed",
     Need::kOptional, {}, apply_rotor_inertia},
    {"energy_ledger", scene_io::flag(PUMASIM_AT(s.plant.energy_ledger)),
     "true: states e_in, e_copper, e_friction [J] and the energy balance"},
    {"joints", joints_codec(), "the first n joints move, the others are held", Need::kRequired},
    {"held", scene_io::numbers(held_count, kJointAngle, get_held, set_held), "[rad] angles of the held joints"},
    {"backend", scene_io::text(PUMASIM_AT(s.plant.backend)), "dynamics back-end (pumasim backends)",
     Need::kOptional, {}, check_backend},
    {"duration", scene_io::number(kPositive, PUMASIM_AT(s.duration)), "[s]; absent: the reference's duration"},
    {"output_interval", scene_io::number(kPositive, PUMASIM_AT(s.output_interval)), "[s] between output rows"},
};

void read_scene(StrictTable& root, Scene& sc) {
  StrictTable t = root.table("scene");
  read_entries(t, kSceneEntries, sc, 0);
}
toml::table write_scene(const Scene& sc) { return write_entries(kSceneEntries, sc, sc.plant.n); }

// ---------------------------------------------------------------- [integrator]

void note_name_where(StrictTable& t, IntegratorSettings& it) {
  if (t.has("name")) it.name_where = t.where("name");
}

const std::vector<Entry<IntegratorSettings>> kIntegratorEntries = {
    {"name", scene_io::text(PUMASIM_AT(s.name)), "integrator (pumasim integrators; checked by the command line)",
     Need::kOptional, {}, note_name_where},
    {"dt", scene_io::number(kPositive, PUMASIM_AT(s.dt)), "[s] step of the fixed-step methods"},
    {"rtol", scene_io::number(Bounds{kRtolMin, kRtolMax}, PUMASIM_AT(s.rtol)), "relative tolerance of the adaptive methods"},
    {"atol", scene_io::number(kPositive, PUMASIM_AT(s.atol)), "absolute tolerance (times each state's scale)"},
};

void read_integrator(StrictTable& root, IntegratorSettings& it) {
  auto t = root.optional_table("integrator");
  if (!t) return;
  read_entries(*t, kIntegratorEntries, it, 0);
  // rtol without atol: atol follows it, as `--rtol` alone sets it, so that a
  // tolerance study does not plateau at the default atol.
  if (t->has("rtol") && !t->has("atol")) it.atol = kAtolPerRtol * it.rtol;
}
toml::table write_integrator(const IntegratorSettings& it) { return write_entries(kIntegratorEntries, it, 0); }

// ---------------------------------------------------------------- [amplifier], [motor]

const std::vector<Entry<PlantConfig>> kAmplifierEntries = {
    {"gain", scene_io::per_joint(kPositive, PUMASIM_AT(s.amplifier[j].gain)), "K_A [V/V]", Need::kRequired},
    {"output_resistance", scene_io::per_joint(kNonNegative, PUMASIM_AT(s.amplifier[j].output_resistance)),
     "R0 [ohm]"},
    {"voltage_limit", scene_io::per_joint(kPositive, PUMASIM_AT(s.amplifier[j].voltage_limit)), "V_max [V]"},
};

// La = 0 for every joint: the current is algebraic (motor.current says how it is kept).
bool zero_inductance(const PlantConfig& pc) {
  return std::all_of(pc.motor.begin(), pc.motor.end(), [](const MotorParams& m) { return m.inductance == 0; });
}

const std::vector<Entry<PlantConfig>> kMotorEntries = {
    {"inductance", scene_io::per_joint(kNonNegative, PUMASIM_AT(s.motor[j].inductance)),
     "La [H]; all 0: the current algebraic (current: eliminated, or kept as an unknown)", Need::kRequired},
    {"resistance", scene_io::per_joint(kPositive, PUMASIM_AT(s.motor[j].resistance)), "R [ohm]", Need::kRequired},
    {"torque_constant", scene_io::per_joint(kPositive, PUMASIM_AT(s.motor[j].torque_constant)),
     "K [N m/A] = back-EMF constant [V s/rad]", Need::kRequired},
    {"current",
     scene_io::choice<bool>({{"eliminated", false}, {"algebraic", true}}, PUMASIM_AT(s.algebraic_current)),
     "La = 0: eliminated (the reduced ODE) | algebraic (states i_motor, 0 = e_a - (R0 + R) i - K w_m: an index-1 "
     "DAE for ida)",
     Need::kOptional,
     {zero_inductance, "inductance", "every inductance = 0"}},
};

// The drive: [amplifier] and [motor] together, or neither.
void read_drive(StrictTable& root, PlantConfig& pc) {
  auto amp = root.optional_table("amplifier");
  auto mot = root.optional_table("motor");
  if (amp.has_value() != mot.has_value()) {
    root.fail(amp ? "motor" : "amplifier", "both [amplifier] and [motor] (the drive) or neither",
              "only one of them");
  }
  pc.drive = amp.has_value();
  if (!pc.drive) return;
  pc.amplifier.assign(pc.n, AmplifierParams{});
  pc.motor.assign(pc.n, MotorParams{});
  read_entries(*amp, kAmplifierEntries, pc, pc.n);
  read_entries(*mot, kMotorEntries, pc, pc.n);
  const auto positive = [](const MotorParams& m) { return m.inductance > 0; };
  const bool any = std::any_of(pc.motor.begin(), pc.motor.end(), positive);
  const bool all = std::all_of(pc.motor.begin(), pc.motor.end(), positive);
  if (any && !all) mot->fail("inductance", "all > 0 (current states) or all 0 (the reduced model)", "a mix");
}

void write_drive(toml::table& doc, const PlantConfig& pc) {
  if (!pc.drive) return;
  doc.insert("amplifier", write_entries(kAmplifierEntries, pc, pc.n));
  doc.insert("motor", write_entries(kMotorEntries, pc, pc.n));
}

// ---------------------------------------------------------------- [friction]


// The keys each law reads, and its default band, from the plant's registry.
FrictionKeys keys_of(const PlantConfig& pc) { return friction_keys(pc.friction[0].model); }
bool dissipative(const PlantConfig& pc) { return keys_of(pc).viscous; }
bool coulomb(const PlantConfig& pc) { return keys_of(pc).levels; }
bool banded(const PlantConfig& pc) { return keys_of(pc).zero_speed; }
bool smooth(const PlantConfig& pc) { return keys_of(pc).speed_scale; }
bool sigmoid(const PlantConfig& pc) { return keys_of(pc).sigmoid; }
bool stribeck(const PlantConfig& pc) { return keys_of(pc).stribeck_speed; }
bool bristles(const PlantConfig& pc) { return keys_of(pc).bristles; }
bool stiff(const PlantConfig& pc) { return keys_of(pc).stiffness; }
bool dahl(const PlantConfig& pc) { return keys_of(pc).dahl; }
bool coulomb_static(const PlantConfig& pc) { return coulomb(pc) && !keys_of(pc).kinetic_only; }

// The Stribeck law's break-away torque is its peak: at least the Coulomb
// level on every joint, or the law would push near rest (stribeck.hpp).
void check_breakaway(StrictTable& t, PlantConfig& pc) {
  if (stiff(pc)) return;  // a law with a state: check_state_levels
  for (int j = 0; j < pc.n; ++j) {
    const FrictionParams& f = pc.friction[static_cast<std::size_t>(j)];
    char got[160];
    if (f.static_torque >= f.kinetic_torque) continue;
    std::snprintf(got, sizeof got, "joint %d: static_torque %.6g N m below kinetic_torque %.6g N m", j + 1,
                  f.static_torque, f.kinetic_torque);
    t.fail("static_torque", "a break-away torque >= kinetic_torque (stribeck: its peak above the Coulomb level)", got);
  }
}

// The stateful laws' rates divide by their levels: LuGre's by
// G(w) = Fk + (Fs - Fk) exp(-(w/vs)^2), Dahl's by Fc: levels > 0 (lugre.hpp, dahl.hpp).
void check_state_levels(StrictTable& t, PlantConfig& pc) {
  const bool kinetic_only = keys_of(pc).kinetic_only;
  for (int j = 0; j < pc.n; ++j) {
    const FrictionParams& f = pc.friction[static_cast<std::size_t>(j)];
    if (f.kinetic_torque > 0 && (kinetic_only || f.static_torque > 0)) continue;
    char got[160];
    std::snprintf(got, sizeof got, "joint %d: static_torque %.6g N m, kinetic_torque %.6g N m", j + 1, f.static_torque,
                  f.kinetic_torque);
    t.fail(f.kinetic_torque > 0 ? "static_torque" : "kinetic_torque",
           kinetic_only ? "a level > 0 (dahl: its rate divides by Fc)"
                        : "levels > 0 (lugre: the bristles' rate divides by Fk + (Fs - Fk) exp(-(w/vs)^2))",
           got);
  }
}

// The law's default band, before zero_speed is read (when it is).
void default_band(StrictTable&, PlantConfig& pc) {
  if (!banded(pc)) return;
  for (FrictionParams& f : pc.friction) f.zero_speed = keys_of(pc).default_zero_speed;
}

// "none | viscous | ...", the registry's names (kept: the entry's meaning is a view).
const std::string& friction_model_names() {
  static const std::string names = [] {
    std::string out;
    for (const auto& choice : friction_model_choices()) out += (out.empty() ? "" : " | ") + choice.first;
    return out;
  }();
  return names;
}

// Whether the robot file gives joint friction of a kind (a URDF's <dynamics
// damping> or <dynamics friction>: JointParams::damping, coulomb) on a
// simulated joint.
bool robot_gives(const PlantConfig& pc, double JointParams::*value) {
  for (int j = 0; j < pc.n; ++j) {
    if (pc.robot.joints[static_cast<std::size_t>(j)].*value > 0) return true;
  }
  return false;
}
bool robot_damping(const PlantConfig& pc) { return robot_gives(pc, &JointParams::damping); }
bool robot_coulomb(const PlantConfig& pc) { return robot_gives(pc, &JointParams::coulomb); }

// static_torque and kinetic_torque are required by the Coulomb laws unless
// the robot file gives the level they default to.
void need_level(StrictTable& t, const PlantConfig& pc, const char* key) {
  if (t.has(key) || robot_coulomb(pc)) return;
  throw ConfigError(t.where() + "missing required key '" + key + "'" +
                    (is_urdf_path(pc.robot.source) ? " (the URDF gives no <dynamics friction> to take it from)" : ""));
}
void need_static(StrictTable& t, PlantConfig& pc) { need_level(t, pc, "static_torque"); }
void need_kinetic(StrictTable& t, PlantConfig& pc) { need_level(t, pc, "kinetic_torque"); }

// Keys that mean nothing for the model are unknown keys.
const std::vector<Entry<PlantConfig>> kFrictionEntries = {
    {"model",
     scene_io::shared_choice(friction_model_choices(), PUMASIM_AT(s.friction[j].model)),
     friction_model_names(),
     Need::kRequired,
     {},
     default_band},
    {"viscous",
     scene_io::per_joint(kNonNegative, PUMASIM_AT(s.friction[j].viscous)),
     "B [N m s/rad] (every model but none; default: the robot file's damping / Z^2, else 0)",
     Need::kOptional,
     {dissipative, "model"}},
    {"static_torque",
     scene_io::per_joint(kNonNegative, PUMASIM_AT(s.friction[j].static_torque)),
     "Fs [N m] (paper, hybrid, karnopp, tanh, lugre; stribeck: the break-away torque; default: the robot file's "
     "friction / "
     "|Z|; required when it gives none)",
     Need::kOptional,
     {coulomb_static, "model"},
     need_static},
    {"kinetic_torque",
     scene_io::per_joint(kNonNegative, PUMASIM_AT(s.friction[j].kinetic_torque)),
     "Fk [N m] (paper, hybrid, karnopp, tanh, lugre; stribeck: the Coulomb level; dahl: Fc; default: the robot file's "
     "friction / "
     "|Z|; "
     "required when it gives none)",
     Need::kOptional,
     {coulomb, "model"},
     need_kinetic},
    {"zero_speed",
     scene_io::shared_number(kPositive, PUMASIM_AT(s.friction[j].zero_speed)),
     "[rad/s] \"zero\" speed (paper), band (karnopp)",
     Need::kOptional,
     {banded, "model"}},
    {"speed_scale",
     scene_io::shared_number(kPositive, PUMASIM_AT(s.friction[j].speed_scale)),
     "[rad/s] tanh(w / speed_scale) (tanh; stribeck: its Coulomb term's scale w_C)",
     Need::kOptional,
     {smooth, "model"}},
    {"stribeck_speed",
     scene_io::shared_number(kPositive, PUMASIM_AT(s.friction[j].stribeck_speed)),
     "[rad/s] w_St, the Stribeck term's speed scale (stribeck: its peak at w_St / sqrt(2); lugre: vs)",
     Need::kRequired,
     {stribeck, "model"},
     check_breakaway},
    {"bristle_stiffness",
     scene_io::per_joint(kPositive, PUMASIM_AT(s.friction[j].bristle_stiffness)),
     "sigma0 [N m/rad] (lugre: the bristles' stiffness; dahl: the stiffness at rest; motor side)",
     Need::kRequired,
     {stiff, "model"},
     check_state_levels},
    {"bristle_damping",
     scene_io::per_joint(kNonNegative, PUMASIM_AT(s.friction[j].bristle_damping)),
     "sigma1 [N m s/rad] (lugre: the bristles' damping, motor side)",
     Need::kRequired,
     {bristles, "model"}},
    {"dahl_exponent",
     scene_io::shared_number(Bounds{1.0, 100.0}, PUMASIM_AT(s.friction[j].dahl_exponent)),
     "alpha (dahl: dF/dx = sigma0 |1 - F sgn(w) / Fc|^alpha sgn(...); >= 1, 1 the usual)",
     Need::kOptional,
     {dahl, "model"}},
    {"sigmoid_level",
     scene_io::per_joint(kNonNegative, PUMASIM_AT(s.friction[j].sigmoid_level)),
     "phi1 [N m] (sigmoid: Gaz et al. 2019's level, motor side)",
     Need::kRequired,
     {sigmoid, "model"}},
    {"sigmoid_slope",
     scene_io::per_joint(kNonNegative, PUMASIM_AT(s.friction[j].sigmoid_slope)),
     "phi2 [s/rad] (sigmoid: the slope, motor side)",
     Need::kRequired,
     {sigmoid, "model"}},
    {"sigmoid_offset",
     scene_io::per_joint(kAny, PUMASIM_AT(s.friction[j].sigmoid_offset)),
     "phi3 [rad/s] (sigmoid: the speed offset, motor side)",
     Need::kRequired,
     {sigmoid, "model"}},
};

// The robot file's joint friction as the motor-side defaults of [friction]
// (the laws act on the motor shaft, drive.hpp: a joint torque Z tau_f at
// motor speed Z qd): B = damping / Z^2, Fs = Fk = friction / |Z| (URDF's
// friction is one Coulomb level, so static and kinetic are equal).
void robot_friction_defaults(PlantConfig& pc) {
  for (int j = 0; j < pc.n; ++j) {
    const JointParams& J = pc.robot.joints[static_cast<std::size_t>(j)];
    FrictionParams& f = pc.friction[static_cast<std::size_t>(j)];
    f.viscous = J.damping / (J.gear_ratio * J.gear_ratio);
    f.static_torque = f.kinetic_torque = J.coulomb / std::abs(J.gear_ratio);
  }
}

// Where each friction value came from, for `pumasim check` (Scene::sources).
void friction_sources(StrictTable& t, const PlantConfig& pc, std::vector<std::string>& out) {
  const bool damping = robot_damping(pc), level = robot_coulomb(pc);
  if (!damping && !level) return;
  const auto line = [&](const char* key, bool applies, bool robot, const char* what) {
    if (!applies) {
      if (robot) {
        out.push_back(std::string("friction.") + key + ": not used by friction.model = \"" + to_string(pc.friction[0].model) +
                      "\" (the robot file's joint " + what + " is left out)");
      }
      return;
    }
    out.push_back(std::string("friction.") + key + ": " +
                  (t.has(key) ? "the scene file (it wins over the robot file's joint " + std::string(what) + ")"
                   : robot    ? "the robot file's joint " + std::string(what) +
                                 (std::string(key) == "viscous" ? " / Z^2 (motor side)" : " / |Z| (motor side)")
                              : std::string("the default, 0")));
  };
  line("viscous", dissipative(pc), damping, "damping (<dynamics damping>)");
  line("static_torque", coulomb_static(pc), level, "friction (<dynamics friction>)");
  line("kinetic_torque", coulomb(pc), level, "friction (<dynamics friction>)");
}

// Without [friction]: the model "none" on every joint, unless the robot file
// gives joint friction: a law must then be chosen (or "none" said).
void read_friction(StrictTable& root, Scene& sc) {
  PlantConfig& pc = sc.plant;
  pc.friction.assign(pc.n, FrictionParams{});
  auto t = root.optional_table("friction");
  if (!t) {
    if (robot_damping(pc) || robot_coulomb(pc)) {
      root.fail("friction",
                "a [friction] section saying which law uses the robot file's joint friction (<dynamics damping "
                "friction>): model = \"viscous\" (damping only), \"hybrid\", \"karnopp\", \"tanh\" or \"paper\" "
                "(damping and friction), or \"none\" to leave it out",
                "none");
    }
    return;
  }
  robot_friction_defaults(pc);
  read_entries(*t, kFrictionEntries, pc, pc.n);
  friction_sources(*t, pc, sc.sources);
}
toml::table write_friction(const PlantConfig& pc) { return write_entries(kFrictionEntries, pc, pc.n); }

// ---------------------------------------------------------------- [controller]

bool sampled(const PlantConfig& pc) { return pc.controller == ControllerMode::kSampled; }

// law: the registry's names; the law's parameters for n joints at their defaults.
scene_io::Codec<PlantConfig> controller_law() {
  return {[](StrictTable& t, std::string_view key, PlantConfig& pc, int n) {
            default_controller_params(t.string(key, controller_law_names()), n, &pc.controller_params);
          },
          [](toml::table& out, std::string_view key, const PlantConfig& pc, int) {
            out.insert(key, std::string(controller_law_name(pc.controller_params)));
          },
          nullptr, scene_io::one_of(controller_law_names()), controller_law_names()};
}

template <class Law>
bool law_is(const PlantConfig& pc) {
  return std::holds_alternative<LawParams<Law>>(pc.controller_params);
}

// A file named in a scene: relative to the scene's folder (or absolute), made
// absolute, so that the resolved scene loads from any working directory.
std::string beside_scene(const std::string& scene_dir, const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path p(name);
  return fs::absolute(p.is_absolute() ? p : fs::path(scene_dir) / p).lexically_normal().string();
}

// A law's file key (ControllerTextKey with rows, law.hpp): the CSV file's
// rows t, v1 ... vn into the law's settings, its path made absolute; errors
// name the key, then the file's line.
template <class Law>
Codec<PlantConfig> law_file(const ControllerTextKey<typename Law::Settings>& k) {
  const auto path = k.member;
  const auto rows = k.rows;
  const std::string column(k.column);
  return {[path, rows, column](StrictTable& t, std::string_view key, PlantConfig& pc, int n) {
            auto& s = std::get<LawParams<Law>>(pc.controller_params).settings;
            const std::string name = t.string(key);
            if (name.empty()) t.fail(key, "a CSV file's name (relative to the scene)", "\"\"");
            s.*path = beside_scene(std::filesystem::path(t.file()).parent_path().string(), name);
            try {
              s.*rows = read_joint_csv(s.*path, n, column);
            } catch (const ConfigError& e) {
              throw ConfigError(t.where(key) + e.what());
            }
          },
          [path](toml::table& out, std::string_view key, const PlantConfig& pc, int) {
            out.insert(key, std::get<LawParams<Law>>(pc.controller_params).settings.*path);
          },
          nullptr,
          "a CSV file's name (relative to the scene) of rows t, " + column + "1 ... " + column + "n",
          {}};
}

// A law's keys: its text keys (settings for all joints: names from a list, or
// a file), then its numbers per joint; each applies when it is the scene's law.
template <class Law>
void add_law_entries(std::vector<Entry<PlantConfig>>& e) {
  const Entry<PlantConfig>::Applies applies{&law_is<Law>, "law"};
  for (const ControllerTextKey<typename Law::Settings>& k : Law::text_keys()) {
    const auto member = k.member;
    const auto at = [member](auto& s, int) -> auto& {
      return std::get<LawParams<Law>>(s.controller_params).settings.*member;
    };
    const Need need = k.required ? Need::kRequired : Need::kOptional;
    if (k.rows) {
      e.push_back({k.key, law_file<Law>(k), k.meaning, need, applies});
    } else {
      e.push_back({k.key, scene_io::text(at, k.allowed), k.meaning, need, applies});
    }
  }
  for (const ControllerKey<typename Law::Params>& k : Law::keys()) {
    const auto member = k.member;
    const auto at = [member](auto& s, int j) -> auto& {
      return std::get<LawParams<Law>>(s.controller_params).joints[static_cast<std::size_t>(j)].*member;
    };
    e.push_back({k.key, scene_io::per_joint(k.bounds, at), k.meaning, k.required ? Need::kRequired : Need::kOptional,
                 applies});
  }
}

// The timing, then each law's own keys (ControllerTextKey, ControllerKey:
// law.hpp), which apply when it is the scene's law.
const std::vector<Entry<PlantConfig>>& controller_entries() {
  static const std::vector<Entry<PlantConfig>> entries = [] {
    std::vector<Entry<PlantConfig>> e = {
        {"law", controller_law(), "the control law (first: the default)"},
        {"mode",
         scene_io::choice<ControllerMode>(
             {{"continuous", ControllerMode::kContinuous}, {"sampled", ControllerMode::kSampled}},
             PUMASIM_AT(s.controller)),
         "continuous (the law's memory is a state) | sampled (zero-order hold)", Need::kRequired},
        {"servo_period", scene_io::number(kPositive, PUMASIM_AT(s.servo_period)), "[s] (sampled)", Need::kRequired,
         {sampled, "mode"}},
        {"setpoint_interval", scene_io::number(kNonNegative, PUMASIM_AT(s.setpoint_interval)),
         "[s] reference held between updates; 0: continuous"},
    };
    ControllerLaws::for_each([&](auto tag) { add_law_entries<typename decltype(tag)::Law>(e); });
    return e;
  }();
  return entries;
}

// A law that commands a voltage drives the drive; a torque input
// (open_loop's input = "torque") acts on the joints without one.
void check_command(StrictTable& root, StrictTable& t, const PlantConfig& pc) {
  const bool torque = controller_command(pc.controller_params) == ControllerCommand::kTorque;
  if (torque && pc.drive) {
    t.fail("input", "\"voltage\" with the drive ([amplifier] and [motor]), or \"torque\" without one",
           "\"torque\" with a drive");
  }
  if (torque || pc.drive) return;
  if (t.has("input")) {
    t.fail("input", "\"torque\" without a drive, or \"voltage\" with the drive ([amplifier] and [motor])",
           "\"voltage\" without a drive");
  }
  root.fail("controller", "a drive ([amplifier] and [motor]) with a controller", "no drive");
}

// A controller drives the drive, both or neither, but for a torque input,
// which needs no drive. Without `law`, the first law.
void read_controller(StrictTable& root, PlantConfig& pc) {
  pc.controller = ControllerMode::kNone;
  if (auto t = root.optional_table("controller")) {
    default_controller_params(controller_law_names().front(), pc.n, &pc.controller_params);
    read_entries(*t, controller_entries(), pc, pc.n);
    check_command(root, *t, pc);
  } else if (pc.drive) {
    root.fail("amplifier", "a [controller] to drive the amplifier", "no controller");
  }
}

void write_controller(toml::table& doc, const PlantConfig& pc) {
  if (pc.controller != ControllerMode::kNone) doc.insert("controller", write_entries(controller_entries(), pc, pc.n));
}

// ---------------------------------------------------------------- [reference]

// [[a, b], [c, d], ...]: rows of `cols` numbers.
std::vector<std::vector<double>> read_rows(StrictTable& t, std::string_view key, int cols) {
  const toml::node* nd = t.node(key);
  const std::string expected = "an array of [" + std::string(cols == 2 ? "a, b" : "a, b, c") +
                               "] rows of numbers";
  if (!nd || !nd->is_array()) t.fail(key, expected, nd ? "another type" : "nothing");
  std::vector<std::vector<double>> rows;
  for (const toml::node& row : *nd->as_array()) {
    const toml::array* r = row.as_array();
    if (!r || r->size() != static_cast<std::size_t>(cols)) {
      t.fail(key, expected, "a row that is not " + std::to_string(cols) + " numbers");
    }
    std::vector<double> v;
    for (const toml::node& x : *r) {
      const auto d = StrictTable::as_double(x);
      if (!d) t.fail(key, expected, x.is_integer() ? "an integer beyond +-2^53" : "a row with a non-number");
      if (!std::isfinite(*d)) t.fail(key, expected + ", each finite", "a row with " + std::to_string(*d));
      v.push_back(*d);
    }
    rows.push_back(v);
  }
  return rows;
}

// The degrees the reader turns back into exactly `angle` [rad] (d * pi / 180),
// so that a resolved scene loads to the same path.
double degrees_of(double angle) {
  double d = angle * 180 / M_PI;
  for (int k = 0; k < 8 && d * M_PI / 180 != angle; ++k) {
    d = std::nextafter(d, d * M_PI / 180 < angle ? HUGE_VAL : -HUGE_VAL);
  }
  return d;
}

// segments: an array of tables, each { line = L } or { arc_radius = r, turn_degrees = a }.
Codec<ReferenceSettings> segments_codec() {
  return {[](StrictTable& t, std::string_view key, ReferenceSettings& r, int) {
            for (StrictTable& seg : t.array_of_tables(key)) {
              PathSegment p;
              if (seg.has("line")) {
                p.length = seg.number("line", kPositive);
              } else {
                p.radius = seg.number("arc_radius", kPositive);
                p.angle = seg.number("turn_degrees", {-360, 360}) * M_PI / 180;
                if (p.angle == 0) seg.fail("turn_degrees", "a non-zero angle", "0");
              }
              seg.finish();
              r.segments.push_back(p);
            }
          },
          [](toml::table& out, std::string_view key, const ReferenceSettings& r, int) {
            toml::array segs;
            for (const PathSegment& p : r.segments) {
              if (p.radius > 0) {
                segs.push_back(toml::table{{"arc_radius", p.radius}, {"turn_degrees", degrees_of(p.angle)}});
              } else {
                segs.push_back(toml::table{{"line", p.length}});
              }
            }
            out.insert(key, segs);
          },
          nullptr,
          "an array of tables, each {line = L [m]} or {arc_radius = r [m], turn_degrees = a}",
          {}};
}

// profile: [[t/T, v/v_max], ...] (the table timing).
Codec<ReferenceSettings> profile_codec() {
  return {[](StrictTable& t, std::string_view key, ReferenceSettings& r, int) {
            for (const auto& row : read_rows(t, key, 2)) r.profile.emplace_back(row[0], row[1]);
          },
          [](toml::table& out, std::string_view key, const ReferenceSettings& r, int) {
            toml::array prof;
            for (const auto& pt : r.profile) prof.push_back(toml::array{pt.x(), pt.y()});
            out.insert(key, prof);
          },
          nullptr,
          "an array of rows [t/T, v/v_max]",
          {}};
}

// orientation: a 3 x 3 rotation matrix, by rows.
Codec<ReferenceSettings> orientation_codec() {
  return {[](StrictTable& t, std::string_view key, ReferenceSettings& r, int) {
            const auto rows = read_rows(t, key, 3);
            if (rows.size() != 3) t.fail(key, "a 3 x 3 rotation matrix (rows)", "another shape");
            for (int i = 0; i < 3; ++i)
              for (int k = 0; k < 3; ++k) r.orientation(i, k) = rows[i][k];
            if ((r.orientation * r.orientation.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-9 ||
                r.orientation.determinant() < 0) {
              t.fail(key, "a rotation matrix (orthonormal, determinant +1)", "another matrix");
            }
          },
          [](toml::table& out, std::string_view key, const ReferenceSettings& r, int) {
            toml::array orient;
            for (int i = 0; i < 3; ++i) {
              orient.push_back(toml::array{r.orientation(i, 0), r.orientation(i, 1), r.orientation(i, 2)});
            }
            out.insert(key, orient);
          },
          nullptr,
          "a 3 x 3 rotation matrix, by rows",
          {}};
}

std::vector<std::pair<std::string, Interpolation>> interpolations() {
  std::vector<std::pair<std::string, Interpolation>> out;
  for (Interpolation i : {Interpolation::kCartesian, Interpolation::kJointCubic, Interpolation::kJointQuintic}) {
    out.emplace_back(to_string(i), i);
  }
  return out;
}

// joints: a CSV file of rows t, q1 ... qn (joint_csv.hpp), relative to the
// scene's folder; the resolved scene names it by its absolute path.
Codec<ReferenceSettings> joints_csv_codec() {
  return {
      [](StrictTable& t, std::string_view key, ReferenceSettings& r, int n) {
        r.joints_file = beside_scene(r.scene_dir, t.string(key));
        try {
          r.points = read_joint_csv(r.joints_file, n);
        } catch (const ConfigError& e) {
          throw ConfigError(t.where(key) + e.what());
        }
      },
      [](toml::table& out, std::string_view key, const ReferenceSettings& r, int) { out.insert(key, r.joints_file); },
      [](const ReferenceSettings& r) { return r.joints_file.empty(); },
      "a CSV file's name (relative to the scene) of rows t, q1 ... qn",
      {}};
}

// via_points: [[t, q1, ..., qn], ...] in the scene (the CSV's rows).
Codec<ReferenceSettings> via_points_codec() {
  return {[](StrictTable& t, std::string_view key, ReferenceSettings& r, int n) {
            const toml::node* nd = t.node(key);
            const std::string expected = "an array of rows [t, q1, ..., q" + std::to_string(n) + "] of numbers";
            if (!nd || !nd->is_array()) t.fail(key, expected, nd ? "another type" : "nothing");
            std::vector<std::vector<double>> rows;
            for (const toml::node& row : *nd->as_array()) {
              const std::string at = "row " + std::to_string(rows.size() + 1);
              const toml::array* a = row.as_array();
              if (!a) t.fail(key, expected, at + " that is no array");
              std::vector<double> v;
              for (const toml::node& x : *a) {
                const auto d = StrictTable::as_double(x);
                if (!d)
                  t.fail(key, expected,
                         at + (x.is_integer() ? " with an integer beyond +-2^53" : " with a non-number"));
                v.push_back(*d);
              }
              rows.push_back(v);
            }
            try {
              check_joint_rows(rows, n, "");
            } catch (const ConfigError& e) {
              throw ConfigError(t.where(key) + e.what());
            }
            r.via_points = rows;
            r.points = rows;
          },
          [](toml::table& out, std::string_view key, const ReferenceSettings& r, int) {
            toml::array rows;
            for (const auto& row : r.via_points) {
              toml::array a;
              for (double x : row) a.push_back(x);
              rows.push_back(a);
            }
            out.insert(key, rows);
          },
          [](const ReferenceSettings& r) { return r.via_points.empty(); },
          "an array of rows [t, q1, ..., qn] of numbers",
          {}};
}

bool no_joints_file(const ReferenceSettings& r) { return r.joints_file.empty(); }
bool cartesian_path(const ReferenceSettings& r) { return !r.joint_source(); }
constexpr std::string_view kCartesianPath = "a Cartesian path (neither joints nor via_points given)";
constexpr std::string_view kClosedFormIk = "ik = \"closed-form\" on a Cartesian path";
bool numerical_ik(const ReferenceSettings& r) { return cartesian_path(r) && r.ik == IkMethod::kNumerical; }
bool closed_form_ik(const ReferenceSettings& r) { return cartesian_path(r) && r.ik == IkMethod::kClosedForm; }

// A joint-space source's defaults, before timing and interpolation are read:
// its own times, the cubic spline.
void joint_defaults(StrictTable&, ReferenceSettings& r) {
  if (!r.joint_source()) return;
  r.timing = "explicit";
  r.interpolation = Interpolation::kJointCubic;
}

bool table_timing(const ReferenceSettings& r) { return r.timing == "table"; }
bool table_speed(const ReferenceSettings& r) { return table_timing(r) && cartesian_path(r); }
bool shaped_timing(const ReferenceSettings& r) {
  return r.timing == "trapezoid" || r.timing == "scurve" || r.timing == "quintic";
}
bool ramped_timing(const ReferenceSettings& r) { return r.timing == "trapezoid" || r.timing == "scurve"; }
bool scurve_timing(const ReferenceSettings& r) { return r.timing == "scurve"; }
bool via_segmented(const ReferenceSettings& r) {
  return cartesian_path(r) && r.interpolation != Interpolation::kCartesian;
}

// "explicit" (the points' own times) only for a joint-space source.
void timing_of_source(StrictTable& t, ReferenceSettings& r) {
  if (r.timing == "explicit" && cartesian_path(r)) {
    t.fail("timing", "table | trapezoid | scurve | quintic | time-optimal for a Cartesian path (\"explicit\" takes "
           "the times of reference.joints or reference.via_points)", "\"explicit\"");
  }
}

// The table's duration: from max_speed or from traversal_time, exactly one;
// a joint-space source has no path speed [m/s]: traversal_time.
void one_table_duration(StrictTable& t, ReferenceSettings& r) {
  if (r.joint_source()) {
    if (t.has("max_speed")) {
      t.fail("max_speed", "traversal_time instead (a joint-space reference has no path speed in m/s)", "max_speed");
    }
    if (!t.has("traversal_time")) t.fail("traversal_time", "the table's duration [s]", "nothing");
    return;
  }
  if (t.has("max_speed") == t.has("traversal_time")) {
    t.fail(t.has("max_speed") ? "traversal_time" : "max_speed",
           "exactly one of max_speed and traversal_time (the table's duration)", "both or neither");
  }
}

// A joint-space source is a spline through its points.
void interpolation_of_source(StrictTable& t, ReferenceSettings& r) {
  if (r.joint_source() && r.interpolation == Interpolation::kCartesian) {
    t.fail("interpolation", "joint-cubic | joint-quintic for a joint-space reference (joints, via_points)",
           "\"cartesian\"");
  }
}

// ik: the closed form where the robot has it (the default there), else numerical.
void ik_of_robot(StrictTable& t, ReferenceSettings& r) {
  if (!t.has("ik")) {
    r.ik = r.closed_form_why.empty() ? IkMethod::kClosedForm : IkMethod::kNumerical;
  } else if (r.ik == IkMethod::kClosedForm && !r.closed_form_why.empty()) {
    t.fail("ik", "\"numerical\" for this robot (" + r.closed_form_why + ")", "\"closed-form\"");
  }
}

// A table, one entry to a few lines as it reads (clang-format would put each
// field on its own line):
// clang-format off
const std::vector<Entry<ReferenceSettings>> kReferenceEntries = {
    {"joints", joints_csv_codec(), "a CSV file of rows t, q1 ... qn (relative to the scene)", Need::kIfSet, {},
     joint_defaults},
    {"via_points", via_points_codec(), "rows [t, q1, ..., qn]: the points in the scene", Need::kIfSet,
     {no_joints_file, "joints", "joints not given"}, joint_defaults},
    {"height", scene_io::number(kAny, PUMASIM_AT(s.height)), "plane z [m]", Need::kRequired, {cartesian_path, {}, kCartesianPath}},
    {"start", scene_io::numbers([](const ReferenceSettings&, int) { return 2; }, kAny,
                                [](const ReferenceSettings& r, int) { return std::vector<double>{r.start.x(), r.start.y()}; },
                                [](ReferenceSettings& r, const std::vector<double>& v) { r.start = {v[0], v[1]}; }),
     "[m] (x, y) in the plane", Need::kRequired, {cartesian_path, {}, kCartesianPath}},
    {"heading", scene_io::number({-2 * M_PI, 2 * M_PI}, PUMASIM_AT(s.heading)), "[rad] of the first segment",
     Need::kOptional, {cartesian_path, {}, kCartesianPath}},
    {"segments", segments_codec(), "lines and arcs, in order", Need::kRequired, {cartesian_path, {}, kCartesianPath}},
    {"timing", scene_io::text(PUMASIM_AT(s.timing), {"table", "trapezoid", "scurve", "quintic", "time-optimal", "explicit"}),
     "the timing law s(t)", Need::kOptional, {}, timing_of_source},
    {"profile", profile_codec(), "table: (t/T, v/v_max) rows", Need::kRequired, {table_timing, "timing"}},
    {"max_speed", scene_io::number(kPositive, PUMASIM_AT(s.max_speed)), "table: [m/s] peak path speed",
     Need::kIfSet, {table_speed, "timing", "timing = \"table\" on a Cartesian path"}},
    {"traversal_time", scene_io::number(kPositive, PUMASIM_AT(s.traversal_time)),
     "table: [s] the duration instead of max_speed (required for a joint-space reference)", Need::kIfSet,
     {table_timing, "timing"}, one_table_duration},
    {"traversal_time", scene_io::number(kPositive, PUMASIM_AT(s.traversal_time)), "[s] the duration",
     Need::kRequired, {shaped_timing, "timing"}},
    {"blend", scene_io::number(kRampShare, PUMASIM_AT(s.blend)), "each acceleration phase's share of T",
     Need::kOptional, {ramped_timing, "timing"}},
    {"jerk_fraction", scene_io::number(kRampShare, PUMASIM_AT(s.jerk_fraction)),
     "share of an acceleration phase spent ramping it", Need::kOptional, {scurve_timing, "timing"}},
    {"interpolation", scene_io::choice(interpolations(), PUMASIM_AT(s.interpolation)),
     "cartesian | joint-cubic | joint-quintic", Need::kOptional, {}, interpolation_of_source},
    {"via_segments", scene_io::whole({1.0, 1e5}, "a whole number >= 1", PUMASIM_AT(s.via_segments)),
     "joint space: the via-points cut the path into this many pieces", Need::kOptional, {via_segmented, "interpolation",
     "interpolation = \"joint-cubic\" or \"joint-quintic\" of a Cartesian path"}},
    {"ik", scene_io::choice<IkMethod>({{"closed-form", IkMethod::kClosedForm}, {"numerical", IkMethod::kNumerical}},
                                      PUMASIM_AT(s.ik)),
     "inverse kinematics: closed-form (the PUMA; its default) | numerical (any arm)", Need::kOptional,
     {cartesian_path, {}, kCartesianPath}, ik_of_robot},
    {"ik_guess", scene_io::numbers([](const ReferenceSettings&, int n) { return n; }, kJointAngle,
                                   [](const ReferenceSettings& r, int) { return r.ik_guess; },
                                   [](ReferenceSettings& r, const std::vector<double>& v) { r.ik_guess = v; }),
     "numerical: [rad] the guess at the path's start (default: mid-range)", Need::kIfSet, {numerical_ik, "ik", "ik = \"numerical\" on a Cartesian path"}},
    {"arm", scene_io::choice<bool>({{"right", true}, {"left", false}}, PUMASIM_AT(s.config.right_arm)),
     "inverse kinematics branch: shoulder", Need::kOptional, {closed_form_ik, "ik", kClosedFormIk}},
    {"elbow", scene_io::choice<bool>({{"up", true}, {"down", false}}, PUMASIM_AT(s.config.elbow_up)),
     "inverse kinematics branch: elbow", Need::kOptional, {closed_form_ik, "ik", kClosedFormIk}},
    {"wrist", scene_io::choice<bool>({{"noflip", false}, {"flip", true}}, PUMASIM_AT(s.config.wrist_flip)),
     "inverse kinematics branch: wrist", Need::kOptional, {closed_form_ik, "ik", kClosedFormIk}},
    {"orientation", orientation_codec(), "6 joints or more: the flange's fixed orientation (rows)", Need::kOptional,
     {cartesian_path, {}, kCartesianPath}},
};
// clang-format on

// ---------------------------------------------------------------- [planning]

const Bounds kVoltageShare{0.0, 1.0, true};
const Bounds kLimit = Bounds::positive_or_infinity();  // inf: no limit

const std::vector<Entry<ReferenceSettings>> kPlanningEntries = {
    {"voltage_fraction", scene_io::number(kVoltageShare, PUMASIM_AT(s.voltage_fraction)),
     "of min(K_A output_limit, voltage_limit); the rest is left to feedback"},
    {"current_limit", scene_io::per_joint(kLimit, PUMASIM_AT(s.current_limit[j])), "[A] per joint (inf: none)"},
    {"joint_speed_limit", scene_io::per_joint(kLimit, PUMASIM_AT(s.joint_speed_limit[j])),
     "[rad/s] per joint (inf: none)"},
    {"grid", scene_io::whole({10.0, 1e6}, "a whole number >= 10", PUMASIM_AT(s.grid)),
     "arc-length grid intervals of the phase-plane passes"},
};

// [planning]: the limits the time-optimal timing plans within (absent: every
// default, no current or speed limit).
void read_planning(std::optional<StrictTable>& plan, const std::string& file, ReferenceSettings& r, int n) {
  const toml::table none;
  StrictTable empty(none, file, "planning");
  r.current_limit.assign(n, std::numeric_limits<double>::infinity());
  r.joint_speed_limit.assign(n, std::numeric_limits<double>::infinity());
  read_entries(plan ? *plan : empty, kPlanningEntries, r, n);
}

// The joint-space source's spline (its points' times as the parameter).
JointCurve joint_curve_of(const ReferenceSettings& r, int n) {
  std::vector<double> knots;
  std::vector<Eigen::VectorXd> points;
  for (const auto& row : r.points) {
    knots.push_back(row[0]);
    Eigen::VectorXd q = Eigen::VectorXd::Zero(n);
    for (int j = 0; j < n; ++j) q[j] = row[static_cast<std::size_t>(j + 1)];
    points.push_back(q);
  }
  const auto kind = r.interpolation == Interpolation::kJointQuintic ? JointCurve::Kind::kQuintic
                                                                    : JointCurve::Kind::kCubic;
  return JointCurve(knots, points, n, kind);
}

IkSettings ik_of(const ReferenceSettings& r, int n) {
  IkSettings ik{r.ik, std::nullopt};
  if (!r.ik_guess.empty()) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
    for (int j = 0; j < n; ++j) g[j] = r.ik_guess[static_cast<std::size_t>(j)];
    ik.guess = g;
  }
  return ik;
}

// The reference of the settings' source (the path with its IK, or the joint
// curve) under `timing`, for the first n joints.
std::unique_ptr<Reference> make_reference(const PlantConfig& pc, int n, const ReferenceSettings& r, Timing timing) {
  if (r.joint_source()) return std::make_unique<Reference>(pc.robot, pc.q_held, joint_curve_of(r, n), std::move(timing));
  const Path path(r.start, r.heading, r.height, r.segments);
  return std::make_unique<Reference>(pc.robot, n, pc.q_held, r.config, r.orientation, path, std::move(timing),
                                     r.interpolation, r.via_segments, ik_of(r, n));
}

// The length the timing law runs along: the path's [m], or the joint
// curve's parameter range (its points' last time) [s].
double source_length(const ReferenceSettings& r) {
  if (r.joint_source()) return r.points.back()[0];
  return Path(r.start, r.heading, r.height, r.segments).length();
}

// The reference the controller follows, from the settings (the constructor
// checks the whole path or curve: reach, joint limits, branch).
std::shared_ptr<const Reference> build_reference(const StrictTable& rt, const PlantConfig& pc,
                                                 const ReferenceSettings& r) {
  try {
    const double L = source_length(r);
    std::optional<Timing> timing;
    if (r.timing == "explicit") {
      timing = Timing::unit_speed(L);
    } else if (r.timing == "table") {
      timing = r.max_speed > 0 ? Timing::table(r.profile, L, r.max_speed)
                               : Timing::table_with_duration(r.profile, L, r.traversal_time);
    } else if (r.timing == "trapezoid") {
      timing = Timing::trapezoid(L, r.traversal_time, r.blend);
    } else if (r.timing == "scurve") {
      timing = Timing::scurve(L, r.traversal_time, r.blend, r.jerk_fraction);
    } else if (r.timing == "quintic") {
      timing = Timing::quintic(L, r.traversal_time);
    } else {
      const PlanningSetup setup = time_optimal_setup(pc, pc.n, r);
      timing = setup.planner->plan(*setup.unit, r.grid);
    }
    return make_reference(pc, pc.n, r, *timing);
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {
    throw ConfigError(rt.where() + e.what());
  }
}

// [reference], and [planning] only with the time-optimal timing.
void read_reference(StrictTable& root, Scene& sc) {
  std::optional<StrictTable> rt = root.optional_table("reference");
  if (!rt) return;
  sc.has_reference = true;
  ReferenceSettings& r = sc.reference;
  r.scene_dir = std::filesystem::path(sc.file).parent_path().string();
  r.closed_form_why = puma_ik_unsupported(sc.plant.robot);
  read_entries(*rt, kReferenceEntries, r, sc.plant.n);
  std::optional<StrictTable> plan = root.optional_table("planning");
  if (plan && r.timing != "time-optimal") {
    root.fail("planning", "[planning] only with reference.timing = \"time-optimal\"", "timing \"" + r.timing + "\"");
  }
  if (r.timing == "time-optimal") {
    if (!sc.plant.drive) {
      rt->fail("timing", "a drive ([amplifier], [motor]) whose limits the time-optimal timing uses", "no drive");
    }
    if (sc.plant.friction[0].model == friction_model<SigmoidFriction>()) {
      // The planner (models/reference/time_optimal.cpp) takes friction as Fk sign(w) + B w.
      rt->fail("timing", "a friction law the time-optimal planner models, Fk sign(w_m) + B w_m (not \"sigmoid\": "
               "its level differs with the direction; use another timing)", "friction.model = \"sigmoid\"");
    }
    read_planning(plan, sc.file, r, sc.plant.n);
  }
  if (template_load && r.timing != "time-optimal") {  // the planner reads the drive too: not shared
    const SceneTemplate::Shared::ReferenceKey key{
        sc.robot_spec, template_load->robot_files, sc.rotor_inertia, sc.plant.n, sc.plant.q_held, r};
    auto shared = template_load->shared->reference(key, [&] { return build_reference(*rt, sc.plant, r); });
    sc.plant.reference = std::move(shared.reference);
    sc.plant.reference_table = std::move(shared.table);
  } else {
    sc.plant.reference = build_reference(*rt, sc.plant, r);
  }
}

void write_reference(toml::table& doc, const Scene& sc) {
  if (!sc.has_reference) return;
  doc.insert("reference", write_entries(kReferenceEntries, sc.reference, sc.plant.n));
  if (sc.reference.timing == "time-optimal") {
    doc.insert("planning", write_entries(kPlanningEntries, sc.reference, sc.plant.n));
  }
}

// ---------------------------------------------------------------- [initial]

// The pose held without a reference: a named pose of the robot file, or the
// angles (resolved as the angles).
struct InitialPose {
  std::string pose;
  std::vector<double> q;  // [rad], the simulated joints
};

bool no_pose(const InitialPose& p) { return p.pose.empty(); }

const std::vector<Entry<InitialPose>> kInitialEntries = {
    {"pose", scene_io::text(PUMASIM_AT(s.pose)), "a pose named in the robot file", Need::kIfSet},
    {"q", scene_io::numbers([](const InitialPose&, int n) { return n; }, kJointAngle,
                            [](const InitialPose& p, int) { return p.q; },
                            [](InitialPose& p, const std::vector<double>& v) { p.q = v; }),
     "[rad] the simulated joints' angles", Need::kRequired, {no_pose, "pose"}},
};

void read_initial(StrictTable& root, PlantConfig& pc) {
  auto t = root.optional_table("initial");
  if (!t) root.fail("initial", "a [reference] to follow or an [initial] pose (held by a controller)", "neither");
  InitialPose init;
  read_entries(*t, kInitialEntries, init, pc.n);
  if (init.pose.empty()) {
    pc.q0 = Eigen::Map<const Eigen::VectorXd>(init.q.data(), pc.n);
    return;
  }
  const NamedPose* p = pc.robot.pose(init.pose);
  if (!p) t->fail("pose", "a pose of the robot file", "\"" + init.pose + "\"");
  pc.q0 = p->q.head(pc.n);
}

void write_initial(toml::table& doc, const PlantConfig& pc) {
  if (pc.reference) return;
  const InitialPose init{"", std::vector<double>(pc.q0.data(), pc.q0.data() + pc.n)};
  doc.insert("initial", write_entries(kInitialEntries, init, pc.n));
}

// Without rotor inertia on some simulated joint, H(q) can be singular (a
// joint that moves no mass): checked at the run's start pose, the pose the
// plant must first invert H at (the robot file checked its zero and named
// poses; every rotor inertia > 0 makes H definite at every pose).
void check_start_inertia(StrictTable& root, const Scene& sc) {
  const PlantConfig& pc = sc.plant;
  const RobotModel sim = simulated_robot(pc.robot, pc.n, pc.q_held);
  const auto has_rotor = [](const JointParams& J) { return J.rotor_inertia > 0; };
  if (std::all_of(sim.joints.begin(), sim.joints.end(), has_rotor)) return;
  const int j = joint_without_inertia(sim, start_pose(pc));
  if (j < 0) return;
  const std::string J = std::to_string(j + 1);
  root.table("scene").fail(sc.rotor_inertia ? "robot" : "rotor_inertia",
                           "a joint-space inertia H(q) that is positive definite at the start pose",
                           "joint " + J + " moving no mass there and without rotor inertia: H(q) is singular");
}

}  // namespace

namespace {

// The scene in `doc` (from `path`), read and checked: load_scene's and
// load_scene_text's work once the document is parsed.
Scene read_scene_document(toml::table& doc, const std::string& path, const InputRecord& record) {
  StrictTable root(doc, path, "");
  // The scene's sections, checked first (every key inside them is checked as
  // it is read, and root.finish() below rejects what no reader asked for).
  root.expect_only({"scene", "integrator", "amplifier", "motor", "friction", "controller", "reference", "planning",
                    "initial"});
  Scene sc;
  sc.file = path;
  PlantConfig& pc = sc.plant;
  read_scene(root, sc);
  read_integrator(root, sc.integrator);
  read_drive(root, pc);
  read_friction(root, sc);
  read_controller(root, pc);
  read_reference(root, sc);
  if (!pc.reference) read_initial(root, pc);
  const bool given = sc.duration != 0;
  if (!given) {  // scene.duration absent (a given one is > 0): the reference's, or the input's
    const double end = pc.controller == ControllerMode::kNone ? HUGE_VAL : controller_input_end(pc.controller_params);
    if (!pc.reference && !std::isfinite(end)) {
      root.fail("scene", "a duration (no reference or open-loop input to take it from)", "none");
    }
    sc.duration = pc.reference ? pc.reference->timing().duration() : end;
  }
  root.finish();
  sc.duration_source = given        ? "scene.duration"
                       : pc.reference ? "the reference's duration (its timing: reference.max_speed, the profile, "
                                        "the planner's limits or the CSV's last time)"
                                      : "the open-loop input's last time (controller.file)";
  try {
    PlantModel::validate(pc);  // the last consistency checks, with no plant and no back-end built
    check_start_inertia(root, sc);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(path + ": " + e.what());
  }
  sc.inputs = record.files();
  return sc;
}

}  // namespace

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides,
                 const std::vector<std::string>& unsets) {
  const InputRecord record;  // every file read from here on
  toml::table doc = parse_toml_file(path);
  remove_keys(doc, unsets, path);
  apply_overrides(doc, overrides);
  return read_scene_document(doc, path, record);
}

Scene load_scene_text(const std::string& text, const std::string& path) {
  const InputRecord record;  // every file read from here on (the robot's, an input CSV's: not the scene's)
  toml::table doc = parse_toml_text(text, path);
  return read_scene_document(doc, path, record);
}

SceneTemplate::SceneTemplate(const std::string& path, const std::vector<std::string>& sets)
    : path_(path), sets_(sets), shared_(std::make_unique<Shared>()) {
  const InputRecord record;
  const std::optional<std::string> text = read_input_file(path);
  if (!text)
    throw ConfigError(path + ": cannot be read (" + unreadable_reason(path) + "); expected a readable TOML file");
  text_ = *text;
  file_ = record.files().front();
  shared_->doc = parse_toml_text(text_, path);  // its errors, and the sets', now rather than at every load
  apply_overrides(shared_->doc, sets_);
}

SceneTemplate::~SceneTemplate() = default;

namespace {

// A template's load from `doc` (its file's document with its sets), the overrides applied.
Scene read_template(SceneTemplate::Shared* shared, const InputFile& file, const std::string& path, toml::table& doc,
                    const std::vector<std::string>& overrides) {
  const InputRecord record;  // every file read from here on, and the scene file read once
  record_input_file(file);
  apply_overrides(doc, overrides);
  struct Scope {  // template_load set for this load (and restored, were loads to nest)
    TemplateLoad load, *outer;
    explicit Scope(SceneTemplate::Shared* s) : load{s, {}}, outer(template_load) { template_load = &load; }
    ~Scope() { template_load = outer; }
  } scope(shared);
  return read_scene_document(doc, path, record);
}

}  // namespace

Scene SceneTemplate::load(const std::vector<std::string>& overrides) const {
  toml::table copy = shared_->doc;  // concurrent loads only read the shared document
  try {
    return read_template(shared_.get(), file_, path_, copy, overrides);
  } catch (const ConfigError&) {
    return load_exact(overrides);  // the same refusal, with its source line
  }
}

Scene SceneTemplate::load_exact(const std::vector<std::string>& overrides) const {
  toml::table doc = parse_toml_text(text_, path_);
  apply_overrides(doc, sets_);
  return read_template(shared_.get(), file_, path_, doc, overrides);
}

PlanningSetup time_optimal_setup(const PlantConfig& pc, int n, const ReferenceSettings& r) {
  PlanningSetup out;
  ReferenceSettings unit = r;
  unit.interpolation = r.joint_source() ? r.interpolation : Interpolation::kCartesian;
  out.unit = make_reference(pc, n, unit, Timing::unit_speed(source_length(r)));
  DriveLimits lim;
  for (int j = 0; j < n; ++j) {
    lim.voltage.push_back(r.voltage_fraction * command_voltage_range(pc.amplifier[j], controller_output_limit(pc.controller_params, j)));
  }
  lim.current = r.current_limit;
  lim.joint_speed = r.joint_speed_limit;
  const RobotModel sim = simulated_robot(pc.robot, n, pc.q_held);
  std::vector<FrictionParams> fr = pc.friction;
  if (fr.empty()) fr.assign(n, FrictionParams{});
  out.planner = std::make_unique<TimeOptimalPlanner>(sim, pc.backend, pc.amplifier, pc.motor, fr, lim);
  return out;
}

std::string resolved_toml(const Scene& sc) {
  const PlantConfig& pc = sc.plant;
  toml::table doc;
  doc.insert("scene", write_scene(sc));
  doc.insert("integrator", write_integrator(sc.integrator));
  write_drive(doc, pc);
  doc.insert("friction", write_friction(pc));
  write_controller(doc, pc);
  write_reference(doc, sc);
  write_initial(doc, pc);
  std::ostringstream out;
  out << "# Resolved scene: every default filled in (from " << sc.file << ")\n" << write_toml(doc) << "\n";
  for (const InputFile& f : sc.inputs) out << "# input file: " << describe(f) << "\n";
  return out.str();
}

std::vector<SceneKeyDoc> scene_key_docs() {
  using scene_io::add_key_docs;
  // The sections' structs at their defaults, sized for one joint: where each
  // entry's condition is evaluated (scene_io::applies_text).
  PlantConfig pc;
  pc.n = 1;
  pc.amplifier.resize(1);
  pc.motor.resize(1);
  pc.friction.resize(1);
  std::vector<SceneKeyDoc> out;
  ReferenceSettings joint_space;  // the other shape of a reference (a CSV file's name suffices here)
  joint_space.joints_file = "joints.csv";
  add_key_docs(out, "scene", kSceneEntries, {Scene{}});
  add_key_docs(out, "integrator", kIntegratorEntries, {IntegratorSettings{}});
  add_key_docs(out, "amplifier", kAmplifierEntries, {pc});
  add_key_docs(out, "motor", kMotorEntries, {pc});
  add_key_docs(out, "friction", kFrictionEntries, {pc});
  add_key_docs(out, "controller", controller_entries(), {pc});
  add_key_docs(out, "reference", kReferenceEntries, {ReferenceSettings{}, joint_space});
  add_key_docs(out, "planning", kPlanningEntries, {ReferenceSettings{}});
  add_key_docs(out, "initial", kInitialEntries, {InitialPose{}});
  return out;
}

std::string discontinuity_note(const Scene& sc) {
  for (const FrictionParams& f : sc.plant.friction) {
    if (!is_set_valued(f.model) || has_stick_slip_events(f.model)) continue;
    if (!(f.static_torque > 0) && !(f.kinetic_torque > 0)) continue;
    return std::string("friction.model = \"") + to_string(f.model) +
           "\" is discontinuous in the state (the friction jumps between the kinetic level and the applied torque at "
           "|w_m| = friction.zero_speed, with no event to stop at): adaptive methods stall on it, their step "
           "collapsing at the switching surface; use a fixed-step method (the paper's: integrator ab2, dt = 5e-4 s), "
           "friction.model = \"hybrid\" (the exact stick/slip model with events) or the integrator moreau-jean "
           "(time-stepping)";
  }
  return {};
}

std::string discrete_state(const Scene& sc) {
  const PlantConfig& pc = sc.plant;
  std::string what;
  const auto add = [&what](const std::string& s) { what += (what.empty() ? "" : "; ") + s; };
  if (pc.controller == ControllerMode::kSampled) {
    add("the sampled controller's held output (controller.mode = \"sampled\")");
  }
  if (pc.reference && pc.setpoint_interval > 0 && pc.controller != ControllerMode::kNone) {
    add("the held set-point (controller.setpoint_interval > 0)");
  }
  for (const FrictionParams& f : pc.friction) {
    if (has_stick_slip_events(f.model)) {
      add(std::string("the stuck and slipping modes of the friction (friction.model = \"") + to_string(f.model) +
          "\")");
      break;
    }
  }
  return what;
}

}  // namespace pumasim
