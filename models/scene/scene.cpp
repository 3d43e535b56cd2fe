#include "models/scene/scene.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "models/dynamics/backend.hpp"
#include "models/robot/robot_file.hpp"
#include "models/reference/time_optimal.hpp"

namespace pumasim {
namespace {

const Bounds kPositive = Bounds::positive();
const Bounds kNonNegative = Bounds::non_negative();

int read_int(StrictTable& t, std::string_view key, int lo, int hi) {
  const double x = t.number(key, {static_cast<double>(lo), static_cast<double>(hi)});
  if (x != std::floor(x)) {
    t.fail(key, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]",
           std::to_string(x));
  }
  return static_cast<int>(x);
}

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
      v.push_back(*d);
    }
    rows.push_back(v);
  }
  return rows;
}

FrictionModel friction_model(const std::string& s) {
  if (s == "none") return FrictionModel::kNone;
  if (s == "viscous") return FrictionModel::kViscous;
  if (s == "paper") return FrictionModel::kPaper;
  if (s == "hybrid") return FrictionModel::kHybrid;
  if (s == "karnopp") return FrictionModel::kKarnopp;
  return FrictionModel::kTanh;
}

toml::array to_array(const std::vector<double>& v) {
  toml::array a;
  for (double x : v) a.push_back(x);
  return a;
}

