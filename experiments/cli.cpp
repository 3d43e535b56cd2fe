#include "experiments/cli.hpp"
#include "experiments/simulation/run_folder.hpp"
#include "experiments/stiffness.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>
#include <thread>
#include <stdexcept>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <sys/utsname.h>

#include <Eigen/Geometry>
#include <boost/version.hpp>
#include <nlohmann/json.hpp>
#include <sundials/sundials_config.h>

#include "experiments/simulation/driver.hpp"
#include "experiments/simulation/run_recorder.hpp"
#include "integrators/integrator.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/robot/robot_file.hpp"
#include "models/scene/scene.hpp"

namespace pumasim {
namespace {

constexpr long kDefaultStepBudget = 10'000'000;  // pumasim run --max-steps
constexpr double kDefaultWallBudget = 600.0;      // [s], pumasim run --max-wall

// Bad command-line input; becomes one line on stderr and exit status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Each command's lines of `pumasim help`.
constexpr const char* kUsage_dynamics =
    "  dynamics --robot <name-or-file> --backend <name> --q=<csv|pose> [--qd=<csv>]\n"
    "           [--qdd=<csv>] [--tau=<csv>] [--no-rotor-inertia]\n"
    "      prints H, h, g (and tau from qdd, qdd from tau) as one JSON object\n";
constexpr const char* kUsage_backends =
    "  backends   lists the dynamics back-ends\n";
constexpr const char* kUsage_check =
    "  check <scene.toml> [--set section.key=value ...]\n"
    "      checks a scene; prints it resolved (every default filled in), its state\n"
    "      layout and initial state\n";
constexpr const char* kUsage_run =
    "  run <scene.toml> [--integrator NAME] [--backend NAME] [--rtol X --atol Y | --dt X]\n"
    "      [--t-end X] [--out DIR [--force]] [--exact-jacobian] [--max-steps N] [--max-wall S]\n"
    "      [--late-events | --stop-at-outputs]\n"
    "      [--set section.key=value ...]\n"
    "      runs a scene and writes DIR (default runs/<scene name>/): trajectory.csv,\n"
    "      stats.json, scene.resolved.toml, meta.json, all at once at the end. DIR must be\n"
    "      new, or a pumasim run folder holding only what pumasim wrote, replaced only with\n"
    "      --force: pumasim never deletes what it did not write. More than N steps in all\n"
    "      (default 10000000; 0: no limit), or more than S seconds of wall-clock time\n"
    "      (--max-wall, default 600; 0: no limit), end the run as a reported failure; a\n"
    "      scene whose controller samples or set-point updates alone exceed the step\n"
    "      budget is refused before it runs.\n"
    "      --atol is per unit of each state's typical magnitude: angles 1 rad, speeds\n"
    "      1 rad/s, currents the stall current at full command, PIV integrals their\n"
    "      full range, energies 1 J (stats.json lists the resulting atol per state).\n"
    "      --set overrides a scene value (TOML syntax), e.g. --set motor.inductance=1e-5.\n"
    "      --late-events: do not stop at controller samples and set-point updates;\n"
    "      apply them late, at the next output (shows what stepping over them does).\n"
    "      The integrator stops only where the right-hand side changes (samples,\n"
    "      set-point updates, the reference's breakpoints, roots); outputs come from\n"
    "      its dense output. --stop-at-outputs also stops it at every output time\n"
    "      (the output grid then caps the step: for comparison only).\n";
constexpr const char* kUsage_stiffness =
    "  stiffness <scene.toml> [--t-end X] [--samples N] [--bisect] [--set section.key=value ...]\n"
    "      eigenvalues of the plant Jacobian along a run (default 20 samples over\n"
    "      min(1 s, the scene)): stiffness ratio, fastest and slowest time constants\n"
    "      by state; each explicit method's largest stable step from its stability\n"
    "      region and, with --bisect, found on the scene\n";
constexpr const char* kUsage_conditioning =
    "  conditioning <scene.toml> [--samples N] [--set section.key=value ...]\n"
    "      cond(H) along the scene's reference (default 200 samples) and every\n"
    "      back-end's forward-dynamics error there (tau from the reference's qdd)\n";
constexpr const char* kUsage_integrators =
    "  integrators   lists the integrators\n";
constexpr const char* kUsage_help =
    "  help       prints this text\n";

// --key=value, --key value, or a bare --flag; values may start with '-'.
struct Options {
  std::map<std::string, std::string> values;
  std::map<std::string, bool> flags;
  std::vector<std::string> sets;  // --set section.key=value, repeatable

