// The `pumasim` command line. CLI11 parses it: one subcommand per command,
// typed options checked as they are read, the help generated. Each command's
// function takes its parsed options and calls the libraries below (a scene's
// run lives in simulation/scene_run). Errors end as one line on
// `err` and exit status 2 (bad input) or 1 (internal); CLI11 never exits.
#include "experiments/cli.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "experiments/stiffness.hpp"
#include "integrators/integrator.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/regressor.hpp"
#include "models/robot/base_parameters.hpp"
#include "models/robot/dynamics_query.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/robot_writer.hpp"
#include "models/scene/scene.hpp"
#include "simulation/ensemble.hpp"
#include "simulation/run.hpp"
#include "simulation/run_folder.hpp"
#include "simulation/scene_run.hpp"

namespace pumasim {
namespace {

namespace fs = std::filesystem;

// Bad command-line input; becomes one line on stderr and exit status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The command line's words for the options the library names neutrally
// (core/option_words.hpp): "--max-steps" for max_steps.
std::string command_line_words(std::string_view name) {
  std::string word = "--" + std::string(name);
  std::replace(word.begin(), word.end(), '_', '-');
  return word;
}

// ---------------------------------------------------------------- values

// A finite number, the whole text (spaces around and a leading '+' allowed),
// converted exactly (std::from_chars: the nearest double).
std::optional<double> to_number(const std::string& s) {
  double x = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  while (b < e && *b == ' ') ++b;
  while (e > b && e[-1] == ' ') --e;
  if (b < e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, x);
  if (b == e || r.ec != std::errc() || r.ptr != e || !std::isfinite(x)) return std::nullopt;
  return x;
}

double parse_double(const std::string& s, const std::string& what) {
  if (const auto x = to_number(s)) return *x;
  throw UsageError(what + ": expected a finite number, got '" + s + "'");
}

// "0.1,-0.2,..." with exactly n entries, or the name of one of the robot's poses.
Eigen::VectorXd parse_vector(const std::string& text, int n, const std::string& what,
                             const RobotModel* poses_from = nullptr) {
  if (poses_from) {
    if (const NamedPose* p = poses_from->pose(text)) return p->q;
  }
  std::vector<double> v;
  std::size_t start = 0;
  while (true) {
    const auto comma = text.find(',', start);
    v.push_back(parse_double(text.substr(start, comma - start), what));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (static_cast<int>(v.size()) != n) {
    std::string poses;
    if (poses_from) {
      for (const auto& p : poses_from->poses) poses += (poses.empty() ? "" : ", ") + p.name;
    }
    throw UsageError(what + ": expected " + std::to_string(n) + " comma-separated numbers" +
                     (poses.empty() ? "" : " or a pose name (" + poses + ")") + ", got " +
                     std::to_string(v.size()) + " values");
  }
  return Eigen::Map<Eigen::VectorXd>(v.data(), n);
}

// ---------------------------------------------------------------- options

// What a number option accepts: said in its help and in its error message.
struct NumberRule {
  const char* expected;  // "a number > 0"
  bool (*ok)(double);
};
constexpr NumberRule kPositive{"a number > 0", [](double x) { return x > 0; }};
constexpr NumberRule kRtol{"a number in [1e-14, 0.1] (below, less than about 50 roundings of a state; above, no "
                           "digit controlled)",
                           [](double x) { return x >= kRtolMin && x <= kRtolMax; }};
constexpr NumberRule kSecondsBudget{"seconds >= 0 (0: no limit)", [](double x) { return x >= 0; }};
constexpr NumberRule kStepBudget{"a whole number in [0, 1e18] (0: no limit)",
                                 [](double x) { return x >= 0 && x <= 1e18 && x == std::floor(x); }};
constexpr NumberRule kSamples{"a whole number in [1, 10000]",
                              [](double x) { return x >= 1 && x <= 10000 && x == std::floor(x); }};
constexpr NumberRule kManySamples{"a whole number in [1, 100000]",
                                  [](double x) { return x >= 1 && x <= 100000 && x == std::floor(x); }};
constexpr NumberRule kThreadCount{"a whole number in [1, 1024]",
                                  [](double x) { return x >= 1 && x <= 1024 && x == std::floor(x); }};
constexpr NumberRule kSampleIndex{"a whole number >= 0",
                                  [](double x) { return x >= 0 && x <= 1e15 && x == std::floor(x); }};

// A number option: checked by CLI11 as it is read ("--t-end: expected a
// number > 0, got 'x'"), then converted exactly; unset when not given.
CLI::Option* add_number(CLI::App* app, const std::string& name, std::optional<double>& target, const NumberRule& rule,
                        const std::string& help, const std::string& type = "X") {
  const CLI::Validator check(
      [rule](std::string& s) -> std::string {
        const auto x = to_number(s);
        return x && rule.ok(*x) ? std::string() : "expected " + std::string(rule.expected) + ", got '" + s + "'";
      },
      "", "number");
  return app->add_option_function<std::string>(name, [&target](const std::string& s) { target = to_number(s); },
                                               help + " (" + rule.expected + ")")
      ->check(check)
      ->type_name(type);
}

CLI::Option* add_text(CLI::App* app, const std::string& name, std::optional<std::string>& target,
                      const std::string& help, const std::string& type) {
  return app->add_option_function<std::string>(name, [&target](const std::string& s) { target = s; }, help)
      ->type_name(type);
}

// A name in a registry: the registry's own message ("unknown integrator 'x';
// expected one of: ...") when it is not there.
template <class Find>
CLI::Validator registry_name(Find find) {
  return CLI::Validator(
      [find](std::string& s) -> std::string {
        try {
          find(s);
          return {};
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      "", "registry");
}

// A file to write: its folder exists, and it is not a folder itself.
const CLI::Validator kWritableFile(
    [](std::string& s) -> std::string {
      const fs::path p(s);
      const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
      if (!fs::is_directory(dir)) return "expected a file in an existing folder, got '" + s + "'";
      if (fs::is_directory(p)) return "expected a file name, got the folder '" + s + "'";
      return {};
    },
    "", "file");

// A scene file and its overrides: what check, run, stiffness and conditioning share.
struct SceneArgs {
  std::string file;
  std::vector<std::string> sets;    // --set section.key=value, repeatable
  std::vector<std::string> unsets;  // --unset section.key, repeatable
};

void add_scene(CLI::App* app, std::string& file, std::vector<std::string>& sets, std::vector<std::string>& unsets) {
  app->add_option("scene", file, "a scene file, e.g. experiments/scenes/paper_slow.toml")
      ->required()
      ->type_name("SCENE.toml");
  app->add_option("--set", sets,
                  "overrides a scene value (TOML syntax), e.g. --set motor.inductance=1e-5; repeatable")
      ->type_name("SECTION.KEY=VALUE")
      ->take_all()
      ->allow_extra_args(false);  // one value per --set: the scene file may follow
  app->add_option("--unset", unsets,
                  "removes a key (or a table) of the scene file before the --set values and the checks, e.g. "
                  "--unset friction.static_torque when --set friction.model=\"viscous\" switches the law; "
                  "repeatable")
      ->type_name("SECTION.KEY")
      ->take_all()
      ->allow_extra_args(false);
}

void add_scene(CLI::App* app, SceneArgs& a) { add_scene(app, a.file, a.sets, a.unsets); }

// The scene, loaded and checked: its integrator exists (`check` says so with
// the file, line and key, as `run` would otherwise fail without them).
Scene load_checked_scene(const SceneArgs& a) { return pumasim::load_checked_scene(a.file, a.sets, a.unsets); }

// ---------------------------------------------------------------- robot

struct RobotArgs {
  std::string robot;
  int random = 0;  // --random N: a random chain of N joints
  long seed = 1;
  std::string types = "R";
  std::string convention = "standard";
};

// ---------------------------------------------------------------- dynamics

struct DynamicsArgs {
  std::string robot, backend, q;
  std::optional<std::string> qd, qdd, tau;
  bool no_rotor_inertia = false;
};

// JSON documents are built with nlohmann-json (ordered: keys in the order
// written); a number that is not finite is written as null.
using Json = nlohmann::ordered_json;

Json json_vector(const Eigen::VectorXd& v) {
  Json a = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(std::isfinite(v[i]) ? Json(v[i]) : Json(nullptr));
  return a;
}

// H, h, g at (q, qd); tau from qdd and qdd from tau when given.
Json dynamics_json(const RobotDynamics& rd, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                   const std::optional<Eigen::VectorXd>& qdd_in, const std::optional<Eigen::VectorXd>& tau_in,
                   const DynamicsValues& v) {
  const int n = rd.model.dof();
  Json doc;
  doc["backend"] = rd.backend->name();
  doc["robot"] = rd.model.name;
  doc["n"] = n;
  doc["rotor_inertia_included"] = rd.rotor_inertia;
  doc["q"] = json_vector(q);
  doc["qd"] = json_vector(qd);
  doc["mass_matrix"] = Json::array();
  for (int i = 0; i < n; ++i) doc["mass_matrix"].push_back(json_vector(v.mass_matrix.row(i).transpose()));
  doc["bias"] = json_vector(v.bias);
  doc["gravity"] = json_vector(v.gravity);
  if (qdd_in) {
    doc["qdd_in"] = json_vector(*qdd_in);
    doc["tau"] = json_vector(*v.tau);
  }
  if (tau_in) {
    doc["tau_in"] = json_vector(*tau_in);
    doc["qdd"] = json_vector(*v.qdd);
  }
  return doc;
}

Json json_matrix(const Eigen::MatrixXd& m) {
  Json a = Json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) a.push_back(json_vector(m.row(i).transpose()));
  return a;
}

// The robot as pumasim reads it: every parameter the dynamics and the
// kinematics use, whatever the file's format (a URDF's, after its
// conversion to DH rows with a base and a tool transform).
Json robot_json(const RobotModel& m) {
  Json doc;
  doc["name"] = m.name;
  doc["source"] = m.source;
  doc["dof"] = m.dof();
  doc["convention"] = m.convention == DhConvention::kStandard ? "standard" : "modified";
  doc["gravity"] = json_vector(m.gravity);
  doc["base"] = {{"R", json_matrix(m.base_R)}, {"p", json_vector(m.base_p)}};
  doc["tool"] = {{"R", json_matrix(m.tool_R)}, {"p", json_vector(m.tool_p)}};
  doc["flange"] = m.flange;
  doc["joints"] = Json::array();
  for (const JointParams& J : m.joints) {
    Json j;
    j["type"] = J.prismatic() ? "prismatic" : "revolute";
    j["a"] = J.a, j["alpha"] = J.alpha, j["d"] = J.d, j["theta"] = J.theta, j["offset"] = J.offset;
    j["mass"] = J.mass;
    j["com"] = json_vector(J.com);
    j["inertia"] = json_matrix(J.inertia);
    j["rotor_inertia"] = J.rotor_inertia;
    j["gear_ratio"] = J.gear_ratio;
    j["damping"] = J.damping;  // joint side (a URDF's <dynamics>)
    j["coulomb"] = J.coulomb;
    j["limits"] = json_vector(Eigen::Vector2d(J.q_min, J.q_max));
    doc["joints"].push_back(std::move(j));
  }
  doc["poses"] = Json::object();
  for (const NamedPose& p : m.poses) doc["poses"][p.name] = json_vector(p.q);
  doc["provenance"] = m.provenance;
  return doc;
}

int cmd_robot(const RobotArgs& a, std::ostream& out) {
  if (a.random > 0) {
    const DhConvention c = a.convention == "modified" ? DhConvention::kModified : DhConvention::kStandard;
    const RobotModel m = random_chain(a.random, static_cast<std::uint64_t>(a.seed), c, a.types);
    out << robot_file_text(m, "A random chain: pumasim robot --random " + std::to_string(a.random) + " --seed " +
                                  std::to_string(a.seed) + " --types " + a.types + " --convention " + a.convention +
                                  "\n(models/robot/random_chain.hpp: random DH rows, masses and inertias; for "
                                  "tests and benchmarks)");
    return kExitOk;
  }
  if (a.robot.empty()) throw UsageError("robot: expected a robot name or file, or --random N");
  out << robot_json(load_robot(a.robot)).dump(2) << "\n";
  return kExitOk;
}

void add_robot(CLI::App* app, RobotArgs& a) {
  app->add_option("robot", a.robot, "a robot name (puma560) or a robot file path (TOML, or URDF: *.urdf)")
      ->type_name("NAME|FILE");
  app->add_option("--random", a.random, "instead: print a robot file of a random chain of N joints")
      ->type_name("N")
      ->check(CLI::Range(1, 1000));
  app->add_option("--seed", a.seed, "the random chain's seed (default 1)")->check(CLI::Range(0L, 1L << 62));
  app->add_option("--types", a.types,
                  "the random chain's joint types, repeated along it: R revolute, P prismatic (default R)")
      ->check([](const std::string& s) -> std::string {
        if (s.empty() || s.find_first_not_of("RP") != std::string::npos) return "expected letters R and P";
        return {};
      });
  app->add_option("--convention", a.convention, "the random chain's DH convention (default standard)")
      ->check(CLI::IsMember({"standard", "modified"}));
}

int cmd_dynamics(const DynamicsArgs& a, std::ostream& out) {
  // The robot, without its rotor inertias if asked, and the back-end (one
  // that cannot describe this robot: invalid_argument).
  const RobotDynamics rd = robot_dynamics(a.robot, a.backend, !a.no_rotor_inertia);
  const int n = rd.model.dof();
  const Eigen::VectorXd q = parse_vector(a.q, n, "--q", &rd.model);
  const Eigen::VectorXd qd = a.qd ? parse_vector(*a.qd, n, "--qd") : Eigen::VectorXd::Zero(n);
  std::optional<Eigen::VectorXd> qdd, tau;
  if (a.qdd) qdd = parse_vector(*a.qdd, n, "--qdd");
  if (a.tau) tau = parse_vector(*a.tau, n, "--tau");
  const DynamicsValues v = evaluate_dynamics(*rd.backend, q, qd, qdd, tau);
  // Everything is checked before anything is printed: nothing half-written.
  out << dynamics_json(rd, q, qd, qdd, tau, v).dump(2) << "\n";
  return kExitOk;
}

void add_dynamics(CLI::App* app, DynamicsArgs& a) {
  app->add_option("--robot", a.robot, "a robot name (puma560) or a robot file path (TOML, or URDF: *.urdf)")->required()->type_name("NAME|FILE");
  app->add_option("--backend", a.backend, "a dynamics back-end (pumasim backends)")
      ->required()
      ->type_name("NAME")
      ->check(registry_name([](const std::string& s) { find_backend(s); }));
  app->add_option("--q", a.q, "joint values [rad; m for a prismatic joint], one per joint, comma-separated, or a pose name of the robot file")
      ->required()
      ->type_name("CSV|POSE");
  add_text(app, "--qd", a.qd, "joint speeds [rad/s; m/s], comma-separated (default 0)", "CSV");
  add_text(app, "--qdd", a.qdd, "joint accelerations [rad/s^2; m/s^2]: prints tau = ID(q, qd, qdd)", "CSV");
  add_text(app, "--tau", a.tau, "joint torques [N m; N for a prismatic joint]: prints qdd = FD(q, qd, tau)", "CSV");
  app->add_flag("--no-rotor-inertia", a.no_rotor_inertia, "the robot without its rotor inertias");
}

// ---------------------------------------------------------------- base-parameters

struct BaseArgs {
  std::string robot;
  bool no_rotor = false, no_friction = false, json = false;
  int samples = 40;
  long seed = 1;
  double tolerance = 1e-8;
};

Json base_parameters_json(const RobotModel& model, const BaseParameters& base, const Eigen::VectorXd& values) {
  Json doc;
  doc["robot"] = model.name;
  doc["columns"] = base.names;
  doc["rank"] = base.rank();
  doc["tolerance"] = base.tolerance;
  doc["samples"] = base.samples;
  doc["gap"] = std::isfinite(base.gap()) ? Json(base.gap()) : Json(nullptr);
  doc["warning"] = base.warning;
  doc["singular_values"] = json_vector(base.singular_values);
  doc["base"] = Json::array();
  for (int i = 0; i < base.rank(); ++i) {
    doc["base"].push_back({{"name", base.label(i)}, {"definition", base.definition(i)}, {"value", values[i]}});
  }
  doc["no_effect"] = Json::array();
  for (int k : base.no_effect) doc["no_effect"].push_back(base.names[static_cast<std::size_t>(k)]);
  return doc;
}

int cmd_base_parameters(const BaseArgs& a, std::ostream& out, std::ostream& err) {
  const RobotModel model = load_robot(a.robot);
  JointTorqueRegressor regressor(model, {.rotor = !a.no_rotor, .friction = !a.no_friction});
  const BaseParameters base =
      base_parameters(regressor, model, a.samples, static_cast<std::uint64_t>(a.seed), a.tolerance);
  const Eigen::VectorXd values = base.values(regressor.parameters_of(model));
  if (a.json) {
    out << base_parameters_json(model, base, values).dump(2) << "\n";
    return kExitOk;
  }
  char line[256];
  std::snprintf(line, sizeof line, "%s: %d base parameters of %d columns (%d per joint)\n", model.name.c_str(),
                base.rank(), regressor.parameters(), regressor.per_joint());
  out << line;
  const Eigen::Index r = base.rank();
  if (r == 0) {
    out << "no parameter acts on the torques\n";
    return kExitOk;
  }
  std::snprintf(line, sizeof line,
                "rank: singular values above %.3g of the largest, of the regressor at %d random states stacked "
                "(columns scaled to unit norm): sigma_%ld = %.3g, sigma_%ld = %.3g, gap %.3g\n",
                base.tolerance, base.samples, static_cast<long>(r), base.singular_values[r - 1],
                static_cast<long>(r + 1), r < base.singular_values.size() ? base.singular_values[r] : 0.0, base.gap());
  out << line << "the robot's values (SI units; inertias about, first moments in, the joint frames):\n";
  if (!base.warning.empty()) err << "pumasim base-parameters: warning: " << base.warning << "\n";
  for (int i = 0; i < base.rank(); ++i) {
    const std::string l = base.label(i), d = base.definition(i);
    std::snprintf(line, sizeof line, "  %-6s = %-13.6g", l.c_str(), values[i]);
    out << line << (l == d ? "" : " (" + d + ")") << "\n";
  }
  if (!base.no_effect.empty()) {
    out << "no effect on the torques:";
    for (int k : base.no_effect) out << " " << base.names[static_cast<std::size_t>(k)];
    out << "\n";
  }
  return kExitOk;
}

void add_base_parameters(CLI::App* app, BaseArgs& a) {
  app->add_option("robot", a.robot, "a robot name (puma560) or a robot file path (TOML, or URDF: *.urdf)")
      ->required()
      ->type_name("NAME|FILE");
  app->add_flag("--no-rotor", a.no_rotor, "without the rotor inertia columns Ia");
  app->add_flag("--no-friction", a.no_friction, "without the friction columns Fv, Fc, Fo");
  app->add_option("--samples", a.samples,
                  "random states stacked (default 40; at least columns / joints, 14 for a 6-joint arm with every "
                  "column)")
      ->check(CLI::Range(1, 10000));
  app->add_option("--seed", a.seed, "their seed (default 1)")->check(CLI::Range(0L, 1L << 62));
  app->add_option("--tolerance", a.tolerance, "rank tolerance, relative to the largest singular value (default 1e-8)")
      ->check([](const std::string& s) -> std::string {
        double v = 0;
        const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
        if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !(v >= 1e-15 && v <= 1e-2)) {
          return "expected a number from 1e-15 to 1e-2, got " + s;
        }
        return {};
      });
  app->add_flag("--json", a.json, "one JSON object: every column, the base parameters, the singular values");
}

// ---------------------------------------------------------------- check

int cmd_check(const SceneArgs& a, std::ostream& out) {
  const Scene sc = load_checked_scene(a);
  // What `pumasim run` refuses up front with its default budgets: the output
  // rows held in memory, more controller samples than steps.
  check_run_size(sc, kDefaultStepBudget);
  Plant plant(sc.plant);
  check_output_size(sc, plant);
  std::vector<double> x(plant.size());
  plant.initial_state(x.data());
  std::ostringstream o;
  o << resolved_toml(sc);
  o << "# state (" << plant.size() << "):";
  for (const auto& name : plant.layout().names) o << " " << name;
  o << "\n# initial state:";
  char buf[32];
  for (double v : x) std::snprintf(buf, sizeof buf, " %.10g", v), o << buf;
  const RunContext robot = run_context({}, sc);  // what meta.json records of the robot file
  o << "\n# robot file: " << robot.robot_file << " (fnv1a64 " << robot.robot_fnv1a64 << ")\n";
  o << "# flange: " << sc.plant.robot.flange << "\n";
  for (const std::string& line : sc.plant.robot.provenance) o << "# robot: " << line << "\n";
  for (const std::string& line : sc.sources) o << "# source: " << line << "\n";
  // (every input file with its hash is in the resolved scene's footer above)
  if (const std::string note = discontinuity_note(sc); !note.empty()) o << "# note: " << note << "\n";
  out << o.str();
  return kExitOk;
}

// ---------------------------------------------------------------- run

// CLI11 binds `pumasim run`'s options into the front door's request
// (simulation/run.hpp); quiet is the command line's own.
struct RunArgs {
  RunRequest request;
  bool quiet = false;
};

// Where the run is, on one line of stderr rewritten in place (simulated time,
// steps, the current step size, wall-clock time): from the driver's step
// loop, first after a second, then every 0.25 s of wall-clock time; only on a
// terminal and without --quiet. `width` keeps the length of the last line, to
// clear it.
// plan: the run's plan once made (RunSinks::planned), read at each report.
ProgressHook progress_line(std::ostream& err, const RunPlan* const& plan, bool quiet, std::size_t& width) {
  if (quiet || !isatty(STDERR_FILENO)) return {};
  ProgressHook hook;
  hook.report = [&err, &width, &plan](const RunProgress& p) {
    const std::string& name = plan->scene.name;
    const double duration = plan->scene.duration;
    char line[320];
    int len = std::snprintf(line, sizeof line,
                            "\rpumasim run %s: t = %.6g / %.6g s (%.0f%%), %ld steps, h = %.3g s, %.1f s elapsed",
                            name.c_str(), p.t, duration, duration > 0 ? 100 * p.t / duration : 0.0, p.steps, p.h,
                            p.wall);
    len = std::clamp(len, 1, static_cast<int>(sizeof line) - 1);
    // Within the terminal's width, so that \r rewinds the whole line (a
    // wrapped line would leave a new row at every report).
    winsize ws{};
    const int columns = ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 1 ? ws.ws_col : 80;
    len = std::min(len, columns);  // the \r and columns - 1 characters
    line[len] = '\0';
    const std::size_t shown = static_cast<std::size_t>(len) - 1;  // without the \r
    err << line << std::string(width > shown ? width - shown : 0, ' ') << std::flush;
    width = shown;
  };
  return hook;
}

int cmd_run(const RunArgs& a, std::ostream& out, std::ostream& err) {
  const RunOptions& o = a.request.options;
  std::size_t progress_width = 0;
  const RunPlan* plan = nullptr;  // the run's, once made
  RunSinks sinks;
  sinks.words = command_line_words;
  sinks.warning = [&err](const std::string& w) { err << "pumasim run: warning: " << w << "\n"; };
  sinks.planned = [&](const RunPlan& p) {
    plan = &p;
    if (!p.controls.adaptive || a.quiet) return;
    char tol[160];
    std::snprintf(tol, sizeof tol, "pumasim run: %s at rtol %.3g, atol %.3g (times each state's scale%s)\n",
                  p.scene.integrator.name.c_str(), p.controls.options.rtol, p.controls.options.atol,
                  o.rtol && !o.atol ? "; 1e-3 x --rtol, as --atol was not given" : "");
    err << tol;
  };
  sinks.progress = progress_line(err, plan, a.quiet, progress_width);
  const auto clear_progress = [&] {
    if (progress_width > 0) err << "\r" << std::string(progress_width, ' ') << "\r" << std::flush;
  };
  RunRecord rec;
  try {
    rec = run(a.request, sinks);
  } catch (const RunFolderError&) {
    clear_progress();
    throw;
  }
  clear_progress();
  out << rec.stats;  // stdout is the JSON document alone (pipe it to a JSON reader); where it went, on stderr
  if (!a.quiet) err << "results: " << rec.plan.folder->string() << "/\n";
  if (!rec.run.result.ok) err << "pumasim run: " << rec.run.result.failure << "\n";
  const bool sensitivities_ok = !rec.sensitivities || rec.sensitivities->run.ok;
  if (!sensitivities_ok) err << "pumasim run: --sensitivity: " << rec.sensitivities->run.failure << "\n";
  return rec.run.result.ok && sensitivities_ok ? kExitOk : kExitInternal;
}

void add_run(CLI::App* app, RunArgs& a) {
  RunRequest& r = a.request;
  RunOptions& o = r.options;
  r.default_out = true;  // without --out: runs/<scene name>
  add_scene(app, r.file, r.sets, r.unsets);
  add_text(app, "--integrator", o.integrator, "the integrator (pumasim integrators; default: the scene's)", "NAME")
      ->check(registry_name([](const std::string& s) { find_integrator(s); }));
  add_text(app, "--backend", o.backend, "the dynamics back-end (pumasim backends; default: the scene's)", "NAME")
      ->check(registry_name([](const std::string& s) { find_backend(s); }));
  add_number(app, "--dt", o.dt, kPositive,
             "fixed-step methods: the step [s] (default: the scene's integrator.dt, "
             "else 5e-4)",
             "SECONDS");
  add_number(app, "--rtol", o.rtol, kRtol,
             "adaptive methods: the relative tolerance (default: the scene's "
             "integrator.rtol, else 1e-6)");
  add_number(app, "--atol", o.atol, kPositive,
             "adaptive methods: the absolute tolerance per unit of each state's typical magnitude (default: "
             "1e-3 x --rtol when --rtol is given, else the scene's integrator.atol, else 1e-8)");
  add_number(app, "--t-end", o.t_end, kPositive, "the run's end [s] (default: the scene's duration)", "SECONDS");
  app->add_option_function<std::string>(
         "--out", [&r](const std::string& s) { r.out = s; }, "the run folder (default runs/<scene name>/)")
      ->type_name("DIR");
  app->add_flag("--force", r.force, "replace DIR if it is a pumasim run folder holding only what pumasim wrote");
  app->add_option("--jacobian", o.jacobian,
                  "cvode-*, arkode-dirk: the plant's exact Jacobian (default) or the integrator's difference "
                  "quotients")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            return s == "exact" || s == "differences" ? "" : "expected exact or differences, got '" + s + "'";
          },
          "exact|differences", "jacobian"));
  add_number(app, "--max-steps", o.max_steps, kStepBudget,
             "steps in all before the run ends as a failure "
             "(default 10000000)",
             "N");
  add_number(app, "--max-wall", o.max_wall, kSecondsBudget,
             "wall-clock seconds before the run ends as a failure "
             "(default 600)",
             "SECONDS");
  app->add_flag("--quiet,-q", a.quiet, "no progress line and no 'results: DIR/' line on stderr (errors and a "
                "failed run's reason still are)");
  auto* late = app->add_flag("--late-events", o.late_events,
                             "do not stop at controller samples and set-point updates; apply them late, at the "
                             "next output (shows what stepping over them does)");
  app->add_flag("--keep-history", o.keep_history,
                "fixed-step multistep methods: carry the history across controller samples and other events "
                "instead of restarting it (the paper's simulation loop, by our reading)");
  app->add_flag("--stop-at-outputs", o.stop_at_outputs,
                "also stop the integrator at every output time (the output grid then caps the step: for "
                "comparison only)")
      ->excludes(late);
  app->add_option("--sensitivity", o.sensitivity,
                  "also integrate the forward sensitivities dx/dp to these scene keys (comma-separated, e.g. "
                  "motor.resistance,controller.kp[1]) by CVODES at the run's rtol and atol: DIR/sensitivity.csv at "
                  "the output times, stats.json's \"sensitivity\" (the final state's, the cost); scenes whose "
                  "right-hand side is continuous only")
      ->delimiter(',')
      ->type_name("KEY,...");
}

