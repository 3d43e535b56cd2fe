#include "simulation/run.hpp"

#include <charconv>
#include <cmath>
#include <complex>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "integrators/registry.hpp"
#include "integrators/stability.hpp"
#include "simulation/run_documents.hpp"
#include "simulation/run_folder.hpp"

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

void check_options(const RunOptions& r) {
  check_value("{{dt}}", r.dt, "a number > 0", r.dt > 0.0);
  check_value("{{rtol}}", r.rtol,
              "a number in [1e-14, 0.1] (below, less than about 50 roundings of a state; above, no digit controlled)",
              r.rtol >= kRtolMin && r.rtol <= kRtolMax);
  check_value("{{atol}}", r.atol, "a number > 0", r.atol > 0.0);
  check_value("{{t_end}}", r.t_end, "a number > 0", r.t_end > 0.0);
  check_value("{{output_interval}}", r.output_interval, "a number > 0", r.output_interval > 0.0);
  if (r.jacobian && *r.jacobian != "exact" && *r.jacobian != "differences") {
    throw std::invalid_argument("{{jacobian}}: expected exact or differences, got '" + *r.jacobian + "'");
  }
  check_value("{{max_steps}}", r.max_steps, "a whole number in [0, 1e18] (0: no limit)",
              r.max_steps && *r.max_steps >= 0 && *r.max_steps <= 1e18 && *r.max_steps == std::floor(*r.max_steps));
  check_value("{{max_wall}}", r.max_wall, "seconds >= 0 (0: no limit)", r.max_wall >= 0.0);
  if (r.late_events && r.stop_at_outputs) {
    throw std::invalid_argument("{{late_events}} excludes {{stop_at_outputs}}");
  }
}

// The back-end: the scene's robot as simulated must be one the back-end can describe.
void override_backend(Scene& sc, const std::string& name) {
  const BackendInfo& info = find_backend(name);
  const RobotModel sim = simulated_robot(sc.plant.robot, sc.plant.n, sc.plant.q_held);
  if (const std::string why = info.why_unsupported(sim); !why.empty())
    throw std::invalid_argument("{{backend}}: " + why);
  sc.plant.backend = name;
}

// The Jacobian, exact or differences, checked against what the method can take.
bool jacobian_choice(const std::string& method, const IntegratorInfo& info, const std::string& choice) {
  const IntegratorCapabilities c = capabilities_of(info);
  const bool exact = choice == "exact";
  if (!c.uses_jacobian) throw std::invalid_argument("{{jacobian}}: " + method + " uses no Jacobian");
  if (exact && !c.exact_jacobian) {
    throw std::invalid_argument("{{jacobian}} exact: " + method + " forms its own difference quotients only");
  }
  if (!exact && !c.jacobian_choice) {
    throw std::invalid_argument("{{jacobian}} differences: " + method + " takes the plant's exact Jacobian only");
  }
  return exact;
}

