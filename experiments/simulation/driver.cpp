#include "experiments/simulation/driver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace pumasim {

RunResult run_plant(Plant& plant, Integrator& integrator, double t_end, double output_interval,
                    const Observer& observe, long max_steps, Stops stops, double max_wall) {
  const auto start = std::chrono::steady_clock::now();
  PlantSystem sys(plant);
  std::vector<double> x(plant.size()), xo(plant.size());
  plant.initial_state(x.data());
  integrator.reset(sys, 0.0, x.data());
  RunResult res;
  if (observe) observe(0.0, x.data());
  const double eps = 1e-12 * std::max(1.0, t_end);
  const bool stop_at_events = stops != Stops::kOutputsLateEvents;
  const bool stop_at_outputs = stops != Stops::kEvents;
  long k_out = 1;
  auto output_time = [&] { return std::min(k_out * output_interval, t_end); };
  double t = 0.0;
  // The next time event not yet applied (initial_state applied those at 0).
  double t_event = plant.next_time_event(0.0);
  while (t < t_end - eps) {
    double stop = t_end;
    if (stop_at_events) stop = std::min(stop, t_event);
    if (stop_at_outputs) stop = std::min(stop, output_time());
    const Outcome o = integrator.step_toward(stop);
    t = integrator.time();
    if (o.status == Outcome::kFailed) {
      res.ok = false;
      res.failure = o.message;
      break;
    }
    // Outputs inside the step, from the method's dense output; one at the
    // step's end waits until the events there are applied.
    for (double to = output_time(); to < t - eps; to = output_time()) {
      integrator.dense_state(to, xo.data());
      if (observe) observe(to, xo.data());
      ++k_out;
    }
    // The state is copied only where the plant may change it (an event) or
    // an output at this instant reads it, not after every step.
    const double* xs = integrator.state();
    if (max_wall > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > max_wall) {
      res.ok = false;
      res.failure = std::string(integrator.name()) + ": wall-clock budget of " + std::to_string(max_wall) +
                    " s exhausted at t = " + std::to_string(t) + " s; fastest-changing component " +
                    fastest_component(sys, t, xs) + " (pumasim run --max-wall S raises the budget; 0: none)";
      break;
    }
    if (max_steps > 0 && integrator.stats().steps > max_steps) {
      res.ok = false;
      res.failure = std::string(integrator.name()) + ": step budget of " + std::to_string(max_steps) +
                    " steps exhausted at t = " + std::to_string(t) + " s; fastest-changing component " +
                    fastest_component(sys, t, xs) + " (pumasim run --max-steps N raises the budget; 0: none)";
      break;
    }
    const bool output_now = t >= output_time() - eps && k_out * output_interval <= t_end + output_interval - eps;
    // Time events due here: the one stopped at, or (late events) every one
    // passed since the last output.
    const bool time_event_now = t >= t_event - eps && (stop_at_events || t >= output_time() - eps);
    if (!output_now && !time_event_now && o.status != Outcome::kRoot) continue;
    x.assign(xs, xs + plant.size());
    bool restart = false;
    if (o.status == Outcome::kRoot) {
      plant.on_root(o.root, t, x.data());
      ++res.root_events;
      restart = true;
    } else if (time_event_now) {
      // Stopping at events, exactly one is due here; otherwise every event
      // passed since the last stop, each applied now (late).
      for (; t_event <= t + eps; t_event = plant.next_time_event(t_event)) {
        plant.on_time_event(t_event, x.data());
        ++res.time_events;
      }
      restart = true;
    }
    if (restart) integrator.reset(sys, t, x.data());
    if (output_now) {
      if (observe) observe(t, x.data());
      ++k_out;
    }
  }
  res.t_final = t;
  res.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

}  // namespace pumasim
