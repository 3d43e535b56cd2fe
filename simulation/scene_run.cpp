#include "simulation/scene_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "integrators/registry.hpp"
#include "simulation/mode_log.hpp"

namespace pumasim {
namespace {

// A period whose stops alone exceed the step budget is refused, naming where
// the duration came from (the scene, --t-end, the reference).
void check_stops(const char* key, double period, const Scene& sc, long max_steps) {
  const double duration = sc.duration;
  if (!(period > 0)) return;
  // A period that the run's last time does not move (t + period == t) would
  // stop the event loop in place: refused whatever the budget (0: none).
  if (!(duration + period > duration)) {
    std::ostringstream m;
    m << key << ": expected a period that advances the time near the run's end, " << duration
      << " s (" << sc.duration_source << "; at least " << duration * 4e-16 << " s), got " << period << " s";
    throw std::invalid_argument(m.str());
  }
  if (max_steps <= 0) return;
  const double stops = duration / period;
  if (stops > static_cast<double>(max_steps)) {
    std::ostringstream m;
    m << key << ": " << period << " s over " << duration << " s (" << sc.duration_source << ") is " << stops
      << " stops, more than the step budget of " << max_steps
      << " steps (a larger {{max_steps}} raises it; a longer period or a shorter duration)";
    throw std::invalid_argument(m.str());
  }
}

}  // namespace

void check_run_size(const Scene& sc, long max_steps) {
  // The output rows are held in memory until the run ends (then written at
  // once): their number is bounded before anything is allocated.
  if (const double rows = sc.duration / sc.output_interval + 1; !(rows <= kMaxOutputRows)) {
    std::ostringstream m;
    m << "scene.output_interval: expected at most " << static_cast<long>(kMaxOutputRows) << " output rows over "
      << sc.duration_source << " (a longer output_interval or a shorter duration), got " << sc.duration << " s / "
      << sc.output_interval << " s = " << rows << " rows";
    throw std::invalid_argument(m.str());
  }
  if (sc.plant.controller == ControllerMode::kSampled) {
    check_stops("controller.servo_period", sc.plant.servo_period, sc, max_steps);
  }
  check_stops("controller.setpoint_interval", sc.plant.setpoint_interval, sc, max_steps);
}

void check_output_size(const Scene& sc, const Plant& plant) {
  const double rows = std::floor(sc.duration / sc.output_interval) + 1;
  const int columns = RunRecorder::columns(plant);
  if (const double values = rows * columns; !(values <= kMaxOutputValues)) {
    std::ostringstream m;
    m << "scene.output_interval: expected at most " << kMaxOutputValues << " numbers in trajectory.csv (rows x "
      << "columns) over " << sc.duration_source << " (a longer output_interval or a shorter duration), got "
      << static_cast<long long>(std::min(rows, 1e18)) << " rows x " << columns << " columns = " << values;
    throw std::invalid_argument(m.str());
  }
}

SceneRun simulate_scene(const Scene& sc, const RunControls& rc, const SceneRunIo& io) {
  Plant plant(sc.plant);
  check_output_size(sc, plant);  // before anything is sized by the rows
  auto integ = make_integrator(sc.integrator.name, rc.options);
  RunRecorder recorder(plant, io.trajectory, io.keep_rows,
                       io.keep_rows ? static_cast<std::size_t>(sc.duration / sc.output_interval + 1) : 0);
  SceneRun run;
  bool modes = false;
  for (int j = 0; j < plant.layout().n; ++j) modes |= plant.joint_has_modes(j);
  // Time-stepping with set-valued friction leaves the hybrid model's modes
  // alone: its modes are those of its steps, classified by speed (a stuck
  // joint's speed is exactly 0 after the step's impulse).
  const bool time_stepping = integ->capabilities().set_valued_friction;
  run.modes_classified = modes && (!plant.has_mode_events() || time_stepping);
  run.speed_only = run.modes_classified && time_stepping;
  ModeClassifier classifier(plant, kStickSpeed, kMinModeDuration, time_stepping);
  const bool speed_twin = modes && plant.has_mode_events() && !time_stepping;
  ModeClassifier by_speed(plant, kStickSpeed, kMinModeDuration, true);  // costs no f
  const auto observe = [&](double t, const double* x) {
    if (t == 0.0 && run.modes_classified && classifier.changes().empty()) classifier.step(0.0, x);  // x(0)
    if (t == 0.0 && speed_twin && by_speed.changes().empty()) by_speed.step(0.0, x);
    if (io.output) io.output(plant, t, x);
    recorder.observe(t, x);
  };
  const Observer on_step = [&](double t, const double* x) {
    const auto start = std::chrono::steady_clock::now();
    classifier.count(t, x);
    if (run.modes_classified) classifier.step(t, x);
    if (speed_twin) by_speed.step(t, x);
    run.mode_log_wall_time += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  run.result = run_plant(plant, *integ,
                         {.t_end = sc.duration,
                          .output_interval = sc.output_interval,
                          .observe = observe,
                          .max_steps = rc.max_steps,
                          .stops = rc.stops,
                          .max_wall = rc.max_wall,
                          .progress = io.progress,
                          .on_step = modes ? on_step : Observer{}});
  if (modes) {
    const auto& changes = run.modes_classified ? classifier.changes() : plant.mode_changes();
    run.events_csv = events_csv(plant, changes);
    if (speed_twin) run.events_speed_csv = events_csv(plant, by_speed.changes());
    run.mode_changes = static_cast<long>(changes.size());
    run.speed_sign_changes = classifier.speed_sign_changes();
    run.shortest_step = classifier.shortest_step();
  }
  // The rows formatted inside the run are the output's cost, not the simulation's.
  run.result.wall_time -= recorder.output_seconds();
  recorder.finish();
  run.figures = recorder.figures();
  if (io.keep_rows) {
    RunRecorder::Rows rows = recorder.take_rows();
    run.rows = std::move(rows.rows);
    run.path_error = std::move(rows.path_error);
    run.path_deviation = std::move(rows.path_deviation);
  }
  run.stats = integ->stats();
  if (!time_stepping) {  // the hybrid model's mode solves (0 without events)
    const Plant::StickStats& s = plant.stick_stats();
    run.stats.friction_solves += s.solves;
    run.stats.friction_iterations += s.iterations;
    run.stats.friction_unconverged += s.unconverged;
    run.stats.friction_worst_residual = std::max(run.stats.friction_worst_residual, s.worst_residual);
  }
  run.state_names = plant.layout().names;
  for (int k = 0; k < plant.size(); ++k) {
    run.tolerance_scales.push_back(plant.tolerance_scale(k));
    run.physical_bounds.push_back(plant.physical_bound(k));
    run.physical_bounds_why.push_back(plant.physical_bound_why(k));
  }
  return run;
}

}  // namespace pumasim