template <class F>
toml::array per_joint_array(int n, F f) {
  toml::array a;
  for (int j = 0; j < n; ++j) a.push_back(f(j));
  return a;
}

}  // namespace

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  toml::table doc = parse_toml_file(path);
  apply_overrides(doc, overrides);
  StrictTable root(doc, path, "");
  Scene sc;
  sc.file = path;
  PlantConfig& pc = sc.plant;

  StrictTable s = root.table("scene");
  sc.name = s.string("name");
  // The name becomes a folder name (runs/<name>/): a plain one only.
  const bool plain = !sc.name.empty() && sc.name.size() <= 100 && sc.name != "." && sc.name != ".." &&
                     std::all_of(sc.name.begin(), sc.name.end(), [](char c) {
                       return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
                     });
  if (!plain) {
    s.fail("name", "a plain name of at most 100 letters, digits, '_', '-' and '.' (not '.' or '..')",
           "\"" + sc.name + "\"");
  }
  sc.robot_spec = s.string("robot");
  std::string robot_path = sc.robot_spec;
  if (robot_path.find('/') != std::string::npos && !std::filesystem::path(robot_path).is_absolute()) {
    robot_path = (std::filesystem::path(path).parent_path() / robot_path).string();
  }
  try {
    pc.robot = load_robot(robot_path);
  } catch (const ConfigError& e) {
    throw ConfigError(s.where("robot") + e.what());
  }
  sc.rotor_inertia = s.boolean_or("rotor_inertia", true);
  pc.energy_ledger = s.boolean_or("energy_ledger", false);
  if (!sc.rotor_inertia) pc.robot = without_rotor_inertia(pc.robot);
  const int dof = pc.robot.dof();
  // The plant and the reference hold a pose in a 6-vector, and lock held
  // joints only on a 6-joint arm: checked here, before any size is used.
  if (dof > 6) s.fail("robot", "a robot with at most 6 joints", "one with " + std::to_string(dof));
  const int n = read_int(s, "joints", 1, dof);
  if (n < dof && dof != 6) {
    s.fail("joints", "all " + std::to_string(dof) + " joints of this robot (held joints need a 6-joint robot)",
           std::to_string(n));
  }
  pc.n = n;
  const auto held = s.optional_numbers("held", dof - n, {-4 * M_PI, 4 * M_PI});
  pc.q_held.setZero();
  if (held) {
    for (int k = 0; k < dof - n; ++k) pc.q_held[n + k] = (*held)[k];
  }
  pc.backend = s.string_or("backend", "crba");
  try {
    const BackendInfo& b = find_backend(pc.backend);
    const RobotModel sim = simulated_robot(pc.robot, n, pc.q_held);
    if (const std::string why = b.why_unsupported(sim); !why.empty()) s.fail("backend", "a back-end that supports this robot", why);
  } catch (const std::invalid_argument& e) {
    s.fail("backend", "one of: " + backend_names(), "\"" + pc.backend + "\"");
  }
  const bool has_duration = s.has("duration");
  sc.duration = s.number_or("duration", 0.0, kPositive);
  sc.output_interval = s.number_or("output_interval", 0.01, kPositive);
  s.finish();

  if (auto it = root.optional_table("integrator")) {
    if (it->has("name")) sc.integrator.name_where = it->where("name");
    sc.integrator.name = it->string_or("name", sc.integrator.name);
    sc.integrator.dt = it->number_or("dt", sc.integrator.dt, kPositive);
    sc.integrator.rtol = it->number_or("rtol", sc.integrator.rtol, kPositive);
    sc.integrator.atol = it->number_or("atol", sc.integrator.atol, kPositive);
    it->finish();
  }

  // Drive: amplifier and motor come together.
  auto amp = root.optional_table("amplifier");
  auto mot = root.optional_table("motor");
  if (amp.has_value() != mot.has_value()) {
    root.fail(amp ? "motor" : "amplifier", "both [amplifier] and [motor] (the drive) or neither",
              "only one of them");
  }
  pc.drive = amp.has_value();
  if (pc.drive) {
    const auto gain = amp->per_joint("gain", n, kPositive);
    const auto r0 = amp->per_joint_or("output_resistance", n, 0.0, kNonNegative);
    const auto vmax = amp->per_joint_or("voltage_limit", n, 1e9, kPositive);
    amp->finish();
    const auto La = mot->per_joint("inductance", n, kNonNegative);
    const auto R = mot->per_joint("resistance", n, kPositive);
    const auto K = mot->per_joint("torque_constant", n, kPositive);
    mot->finish();
    const bool any = std::any_of(La.begin(), La.end(), [](double x) { return x > 0; });
    const bool all = std::all_of(La.begin(), La.end(), [](double x) { return x > 0; });
    if (any && !all) {
      mot->fail("inductance", "all > 0 (current states) or all 0 (the reduced model)", "a mix");
    }
    for (int j = 0; j < n; ++j) {
      pc.amplifier.push_back({gain[j], r0[j], vmax[j]});
      pc.motor.push_back({La[j], R[j], K[j]});
    }
  }

  pc.friction.assign(n, FrictionParams{});
  if (auto fr = root.optional_table("friction")) {
    const std::string model =
        fr->string("model", {"none", "viscous", "paper", "hybrid", "karnopp", "tanh"});
    const FrictionModel m = friction_model(model);
    const bool coulomb = m != FrictionModel::kNone && m != FrictionModel::kViscous;
    const auto B = m == FrictionModel::kNone ? std::vector<double>(n, 0.0)
                                             : fr->per_joint_or("viscous", n, 0.0, kNonNegative);
    const auto Fs = coulomb ? fr->per_joint("static_torque", n, kNonNegative)
                            : std::vector<double>(n, 0.0);
    const auto Fk = coulomb ? fr->per_joint("kinetic_torque", n, kNonNegative)
                            : std::vector<double>(n, 0.0);
    // Keys that mean nothing for the model are unknown keys (finish() says so).
    const bool banded = m == FrictionModel::kPaper || m == FrictionModel::kKarnopp;
    const double zero_default = m == FrictionModel::kKarnopp ? 1e-3 : 1e-6;
    const double zero = banded ? fr->number_or("zero_speed", zero_default, kPositive) : zero_default;
    const double scale =
        m == FrictionModel::kTanh ? fr->number_or("speed_scale", 1e-2, kPositive) : 1e-2;
    fr->finish();
    for (int j = 0; j < n; ++j) pc.friction[j] = {m, B[j], Fs[j], Fk[j], zero, scale};
  }

  pc.controller = ControllerMode::kNone;
  if (auto ct = root.optional_table("controller")) {
    const std::string mode = ct->string("mode", {"continuous", "sampled"});
    pc.controller = mode == "sampled" ? ControllerMode::kSampled : ControllerMode::kContinuous;
    if (pc.controller == ControllerMode::kSampled) {
      pc.servo_period = ct->number("servo_period", kPositive);
    }
    pc.setpoint_interval = ct->number_or("setpoint_interval", 0.0, kNonNegative);
    const auto kp = ct->per_joint("kp", n), ki = ct->per_joint_or("ki", n, 0.0),
               kv = ct->per_joint_or("kv", n, 0.0), kvff = ct->per_joint_or("kvff", n, 0.0),
               kaff = ct->per_joint_or("kaff", n, 0.0),
               ilim = ct->per_joint_or("integral_limit", n, 10.0, kPositive),
               ulim = ct->per_joint_or("output_limit", n, 10.0, kPositive),
               off = ct->per_joint_or("offset", n, 0.0);
    ct->finish();
    for (int j = 0; j < n; ++j) pc.piv.push_back({kp[j], ki[j], kv[j], kvff[j], kaff[j], ilim[j], ulim[j], off[j]});
    if (!pc.drive) root.fail("controller", "a drive ([amplifier] and [motor]) with a controller", "no drive");
  } else if (pc.drive) {
    root.fail("amplifier", "a [controller] to drive the amplifier", "no controller");
  }

  if (auto rt = root.optional_table("reference")) {
    ReferenceSettings& r = sc.reference;
    sc.has_reference = true;
    r.height = rt->number("height");
    const auto st = rt->numbers("start", 2);
    r.start = Eigen::Vector2d(st[0], st[1]);
    r.heading = rt->number_or("heading", 0.0, {-2 * M_PI, 2 * M_PI});
    for (StrictTable& seg : rt->array_of_tables("segments")) {
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
    r.timing = rt->string_or("timing", "table", {"table", "trapezoid", "scurve", "quintic", "time-optimal"});
    if (r.timing == "table") {
      for (const auto& row : read_rows(*rt, "profile", 2)) r.profile.emplace_back(row[0], row[1]);
      if (rt->has("max_speed") == rt->has("traversal_time")) {
        rt->fail(rt->has("max_speed") ? "traversal_time" : "max_speed",
                 "exactly one of max_speed and traversal_time (the table's duration)", "both or neither");
      }
      r.max_speed = rt->number_or("max_speed", 0.0, kPositive);
      r.traversal_time = rt->number_or("traversal_time", 0.0, kPositive);
    } else if (r.timing != "time-optimal") {
      r.traversal_time = rt->number("traversal_time", kPositive);
      if (r.timing != "quintic") r.blend = rt->number_or("blend", r.blend, {0.0, 0.5, true});
      if (r.timing == "scurve") r.jerk_fraction = rt->number_or("jerk_fraction", r.jerk_fraction, {0.0, 0.5, true});
    }
    const std::vector<Interpolation> interps{Interpolation::kCartesian, Interpolation::kJointCubic,
                                             Interpolation::kJointQuintic};
    std::vector<std::string> interp_names;
    for (Interpolation i : interps) interp_names.emplace_back(to_string(i));
    const std::string interp = rt->string_or("interpolation", interp_names[0], interp_names);
    r.interpolation = interps[std::find(interp_names.begin(), interp_names.end(), interp) - interp_names.begin()];
    if (r.interpolation != Interpolation::kCartesian) {
      const double v = rt->number_or("via_segments", r.via_segments, {1.0, 1e5});
      if (v != std::floor(v)) rt->fail("via_segments", "a whole number >= 1", std::to_string(v));
      r.via_segments = static_cast<int>(v);
    }
    r.config.right_arm = rt->string_or("arm", "right", {"right", "left"}) == "right";
    r.config.elbow_up = rt->string_or("elbow", "up", {"up", "down"}) == "up";
    r.config.wrist_flip = rt->string_or("wrist", "noflip", {"noflip", "flip"}) == "flip";
    r.orientation << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // flange z pointing down
    if (rt->has("orientation")) {
      const auto rows = read_rows(*rt, "orientation", 3);
      if (rows.size() != 3) rt->fail("orientation", "a 3 x 3 rotation matrix (rows)", "another shape");
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) r.orientation(i, k) = rows[i][k];
      if ((r.orientation * r.orientation.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-9 ||
          r.orientation.determinant() < 0) {
        rt->fail("orientation", "a rotation matrix (orthonormal, determinant +1)", "another matrix");
      }
    }
    std::optional<StrictTable> plan = root.optional_table("planning");
    if (plan && r.timing != "time-optimal") {
      root.fail("planning", "[planning] only with reference.timing = \"time-optimal\"", "timing \"" + r.timing + "\"");
    }
    if (r.timing == "time-optimal") {
      if (!pc.drive) rt->fail("timing", "a drive ([amplifier], [motor]) whose limits the time-optimal timing uses", "no drive");
      const toml::table none;
      StrictTable empty(none, sc.file, "planning");
      StrictTable& pt = plan ? *plan : empty;
      r.voltage_fraction = pt.number_or("voltage_fraction", r.voltage_fraction, {0.0, 1.0, true});
      r.current_limit = pt.per_joint_or("current_limit", n, std::numeric_limits<double>::infinity(), kPositive);
      r.joint_speed_limit = pt.per_joint_or("joint_speed_limit", n, std::numeric_limits<double>::infinity(), kPositive);
      const double g = pt.number_or("grid", r.grid, {10.0, 1e6});
      if (g != std::floor(g)) pt.fail("grid", "a whole number >= 10", std::to_string(g));
      r.grid = static_cast<int>(g);
      pt.finish();
    }
    try {
      Path path(r.start, r.heading, r.height, r.segments);
      const double L = path.length();
      std::optional<Timing> timing;
      if (r.timing == "table") {
        timing = r.max_speed > 0 ? Timing::table(r.profile, L, r.max_speed)
                                 : Timing::table_with_duration(r.profile, L, r.traversal_time);
      } else if (r.timing == "trapezoid") {
        timing = Timing::trapezoid(L, r.traversal_time, r.blend);
      } else if (r.timing == "scurve") {
        timing = Timing::scurve(L, r.traversal_time, r.blend, r.jerk_fraction);
      } else if (r.timing == "quintic") {
        timing = Timing::quintic(L, r.traversal_time);
      } else {
        const PlanningSetup setup = time_optimal_setup(pc, n, r);
        timing = setup.planner->plan(*setup.unit, r.grid);
      }
      auto ref = std::make_shared<Reference>(pc.robot, n, pc.q_held, r.config, r.orientation, path, *timing,
                                             r.interpolation, r.via_segments);
      // (The constructor checks the whole path: reach, joint limits, branch.)
      pc.reference = ref;
    } catch (const ConfigError&) {
      throw;
    } catch (const std::exception& e) {
      throw ConfigError(rt->where() + e.what());
    }
    rt->finish();
  }
  if (!pc.reference) {
    auto init = root.optional_table("initial");
    if (!init) {
      root.fail("initial", "a [reference] to follow or an [initial] pose (held by a controller)", "neither");
    }
    if (init->has("pose")) {
      const std::string pose = init->string("pose");
      const NamedPose* p = pc.robot.pose(pose);
      if (!p) init->fail("pose", "a pose of the robot file", "\"" + pose + "\"");
      pc.q0 = p->q.head(n);
    } else {
      const auto q = init->numbers("q", n, {-4 * M_PI, 4 * M_PI});
      pc.q0 = Eigen::Map<const Eigen::VectorXd>(q.data(), n);
    }
    init->finish();
  }
  if (!has_duration) {
    if (!pc.reference) root.fail("scene", "a duration (no reference to take it from)", "none");
    sc.duration = pc.reference->timing().duration();
  }
  root.finish();
  try {
    Plant check(pc);  // the last consistency checks
  } catch (const std::invalid_argument& e) {
    throw ConfigError(path + ": " + e.what());
  }
  return sc;
}

