#include "experiments/simulation/run_request.hpp"

#include <charconv>
#include <cmath>
#include <complex>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "experiments/simulation/run_documents.hpp"
#include "experiments/simulation/run_folder.hpp"
#include "integrators/registry.hpp"
#include "integrators/stability.hpp"

namespace pumasim {
namespace {

// What the command line's validators refuse before a request is made; the
// same message for a request made otherwise (the Python module).
void check_value(const char* option, const std::optional<double>& v, const char* expected, bool ok) {
  if (!v || (std::isfinite(*v) && ok)) return;
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, *v);
  throw std::invalid_argument(std::string(option) + ": expected " + expected + ", got '" + std::string(buf, r.ptr) +
                              "'");
}

void check_request(const RunRequest& r) {
  check_value("--dt", r.dt, "a number > 0", r.dt > 0.0);
  check_value("--rtol", r.rtol, "a number in [1e-14, 0.1] (below, less than about 50 roundings of a state; above, no digit controlled)",
              r.rtol >= kRtolMin && r.rtol <= kRtolMax);
  check_value("--atol", r.atol, "a number > 0", r.atol > 0.0);
  check_value("--t-end", r.t_end, "a number > 0", r.t_end > 0.0);
  if (r.jacobian && *r.jacobian != "exact" && *r.jacobian != "differences") {
    throw std::invalid_argument("--jacobian: expected exact or differences, got '" + *r.jacobian + "'");
  }
  check_value("--max-steps", r.max_steps, "a whole number in [0, 1e18] (0: no limit)",
              r.max_steps && *r.max_steps >= 0 && *r.max_steps <= 1e18 && *r.max_steps == std::floor(*r.max_steps));
  check_value("--max-wall", r.max_wall, "seconds >= 0 (0: no limit)", r.max_wall >= 0.0);
  if (r.late_events && r.stop_at_outputs) throw std::invalid_argument("--late-events excludes --stop-at-outputs");
}

// --backend: the scene's robot as simulated must be one the back-end can describe.
void override_backend(Scene& sc, const std::string& name) {
  const BackendInfo& info = find_backend(name);
  const RobotModel sim = simulated_robot(sc.plant.robot, sc.plant.n, sc.plant.q_held);
  if (const std::string why = info.why_unsupported(sim); !why.empty()) throw std::invalid_argument("--backend: " + why);
  sc.plant.backend = name;
}

// --jacobian exact|differences, checked against what the method can take.
bool jacobian_choice(const std::string& method, const IntegratorInfo& info, const std::string& choice) {
  const IntegratorCapabilities c = capabilities_of(info);
  const bool exact = choice == "exact";
  if (!c.uses_jacobian) throw std::invalid_argument("--jacobian: " + method + " uses no Jacobian");
  if (exact && !c.exact_jacobian) {
    throw std::invalid_argument("--jacobian exact: " + method + " forms its own difference quotients only");
  }
  if (!exact && !c.jacobian_choice) {
    throw std::invalid_argument("--jacobian differences: " + method + " takes the plant's exact Jacobian only");
  }
  return exact;
}

// The integrator's settings: the scene's, overridden by --dt (fixed-step
// methods) or --rtol and --atol (adaptive ones); an option the method cannot
// honour is refused. The scene records what was used.
IntegratorOptions integrator_options(Scene& sc, const RunRequest& a, bool& adaptive) {
  const IntegratorInfo& info = find_integrator(sc.integrator.name);
  IntegratorOptions io;
  io.dt = sc.integrator.dt;
  io.rtol = sc.integrator.rtol;
  io.atol = sc.integrator.atol;
  io.keep_history = a.keep_history;
  adaptive = info.kind == IntegratorKind::kAdaptive;
  if (io.keep_history && adaptive) {
    throw std::invalid_argument("--keep-history: " + sc.integrator.name + " is adaptive; expected a fixed-step method");
  }
  if (a.dt) {
    if (adaptive) throw std::invalid_argument("--dt: " + sc.integrator.name + " is adaptive; expected --rtol and --atol");
    io.dt = sc.integrator.dt = *a.dt;
  }
  if (a.rtol || a.atol) {
    if (!adaptive) throw std::invalid_argument("--rtol/--atol: " + sc.integrator.name + " has a fixed step; expected --dt");
    if (a.rtol) io.rtol = sc.integrator.rtol = *a.rtol;
    if (a.atol) io.atol = sc.integrator.atol = *a.atol;
    // --rtol alone: atol follows it (1e-3 rtol per unit of each state's
    // scale), so that a tolerance study does not plateau at the scene's atol.
    if (a.rtol && !a.atol) io.atol = sc.integrator.atol = kAtolPerRtol * *a.rtol;
  }
  if (a.jacobian) io.exact_jacobian = jacobian_choice(sc.integrator.name, info, *a.jacobian);
  if (info.set_valued_friction && sc.plant.energy_ledger) {
    for (const FrictionParams& f : sc.plant.friction) {
      if (is_set_valued(f.model) && (f.static_torque > 0 || f.kinetic_torque > 0)) {
        throw std::invalid_argument(
            sc.integrator.name + ": the energy ledger does not count the friction impulses' loss (set-valued friction, "
            "model " + std::string(to_string(f.model)) +
            "); expected scene.energy_ledger = false (--set scene.energy_ledger=false), or a smooth law "
            "(tanh, viscous, none)");
      }
    }
  }
  if (!(io.dt > 0) || !(io.rtol > 0) || !(io.atol > 0)) {
    throw std::invalid_argument("--dt, --rtol, --atol: expected numbers > 0");
  }
  return io;
}

}  // namespace

