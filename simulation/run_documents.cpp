#include "simulation/run_documents.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <sys/utsname.h>

#include <Eigen/Core>
#include <boost/version.hpp>
#include <nlohmann/json.hpp>
#include <sundials/sundials_config.h>
#include <toml++/toml.h>

#include "integrators/registry.hpp"
#include "models/robot/urdf_file.hpp"
#include "pumasim_build_info.hpp"  // generated at build time
#include "simulation/mode_log.hpp"

namespace pumasim {
namespace {

using Json = nlohmann::ordered_json;

Json json_number(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }

Json json_list(const std::vector<double>& v) {
  Json a = Json::array();
  for (double x : v) a.push_back(json_number(x));
  return a;
}

// What was run: scene, methods, tolerances (null where they mean nothing).
void settings(Json& js, const Scene& sc, const RunControls& rc, const SceneRun& run) {
  const IntegratorOptions& io = rc.options;
  const bool adaptive = rc.adaptive;
  js["scene"] = sc.name;
  js["integrator"] = sc.integrator.name;
  js["backend"] = sc.plant.backend;
  js["ok"] = run.result.ok;
  js["failure"] = run.result.failure;
  js["failure_kind"] = run.result.failure_kind;
  js["t_end"] = json_number(sc.duration);
  js["t_reached"] = json_number(run.result.t_final);
  js["dt"] = json_number(adaptive ? std::nan("") : io.dt);
  js["rtol"] = json_number(adaptive ? io.rtol : std::nan(""));
  js["atol"] = json_number(adaptive ? io.atol : std::nan(""));
  Json& bounds = js["physical_bounds"] = Json::object();  // finite ones; the run ends past kUnstableFactor x
  for (std::size_t k = 0; k < run.physical_bounds.size(); ++k) {
    if (!std::isfinite(run.physical_bounds[k])) continue;
    bounds[run.state_names[k]] = {{"bound", run.physical_bounds[k]}, {"why", run.physical_bounds_why[k]}};
  }
  Json& atol = js["atol_per_component"] = Json::object();  // atol * the plant's typical magnitude of each state
  for (std::size_t k = 0; k < run.state_names.size(); ++k) {
    atol[run.state_names[k]] = json_number(adaptive ? io.atol * run.tolerance_scales[k] : std::nan(""));
  }
  js["jacobian"] = jacobian_used(capabilities_of(find_integrator(sc.integrator.name)), io);
  js["late_events"] = rc.stops == Stops::kOutputsLateEvents;
  js["keep_history"] = io.keep_history;
  js["stops"] = rc.stops == Stops::kEvents             ? "events (outputs from the dense output)"
                : rc.stops == Stops::kEventsAndOutputs ? "events and outputs"
                                                       : "outputs (time events applied late)";
}

void statistics(Json& js, const SceneRun& run) {
  const IntegratorStats& st = run.stats;
  js["steps"] = st.steps;
  js["rhs_evaluations"] = st.rhs_evaluations;
  js["jacobian_evaluations"] = st.jacobian_evaluations;
  js["linear_solves"] = st.linear_solves;
  js["rejected_steps"] = st.rejected_steps;
  js["nonlinear_iterations"] = st.nonlinear_iterations;
  js["restarts"] = st.restarts;
  // The coupled stick/slip solves: time-stepping's, one per step (moreau-jean),
  // or the hybrid model's at its mode switches; 0 for the others.
  js["friction_solves"] = st.friction_solves;
  js["friction_iterations"] = st.friction_iterations;
  js["friction_unconverged"] = st.friction_unconverged;
  js["friction_worst_residual"] = json_number(st.friction_worst_residual);
  js["time_events"] = run.result.time_events;
  js["root_events"] = run.result.root_events;
  js["integration_wall_time_s"] = json_number(st.wall_time);
  js["wall_time_s"] = json_number(run.result.wall_time);
  // The friction mode log (events.csv; mode_log.hpp): its rows, how they were
  // found, and the wall time its per-step work took (inside wall_time_s).
  js["mode_changes"] = run.mode_changes;
  char how[240];
  std::snprintf(how, sizeof how,
                "accepted steps classified: stuck at |w_m| <= %g rad/s%s, modes lasting >= %g s", kStickSpeed,
                run.speed_only ? " (the speed alone: the integrator's own friction solve)" : " (and the law's stick branch)",
                kMinModeDuration);
  js["mode_log"] = run.events_csv.empty()   ? "none (no joint has friction modes)"
                   : run.modes_classified ? how
                                          : "hybrid model's events";
  js["mode_log_wall_time_s"] = json_number(run.mode_log_wall_time);
  if (!run.events_csv.empty()) {  // over the accepted steps: why a method grinds at a switch
    js["speed_sign_changes"] = run.speed_sign_changes;
    js["shortest_step_s"] = json_number(run.shortest_step);
  }
}

void figures(Json& js, const Scene& sc, const RunFigures& fig) {
  const double none = std::nan("");
  js["max_path_error_mm"] = json_number(fig.samples ? 1e3 * fig.max_path_error : none);
  js["rms_path_error_mm"] = json_number(fig.samples ? 1e3 * fig.rms_path_error : none);
  js["max_path_deviation_mm"] = json_number(fig.samples ? 1e3 * fig.max_path_deviation : none);
  js["rms_path_deviation_mm"] = json_number(fig.samples ? 1e3 * fig.rms_path_deviation : none);
  js["reference_duration_s"] = json_number(sc.plant.reference ? sc.plant.reference->timing().duration() : none);
  if (sc.plant.drive) {
    js["peak_controller_output_V"] = json_list(fig.peak_u);
    js["peak_voltage_V"] = json_list(fig.peak_ea);
    js["peak_current_A"] = json_list(fig.peak_i);
    js["saturated_fraction"] = json_list(fig.saturated_fraction);
  }
  if (fig.ledger) {
    js["max_ledger_residual_J"] = json_number(fig.max_ledger_residual);
    js["ledger_energy_scale_J"] = json_number(fig.ledger_energy_scale);
  }
}

}  // namespace

std::string stats_json(const Scene& sc, const RunControls& rc, const SceneRun& run) {
  Json js;
  settings(js, sc, rc, run);
  statistics(js, run);
  figures(js, sc, run.figures);
  return js.dump(2) + "\n";
}

std::string shell_quoted(const std::vector<std::string>& argv) {
  std::string out;
  for (const std::string& a : argv) {
    if (!out.empty()) out += ' ';
    const bool plain = !a.empty() && std::all_of(a.begin(), a.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("@%+=:,./_-", c) != nullptr;
    });
    if (plain) {
      out += a;
      continue;
    }
    out += '\'';
    for (const char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += '\'';
  }
  return out;
}

std::string version_text() {
  return std::string("pumasim ") + build_info::kGitRevision + " (" + build_info::kCompiler + ", " + build_info::kFlags +
         ", " + build_info::kBuildType + ")";
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  for (std::string line; std::getline(f, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) break;
    const auto b = line.find_first_not_of(" \t", colon + 1);
    return b == std::string::npos ? "unknown" : line.substr(b);
  }
  return "unknown";
}

RunContext run_context(const std::vector<std::string>& argv, const Scene& sc) {
  namespace fs = std::filesystem;
  RunContext c;
  c.command_line = shell_quoted(argv);
  std::error_code ec;
  c.working_directory = fs::current_path(ec).string();
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &utc);
  c.started_utc = stamp;
  c.robot_file = fs::absolute(sc.plant.robot.source, ec).lexically_normal().string();
  for (const InputFile& f : sc.inputs) {
    if (f.path == c.robot_file) c.robot_fnv1a64 = hex64(f.fnv1a64);
  }
  c.inputs = sc.inputs;
  return c;
}