  static Options parse(const std::vector<std::string>& args, std::size_t first,
                       const std::vector<std::string>& valued,
                       const std::vector<std::string>& flag_names) {
    auto is_in = [](const std::vector<std::string>& v, const std::string& s) {
      for (const auto& x : v) if (x == s) return true;
      return false;
    };
    Options o;
    for (std::size_t i = first; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + a + "'; expected --option");
      const auto eq = a.find('=');
      const std::string key = a.substr(2, eq == std::string::npos ? std::string::npos : eq - 2);
      if (is_in(flag_names, key)) {
        if (eq != std::string::npos) throw UsageError("--" + key + " takes no value");
        o.flags[key] = true;
      } else if (key == "set" && is_in(valued, key)) {
        if (eq != std::string::npos) {
          o.sets.push_back(a.substr(eq + 1));
        } else if (i + 1 < args.size()) {
          o.sets.push_back(args[++i]);
        } else {
          throw UsageError("--set expects section.key=value");
        }
      } else if (is_in(valued, key)) {
        if (eq != std::string::npos) {
          o.values[key] = a.substr(eq + 1);
        } else if (i + 1 < args.size()) {
          o.values[key] = args[++i];
        } else {
          throw UsageError("--" + key + " expects a value");
        }
      } else {
        std::string known;
        for (const auto& k : valued) known += " --" + k;
        for (const auto& k : flag_names) known += " --" + k;
        throw UsageError("unknown option '--" + key + "'; expected one of:" + known);
      }
    }
    return o;
  }