// The integrator's settings: the scene's, overridden by dt (fixed-step
// methods) or rtol and atol (adaptive ones); an option the method cannot
// honour is refused. The scene (the plan's copy) records what is used.
IntegratorOptions integrator_options(Scene& sc, const RunOptions& a, bool& adaptive) {
  const IntegratorInfo& info = find_integrator(sc.integrator.name);
  IntegratorOptions io;
  io.dt = sc.integrator.dt;
  io.rtol = sc.integrator.rtol;
  io.atol = sc.integrator.atol;
  io.keep_history = a.keep_history;
  adaptive = info.kind == IntegratorKind::kAdaptive;
  if (io.keep_history && adaptive) {
    throw std::invalid_argument("{{keep_history}}: " + sc.integrator.name +
                                " is adaptive; expected a fixed-step method");
  }
  if (a.dt) {
    if (adaptive)
      throw std::invalid_argument("{{dt}}: " + sc.integrator.name + " is adaptive; expected {{rtol}} and {{atol}}");
    io.dt = sc.integrator.dt = *a.dt;
  }
  if (a.rtol || a.atol) {
    if (!adaptive)
      throw std::invalid_argument("{{rtol}}/{{atol}}: " + sc.integrator.name + " has a fixed step; expected {{dt}}");
    if (a.rtol) io.rtol = sc.integrator.rtol = *a.rtol;
    if (a.atol) io.atol = sc.integrator.atol = *a.atol;
    // rtol alone: atol follows it (1e-3 rtol per unit of each state's
    // scale), so that a tolerance study does not plateau at the scene's atol.
    if (a.rtol && !a.atol) io.atol = sc.integrator.atol = kAtolPerRtol * *a.rtol;
  }
  if (a.jacobian) io.exact_jacobian = jacobian_choice(sc.integrator.name, info, *a.jacobian);
  if (!info.residual_form) {
    if (const std::string why = why_no_ode_form(sc.plant); !why.empty()) {
      throw std::invalid_argument(sc.integrator.name + " integrates an ODE, and this scene is not one: " + why);
    }
  }
  if (info.residual_form) {
    if (const std::string why = why_no_implicit_form(sc.plant); !why.empty()) {
      throw std::invalid_argument(sc.integrator.name +
                                  " integrates the plant's residual form, which this scene has "
                                  "not: " +
                                  why);
    }
  }
  if (info.conservative_only) {
    if (const std::string why = why_not_conservative(sc.plant); !why.empty()) {
      throw std::invalid_argument(sc.integrator.name +
                                  " integrates lossless, unforced arms only, and this scene is not one: " + why);
    }
  }
  if (info.set_valued_friction && sc.plant.energy_ledger) {
    for (const FrictionParams& f : sc.plant.friction) {
      if (is_set_valued(f.model) && (f.static_torque > 0 || f.kinetic_torque > 0)) {
        throw std::invalid_argument(
            sc.integrator.name +
            ": the energy ledger does not count the friction impulses' loss (set-valued friction, "
            "model " +
            std::string(to_string(f.model)) +
            "); expected scene.energy_ledger = false ({{set}} scene.energy_ledger=false), or a smooth law "
            "(tanh, viscous, none)");
      }
    }
  }
  if (!(io.dt > 0) || !(io.rtol > 0) || !(io.atol > 0)) {
    throw std::invalid_argument("{{dt}}, {{rtol}}, {{atol}}: expected numbers > 0");
  }
  return io;
}

Scene with_known_integrator(Scene sc) {
  try {
    find_integrator(sc.integrator.name);
  } catch (const std::invalid_argument&) {
    throw ConfigError(sc.integrator.name_where + "expected one of: " + integrator_names() + "; got \"" +
                      sc.integrator.name + "\"");
  }
  return sc;
}

}  // namespace

Scene load_checked_scene(const std::string& file, const std::vector<std::string>& overrides,
                         const std::vector<std::string>& unsets) {
  return with_known_integrator(load_scene(file, overrides, unsets));
}

Scene load_checked_scene_text(const std::string& text, const std::string& file) {
  return with_known_integrator(load_scene_text(text, file));
}

Scene load_checked_scene(const SceneTemplate& scene, const std::vector<std::string>& overrides) {
  Scene sc = scene.load(overrides);  // its own refusals name their lines (it reads the text again for them)
  try {
    return with_known_integrator(std::move(sc));
  } catch (const ConfigError&) {  // an unknown integrator: its name's line, from the text
    return with_known_integrator(scene.load_exact(overrides));
  }
}

