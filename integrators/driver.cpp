#include "integrators/driver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace pumasim {

RunResult run_plant(Plant& plant, Integrator& integrator, double t_end, double output_interval,
                    const Observer& observe, long max_steps, bool stop_at_events) {
  const auto start = std::chrono::steady_clock::now();
  PlantSystem sys(plant);
  std::vector<double> x(plant.size());
  plant.initial_state(x.data());
  integrator.reset(sys, 0.0, x.data());
  RunResult res;
  if (observe) observe(0.0, x.data());
  const double eps = 1e-12 * std::max(1.0, t_end);
  long k_out = 1;
  double t = 0.0;
  while (t < t_end - eps) {
    const double t_out = std::min(k_out * output_interval, t_end);
    const double t_event = plant.next_time_event(t);
    const double stop = stop_at_events ? std::min(t_out, t_event) : t_out;
    const Outcome o = integrator.advance_to(stop);
    t = integrator.time();
    const double* xs = integrator.state();
    if (o.status == Outcome::kFailed) {
      res.ok = false;
      res.failure = o.message;
      break;
    }
    x.assign(xs, xs + plant.size());
    if (max_steps > 0 && integrator.stats().steps > max_steps) {
      res.ok = false;
      res.failure = std::string(integrator.name()) + ": step budget of " + std::to_string(max_steps) +
                    " steps exhausted at t = " + std::to_string(t) + " s; fastest-changing component " +
                    fastest_component(sys, t, x.data());
      break;
    }
    if (o.status == Outcome::kRoot) {
      plant.on_root(o.root, t, x.data());
      integrator.reset(sys, t, x.data());
      ++res.root_events;
      continue;
    }
    if (t >= t_event - eps) {
      // Stopping at events, exactly one is due here; otherwise every event
      // passed since the last stop, each applied now (late).
      for (double te = t_event; te <= t + eps; te = plant.next_time_event(te)) {
        plant.on_time_event(te, x.data());
        ++res.time_events;
      }
      integrator.reset(sys, t, x.data());
    }
    if (t >= t_out - eps) {
      if (observe) observe(t, x.data());
      ++k_out;
    }
  }
  res.t_final = t;
  res.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

}  // namespace pumasim