PlanningSetup time_optimal_setup(const PlantConfig& pc, int n, const ReferenceSettings& r) {
  PlanningSetup out;
  const Path path(r.start, r.heading, r.height, r.segments);
  out.unit = std::make_unique<Reference>(pc.robot, n, pc.q_held, r.config, r.orientation, path,
                                         Timing::unit_speed(path.length()));
  DriveLimits lim;
  for (int j = 0; j < n; ++j) {
    lim.voltage.push_back(r.voltage_fraction * command_voltage_range(pc.amplifier[j], pc.piv[j]));
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
  const int n = pc.n;
  toml::table doc;
  toml::table scene{{"name", sc.name},
                    {"robot", sc.robot_spec},
                    {"joints", n},
                    {"rotor_inertia", sc.rotor_inertia},
                    {"energy_ledger", pc.energy_ledger},
                    {"backend", pc.backend},
                    {"duration", sc.duration},
                    {"output_interval", sc.output_interval}};
  toml::array held;
  for (int k = n; k < pc.robot.dof(); ++k) held.push_back(pc.q_held[k]);
  scene.insert("held", held);
  doc.insert("scene", scene);
  doc.insert("integrator", toml::table{{"name", sc.integrator.name},
                                       {"dt", sc.integrator.dt},
                                       {"rtol", sc.integrator.rtol},
                                       {"atol", sc.integrator.atol}});
  if (pc.drive) {
    doc.insert("amplifier",
               toml::table{{"gain", per_joint_array(n, [&](int j) { return pc.amplifier[j].gain; })},
                           {"output_resistance", per_joint_array(n, [&](int j) { return pc.amplifier[j].output_resistance; })},
                           {"voltage_limit", per_joint_array(n, [&](int j) { return pc.amplifier[j].voltage_limit; })}});
    doc.insert("motor",
               toml::table{{"inductance", per_joint_array(n, [&](int j) { return pc.motor[j].inductance; })},
                           {"resistance", per_joint_array(n, [&](int j) { return pc.motor[j].resistance; })},
                           {"torque_constant", per_joint_array(n, [&](int j) { return pc.motor[j].torque_constant; })}});
  }
  const FrictionParams& f0 = pc.friction[0];
  toml::table fr{{"model", to_string(f0.model)}};
  if (f0.model != FrictionModel::kNone) {
    fr.insert("viscous", per_joint_array(n, [&](int j) { return pc.friction[j].viscous; }));
  }
  if (f0.model != FrictionModel::kNone && f0.model != FrictionModel::kViscous) {
    fr.insert("static_torque", per_joint_array(n, [&](int j) { return pc.friction[j].static_torque; }));
    fr.insert("kinetic_torque", per_joint_array(n, [&](int j) { return pc.friction[j].kinetic_torque; }));
  }
  if (f0.model == FrictionModel::kPaper || f0.model == FrictionModel::kKarnopp) {
    fr.insert("zero_speed", f0.zero_speed);
  }
  if (f0.model == FrictionModel::kTanh) fr.insert("speed_scale", f0.speed_scale);
  doc.insert("friction", fr);
  if (pc.controller != ControllerMode::kNone) {
    toml::table c{{"mode", pc.controller == ControllerMode::kSampled ? "sampled" : "continuous"},
                  {"setpoint_interval", pc.setpoint_interval}};
    if (pc.controller == ControllerMode::kSampled) c.insert("servo_period", pc.servo_period);
    c.insert("kp", per_joint_array(n, [&](int j) { return pc.piv[j].kp; }));
    c.insert("ki", per_joint_array(n, [&](int j) { return pc.piv[j].ki; }));
    c.insert("kv", per_joint_array(n, [&](int j) { return pc.piv[j].kv; }));
    c.insert("kvff", per_joint_array(n, [&](int j) { return pc.piv[j].kvff; }));
    c.insert("kaff", per_joint_array(n, [&](int j) { return pc.piv[j].kaff; }));
    c.insert("integral_limit", per_joint_array(n, [&](int j) { return pc.piv[j].integral_limit; }));
    c.insert("output_limit", per_joint_array(n, [&](int j) { return pc.piv[j].output_limit; }));
    c.insert("offset", per_joint_array(n, [&](int j) { return pc.piv[j].offset; }));
    doc.insert("controller", c);
  }
  if (sc.has_reference) {
    const ReferenceSettings& r = sc.reference;
    toml::array segs;
    for (const PathSegment& p : r.segments) {
      if (p.radius > 0) {
        segs.push_back(toml::table{{"arc_radius", p.radius}, {"turn_degrees", p.angle * 180 / M_PI}});
      } else {
        segs.push_back(toml::table{{"line", p.length}});
      }
    }
    toml::array prof, orient;
    for (const auto& pt : r.profile) prof.push_back(toml::array{pt.x(), pt.y()});
    for (int i = 0; i < 3; ++i) {
      orient.push_back(toml::array{r.orientation(i, 0), r.orientation(i, 1), r.orientation(i, 2)});
    }
    toml::table rt{{"height", r.height},
                   {"start", toml::array{r.start.x(), r.start.y()}},
                   {"heading", r.heading},
                   {"segments", segs},
                   {"timing", r.timing},
                   {"arm", r.config.right_arm ? "right" : "left"},
                   {"elbow", r.config.elbow_up ? "up" : "down"},
                   {"wrist", r.config.wrist_flip ? "flip" : "noflip"},
                   {"orientation", orient}};
    if (r.timing == "table") {
      rt.insert("profile", prof);
      if (r.max_speed > 0) rt.insert("max_speed", r.max_speed);
    }
    if (r.traversal_time > 0) rt.insert("traversal_time", r.traversal_time);
    if (r.timing == "trapezoid" || r.timing == "scurve") rt.insert("blend", r.blend);
    if (r.timing == "scurve") rt.insert("jerk_fraction", r.jerk_fraction);
    rt.insert("interpolation", to_string(r.interpolation));
    if (r.interpolation != Interpolation::kCartesian) rt.insert("via_segments", r.via_segments);
    doc.insert("reference", rt);
    if (r.timing == "time-optimal") {
      auto limits = [&](const std::vector<double>& v) {
        toml::array a;
        for (double x : v) a.push_back(x);  // inf: no limit (TOML has inf)
        return a;
      };
      doc.insert("planning", toml::table{{"voltage_fraction", r.voltage_fraction},
                                         {"current_limit", limits(r.current_limit)},
                                         {"joint_speed_limit", limits(r.joint_speed_limit)},
                                         {"grid", r.grid}});
    }
  }
  if (!pc.reference) {
    doc.insert("initial", toml::table{{"q", to_array(std::vector<double>(pc.q0.data(), pc.q0.data() + n))}});
  }
  std::ostringstream out;
  out << "# Resolved scene: every default filled in (from " << sc.file << ")\n" << doc << "\n";
  return out.str();
}

}  // namespace pumasim