Scene load_checked_scene(const std::string& file, const std::vector<std::string>& overrides,
                         const std::vector<std::string>& unsets) {
  Scene sc = load_scene(file, overrides, unsets);
  try {
    find_integrator(sc.integrator.name);
  } catch (const std::invalid_argument&) {
    throw ConfigError(sc.integrator.name_where + "expected one of: " + integrator_names() + "; got \"" +
                      sc.integrator.name + "\"");
  }
  return sc;
}

RunControls run_controls(Scene& sc, const RunRequest& a) {
  check_request(a);
  if (a.backend) override_backend(sc, *a.backend);
  if (a.integrator) {
    find_integrator(*a.integrator);  // an unknown name: the registry's message, before the scene changes
    sc.integrator.name = *a.integrator;
  }
  RunControls rc;
  rc.options = integrator_options(sc, a, rc.adaptive);
  // A step budget for the whole run, so that a method crawling through a
  // chattering discontinuity (steps of nanoseconds) ends as a reported
  // failure instead of running for hours; and a wall-clock budget, as the
  // step budget's time depends on the method.
  if (a.max_steps) rc.max_steps = static_cast<long>(*a.max_steps);
  if (rc.max_steps > 0) rc.options.max_steps = rc.max_steps;  // also each integrator's own per-call limit
  if (a.max_wall) rc.max_wall = *a.max_wall;
  if (a.t_end) sc.duration = *a.t_end, sc.duration_source = "the run's end time (t_end)";
  rc.stops = a.late_events       ? Stops::kOutputsLateEvents
             : a.stop_at_outputs ? Stops::kEventsAndOutputs
                                 : Stops::kEvents;
  return rc;
}

std::string stability_warning(const Scene& sc, const RunControls& rc) {
  if (rc.adaptive) return {};
  Plant plant(sc.plant);
  std::vector<double> x(static_cast<std::size_t>(plant.size()));
  plant.initial_state(x.data());
  Eigen::MatrixXd J(plant.size(), plant.size());
  plant.jacobian_exact(0.0, x.data(), J);
  const Eigen::EigenSolver<Eigen::MatrixXd> es(J, false);
  if (es.info() != Eigen::Success) return {};
  std::vector<std::complex<double>> decaying;
  std::complex<double> fastest = 0;
  for (const std::complex<double>& l : es.eigenvalues()) {
    if (l.real() >= 0) continue;
    decaying.push_back(l);
    if (std::abs(l) > std::abs(fastest)) fastest = l;
  }
  const std::optional<double> h = max_stable_step(sc.integrator.name, decaying);
  if (!h || !(rc.options.dt > *h)) return {};
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "the step %.4g s exceeds the largest stable step %.4g s that %s's stability region "
                "predicts from the plant's Jacobian at t = 0 (fastest mode lambda = %.4g%+.4gi 1/s); the run may "
                "diverge (pumasim stiffness %s shows the prediction along the run)",
                rc.options.dt, *h, sc.integrator.name.c_str(), fastest.real(), fastest.imag(), sc.file.c_str());
  return buf;
}

std::vector<std::string> run_start_warnings(const Scene& sc, const RunControls& rc) {
  std::vector<std::string> out;
  if (const std::string note = discontinuity_note(sc); rc.adaptive && !note.empty()) {
    out.push_back(sc.integrator.name + " is adaptive and " + note);
  }
  if (std::string w = stability_warning(sc, rc); !w.empty()) out.push_back(std::move(w));
  return out;
}

CompletedRun run_scene(const Scene& sc, const RunControls& rc, const std::optional<std::filesystem::path>& out,
                       bool force, const ProgressHook& progress, const RunContext* context, bool keep_rows) {
  check_run_size(sc, rc.max_steps);
  // Before the run: a refusal costs nothing; the trajectory then streams into
  // the folder's temporary twin, which a failure below removes.
  std::optional<RunFolderWriter> folder;
  if (out) folder.emplace(*out, force);
  const RunContext started = context ? *context : run_context({}, sc);  // the start time, the robot file as loaded
  CompletedRun done;
  done.run = simulate_scene(sc, rc, progress, keep_rows, folder ? &folder->stream("trajectory.csv") : nullptr);
  done.stats = stats_json(sc, rc, done.run);
  // An interrupted run (ProgressHook::cancel: Ctrl-C in the Python module)
  // leaves no folder: the twin goes, and a folder it would replace stays.
  if (folder && done.run.result.failure_kind != "interrupted") {
    folder->write("stats.json", done.stats);
    folder->write("meta.json", meta_json(started));
    folder->write("scene.resolved.toml", resolved_toml(sc));
    if (!done.run.events_csv.empty()) folder->write("events.csv", done.run.events_csv);
    if (!done.run.events_speed_csv.empty()) folder->write("events_speed.csv", done.run.events_speed_csv);
    folder->commit();
  }
  return done;
}

}  // namespace pumasim