  std::optional<std::string> get(const std::string& key) const {
    const auto it = values.find(key);
    if (it == values.end()) return std::nullopt;
    return it->second;
  }
  std::string require(const std::string& key, const std::string& what) const {
    auto v = get(key);
    if (!v) throw UsageError("missing --" + key + "; expected " + what);
    return *v;
  }
};

double parse_double(const std::string& s, const std::string& what) {
  double x = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  while (b < e && *b == ' ') ++b;
  while (e > b && e[-1] == ' ') --e;
  if (b < e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, x);
  if (b == e || r.ec != std::errc() || r.ptr != e || !std::isfinite(x)) {
    throw UsageError(what + ": expected a finite number, got '" + s + "'");
  }
  return x;
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

// JSON documents are built with nlohmann-json (ordered: keys in the order
// written); a number that is not finite is written as null.
using Json = nlohmann::ordered_json;

Json json_number(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }

Json json_vector(const Eigen::VectorXd& v) {
  Json a = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(json_number(v[i]));
  return a;
}

int cmd_dynamics(const std::vector<std::string>& args, std::ostream& final_out) {
  const Options opt = Options::parse(args, 1, {"robot", "backend", "q", "qd", "qdd", "tau"},
                                     {"no-rotor-inertia"});
  RobotModel model = load_robot(opt.require("robot", "a robot name (puma560) or a robot file path"));
  const bool rotor = !opt.flags.count("no-rotor-inertia");
  if (!rotor) model = without_rotor_inertia(model);
  const std::string backend_name = opt.require("backend", "one of: " + backend_names());
  auto backend = make_backend(backend_name, model);  // unknown name: invalid_argument
  const int n = model.dof();
  const Eigen::VectorXd q =
      parse_vector(opt.require("q", std::to_string(n) + " joint angles [rad] or a pose name"), n,
                   "--q", &model);
  const Eigen::VectorXd qd =
      opt.get("qd") ? parse_vector(*opt.get("qd"), n, "--qd") : Eigen::VectorXd::Zero(n);
  std::optional<Eigen::VectorXd> qdd_in, tau_in;
  if (auto s = opt.get("qdd")) qdd_in = parse_vector(*s, n, "--qdd");
  if (auto s = opt.get("tau")) tau_in = parse_vector(*s, n, "--tau");
  // Everything is checked before anything is printed: nothing half-written.

  Eigen::MatrixXd H(n, n);
  Eigen::VectorXd h(n), g(n);
  backend->mass_matrix(q, H);
  backend->bias(q, qd, h);
  backend->gravity(q, g);

  Json doc;
  doc["backend"] = backend->name();
  doc["robot"] = model.name;
  doc["n"] = n;
  doc["rotor_inertia_included"] = rotor;
  doc["q"] = json_vector(q);
  doc["qd"] = json_vector(qd);
  doc["mass_matrix"] = Json::array();
  for (int i = 0; i < n; ++i) doc["mass_matrix"].push_back(json_vector(H.row(i).transpose()));
  doc["bias"] = json_vector(h);
  doc["gravity"] = json_vector(g);
  if (qdd_in) {
    const Eigen::VectorXd& qdd = *qdd_in;
    Eigen::VectorXd tau(n);
    backend->inverse_dynamics(q, qd, qdd, tau);
    doc["qdd_in"] = json_vector(qdd);
    doc["tau"] = json_vector(tau);
  }
  if (tau_in) {
    const Eigen::VectorXd& tau = *tau_in;
    Eigen::VectorXd qdd(n);
    backend->forward_dynamics(q, qd, tau, qdd);
    doc["tau_in"] = json_vector(tau);
    doc["qdd"] = json_vector(qdd);
  }
  final_out << doc.dump(2) << "\n";
  return kExitOk;
}

Scene scene_argument(const std::vector<std::string>& args, const Options& opt) {
  if (args.size() < 2 || args[1].rfind("--", 0) == 0) {
    throw UsageError(args[0] + ": expected a scene file, e.g. experiments/scenes/paper_slow.toml");
  }
  Scene sc = load_scene(args[1], opt.sets);
  // The integrator named by the scene exists: `check` says so with the file,
  // line and key, as `run` would otherwise fail without them.
  try {
    find_integrator(sc.integrator.name);
  } catch (const std::invalid_argument&) {
    throw ConfigError(sc.integrator.name_where + "expected one of: " + integrator_names() + "; got \"" +
                      sc.integrator.name + "\"");
  }
  return sc;
}

int cmd_check(const std::vector<std::string>& args, std::ostream& out) {
  const Options opt = Options::parse(args, 2, {"set"}, {});
  const Scene sc = scene_argument(args, opt);
  Plant plant(sc.plant);
  std::vector<double> x(plant.size());
  plant.initial_state(x.data());
  std::ostringstream o;
  o << resolved_toml(sc);
  o << "# state (" << plant.size() << "):";
  for (const auto& name : plant.layout().names) o << " " << name;
  o << "\n# initial state:";
  char buf[32];
  for (double v : x) std::snprintf(buf, sizeof buf, " %.10g", v), o << buf;
  o << "\n";
  out << o.str();
  return kExitOk;
}


std::string shell_line(const char* cmd) {
  std::string outp;
  if (FILE* f = popen(cmd, "r")) {
    char buf[256];
    while (fgets(buf, sizeof buf, f)) outp += buf;
    pclose(f);
  }
  while (!outp.empty() && (outp.back() == '\n' || outp.back() == ' ')) outp.pop_back();
  return outp;
}

int cmd_run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  const Options opt = Options::parse(args, 2, {"set", "integrator", "backend", "rtol", "atol", "dt", "t-end", "out",
                                               "max-steps", "max-wall"},
                                     {"exact-jacobian", "late-events", "stop-at-outputs", "force"});
  Scene sc = scene_argument(args, opt);
  if (auto b = opt.get("backend")) {
    const BackendInfo& info = find_backend(*b);  // unknown: invalid_argument listing the names
    const RobotModel sim = simulated_robot(sc.plant.robot, sc.plant.n, sc.plant.q_held);
    if (const std::string why = info.why_unsupported(sim); !why.empty()) throw UsageError("--backend: " + why);
    sc.plant.backend = *b;
  }
  if (auto i = opt.get("integrator")) sc.integrator.name = *i;
  const IntegratorInfo& iinfo = find_integrator(sc.integrator.name);
  IntegratorOptions io;
  io.dt = sc.integrator.dt;
  io.rtol = sc.integrator.rtol;
  io.atol = sc.integrator.atol;
  io.exact_jacobian = opt.flags.count("exact-jacobian") > 0;
  const bool adaptive = iinfo.make(io)->capabilities().adaptive;
  if (opt.get("dt")) {
    if (adaptive) throw UsageError("--dt: " + sc.integrator.name + " is adaptive; expected --rtol and --atol");
    io.dt = sc.integrator.dt = parse_double(*opt.get("dt"), "--dt");
  }
  if (opt.get("rtol") || opt.get("atol")) {
    if (!adaptive) throw UsageError("--rtol/--atol: " + sc.integrator.name + " has a fixed step; expected --dt");
    if (opt.get("rtol")) io.rtol = sc.integrator.rtol = parse_double(*opt.get("rtol"), "--rtol");
    if (opt.get("atol")) io.atol = sc.integrator.atol = parse_double(*opt.get("atol"), "--atol");
  }
  if (io.exact_jacobian && !iinfo.make(IntegratorOptions{})->capabilities().uses_jacobian) {
    throw UsageError("--exact-jacobian: " + sc.integrator.name + " uses no Jacobian");
  }
  if (!(io.dt > 0) || !(io.rtol > 0) || !(io.atol > 0)) throw UsageError("--dt, --rtol, --atol: expected numbers > 0");
  // A step budget for the whole run, so that a method crawling through a
  // chattering discontinuity (steps of nanoseconds) ends as a reported failure
  // within about a minute instead of running for hours; 0: no limit.
  long max_steps = kDefaultStepBudget;
  if (auto m = opt.get("max-steps")) {
    const double v = parse_double(*m, "--max-steps");
    if (!(v >= 0) || v != std::floor(v)) throw UsageError("--max-steps: expected a whole number >= 0 (0: no limit)");
    max_steps = static_cast<long>(v);
  }
  if (max_steps > 0) io.max_steps = max_steps;  // also each integrator's own per-call limit
  // A wall-clock budget too: the step budget's time depends on the method
  // (an implicit step on six joints costs a hundred explicit ones).
  double max_wall = kDefaultWallBudget;
  if (auto w = opt.get("max-wall")) {
    max_wall = parse_double(*w, "--max-wall");
    if (!(max_wall >= 0)) throw UsageError("--max-wall: expected seconds >= 0 (0: no limit)");
  }
  if (auto t = opt.get("t-end")) sc.duration = parse_double(*t, "--t-end");
  if (!(sc.duration > 0)) throw UsageError("--t-end: expected a number > 0");
  // The output rows are held in memory until the run ends (then written at
  // once): their number is bounded before anything is allocated.
  constexpr double kMaxOutputRows = 1e7;
  if (const double rows = sc.duration / sc.output_interval + 1; !(rows <= kMaxOutputRows)) {
    std::ostringstream m;
    m << "scene.duration / scene.output_interval: expected at most " << kMaxOutputRows
      << " output rows (a longer output_interval, or a shorter duration), got " << rows;
    throw UsageError(m.str());
  }
  // Every controller sample and set-point update is a stop, so at least one
  // step: a period so small that they alone exceed the step budget is refused
  // up front (a 1e-12 s servo period ground through 10 million steps first).
  if (max_steps > 0) {
    auto too_many = [&](const char* key, double period) {
      if (!(period > 0)) return;
      const double stops = sc.duration / period;
      if (stops > static_cast<double>(max_steps)) {
        std::ostringstream m;
        m << key << ": " << period << " s over " << sc.duration << " s is " << stops
          << " stops, more than the step budget of " << max_steps
          << " steps (--max-steps N raises it; a longer period or a shorter duration)";
        throw UsageError(m.str());
      }
    };
    if (sc.plant.controller == ControllerMode::kSampled) too_many("controller.servo_period", sc.plant.servo_period);
    too_many("controller.setpoint_interval", sc.plant.setpoint_interval);
  }
  // Outside the committed results/: runs/ is the user's scratch space (ignored by git).
  const std::filesystem::path dir = opt.get("out") ? std::filesystem::path(*opt.get("out")) : "runs" / std::filesystem::path(sc.name);
  const bool force = opt.flags.count("force") > 0;
  check_run_folder_target(dir, force);  // before the run: a refusal costs nothing

  Plant plant(sc.plant);
  auto integ = iinfo.make(io);
  const int n = plant.layout().n;
  RunRecorder recorder(plant, sc.duration, sc.output_interval);
  const bool tty = isatty(STDERR_FILENO);
  auto last_progress = std::chrono::steady_clock::now();
  if (opt.flags.count("late-events") && opt.flags.count("stop-at-outputs")) {
    throw UsageError("--late-events and --stop-at-outputs: expected at most one (--late-events stops at outputs)");
  }
  const Stops stops = opt.flags.count("late-events")       ? Stops::kOutputsLateEvents
                      : opt.flags.count("stop-at-outputs") ? Stops::kEventsAndOutputs
                                                            : Stops::kEvents;
  const RunResult r = run_plant(plant, *integ, sc.duration, sc.output_interval, [&](double t, const double* x) {
    recorder.observe(t, x);
    if (tty && std::chrono::steady_clock::now() - last_progress > std::chrono::milliseconds(500)) {
      err << "\rpumasim run " << sc.name << ": t = " << t << " / " << sc.duration << " s   " << std::flush;
      last_progress = std::chrono::steady_clock::now();
    }
  }, max_steps, stops, max_wall);
  const std::string csv = recorder.finish();
  const RunFigures& fig = recorder.figures();
  if (tty) err << "\r" << std::string(60, ' ') << "\r";
  Json js;
  js["scene"] = sc.name;
  js["integrator"] = sc.integrator.name;
  js["backend"] = sc.plant.backend;
  js["ok"] = r.ok;
  js["failure"] = r.failure;
  js["t_end"] = json_number(sc.duration);
  js["t_reached"] = json_number(r.t_final);
  js["dt"] = json_number(adaptive ? std::nan("") : io.dt);
  js["rtol"] = json_number(adaptive ? io.rtol : std::nan(""));
  js["atol"] = json_number(adaptive ? io.atol : std::nan(""));
  Json& atol = js["atol_per_component"] = Json::object();  // atol * the plant's typical magnitude of each state
  for (int k = 0; k < plant.size(); ++k) {
    atol[plant.layout().names[static_cast<std::size_t>(k)]] =
        json_number(adaptive ? io.atol * plant.tolerance_scale(k) : std::nan(""));
  }
  js["exact_jacobian"] = io.exact_jacobian;
  js["late_events"] = opt.flags.count("late-events") > 0;
  js["stops"] = stops == Stops::kEvents             ? "events (outputs from the dense output)"
                : stops == Stops::kEventsAndOutputs ? "events and outputs"
                                                    : "outputs (time events applied late)";
  const IntegratorStats& st = integ->stats();
  js["steps"] = st.steps;
  js["rhs_evaluations"] = st.rhs_evaluations;
  js["jacobian_evaluations"] = st.jacobian_evaluations;
  js["linear_solves"] = st.linear_solves;
  js["rejected_steps"] = st.rejected_steps;
  js["nonlinear_iterations"] = st.nonlinear_iterations;
  js["restarts"] = st.restarts;
  js["time_events"] = r.time_events;
  js["root_events"] = r.root_events;
  js["integration_wall_time_s"] = json_number(st.wall_time);
  js["wall_time_s"] = json_number(r.wall_time);
  const double none = std::nan("");
  js["max_path_error_mm"] = json_number(fig.samples ? 1e3 * fig.max_path_error : none);
  js["rms_path_error_mm"] = json_number(fig.samples ? 1e3 * fig.rms_path_error : none);
  js["max_path_deviation_mm"] = json_number(fig.samples ? 1e3 * fig.max_path_deviation : none);
  js["rms_path_deviation_mm"] = json_number(fig.samples ? 1e3 * fig.rms_path_deviation : none);
  js["reference_duration_s"] = json_number(sc.plant.reference ? sc.plant.reference->timing().duration() : none);
  if (sc.plant.drive) {
    auto list = [](const std::vector<double>& v) { return json_vector(Eigen::Map<const Eigen::VectorXd>(v.data(), std::ssize(v))); };
    js["peak_controller_output_V"] = list(fig.peak_u);
    js["peak_voltage_V"] = list(fig.peak_ea);
    js["peak_current_A"] = list(fig.peak_i);
    js["saturated_fraction"] = list(fig.saturated_fraction);
  }
  if (fig.ledger) {
    js["max_ledger_residual_J"] = json_number(fig.max_ledger_residual);
    js["ledger_energy_scale_J"] = json_number(fig.ledger_energy_scale);
  }
  const std::string stats = js.dump(2) + "\n";

  utsname u{};
  uname(&u);
  Json meta;
  meta["git_revision"] = shell_line("git rev-parse --short HEAD 2>/dev/null");
  meta["git_dirty"] = !shell_line("git status --porcelain 2>/dev/null | head -1").empty();
  meta["compiler"] = std::string("g++ ") + __VERSION__;
  meta["flags"] = PUMASIM_CXX_FLAGS;
  meta["eigen"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                  std::to_string(EIGEN_MINOR_VERSION);
  meta["sundials"] = SUNDIALS_VERSION;
  meta["boost"] = std::to_string(BOOST_VERSION / 100000) + "." + std::to_string(BOOST_VERSION / 100 % 1000);
  meta["tomlplusplus"] = std::to_string(TOML_LIB_MAJOR) + "." + std::to_string(TOML_LIB_MINOR) + "." +
                         std::to_string(TOML_LIB_PATCH);
  meta["machine"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  meta["cpus"] = std::thread::hardware_concurrency();

  write_run_folder(dir, {{"trajectory.csv", csv}, {"stats.json", stats}, {"meta.json", meta.dump(2) + "\n"},
                         {"scene.resolved.toml", resolved_toml(sc)}},
                   force);
  out << stats;  // stdout is the JSON document alone (pipe it to a JSON reader); where it went, on stderr
  err << "results: " << dir.string() << "/\n";
  if (!r.ok) err << "pumasim run: " << r.failure << "\n";
  return r.ok ? kExitOk : kExitInternal;
}

int cmd_stiffness(const std::vector<std::string>& args, std::ostream& out) {
  const Options opt = Options::parse(args, 2, {"set", "t-end", "samples"}, {"bisect"});
  const Scene sc = scene_argument(args, opt);
  const double t_end = opt.get("t-end") ? parse_double(*opt.get("t-end"), "--t-end") : std::min(1.0, sc.duration);
  if (!(t_end > 0)) throw UsageError("--t-end: expected a number > 0");
  double samples = 20;
  if (auto s = opt.get("samples")) {
    samples = parse_double(*s, "--samples");
    if (!(samples >= 1 && samples <= 10000) || samples != std::floor(samples)) {
      throw UsageError("--samples: expected a whole number in [1, 10000]");
    }
  }
  const StiffnessReport rep = analyse_stiffness(sc, t_end, static_cast<int>(samples), opt.flags.count("bisect") > 0);
  char line[256];
  out << "# stiffness of " << sc.name << " over [0, " << t_end << "] s: eigenvalues of the exact plant Jacobian\n"
      << "# along a run with " << sc.integrator.name << "; tau = 1/|Re lambda|; state: largest participation\n";
  out << "t [s]\tspectral radius [1/s]\tstiffness ratio\tfastest tau [s]\tfastest state\tslowest tau [s]\t"
         "slowest state\tunstable modes\n";
  for (const StiffnessSample& s : rep.samples) {
    std::snprintf(line, sizeof line, "%.4g\t%.4g\t%.4g\t%.3g\t%s\t%.3g\t%s\t%d\n", s.t, s.spectral_radius,
                  s.stiffness_ratio, s.fastest.re != 0 ? -1 / s.fastest.re : 0.0, s.fastest.state.c_str(),
                  s.slowest.re != 0 ? -1 / s.slowest.re : 0.0, s.slowest.state.c_str(), s.unstable_modes);
    out << line;
  }
  out << "\n# largest stable fixed step: predicted from the stability region and every decaying\n"
      << "# eigenvalue sampled" << (opt.flags.count("bisect") ? "; measured by bisection on the scene" : "") << "\n"
      << "integrator\tpredicted [s]\tmeasured [s]\tnote\n";
  for (const StepBound& b : rep.steps) {
    std::snprintf(line, sizeof line, "%s\t%.4g\t%.4g\t%s\n", b.integrator.c_str(), b.predicted, b.measured,
                  b.note.c_str());
    out << line;
  }
  return kExitOk;
}

int cmd_conditioning(const std::vector<std::string>& args, std::ostream& out) {
  const Options opt = Options::parse(args, 2, {"set", "samples"}, {});
  const Scene sc = scene_argument(args, opt);
  double samples = 200;
  if (auto s = opt.get("samples")) {
    samples = parse_double(*s, "--samples");
    if (!(samples >= 1 && samples <= 100000) || samples != std::floor(samples)) {
      throw UsageError("--samples: expected a whole number in [1, 100000]");
    }
  }
  const ConditioningReport rep = analyse_conditioning(sc, static_cast<int>(samples));
  out << "# conditioning of H along the reference of " << sc.name << " (" << sc.plant.n << " joints"
      << (sc.rotor_inertia ? "" : ", rotor inertia removed") << "); back-ends' qdd error:\n"
      << "# max_j |qdd_backend - qdd_ref| / max(max_j |qdd_ref|, 1 rad/s^2) for tau = ID(q, qd, qdd_ref)\n";
  out << "t [s]";
  for (int j = 0; j < sc.plant.n; ++j) out << "\tq" << j + 1 << " [rad]";
  out << "\tcond(H)\tmin eig(H)";
  for (const auto& b : rep.backends) out << "\t" << b;
  out << "\n";
  char buf[64];
  for (const ConditioningSample& s : rep.samples) {
    std::snprintf(buf, sizeof buf, "%.6g", s.t);
    out << buf;
    for (double v : s.q) {
      std::snprintf(buf, sizeof buf, "\t%.6g", v);
      out << buf;
    }
    std::snprintf(buf, sizeof buf, "\t%.6g\t%.6g", s.cond_H, s.min_eig_H);
    out << buf;
    for (double e : s.qdd_error) {
      std::snprintf(buf, sizeof buf, "\t%.3g", e);
      out << buf;
    }
    out << "\n";
  }
  return kExitOk;
}

int cmd_integrators(std::ostream& out) {
  for (const auto& i : integrators()) out << i.name << "\t" << i.summary << "\n";
  return kExitOk;
}

int cmd_backends(std::ostream& out) {
  for (const auto& b : backends()) out << b.name << "\t" << b.summary << "\n";
  return kExitOk;
}

// The commands: `pumasim help` and the messages that name the commands are
// generated from this table.
struct Command {
  const char* name;
  const char* usage;
  int (*run)(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
};
int cmd_help(const std::vector<std::string>&, std::ostream& out, std::ostream&);
constexpr Command kCommands[] = {
    {"dynamics", kUsage_dynamics, [](const auto& a, auto& o, auto&) { return cmd_dynamics(a, o); }},
    {"backends", kUsage_backends, [](const auto&, auto& o, auto&) { return cmd_backends(o); }},
    {"check", kUsage_check, [](const auto& a, auto& o, auto&) { return cmd_check(a, o); }},
    {"run", kUsage_run, &cmd_run},
    {"stiffness", kUsage_stiffness, [](const auto& a, auto& o, auto&) { return cmd_stiffness(a, o); }},
    {"conditioning", kUsage_conditioning, [](const auto& a, auto& o, auto&) { return cmd_conditioning(a, o); }},
    {"integrators", kUsage_integrators, [](const auto&, auto& o, auto&) { return cmd_integrators(o); }},
    {"help", kUsage_help, &cmd_help},
};

int cmd_help(const std::vector<std::string>&, std::ostream& out, std::ostream&) {
  out << "usage: pumasim <command> [options]\ncommands:\n";
  for (const Command& c : kCommands) out << c.usage;
  return kExitOk;
}

std::string command_names() {
  std::string s;
  for (const Command& c : kCommands) s += std::string(s.empty() ? "" : ", ") + c.name;
  return s;
}

}  // namespace

int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    if (args.empty()) throw UsageError("missing command; expected one of: " + command_names());
    std::string cmd = args[0];
    if (cmd == "--help" || cmd == "-h") cmd = "help";
    for (const Command& c : kCommands) {
      if (cmd == c.name) return c.run(args, out, err);
    }
    throw UsageError("unknown command '" + cmd + "'; expected one of: " + command_names());
  } catch (const UsageError& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const ConfigError& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const std::invalid_argument& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const RunFolderError& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const std::exception& e) {
    err << "pumasim: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
  return kExitBadInput;
}

}  // namespace pumasim
