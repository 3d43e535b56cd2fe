#include "experiments/simulation/scene_run.hpp"

#include <sstream>
#include <stdexcept>

#include "integrators/registry.hpp"

namespace pumasim {
namespace {

// A period whose stops alone exceed the step budget is refused.
void check_stops(const char* key, double period, double duration, long max_steps) {
  if (!(period > 0)) return;
  const double stops = duration / period;
  if (stops > static_cast<double>(max_steps)) {
    std::ostringstream m;
    m << key << ": " << period << " s over " << duration << " s is " << stops
      << " stops, more than the step budget of " << max_steps
      << " steps (--max-steps N raises it; a longer period or a shorter duration)";
    throw std::invalid_argument(m.str());
  }
}

}  // namespace

void check_run_size(const Scene& sc, long max_steps) {
  // The output rows are held in memory until the run ends (then written at
  // once): their number is bounded before anything is allocated.
  if (const double rows = sc.duration / sc.output_interval + 1; !(rows <= kMaxOutputRows)) {
    std::ostringstream m;
    m << "scene.duration / scene.output_interval: expected at most " << kMaxOutputRows
      << " output rows (a longer output_interval, or a shorter duration), got " << rows;
    throw std::invalid_argument(m.str());
  }
  if (max_steps <= 0) return;
  if (sc.plant.controller == ControllerMode::kSampled) {
    check_stops("controller.servo_period", sc.plant.servo_period, sc.duration, max_steps);
  }
  check_stops("controller.setpoint_interval", sc.plant.setpoint_interval, sc.duration, max_steps);
}

SceneRun simulate_scene(const Scene& sc, const RunControls& rc, const ProgressHook& progress, bool keep_rows) {
  Plant plant(sc.plant);
  auto integ = make_integrator(sc.integrator.name, rc.options);
  RunRecorder recorder(plant, sc.duration, sc.output_interval);
  SceneRun run;
  run.result = run_plant(plant, *integ, sc.duration, sc.output_interval,
                         [&](double t, const double* x) { recorder.observe(t, x); }, rc.max_steps, rc.stops,
                         rc.max_wall, progress);
  run.trajectory_csv = recorder.finish();
  run.figures = recorder.figures();
  if (keep_rows) {
    RunRecorder::Rows rows = recorder.take_rows();
    run.rows = std::move(rows.rows);
    run.path_error = std::move(rows.path_error);
    run.path_deviation = std::move(rows.path_deviation);
  }
  run.stats = integ->stats();
  run.state_names = plant.layout().names;
  for (int k = 0; k < plant.size(); ++k) run.tolerance_scales.push_back(plant.tolerance_scale(k));
  return run;
}

}  // namespace pumasim