RunPlan plan_run(Scene sc, const RunOptions& a) {
  check_options(a);
  if (a.backend) override_backend(sc, *a.backend);
  if (a.integrator) {
    find_integrator(*a.integrator);  // an unknown name: the registry's message
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
  if (a.output_interval) sc.output_interval = *a.output_interval;
  rc.stops = a.late_events       ? Stops::kOutputsLateEvents
             : a.stop_at_outputs ? Stops::kEventsAndOutputs
                                 : Stops::kEvents;
  return {std::move(sc), rc, std::nullopt};
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

namespace {

// Writes the run's folder from its twin (the trajectory already streamed in).
// stats.json with its "sensitivity" object (simulation/sensitivity.hpp).
std::string with_sensitivity(const std::string& stats, const SceneSensitivities& s, const RunControls& rc) {
  nlohmann::ordered_json js = nlohmann::ordered_json::parse(stats);
  js["sensitivity"] = nlohmann::ordered_json::parse(sensitivity_json(s, rc.options.rtol, rc.options.atol));
  return js.dump(2) + "\n";
}

void write_folder(RunFolderWriter& folder, const RunRecord& rec, const RunContext& started) {
  folder.write("stats.json", rec.stats);
  folder.write("meta.json", meta_json(started));
  folder.write("scene.resolved.toml", resolved_toml(rec.plan.scene));
  if (!rec.run.events_csv.empty()) folder.write("events.csv", rec.run.events_csv);
  if (!rec.run.events_speed_csv.empty()) folder.write("events_speed.csv", rec.run.events_speed_csv);
  if (rec.sensitivities) folder.write("sensitivity.csv", sensitivity_csv(*rec.sensitivities));
  folder.commit();
}

}  // namespace

RunRecord run(const RunRequest& request, const RunSinks& sinks) {
  std::optional<Scene> loaded;
  if (!request.scene) loaded.emplace(load_checked_scene(request.file, request.sets, request.unsets));
  const Scene& given = request.scene ? *request.scene : *loaded;
  // The start time and the files as loaded, before anything else is read
  // (meta.json's: with a folder to write).
  std::optional<RunContext> started;
  if (request.out || request.default_out) started = run_context(request.argv, given);
  RunRecord rec{loaded ? plan_run(std::move(*loaded), request.options) : plan_run(given, request.options), {}, {}};
  const Scene& sc = rec.plan.scene;
  const RunControls& rc = rec.plan.controls;
  if (request.out)
    rec.plan.folder = *request.out;
  else if (request.default_out)
    rec.plan.folder = "runs" / std::filesystem::path(sc.name);  // the user's scratch space
  if (sinks.warning) {
    for (const std::string& w : run_start_warnings(sc, rc)) sinks.warning(phrased(w, sinks.words));
  }
  check_run_size(sc, rc.max_steps);
  std::shared_ptr<SensitivityPlan> sensitivities;  // before the run: a refusal costs nothing
  if (!request.options.sensitivity.empty()) sensitivities = plan_sensitivities(sc, request.options.sensitivity);
  // Before the run: a refusal costs nothing; the trajectory then streams into
  // the folder's temporary twin, which a failure below removes.
  std::optional<RunFolderWriter> folder;
  if (rec.plan.folder) folder.emplace(*rec.plan.folder, request.force);
  if (sinks.planned) sinks.planned(rec.plan);
  rec.run = simulate_scene(sc, rc,
                           {.progress = sinks.progress,
                            .output = sinks.output,
                            .keep_rows = request.keep_rows,
                            .trajectory = folder ? &folder->stream("trajectory.csv") : nullptr});
  rec.run.result.failure = phrased(rec.run.result.failure, sinks.words);
  if (sensitivities && rec.run.result.ok) {  // a failed run has no sensitivities to give
    rec.sensitivities = scene_sensitivities(*sensitivities, sc, rc);
  }
  if (request.stats || folder) {
    rec.stats = stats_json(sc, rc, rec.run);
    if (rec.sensitivities) rec.stats = with_sensitivity(rec.stats, *rec.sensitivities, rc);
  }
  // An interrupted run (ProgressHook::cancel: Ctrl-C in the Python module)
  // leaves no folder: the twin goes, and a folder it would replace stays.
  if (folder && rec.run.result.failure_kind != "interrupted") write_folder(*folder, rec, *started);
  return rec;
}

}  // namespace pumasim
