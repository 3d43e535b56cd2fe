// The front door: one run of a scene, as the command line (experiments/cli.cpp:
// CLI11 binds its options into a RunRequest), the Python module (python/) and
// the stiffness command (experiments/stiffness.cpp) ask for it. run(request,
// sinks) loads the scene (or takes one already loaded), applies the request's
// options to a copy of it with their checks (the run's record, RunPlan: the
// scene as run; the caller's scene is not changed), runs it, and writes
// stats.json and, when one is asked for, the run folder. What reaches the
// caller while it runs (warnings, progress, each output) goes through the
// sinks.
//
// Messages name an option neutrally, as {{name}} (core/option_words.hpp): the
// command line and the Python module each phrase it in their own words.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/option_words.hpp"
#include "models/scene/scene.hpp"
#include "simulation/run_documents.hpp"
#include "simulation/scene_run.hpp"
#include "simulation/sensitivity.hpp"

namespace pumasim {

// The options of a run, each unset when not given (then the scene's value or
// the default). Messages name them by these members' names ({{max_steps}}).
struct RunOptions {
  std::optional<std::string> integrator;  // default: the scene's
  std::optional<std::string> backend;     // default: the scene's
  std::optional<double> dt;               // fixed-step methods [s]
  std::optional<double> rtol, atol;       // adaptive methods
  std::optional<double> t_end;            // [s] (default: the scene's duration)
  std::optional<double> output_interval;  // [s] (default: the scene's; the command line does not offer it)
  std::optional<double> max_steps;        // a whole number >= 0 (0: no limit; default kDefaultStepBudget)
  std::optional<double> max_wall;         // [s] >= 0 (0: no limit; default kDefaultWallBudget)
  std::optional<std::string> jacobian;    // exact|differences (default: exact where taken)
  bool late_events = false;               // time events applied late, at the next output (Stops)
  bool stop_at_outputs = false;           // the integrator also stops at every output (Stops)
  bool keep_history = false;              // fixed-step multistep methods keep their history across events
  // Scene keys whose forward sensitivities the run also integrates
  // (simulation/sensitivity.hpp): sensitivity.csv in the folder, and
  // stats.json's "sensitivity" object. Empty: none.
  std::vector<std::string> sensitivity;
};

// A run as it is asked for.
struct RunRequest {
  // The scene: a file with its overrides (section.key=value) and the keys
  // removed before them, loaded by run() (load_checked_scene); or, when
  // `scene` is set, that scene as loaded (file, sets and unsets unread).
  std::string file;
  std::vector<std::string> sets, unsets;
  const Scene* scene = nullptr;
  RunOptions options;
  std::optional<std::filesystem::path> out;  // the run folder (none: none, unless default_out)
  bool default_out = false;                  // without out: runs/<the scene's name> (the command line's default)
  bool force = false;                        // out may replace a pumasim run folder holding only what pumasim wrote
  bool keep_rows = false;                    // the output rows kept in SceneRun::rows, with their path errors
  bool stats = true;                         // stats.json's text made (RunRecord::stats) without a folder too
  std::vector<std::string> argv;             // the command line, for meta.json (empty: none)
};

// The run's record, made before it runs: the scene as run (the request's
// options applied to a copy: integrator, back-end, step or tolerances, end
// time and output interval, which scene.resolved.toml then records) and how
// the run is driven.
struct RunPlan {
  Scene scene;
  RunControls controls;
  std::optional<std::filesystem::path> folder;  // the run folder to be written
};

// What reaches the caller while the run is made; each may be empty.
struct RunSinks {
  std::function<void(const RunPlan&)> planned;      // the plan, once made, before the run
  std::function<void(const std::string&)> warning;  // each warning before the run (run_start_warnings)
  ProgressHook progress;                            // from the step loop (driver.hpp)
  OutputSink output;                                // each output, with the run's plant (scene_run.hpp)
  OptionWords words;  // the caller's words for the options in the warnings and the failure (empty: neutral)
};

struct RunRecord {
  RunPlan plan;
  SceneRun run;       // run.result.failure phrased in sinks.words
  std::string stats;  // stats.json's text ("" when neither asked for nor written)
  std::optional<SceneSensitivities> sensitivities;  // with options.sensitivity
};

// The run as requested: the scene loaded (or taken), the plan made
// (plan_run), its size and its folder checked before the run (a refusal costs
// nothing), the warnings, the run, stats.json, and the folder when one is
// asked for (RunFolderWriter: an existing run folder replaced only with
// force; an interrupted run writes none). Bad input is ConfigError,
// RunFolderError or std::invalid_argument naming the key or the option; a run
// that fails is a result (run.result.ok false), not an exception.
RunRecord run(const RunRequest& request, const RunSinks& sinks = {});

// load_scene(file, overrides, unsets), and the scene's integrator in the registry;
// ConfigError naming the file, line and key otherwise (what `pumasim check`
// and run() load).
Scene load_checked_scene(const std::string& file, const std::vector<std::string>& overrides,
                         const std::vector<std::string>& unsets = {});
// The same from a scene's text (load_scene_text), as if read from `file`.
Scene load_checked_scene_text(const std::string& text, const std::string& file);
// The same through a template (many loads of one file: an ensemble's samples).
Scene load_checked_scene(const SceneTemplate& scene, const std::vector<std::string>& overrides);

// The options applied to the scene (taken as a copy: the plan's scene is
// the record of what is run) with their checks. An option the method cannot
// honour, a back-end that cannot describe the scene's robot, or a value out
// of range is std::invalid_argument naming the option ("{{dt}}: cvode-bdf is
// adaptive; expected {{rtol}} and {{atol}}").
RunPlan plan_run(Scene scene, const RunOptions& options);

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

}  // namespace pumasim