// ---------------------------------------------------------------- ensemble

struct EnsembleArgs {
  std::string file;
  std::optional<double> threads;
  std::optional<double> sample;    // one sample alone, by its index
  std::string table;               // given samples (a CSV table) instead of the file's draws
  std::string shard;               // K/N: that share of the samples alone (sweep.py's contract)
  std::vector<std::string> merge;  // the shards' tables, merged into one
  std::string out;                 // PATH.csv, with PATH.json beside it ("": the table on stdout)
  bool force = false;
  bool quiet = false;
};

std::filesystem::path sidecar_of(const std::filesystem::path& csv) { return ensemble_sidecar_path(csv); }

// An existing table is replaced only with --force, and only if its sidecar
// says pumasim ensemble wrote it: never what the program did not write.
void check_ensemble_out(const std::filesystem::path& csv, bool force) {
  const std::filesystem::path json = sidecar_of(csv);
  if (!std::filesystem::exists(csv) && !std::filesystem::exists(json)) return;
  std::string writer;
  if (std::filesystem::exists(json)) {
    std::ifstream in(json);
    const auto j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_object() && j.contains("written_by") && j["written_by"].is_string()) writer = j["written_by"];
  }
  if (writer != "pumasim ensemble") {
    throw RunFolderError("--out " + csv.string() + ": " + (std::filesystem::exists(csv) ? csv : json).string() +
                         " exists and was not written by pumasim ensemble (no " + json.string() +
                         " saying so); pumasim never overwrites what it did not write: choose another --out");
  }
  if (!force) {
    throw RunFolderError("--out " + csv.string() + ": an ensemble table is there; pass --force to replace it");
  }
}

