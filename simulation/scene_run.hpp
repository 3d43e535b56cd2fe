// One run of a scene, apart from the command line: the budgets a run gets
// (refused up front when the scene alone exceeds them), the plant and the
// integrator made from the scene, the driver run with the run recorder as its
// observer, and what the run leaves: the trajectory's text, the figures and
// the integrator's statistics, from which run_documents writes stats.json.
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "integrators/integrator.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "simulation/run_recorder.hpp"

namespace pumasim {

inline constexpr long kDefaultStepBudget = 10'000'000;  // pumasim run --max-steps
inline constexpr double kDefaultWallBudget = 600.0;      // [s], pumasim run --max-wall

// How a run is driven, beyond the scene.
struct RunControls {
  IntegratorOptions options;              // the scene's integrator settings, as resolved
  bool adaptive = false;                  // the scene's integrator adapts its step (rtol, atol)
  long max_steps = kDefaultStepBudget;    // steps in all; 0: no limit
  double max_wall = kDefaultWallBudget;   // [s] wall-clock time; 0: no limit
  Stops stops = Stops::kEvents;
};

// Refuses (std::invalid_argument, naming the scene keys) a run whose output
// rows exceed kMaxOutputRows, or whose controller samples or set-point
// updates alone exceed the step budget (each is a stop, so at least a step):
// a refusal costs nothing, a 1e-12 s servo period would grind through the
// whole budget first.
void check_run_size(const Scene& scene, long max_steps);

// The numbers trajectory.csv may hold, rows times columns: 1e8, a file of
// at most about 2.4 GB (a number at full precision takes up to 24
// characters with its comma), or 800 MB of rows kept in memory (the Python
// module's arrays). `pumasim run` itself streams the rows to the file and
// holds at most a chunk of them (run_recorder.hpp).
inline constexpr double kMaxOutputValues = 1e8;

// Refuses (std::invalid_argument, naming the scene keys) a run whose
// trajectory would hold more than kMaxOutputValues numbers with this plant's
// columns (RunRecorder::columns).
void check_output_size(const Scene& scene, const Plant& plant);

struct SceneRun {
  RunResult result;
  IntegratorStats stats;
  std::vector<std::string> state_names;
  std::vector<double> tolerance_scales;  // the plant's typical magnitude of each state
  std::vector<double> physical_bounds;   // |x_k| <= bound (+inf: none; models/plant/physical_bounds.hpp)
  std::vector<std::string> physical_bounds_why;
  std::string events_csv;         // the friction modes (mode_log.hpp); "" when no joint has modes
  long mode_changes = 0;          // its rows
  bool modes_classified = false;  // from the accepted steps (else: the hybrid model's events)
  bool speed_only = false;        // classified by speed alone (time-stepping: moreau-jean)
  // The hybrid model's run classified as the laws without modes and
  // time-stepping are, by speed alone (|w_m| <= kStickSpeed, modes lasting
  // kMinModeDuration): their like-for-like yardstick (events_speed.csv); ""
  // for other runs.
  std::string events_speed_csv;
  double mode_log_wall_time = 0;  // [s] spent classifying the steps (part of result.wall_time)
  long speed_sign_changes = 0;    // over the accepted steps, summed over the joints (with modes only)
  double shortest_step = 0;       // [s], the shortest accepted step (with modes only)
  RunFigures figures;
  // With keep_rows: the output rows, [t, x...] per row (state_names.size() + 1
  // numbers each), and each row's path error and deviation [m] (empty
  // without a reference).
  std::vector<double> rows, path_error, path_deviation;
};

// Each output's state, with the run's plant at its discrete state then (the
// stiffness command takes its Jacobian there); it sees the output before
// the run recorder does and must not change the plant's discrete state.
using OutputSink = std::function<void(Plant& plant, double t, const double* x)>;

// What a scene's run reports, and to whom, besides its result.
struct SceneRunIo {
  ProgressHook progress;   // by wall-clock time from the step loop (driver.hpp); may be empty
  OutputSink output;       // may be empty
  bool keep_rows = false;  // SceneRun::rows and the path errors
  // Where trajectory.csv's text is written as the run goes (nullptr: no text).
  std::ostream* trajectory = nullptr;
};

// Runs the scene (integrator scene.integrator.name) over scene.duration. The
// run's wall time leaves out the time spent formatting its output; its
// wall-clock budget (controls.max_wall) does not.
SceneRun simulate_scene(const Scene& scene, const RunControls& controls, const SceneRunIo& io = {});

}  // namespace pumasim
