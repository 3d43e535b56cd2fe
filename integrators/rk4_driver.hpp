// Classical RK4 with a fixed step that lands exactly on every time event of
// the plant (controller samples, set-point updates): the step before an event
// is shortened, the plant updates its discrete state there, and stepping goes
// on. The first integrator; the integrators issue puts it behind the common
// interface with the others.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

#include "models/plant.hpp"

namespace pumasim {

struct Rk4Stats {
  long steps = 0;
  long rhs_evaluations = 0;
  long time_events = 0;
};

// Integrates from the plant's initial state to t_end. observe(t, x) is called
// at t = 0 and after every step whose end is a multiple of `output_interval`.
inline Rk4Stats integrate_rk4(Plant& plant, double t_end, double dt, double output_interval,
                              const std::function<void(double, const double*)>& observe) {
  const int m = plant.size();
  std::vector<double> x(m), k1(m), k2(m), k3(m), k4(m), tmp(m);
  plant.initial_state(x.data());
  Rk4Stats st;
  double t = 0.0;
  double next_output = 0.0;
  const double eps = 1e-12 * std::max(1.0, t_end);
  if (observe) observe(t, x.data()), next_output += output_interval;
  while (t < t_end - eps) {
    const double t_event = plant.next_time_event(t);
    double h = std::min(dt, t_end - t);
    bool at_event = false;
    if (t_event <= t + h + eps) h = t_event - t, at_event = true;
    plant.rhs(t, x.data(), k1.data());
    for (int i = 0; i < m; ++i) tmp[i] = x[i] + 0.5 * h * k1[i];
    plant.rhs(t + 0.5 * h, tmp.data(), k2.data());
    for (int i = 0; i < m; ++i) tmp[i] = x[i] + 0.5 * h * k2[i];
    plant.rhs(t + 0.5 * h, tmp.data(), k3.data());
    for (int i = 0; i < m; ++i) tmp[i] = x[i] + h * k3[i];
    plant.rhs(t + h, tmp.data(), k4.data());
    for (int i = 0; i < m; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    t = at_event ? t_event : t + h;
    st.steps++;
    st.rhs_evaluations += 4;
    if (at_event) plant.on_time_event(t, x.data()), st.time_events++;
    if (observe && t >= next_output - eps) {
      observe(t, x.data());
      next_output += output_interval;
    }
  }
  return st;
}

}  // namespace pumasim
