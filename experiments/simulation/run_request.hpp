// A run as `pumasim run` asks for it, apart from the command line (the
// Python module, python/, asks through the same functions): the scene loaded
// and its integrator checked, the options applied to it (integrator,
// back-end, step or tolerances, end time, budgets, stops), then the run, its
// stats.json, and its run folder when one is asked for.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "experiments/simulation/run_documents.hpp"
#include "experiments/simulation/scene_run.hpp"
#include "models/scene/scene.hpp"

namespace pumasim {

// The options of `pumasim run`, each unset when not given (then the scene's
// value or the default). Errors name them as the command line spells them.
struct RunRequest {
  std::optional<std::string> integrator;  // --integrator (default: the scene's)
  std::optional<std::string> backend;     // --backend (default: the scene's)
  std::optional<double> dt;               // --dt, fixed-step methods [s]
  std::optional<double> rtol, atol;       // --rtol, --atol, adaptive methods
  std::optional<double> t_end;            // --t-end [s] (default: the scene's duration)
  std::optional<double> max_steps;        // --max-steps, a whole number >= 0 (0: no limit)
  std::optional<double> max_wall;         // --max-wall [s] >= 0 (0: no limit)
  std::optional<std::string> jacobian;    // --jacobian exact|differences (default: exact where taken)
  bool late_events = false;               // --late-events
  bool stop_at_outputs = false;           // --stop-at-outputs
  bool keep_history = false;              // --keep-history
};

// load_scene(file, overrides, unsets), and the scene's integrator in the registry;
// ConfigError naming the file, line and key otherwise (what `pumasim check`
// and `pumasim run` load).
Scene load_checked_scene(const std::string& file, const std::vector<std::string>& overrides,
                         const std::vector<std::string>& unsets = {});

// Applies the request to the scene (back-end, integrator, dt or rtol and
// atol, t_end: the scene then records what is run) and returns how the run is
// driven. An option the method cannot honour, a back-end that cannot describe
// the scene's robot, or a value out of range is std::invalid_argument naming
// the option ("--dt: cvode-bdf is adaptive; expected --rtol and --atol").
RunControls run_controls(Scene& scene, const RunRequest& request);

// A fixed-step run whose step exceeds the largest stable step that its
// method's stability region predicts from the plant's Jacobian at t = 0
// (what `pumasim stiffness` computes along the run): a warning naming both
// steps and the fastest mode, or "" (an adaptive method, a method without a
// stability table, a step within the prediction).
std::string stability_warning(const Scene& scene, const RunControls& controls);

// What a run warns of before it starts, each a sentence without a prefix:
// an adaptive method on a friction law discontinuous in the state
// (discontinuity_note), and the stability warning above. `pumasim run`
// prints them on stderr, the Python module raises them as RuntimeWarnings.
std::vector<std::string> run_start_warnings(const Scene& scene, const RunControls& controls);

struct CompletedRun {
  SceneRun run;
  std::string stats;  // stats.json's text
};

// The rest of `pumasim run` once the scene and its controls are resolved:
// the run's size checked against its budgets (check_run_size), the folder
// `out` checked before the run when given (check_run_folder_target: a
// refusal costs nothing), the run (progress may be empty), stats.json, and
// the folder written when `out` is given (write_run_folder; an existing run
// folder replaced only with force; meta.json from context, or from a context
// made now without a command line when null). keep_rows keeps the output rows in
// SceneRun::rows. A run that fails is a result (run.result.ok false), not an
// exception; one interrupted (progress.cancel) writes no folder.
CompletedRun run_scene(const Scene& scene, const RunControls& controls, const std::optional<std::filesystem::path>& out,
                       bool force, const ProgressHook& progress = {}, const RunContext* context = nullptr,
                       bool keep_rows = false);

}  // namespace pumasim
