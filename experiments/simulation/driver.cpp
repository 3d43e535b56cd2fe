#include "experiments/simulation/driver.hpp"

#include "integrators/time_rule.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace pumasim {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// After a step: the failure that ends the run when a budget is exhausted
// (wall-clock time first, then steps), or "".
std::string budget_failure(Integrator& integrator, PlantSystem& sys, double t, const double* xs, long max_steps,
                           double max_wall, Clock::time_point start) {
  if (max_wall > 0 && seconds_since(start) > max_wall) {
    return std::string(integrator.name()) + ": wall-clock budget of " + std::to_string(max_wall) +
           " s exhausted at t = " + std::to_string(t) + " s; fastest-changing component " +
           fastest_component(sys, t, xs) + " (pumasim run --max-wall S raises the budget; 0: none)";
  }
  if (max_steps > 0 && integrator.stats().steps > max_steps) {
    return std::string(integrator.name()) + ": step budget of " + std::to_string(max_steps) +
           " steps exhausted at t = " + std::to_string(t) + " s; fastest-changing component " +
           fastest_component(sys, t, xs) + " (pumasim run --max-steps N raises the budget; 0: none)";
  }
  return {};
}

// The discrete changes due at t, applied to the state x: the root found, or
// the time events due (stopping at events, exactly the one stopped at;
// otherwise every event passed since the last stop, each applied now, late).
// True when the integrator must restart.
bool apply_events(Plant& plant, const Outcome& o, double t, double t_end, bool time_event_now, double& t_event,
                  double* x, RunResult& res) {
  if (o.status == Outcome::kRoot) {
    plant.on_root(o.root, t, x);
    ++res.root_events;
    return true;
  }
  if (!time_event_now) return false;
  for (; !before(t, t_event, t_end); t_event = plant.next_time_event(t_event)) {
    plant.on_time_event(t_event, x);
    ++res.time_events;
  }
  return true;
}

}  // namespace

RunResult run_plant(Plant& plant, Integrator& integrator, double t_end, double output_interval,
                    const Observer& observe, long max_steps, Stops stops, double max_wall) {
  const auto start = Clock::now();
  PlantSystem sys(plant);
  std::vector<double> x(plant.size()), xo(plant.size());
  plant.initial_state(x.data());
  integrator.reset(sys, 0.0, x.data());
  RunResult res;
  if (observe) observe(0.0, x.data());
  const bool stop_at_events = stops != Stops::kOutputsLateEvents;
  const bool stop_at_outputs = stops != Stops::kEvents;
  long k_out = 1;
  auto output_time = [&] { return std::min(k_out * output_interval, t_end); };
  double t = 0.0;
  // The next time event not yet applied (initial_state applied those at 0).
  double t_event = plant.next_time_event(0.0);
  while (before(t, t_end, t_end)) {
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
    for (double to = output_time(); before(to, t, t_end); to = output_time()) {
      integrator.dense_state(to, xo.data());
      if (observe) observe(to, xo.data());
      ++k_out;
    }
    // The state is copied only where the plant may change it (an event) or
    // an output at this instant reads it, not after every step.
    const double* xs = integrator.state();
    if (std::string why = budget_failure(integrator, sys, t, xs, max_steps, max_wall, start); !why.empty()) {
      res.ok = false;
      res.failure = std::move(why);
      break;
    }
    const bool output_now = !before(t, output_time(), t_end) &&
                            k_out * output_interval <= t_end + output_interval - time_tolerance(t_end);
    // Time events due here: the one stopped at, or (late events) every one
    // passed since the last output.
    const bool time_event_now = !before(t, t_event, t_end) && (stop_at_events || !before(t, output_time(), t_end));
    if (!output_now && !time_event_now && o.status != Outcome::kRoot) continue;
    x.assign(xs, xs + plant.size());
    if (apply_events(plant, o, t, t_end, time_event_now, t_event, x.data(), res)) integrator.reset(sys, t, x.data());
    if (output_now) {
      if (observe) observe(t, x.data());
      ++k_out;
    }
  }
  res.t_final = t;
  res.wall_time = seconds_since(start);
  return res;
}

}  // namespace pumasim