// Writes text to path through a temporary file beside it and a rename: a
// reader sees the old file or the whole new one.
void write_whole(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << text;
    f.flush();
    if (!f) throw RunFolderError("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
}

// pumasim ensemble FILE --merge SHARD.csv...: the shards' tables as the one
// table a single process writes (merge_ensemble_shards checks that they are
// every shard of FILE as it is now, each once).
int merge_ensemble(const EnsembleArgs& a, std::ostream& out, std::ostream& err) {
  if (a.sample || !a.table.empty() || !a.shard.empty() || a.threads) {
    throw UsageError("--merge: the shards' tables alone, with --out; not with --sample, --table, --shard or --threads");
  }
  for (const std::string& t : a.merge) {
    if (!a.out.empty() && std::filesystem::weakly_canonical(t) == std::filesystem::weakly_canonical(a.out)) {
      throw UsageError("--out " + a.out + ": is one of the shards to merge; expected another path");
    }
  }
  const MergedEnsemble m = merge_ensemble_shards(a.merge, a.file);
  if (a.out.empty()) {
    out << m.csv;
    return kExitOk;
  }
  check_ensemble_out(a.out, a.force);
  write_whole(a.out, m.csv);
  write_whole(sidecar_of(a.out), m.sidecar);
  if (!a.quiet)
    err << "results: " << a.out << " (" << sidecar_of(a.out).string() << " describes it), merged from "
        << a.merge.size() << " shards\n";
  return kExitOk;
}

// The samples this process runs (the table's or the file's draws, one
// with --sample), the ensemble's count of them, and the shard.
struct ChosenSamples {
  std::vector<EnsembleSample> samples;
  long total = 0;
  std::optional<EnsembleShard> shard;
};

ChosenSamples choose_samples(const EnsembleArgs& a, EnsembleSpec& spec) {
  ChosenSamples c;
  if (!a.shard.empty()) {
    if (a.sample) throw UsageError("--shard " + a.shard + ": not with --sample (one sample is no share)");
    try {
      c.shard = parse_shard(a.shard);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--") + e.what());
    }
  }
  std::vector<EnsembleSample>& samples = c.samples;
  c.total = spec.samples;
  if (!a.table.empty()) {
    samples = read_sample_table(a.table);
    c.total = static_cast<long>(samples.size());
    spec.factors.clear(), spec.table = a.table;  // the table's values, not the file's draws
    if (a.sample) {
      if (*a.sample >= static_cast<double>(samples.size())) {
        throw UsageError("--sample " + std::to_string(static_cast<long>(*a.sample)) + ": expected an index below " +
                         std::to_string(samples.size()) + " (" + a.table + "'s rows)");
      }
      samples = {samples[static_cast<std::size_t>(*a.sample)]};
    }
  } else if (a.sample) {
    if (*a.sample >= static_cast<double>(spec.samples)) {
      throw UsageError("--sample " + std::to_string(static_cast<long>(*a.sample)) + ": expected an index below " +
                       std::to_string(spec.samples) + " (" + a.file + "'s samples)");
    }
    samples.push_back(draw_sample(spec, static_cast<long>(*a.sample)));
  } else {
    samples = draw_samples(spec);
  }
  return c;
}

int cmd_ensemble(const EnsembleArgs& a, std::ostream& out, std::ostream& err) {
  if (!a.merge.empty()) return merge_ensemble(a, out, err);
  EnsembleSpec spec = read_ensemble_file(a.file);
  ChosenSamples chosen = choose_samples(a, spec);
  std::vector<EnsembleSample>& samples = chosen.samples;
  const long total = chosen.total;
  const std::optional<EnsembleShard>& shard = chosen.shard;
  // The file's own mistakes (a key the scene does not have, a value of the
  // wrong type) stop here, before any run: the first sample's scene loads.
  std::vector<std::string> first = spec.sets;
  for (const std::string& s : samples.front().sets()) first.push_back(s);
  const Scene first_scene = ::pumasim::load_checked_scene(spec.scene, first);
  const EnsembleProvenance provenance = ensemble_provenance(spec, first_scene, total, shard);
  if (shard) {
    samples = select_shard(samples, *shard);
    if (samples.empty()) {
      throw UsageError("--shard " + a.shard + ": no sample is in it; expected N at most the ensemble's " +
                       std::to_string(total) + " samples");
    }
  }
  if (!a.out.empty()) check_ensemble_out(a.out, a.force);
  const int threads =
      a.threads ? static_cast<int>(*a.threads) : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const bool bar = !a.quiet && isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  double shown = -1;
  EnsembleProgress progress;
  if (bar) {
    progress = [&](long done, long failed, long total) {
      const double t = elapsed();
      if (done < total && t - shown < 0.25) return;
      shown = t;
      const int width = 30, filled = static_cast<int>(width * done / std::max(total, 1L));
      char line[200];
      std::snprintf(line, sizeof line, "\rpumasim ensemble: [%s%s] %ld / %ld samples, %ld failed, %.1f s",
                    std::string(static_cast<std::size_t>(filled), '#').c_str(),
                    std::string(static_cast<std::size_t>(width - filled), '.').c_str(), done, total, failed, t);
      err << line << std::flush;
    };
  }
  const std::vector<SampleResult> results = run_ensemble(spec, samples, threads, progress);
  if (bar) err << "\n";
  const double wall = elapsed();
  const std::string csv = ensemble_csv(results, spec.final_state);
  long failed = 0;
  for (const SampleResult& r : results) failed += r.ok ? 0 : 1;
  if (a.out.empty()) {
    out << csv;
  } else {
    write_whole(a.out, csv);
    write_whole(sidecar_of(a.out), ensemble_sidecar(spec, results, threads, wall, provenance));
    if (!a.quiet) err << "results: " << a.out << " (" << sidecar_of(a.out).string() << " describes it)\n";
  }
  if (!a.quiet) {
    char line[200];
    std::snprintf(line, sizeof line, "pumasim ensemble: %zu samples on %d threads, %ld failed, %.2f s\n",
                  results.size(), threads, failed, wall);
    err << line;
  }
  return kExitOk;
}

void add_ensemble(CLI::App* app, EnsembleArgs& a) {
  app->add_option("file", a.file, "the ensemble file (TOML: scene, samples, seed, [run], [[vary]])")
      ->required()
      ->type_name("FILE");
  add_number(app, "--threads", a.threads, kThreadCount, "threads (default: the machine's cores)", "N");
  add_number(app, "--sample", a.sample, kSampleIndex, "run sample K alone (its row, bit for bit)", "K");
  app->add_option("--table", a.table,
                  "run the samples of a CSV table instead of the file's draws (header: scene keys; a row per "
                  "sample, values as TOML text)")
      ->type_name("CSV");
  app->add_option("--out", a.out, "the table PATH.csv, with PATH.json describing it (default: the table on stdout)")
      ->type_name("PATH");
  app->add_option("--shard", a.shard,
                  "run only the K-th of N shares of the samples (index K-1 modulo N); the shards' tables merge "
                  "with --merge")
      ->type_name("K/N");
  app->add_option("--merge", a.merge,
                  "merge the tables of every shard of FILE (each with its sidecar) into one, rows in sample order: "
                  "the table one process writes, every field but wall_time equal")
      ->type_name("SHARD.csv...")
      ->expected(1, -1);
  app->add_flag("--force", a.force, "replace PATH if pumasim ensemble wrote it");
  app->add_flag("--quiet,-q", a.quiet, "no progress bar and no summary on stderr");
}

// ---------------------------------------------------------------- stiffness, conditioning

struct StiffnessArgs {
  SceneArgs scene;
  std::optional<double> t_end, samples;
  bool bisect = false;
  std::optional<std::string> csv, steps_csv;
};

void print_stiffness(std::ostream& out, const Scene& sc, double t_end, const StiffnessReport& rep, bool bisect) {
  out << "stiffness of " << sc.name << " over [0, " << t_end << "] s, " << rep.samples.size()
      << " samples of the exact plant Jacobian along a run with " << sc.integrator.name << ":\n";
  char line[256];
  if (!rep.samples.empty()) {
    const auto worst = std::max_element(rep.samples.begin(), rep.samples.end(), [](const auto& x, const auto& y) {
      return x.spectral_radius < y.spectral_radius;
    });
    double ratio = 0;
    int unstable = 0;
    for (const StiffnessSample& s : rep.samples) {
      ratio = std::max(ratio, s.stiffness_ratio);
      if (s.unstable_modes > 0) ++unstable;
    }
    std::snprintf(line, sizeof line,
                  "  largest spectral radius %.4g 1/s (t = %.4g s), its fastest mode tau = %.3g s (%s)\n"
                  "  largest stiffness ratio %.4g; samples with an unstable mode: %d\n",
                  worst->spectral_radius, worst->t, worst->fastest.re != 0 ? -1 / worst->fastest.re : 0.0,
                  worst->fastest.state.c_str(), ratio, unstable);
    out << line;
  }
  out << "largest stable fixed step [s], predicted from the stability region"
      << (bisect ? ", measured by bisection on the scene" : "") << ":\n";
  for (const StepBound& b : rep.steps) {
    std::snprintf(line, sizeof line, "  %-6s predicted %.4g", b.integrator.c_str(), b.predicted);
    out << line;
    if (bisect) {
      std::snprintf(line, sizeof line, ", measured %.4g", b.measured);
      out << line;
    }
    out << (b.note.empty() ? "" : "  (" + b.note + ")") << "\n";
  }
}

int cmd_stiffness(const StiffnessArgs& a, std::ostream& out, std::ostream& err) {
  const Scene sc = load_checked_scene(a.scene);
  const double t_end = a.t_end.value_or(std::min(1.0, sc.duration));
  const int samples = static_cast<int>(a.samples.value_or(20));
  const StiffnessReport rep = analyse_stiffness(sc, t_end, samples, a.bisect);
  if (a.csv) write_file_atomically(*a.csv, stiffness_samples_csv(rep));
  if (a.steps_csv) write_file_atomically(*a.steps_csv, step_bounds_csv(rep));
  print_stiffness(out, sc, t_end, rep, a.bisect);
  if (a.csv) err << "samples: " << *a.csv << "\n";
  if (a.steps_csv) err << "step bounds: " << *a.steps_csv << "\n";
  return kExitOk;
}

void add_stiffness(CLI::App* app, StiffnessArgs& a) {
  add_scene(app, a.scene);
  add_number(app, "--t-end", a.t_end, kPositive, "the run's end [s] (default min(1 s, the scene's duration))",
             "SECONDS");
  add_number(app, "--samples", a.samples, kSamples, "Jacobians along the run (default 20)", "N");
  app->add_flag("--bisect", a.bisect, "also measure each explicit method's largest stable step on the scene");
  add_text(app, "--csv", a.csv, "writes the samples as CSV: t, spectral radius, stiffness ratio, fastest and "
           "slowest mode (time constant, eigenvalue, state), unstable modes", "FILE")
      ->check(kWritableFile);
  add_text(app, "--steps-csv", a.steps_csv, "writes the largest stable steps as CSV: integrator, predicted, "
           "measured, note", "FILE")
      ->check(kWritableFile);
}

struct ConditioningArgs {
  SceneArgs scene;
  std::optional<double> samples;
  std::optional<std::string> csv;
};

void print_conditioning(std::ostream& out, const Scene& sc, const ConditioningReport& rep) {
  out << "conditioning of H along the reference of " << sc.name << " (" << sc.plant.n << " joints"
      << (sc.rotor_inertia ? "" : ", rotor inertia removed") << "), " << rep.samples.size() << " samples:\n";
  if (rep.samples.empty()) return;
  const auto worst = std::max_element(rep.samples.begin(), rep.samples.end(),
                                      [](const auto& x, const auto& y) { return x.cond_H < y.cond_H; });
  double min_eig = worst->min_eig_H;
  for (const ConditioningSample& s : rep.samples) min_eig = std::min(min_eig, s.min_eig_H);
  char line[160];
  std::snprintf(line, sizeof line, "  largest cond(H) %.6g (t = %.6g s); smallest eigenvalue of H %.6g kg m^2\n",
                worst->cond_H, worst->t, min_eig);
  out << line << "  largest qdd error per back-end, max_j |qdd_b - qdd_ref| / max(max_j |qdd_ref|, 1 rad/s^2):\n";
  for (std::size_t b = 0; b < rep.backends.size(); ++b) {
    double e = 0;
    for (const ConditioningSample& s : rep.samples) e = std::max(e, s.qdd_error[b]);
    std::snprintf(line, sizeof line, "    %-28s %.3g\n", rep.backends[b].c_str(), e);
    out << line;
  }
}

int cmd_conditioning(const ConditioningArgs& a, std::ostream& out, std::ostream& err) {
  const Scene sc = load_checked_scene(a.scene);
  const ConditioningReport rep = analyse_conditioning(sc, static_cast<int>(a.samples.value_or(200)));
  if (a.csv) write_file_atomically(*a.csv, conditioning_csv(rep));
  print_conditioning(out, sc, rep);
  if (a.csv) err << "samples: " << *a.csv << "\n";
  return kExitOk;
}

void add_conditioning(CLI::App* app, ConditioningArgs& a) {
  add_scene(app, a.scene);
  add_number(app, "--samples", a.samples, kManySamples, "samples along the reference (default 200)", "N");
  add_text(app, "--csv", a.csv, "writes the samples as CSV: t, q, cond(H), smallest eigenvalue of H, each "
           "back-end's qdd error", "FILE")
      ->check(kWritableFile);
}

// ---------------------------------------------------------------- the command table

// With --json, every field of every registry entry (what scripts read; the
// text is for people).
Json integrator_json(const IntegratorInfo& i) {
  Json j;
  j["name"] = i.name;
  j["summary"] = i.summary;
  j["kind"] = i.kind == IntegratorKind::kAdaptive ? "adaptive" : "fixed-step";
  j["order"] = i.order;
  j["variable_order"] = i.variable_order;
  j["implicit"] = i.implicit;
  j["rhs_per_step"] = i.rhs_per_step;
  j["real_stability"] = std::isfinite(i.real_stability) ? Json(i.real_stability) : Json("infinity");
  j["stability_region"] = i.stable_at != nullptr;
  j["dense_order"] = i.dense_order;
  j["starter_steps"] = i.starter_steps;
  j["uses_jacobian"] = i.uses_jacobian;
  j["exact_jacobian"] = i.exact_jacobian;
  j["jacobian_choice"] = i.jacobian_choice;
  j["finds_roots"] = i.finds_roots;
  j["set_valued_friction"] = i.set_valued_friction;
  j["conservative_only"] = i.conservative_only;
  j["residual_form"] = i.residual_form;
  return j;
}

// A registry as text ("name<TAB>summary" lines) or as one JSON array.
template <class Entry, class ToJson>
int print_registry(std::span<const Entry> all, bool json, ToJson to_json, std::ostream& out) {
  if (!json) {
    for (const Entry& e : all) out << e.name << "\t" << e.summary << "\n";
    return kExitOk;
  }
  Json doc = Json::array();
  for (const Entry& e : all) doc.push_back(to_json(e));
  out << doc.dump(2) << "\n";
  return kExitOk;
}

int cmd_integrators(bool json, std::ostream& out) { return print_registry(integrators(), json, integrator_json, out); }

int cmd_backends(bool json, std::ostream& out) {
  return print_registry(backends(), json, [](const BackendInfo& b) { return Json{{"name", b.name}, {"summary", b.summary}}; },
                        out);
}

// Every scene key (models/scene/scene.cpp's entry tables), as text lines
// "section.key<TAB>need<TAB>what<TAB>meaning[<TAB>applies when ...]" or one
// JSON array of objects with those fields.
int cmd_keys(bool json, std::ostream& out) {
  const std::vector<SceneKeyDoc> keys = scene_key_docs();
  if (!json) {
    for (const SceneKeyDoc& k : keys) {
      out << k.section << "." << k.key << "\t" << k.need << "\t" << k.what << "\t" << k.meaning
          << (k.applies.empty() ? "" : "\tapplies when " + k.applies) << "\n";
    }
    return kExitOk;
  }
  Json doc = Json::array();
  for (const SceneKeyDoc& k : keys) {
    doc.push_back({{"section", k.section},
                   {"key", k.key},
                   {"need", k.need},
                   {"what", k.what},
                   {"meaning", k.meaning},
                   {"applies", k.applies}});
  }
  out << doc.dump(2) << "\n";
  return kExitOk;
}

// Every command's parsed options, filled by CLI11.
struct Parsed {
  DynamicsArgs dynamics;
  RobotArgs robot;
  BaseArgs base;
  SceneArgs check;
  RunArgs run;
  StiffnessArgs stiffness;
  ConditioningArgs conditioning;
  EnsembleArgs ensemble;
  std::string help_topic;
  bool json = false;  // integrators, backends, keys: --json
};

using Handler = std::function<int(std::ostream& out, std::ostream& err)>;

// The commands: CLI11's subcommands (and so the help and the messages that
// name the commands) come from this table.
struct Command {
  const char* name;
  const char* summary;  // one line in `pumasim help`
  const char* details;  // the end of `pumasim help <command>`
  void (*add)(CLI::App* app, Parsed& p);
  int (*run)(const Parsed& p, CLI::App& top, std::ostream& out, std::ostream& err);
};

int cmd_help(const Parsed& p, CLI::App& top, std::ostream& out, std::ostream&);

const Command kCommands[] = {
    {"dynamics", "prints H, h, g (and tau from qdd, qdd from tau) as one JSON object", "",
     [](CLI::App* a, Parsed& p) { add_dynamics(a, p.dynamics); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream&) { return cmd_dynamics(p.dynamics, o); }},
    {"robot", "prints a robot as pumasim reads it (JSON), or a random chain's robot file",
     "pumasim robot FILE prints every parameter of the robot after reading it (a URDF's after its conversion): "
     "what the dynamics and the scripts use. pumasim robot --random N [--seed S] [--types RP] prints a robot "
     "file (TOML) of a random chain of N joints, for a scene on a long arm.",
     [](CLI::App* a, Parsed& p) { add_robot(a, p.robot); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream&) { return cmd_robot(p.robot, o); }},
    {"base-parameters", "the joint-torque regressor's base parameters, their regrouping and the robot's values",
     "Stacks the regressor tau = Y(q, qd, qdd) pi (10 inertial parameters per link, the rotor inertia and "
     "viscous, Coulomb and offset friction per joint) at random states and finds its rank by SVD; the base "
     "parameters are the columns kept in order by a QR of the stacked regressor, each with the columns that "
     "regroup onto it (models/robot/base_parameters.hpp).",
     [](CLI::App* a, Parsed& p) { add_base_parameters(a, p.base); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream& e) { return cmd_base_parameters(p.base, o, e); }},
    {"backends", "lists the dynamics back-ends", "",
     [](CLI::App* a, Parsed& p) { a->add_flag("--json", p.json, "one JSON array of the entries (name, summary)"); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream&) { return cmd_backends(p.json, o); }},
    {"check", "checks a scene; prints it resolved, its state layout and initial state",
     "Prints the scene with every default filled in (a robot file path made absolute), its state layout, its "
     "initial state and the robot file with its hash.",
     [](CLI::App* a, Parsed& p) { add_scene(a, p.check); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream&) { return cmd_check(p.check, o); }},
    {"run", "runs a scene and writes its run folder",
     "Writes DIR: trajectory.csv, stats.json, scene.resolved.toml (re-runs as it is, from any folder), meta.json "
     "(command line, start time, build, CPU, robot file hash) and, when a joint's friction has Coulomb levels, "
     "events.csv (its stick/slip modes: the hybrid model's events, or the accepted steps classified), all at "
     "once at the end. stdout carries stats.json "
     "alone (pipe it to jq); stderr the progress line (on a terminal, for runs over a second), 'results: DIR/' "
     "and errors (--quiet: errors only). DIR must be new, or a pumasim run folder holding only what pumasim "
     "wrote, replaced only with --force: pumasim never deletes what it did not write. More steps than "
     "--max-steps or more wall-clock time than --max-wall end the run as a reported failure (exit status 1) "
     "naming the state changing fastest relative to its typical magnitude; a scene whose controller samples or "
     "set-point updates alone exceed the step budget is refused before it runs. --atol is per unit of each "
     "state's typical magnitude: angles 1 rad, speeds 1 rad/s, currents the stall current at full command, PIV "
     "integrals their full range, energies 1 J (stats.json lists the resulting atol per state). The integrator "
     "stops only where the right-hand side changes (samples, set-point updates, the reference's breakpoints, "
     "roots); outputs come from its dense output.",
     [](CLI::App* a, Parsed& p) { add_run(a, p.run); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream& e) { return cmd_run(p.run, o, e); }},
    {"stiffness", "eigenvalues of the plant Jacobian along a run; explicit methods' largest stable steps",
     "Samples the exact plant Jacobian along a run with the scene's integrator: stiffness ratio, fastest and "
     "slowest time constants by state; each explicit method's largest stable step from its stability region "
     "and, with --bisect, found on the scene. stdout has a summary; --csv and --steps-csv write the tables.",
     [](CLI::App* a, Parsed& p) { add_stiffness(a, p.stiffness); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream& e) { return cmd_stiffness(p.stiffness, o, e); }},
    {"conditioning", "cond(H) along the scene's reference and every back-end's forward-dynamics error there",
     "At each sample of the reference: cond(H), and each back-end's forward dynamics of tau = ID(q, qd, qdd_ref) "
     "against qdd_ref. stdout has a summary; --csv writes the table.",
     [](CLI::App* a, Parsed& p) { add_conditioning(a, p.conditioning); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream& e) {
       return cmd_conditioning(p.conditioning, o, e);
     }},
    {"integrators", "lists the integrators", "",
     [](CLI::App* a, Parsed& p) {
       a->add_flag("--json", p.json,
                   "one JSON array of the registry's entries, every field (kind, order, stability interval, "
                   "Jacobian use, ...)");
     },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream&) { return cmd_integrators(p.json, o); }},
    {"keys", "lists every scene key: its section, need, value, meaning and when it applies",
     "The entries of the scene reader's tables, in the order a scene is read (docs/reference/scene-keys.md is "
     "generated from --json).",
     [](CLI::App* a, Parsed& p) {
       a->add_flag("--json", p.json, "one JSON array: section, key, need, what, meaning, applies");
     },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream&) { return cmd_keys(p.json, o); }},
    {"ensemble", "runs many samples of a scene on every core; one table of their results",
     "Reads an ensemble file: the scene, its overrides (set), the runs' options ([run]: integrator, dt, rtol, "
     "atol, t_end, max_steps, max_wall), samples, seed, final_state (the runs' final states as columns) and the varied "
     "keys ([[vary]]: key, distribution "
     "normal (mean, sd), uniform or log-uniform (low, high) or choice (values)). Sample k draws from its own "
     "generator, seeded from the seed and k: --sample K re-runs it alone with exactly its row. Writes one row "
     "per sample (its values, ok, failure kind, steps, RHS, Jacobians, wall time, path errors, the failure's "
     "reason) as CSV with 17 significant digits, and PATH.json describing every column. A failed run is a row; "
     "an ensemble file or a first sample the scene reader refuses is bad input (exit status 2). --shard K/N runs "
     "the samples whose index is K-1 modulo N (one job of GNU parallel or a Slurm array each); --merge "
     "SHARD.csv... joins every shard's table into the one table a single process writes, refusing shards of "
     "another ensemble, file or build.",
     [](CLI::App* a, Parsed& p) { add_ensemble(a, p.ensemble); },
     [](const Parsed& p, CLI::App&, std::ostream& o, std::ostream& e) { return cmd_ensemble(p.ensemble, o, e); }},
    {"help", "prints this text, or a command's options", "",
     [](CLI::App* a, Parsed& p) {
       a->add_option("command", p.help_topic, "the command whose options to print")->type_name("COMMAND");
     },
     &cmd_help},
};