std::string meta_json(const RunContext& context) {
  utsname u{};
  uname(&u);
  Json meta;
  meta["command_line"] = context.command_line;
  meta["working_directory"] = context.working_directory;
  meta["started_utc"] = context.started_utc;
  meta["git_revision"] = build_info::kGitRevision;
  meta["git_dirty"] = build_info::kGitDirty;
  meta["compiler"] = build_info::kCompiler;
  meta["flags"] = build_info::kFlags;
  meta["build_type"] = build_info::kBuildType;
  meta["eigen"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                  std::to_string(EIGEN_MINOR_VERSION);
  meta["sundials"] = SUNDIALS_VERSION;
  meta["boost"] = std::to_string(BOOST_VERSION / 100000) + "." + std::to_string(BOOST_VERSION / 100 % 1000);
  meta["tomlplusplus"] = std::to_string(TOML_LIB_MAJOR) + "." + std::to_string(TOML_LIB_MINOR) + "." +
                         std::to_string(TOML_LIB_PATCH);
  meta["machine"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  meta["cpus"] = std::thread::hardware_concurrency();
  meta["cpu_model"] = cpu_model();
  meta["robot_file"] = {{"path", context.robot_file},
                        {"fnv1a64", context.robot_fnv1a64.empty() ? Json(nullptr) : Json(context.robot_fnv1a64)}};
  Json inputs = Json::array();
  for (const InputFile& f : context.inputs) {
    inputs.push_back({{"path", f.path}, {"bytes", f.bytes}, {"fnv1a64", hex64(f.fnv1a64)}});
  }
  meta["input_files"] = inputs;
  return meta.dump(2) + "\n";
}

}  // namespace pumasim