std::string command_names() {
  std::string s;
  for (const Command& c : kCommands) s += std::string(s.empty() ? "" : ", ") + c.name;
  return s;
}

int cmd_help(const Parsed& p, CLI::App& top, std::ostream& out, std::ostream&) {
  if (p.help_topic.empty()) {  // the top level's help (top.help() would print the selected `help` command's)
    out << top.get_formatter()->make_help(&top, top.get_name(), CLI::AppFormatMode::Normal);
    return kExitOk;
  }
  for (const Command& c : kCommands) {
    if (p.help_topic == c.name) {
      out << top.get_subcommand(c.name)->help(top.get_name());
      return kExitOk;
    }
  }
  throw UsageError("help: unknown command '" + p.help_topic + "'; expected one of: " + command_names());
}

// ---------------------------------------------------------------- parsing

// text in lines of at most `width` characters, broken at spaces.
std::string wrapped(const std::string& text, std::size_t width) {
  std::istringstream words(text);
  std::string out, line, word;
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > width) out += line + "\n", line.clear();
    line += (line.empty() ? "" : " ") + word;
  }
  return out + line;
}

std::unique_ptr<CLI::App> make_app(Parsed& p) {
  auto app = std::make_unique<CLI::App>("pumasim: the PUMA 560 as one stiff state-space ODE, a testbed", "pumasim");
  app->footer("pumasim help <command> (or pumasim <command> --help) prints a command's options.\n"
              "Exit status: 0 success, 1 internal error or a failed run, 2 bad input.");
  app->require_subcommand(1);
  app->set_version_flag("--version", std::string(), "prints the revision, compiler, flags and build type");
  app->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);  // a repeated option: the last
  for (const Command& c : kCommands) {
    CLI::App* sub = app->add_subcommand(c.name, c.summary);
    sub->allow_extras();  // unknown arguments are reported below, naming the valid options
    if (*c.details) sub->footer(wrapped(c.details, 80));
    c.add(sub, p);
  }
  return app;
}

// "--speed" for "--speed=3"; the options `app` knows.
std::string unknown_argument_message(const CLI::App& app, const std::string& arg) {
  std::string known;
  for (const CLI::Option* o : app.get_options()) {
    if (!o->get_lnames().empty() && o->get_lnames().front() != "help") known += " --" + o->get_lnames().front();
  }
  if (arg.rfind("-", 0) != 0) {
    return app.get_name() + ": unexpected argument '" + arg + "'; expected an option:" + known;
  }
  return app.get_name() + ": unknown option '" + arg.substr(0, arg.find('=')) + "'; expected one of:" + known;
}

// CLI11's parse error as one line naming the option and what it expects.
std::string parse_error_message(const CLI::App& sub, const CLI::ParseError& e) {
  if (dynamic_cast<const CLI::RequiredError*>(&e)) {
    for (const CLI::Option* o : sub.get_options()) {
      if (o->get_required() && o->count() == 0) {
        return sub.get_name() + ": missing " + (o->get_lnames().empty() ? o->get_name() : "--" + o->get_lnames().front()) +
               "; expected " + o->get_description();
      }
    }
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e)) {
    const std::string what = e.what();
    const std::string name = what.substr(0, what.find(':'));
    if (const CLI::Option* o = sub.get_option_no_throw(name)) {
      return name + ": expected a value (" + o->get_type_name() + "), got none";
    }
  }
  return e.what();
}

// Parses args into p; returns the command to run, or nullptr when help was
// asked for with --help or the version with --version (then printed to out).
const Command* parse(CLI::App& app, const std::vector<std::string>& args, std::ostream& out) {
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
  try {
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    out << app.help();  // the command's, when one was named
    return nullptr;
  } catch (const CLI::CallForVersion&) {
    out << version_text() << "\n";
    return nullptr;
  } catch (const CLI::ParseError& e) {
    const auto chosen = app.get_subcommands();
    throw UsageError(parse_error_message(chosen.empty() ? app : *chosen.front(), e));
  }
  const CLI::App* sub = app.get_subcommands().front();
  if (const auto extra = sub->remaining(); !extra.empty()) throw UsageError(unknown_argument_message(*sub, extra.front()));
  for (const Command& c : kCommands) {
    if (sub->get_name() == c.name) return &c;
  }
  throw std::logic_error("a subcommand with no command");
}

bool is_command(const std::string& s) {
  return std::any_of(std::begin(kCommands), std::end(kCommands), [&](const Command& c) { return s == c.name; });
}

}  // namespace

int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err, const std::string& program) {
  try {
    if (args.empty()) throw UsageError("missing command; expected one of: " + command_names());
    if (!is_command(args[0]) && args[0] != "--help" && args[0] != "-h" && args[0] != "--version") {
      throw UsageError("unknown command '" + args[0] + "'; expected one of: " + command_names());
    }
    Parsed parsed;
    parsed.run.request.argv.assign(1, program);
    parsed.run.request.argv.insert(parsed.run.request.argv.end(), args.begin(), args.end());
    const auto app = make_app(parsed);
    const Command* c = parse(*app, args, out);
    return c ? c->run(parsed, *app, out, err) : kExitOk;
  } catch (const UsageError& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const ConfigError& e) {
    err << "pumasim: " << phrased(e.what(), command_line_words) << "\n";
  } catch (const std::invalid_argument& e) {
    err << "pumasim: " << phrased(e.what(), command_line_words) << "\n";
  } catch (const RunFolderError& e) {
    err << "pumasim: " << phrased(e.what(), command_line_words) << "\n";
  } catch (const std::exception& e) {
    err << "pumasim: internal error: " << phrased(e.what(), command_line_words) << "\n";
    return kExitInternal;
  }
  return kExitBadInput;
}

}  // namespace pumasim
