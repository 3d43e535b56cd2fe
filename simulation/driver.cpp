#include "simulation/driver.hpp"

#include "core/time_rule.hpp"
#include "models/plant/physical_bounds.hpp"
#include "models/plant/profile.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace pumasim {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// The steady clock, read only every k-th step: k doubles while reads fall
// less than 2.5 ms apart, and when they fall more than 10 ms apart it shrinks
// at once in proportion (to what would have taken 5 ms), so that a fast
// method pays a counter per step and one whose steps turn slow (Newton
// failures, rejected steps) is looked at again within a read or two.
class StepClock {
 public:
  explicit StepClock(Clock::time_point start) : start_(start), last_(start) {}
  // Counts a step; true when the clock was read at it (elapsed() is then current).
  bool tick() {
    if (++count_ < every_) return false;
    count_ = 0;
    const Clock::time_point now = Clock::now();
    const Clock::duration gap = now - last_;
    if (gap < std::chrono::microseconds(2500) && every_ < kMaxEvery) {
      every_ *= 2;
    } else if (gap > std::chrono::milliseconds(10) && every_ > 1) {
      every_ = std::max(1L, static_cast<long>(static_cast<double>(every_) * 5e-3 / seconds(gap)));
    }
    last_ = now;
    return true;
  }
  double elapsed() const { return seconds(last_ - start_); }  // [s] at the last read

 private:
  static constexpr long kMaxEvery = 1L << 16;
  Clock::time_point start_, last_;
  long count_ = 0, every_ = 1;
};

// Chattering at a friction switching surface. A set-valued friction row
// without events (the paper's rule, Karnopp's: a zero-speed band) has a
// branch (at rest within the band, or slipping either way) and switching
// surfaces at the band's edges; the hybrid model's rows are left out, its
// events stopping at each switch.
// Counted over the accepted steps: branch changes, in all and in the last two
// windows of kWindow steps. Diagnosed where the run fails: when the step has
// collapsed (the last one under kCollapse times the run's length) and a row's
// speed reaches its surface within kNear of those last steps at its current
// rate, the step is pinned there (an adaptive method rejects every step that
// crosses it), and more steps will not help.
class ChatterCount {
 public:
  explicit ChatterCount(const OdeSystem& sys) {
    for (int c = 0; c < sys.set_valued_rows(); ++c) {
      const SetValuedRow r = sys.set_valued_row(c);
      if (!(r.band > 0)) continue;  // an exact law (the hybrid model): its events stop at every switch
      velocity_.push_back(r.velocity);
      band_.push_back(r.band / std::abs(r.scale));  // on the state's speed
    }
    last_.assign(velocity_.size(), 2);  // no branch yet
    total_.assign(velocity_.size(), 0);
    window_.assign(velocity_.size(), 0);
    previous_.assign(velocity_.size(), 0);
  }
  void step(const double* x) {
    if (velocity_.empty()) return;
    if (++steps_ % kWindow == 0) previous_.swap(window_), std::fill(window_.begin(), window_.end(), 0);
    for (std::size_t k = 0; k < velocity_.size(); ++k) {
      const double v = x[velocity_[k]];
      const signed char branch = std::abs(v) <= band_[k] ? 0 : (v > 0 ? 1 : -1);
      if (last_[k] != 2 && branch != last_[k]) ++total_[k], ++window_[k];
      last_[k] = branch;
    }
  }
  // "" or the diagnosis at (t, x) after `steps` steps, the last one h long.
  std::string diagnosis(OdeSystem& sys, double t, const double* x, double h, double t_end, long rejected) const {
    if (velocity_.empty() || !(h < kCollapse * t_end)) return {};
    std::vector<double> f(static_cast<std::size_t>(sys.size()));
    sys.rhs(t, x, f.data());
    std::size_t worst = 0;
    double soonest = HUGE_VAL;  // [s] to the nearest surface at the current rate
    for (std::size_t k = 0; k < velocity_.size(); ++k) {
      const double v = x[velocity_[k]], rate = std::abs(f[static_cast<std::size_t>(velocity_[k])]);
      const double gap = std::abs(std::abs(v) - band_[k]);
      if (gap / rate < soonest) soonest = gap / rate, worst = k;
    }
    if (!(soonest <= kNear * h)) return {};
    char buf[200];
    std::snprintf(buf, sizeof buf, " = %.4g reaches its friction switching surface (|%s| = %.4g) in %.3g s at its "
                  "current rate, %.3g of the last steps (h = %.3g s)", x[velocity_[worst]],
                  sys.state_name(velocity_[worst]).c_str(), band_[worst], soonest, soonest / h, h);
    return "chattering at a friction switching surface: " + sys.state_name(velocity_[worst]) + buf + "; " +
           std::to_string(rejected) + " rejected steps, and its friction branch changed " +
           std::to_string(window_[worst] + previous_[worst]) + " times in the last accepted steps (" +
           std::to_string(total_[worst]) + " in all); the friction law is discontinuous in the state there and the "
           "step collapses on it, so more steps will not help: use a fixed-step method, friction.model = \"hybrid\" "
           "or the integrator moreau-jean";
  }

 private:
  static constexpr long kWindow = 1000;
  static constexpr double kCollapse = 1e-6;  // the last step under this times the run's length: collapsed
  static constexpr double kNear = 1000;      // the surface within this many of the last steps: pinned there
  std::vector<int> velocity_;
  std::vector<double> band_;
  std::vector<signed char> last_;
  std::vector<long> total_, window_, previous_;
  long steps_ = 0;
};

// The failure that ends the run when a budget is exhausted, or "".
// wall: the wall-clock time at this step, or < 0 when the clock was not read.
// chatter_count: its diagnosis replaces the advice to allow more.
std::string budget_failure(Integrator& integrator, PlantSystem& sys, double t, double t_end, const double* xs,
                           long max_steps, double max_wall, double wall, const ChatterCount& chatter_count) {
  const auto g = [](double x) {  // all the digits a time needs (std::to_string's %f shows 1e-7 s as 0.000000)
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", x);
    return std::string(b);
  };
  const auto where = [&] {
    char h[64];
    std::snprintf(h, sizeof h, " (last step h = %.3g s)", integrator.time() - integrator.step_start());
    return " exhausted at t = " + g(t) + " s" + h + "; fastest-changing component " +
           fastest_scaled_component(sys, t, xs);
  };
  // The chattering diagnosis, made only once a budget is exhausted.
  const auto chatter = [&] {
    return chatter_count.diagnosis(sys, t, xs, integrator.time() - integrator.step_start(), t_end,
                                   integrator.stats().rejected_steps);
  };
  if (max_wall > 0 && wall > max_wall) {
    const std::string c = chatter();
    return std::string(integrator.name()) + ": wall-clock budget of " + g(max_wall) + " s" + where() + "; " +
           (c.empty() ? "more time: a larger {{max_wall}} (0: no limit)" : c);
  }
  if (max_steps > 0 && integrator.stats().steps > max_steps) {
    const std::string c = chatter();
    return std::string(integrator.name()) + ": step budget of " + std::to_string(max_steps) + " steps" + where() +
           "; " + (c.empty() ? "more steps: a larger {{max_steps}} (0: no limit)" : c);
  }
  return {};
}

// The failure that ends a cancelled run (ProgressHook::cancel), with where it was.
std::string interrupted_failure(const Integrator& integrator, double t, double wall) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "interrupted at t = %.9g s, after %ld steps and %.3g s of wall-clock time", t,
                integrator.stats().steps, wall);
  return std::string(integrator.name()) + ": " + buf;
}

// The components with a finite physical bound and kUnstableFactor times it,
// read once (no virtual call in the step loop).
struct BoundedComponent {
  int index;
  double limit;
};
std::vector<BoundedComponent> bounded_components(const OdeSystem& sys) {
  std::vector<BoundedComponent> k;
  for (int i = 0; i < sys.size(); ++i) {
    if (std::isfinite(sys.physical_bound(i))) k.push_back({i, kUnstableFactor * sys.physical_bound(i)});
  }
  return k;
}

// The first component past its limit, or -1 (after every step: compares only).
int unstable_component(const std::vector<BoundedComponent>& bounded, const double* x) {
  for (const BoundedComponent& c : bounded) {
    if (std::abs(x[c.index]) > c.limit) return c.index;
  }
  return -1;
}

// The failure that ends a run whose state left its physical range by more
// than kUnstableFactor (a diverged method).
std::string unstable_failure(const OdeSystem& sys, int i, double t, const double* x) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "unstable at t = %.9g s: %s = %.6g, more than %g times its physical bound %.4g (", t,
                sys.state_name(i).c_str(), x[i], kUnstableFactor, sys.physical_bound(i));
  return buf + sys.physical_bound_why(i) + "); the method diverged: a smaller step, a stable method "
         "(pumasim stiffness SCENE predicts the stable steps) or a tolerance";
}

// The discrete changes due at t, applied to the state x: the root found, or
// the time events due (stopping at events, exactly the one stopped at;
// otherwise every event passed since the last stop, each applied now, late).
// True when the integrator must restart. The hybrid friction's modes are
// settled at time events, except for a method that solves the set-valued
// friction itself (Plant::on_time_event).
bool apply_events(Plant& plant, const Integrator& integrator, const Outcome& o, double t, double t_end,
                  bool time_event_now, double& t_event, double* x, RunResult& res) {
  const bool settle_modes = !integrator.capabilities().set_valued_friction;
  if (o.status == Outcome::kRoot) {
    plant.on_root(o.root, t, x);
    ++res.root_events;
    return true;
  }
  if (!time_event_now) return false;
  for (; !before(t, t_event, t_end); t_event = plant.next_time_event(t_event)) {
    plant.on_time_event(t_event, x, settle_modes);
    ++res.time_events;
  }
  return true;
}

// The cost breakdown of the run (models/plant/profile.hpp; a build with
// PUMASIM_PROFILE only): reset at its start, written at its end into the
// file named by PUMASIM_PROFILE_OUT (experiments/cost_breakdown.py reads it).
void start_profile() {
#ifdef PUMASIM_PROFILE
  profile::reset();
#endif
}
void write_profile() {
#ifdef PUMASIM_PROFILE
  const char* path = std::getenv("PUMASIM_PROFILE_OUT");
  if (!path) return;
  if (std::FILE* f = std::fopen(path, "w")) {
    profile::write(f);
    std::fclose(f);
  }
#endif
}

// The outputs inside the step that ended at t, from the method's dense
// output (k_out: the next output's index, output k at min(k dt_out, t_end));
// one at the step's end waits until the events there are applied.
void dense_outputs(Integrator& integrator, const Observer& observe, double t, double t_end, double output_interval,
                   long& k_out, std::vector<double>& xo) {
  for (double to = std::min(k_out * output_interval, t_end); before(to, t, t_end);
       to = std::min(k_out * output_interval, t_end)) {
    PUMASIM_PROFILE_CONTEXT(kOutput);
    integrator.dense_state(to, xo.data());
    if (observe) observe(to, xo.data());
    ++k_out;
  }
}

// The progress hooks at a step where the loop read the clock (wall seconds
// so far): the report and the poll when due; true when the run is cancelled.
bool wall_clock_hooks(const ProgressHook& progress, const RunProgress& where, double& next_report,
                      double& next_poll) {
  if (progress.report && where.wall >= next_report) {
    progress.report(where);
    next_report = where.wall + progress.period;
  }
  if (progress.poll && where.wall >= next_poll) {
    progress.poll();
    next_poll = where.wall + progress.poll_period;
  }
  return progress.cancel && progress.cancel->load(std::memory_order_relaxed);
}

// A run ended as a reported failure of the kind given (RunResult::failure_kind).
void fail(RunResult& res, std::string why, const char* kind) {
  res.ok = false;
  res.failure = std::move(why);
  res.failure_kind = kind;
}

// The integrator's failure message, with the chattering diagnosis when the
// step collapsed at a friction law's switching surface.
std::string integrator_failure(const Outcome& o, const ChatterCount& chatter, PlantSystem& sys, Integrator& integrator,
                               double t, double t_end) {
  std::string why = o.message;
  if (const std::string c = chatter.diagnosis(sys, t, integrator.state(), integrator.time() - integrator.step_start(),
                                              t_end, integrator.stats().rejected_steps);
      !c.empty()) {
    why += "; " + c;
  }
  return why;
}

}  // namespace

SetValuedRow PlantSystem::set_valued_row(int c) const {
  const int j = p_.set_valued_joint(c);
  const FrictionParams& f = p_.config().friction[static_cast<std::size_t>(j)];
  // A law with Fs < Fk holds up to Fk (else a joint at rest could neither
  // stick nor slip consistently): s = max(Fs, Fk), as in the hybrid model's solve.
  return {p_.layout().qd + j, p_.config().robot.joints[static_cast<std::size_t>(j)].gear_ratio,
          std::max(f.static_torque, f.kinetic_torque), f.kinetic_torque,
          friction_keys(f.model).zero_speed && !has_stick_slip_events(f.model) ? f.zero_speed : 0.0};
}

SetValuedSolve PlantSystem::solve_set_valued(int k, const double* W, const double* b, const double* s,
                                             const double* kin, double* r) {
  const StickResult res = p_.solve_stick({k, W, b, s, kin, nullptr}, r, mode_.data());
  return {res.iterations, res.residual, res.converged && res.consistent};
}

std::string fastest_scaled_component(OdeSystem& sys, double t, const double* x) {
  const int n = sys.size();
  std::vector<double> f(static_cast<std::size_t>(n));
  sys.rhs(t, x, f.data());
  int worst = 0;
  double rate = -1, worst_scale = 1;
  std::string no_form;
  const ImplicitForm* form = sys.implicit_form(no_form);  // a DAE's algebraic rows hold residuals, not rates
  for (int i = 0; i < n; ++i) {
    if (form && form->algebraic(i)) continue;
    const double scale = sys.tolerance_scale(i) > 0 ? sys.tolerance_scale(i) : 1.0;
    const double r = std::abs(f[static_cast<std::size_t>(i)]) / scale;
    if (r > rate || !std::isfinite(r)) rate = r, worst = i, worst_scale = scale;
    if (!std::isfinite(r)) break;
  }
  char buf[128];
  std::snprintf(buf, sizeof buf, " = %.6g (|f| / scale = %.3g 1/s, scale %.3g)", x[worst], rate, worst_scale);
  return sys.state_name(worst) + buf;
}

namespace {
// (Re)starts the integrator at (t, x) and reads its state back into x: a
// DAE's start is made consistent there (Integrator::reset).
void restart(Integrator& integrator, OdeSystem& sys, double t, std::vector<double>& x) {
  integrator.reset(sys, t, x.data());
  x.assign(integrator.state(), integrator.state() + x.size());
}
}  // namespace

RunResult run_plant(Plant& plant, Integrator& integrator, const PlantRunSpec& spec) {
  const auto& [t_end, output_interval, observe, max_steps, stops, max_wall, progress, on_step] = spec;
  start_profile();
  const auto start = Clock::now();
  StepClock clock(start);
  double next_report = progress.delay, next_poll = 0;  // [s] of wall-clock time: the next report, poll
  PlantSystem sys(plant);
  const std::vector<BoundedComponent> bounded = bounded_components(sys);
  ChatterCount chatter(sys);
  std::vector<double> x(plant.size()), xo(plant.size());
  plant.initial_state(x.data());
  restart(integrator, sys, 0.0, x);
  RunResult res;
  if (observe) observe(0.0, x.data());
  const bool stop_at_events = stops != Stops::kOutputsLateEvents;
  const bool stop_at_outputs = stops != Stops::kEvents;
  long k_out = 1;
  // The spec's fields, not the bindings: clang 14 cannot capture those (P1091).
  auto output_time = [&] { return std::min(k_out * spec.output_interval, spec.t_end); };
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
      fail(res, integrator_failure(o, chatter, sys, integrator, t, t_end), "integrator");
      break;
    }
    chatter.step(integrator.state());
    if (const int i = unstable_component(bounded, integrator.state()); i >= 0) {
      fail(res, unstable_failure(sys, i, t, integrator.state()), "unstable");
      break;
    }
    if (on_step) on_step(t, integrator.state());
    dense_outputs(integrator, observe, t, t_end, output_interval, k_out, xo);
    // The state is copied only where the plant may change it (an event) or
    // an output at this instant reads it, not after every step.
    const double* xs = integrator.state();
    double wall = -1;  // [s], when the clock is read at this step
    if (clock.tick()) {
      wall = clock.elapsed();
      const RunProgress where{t, integrator.stats().steps, integrator.time() - integrator.step_start(), wall};
      if (wall_clock_hooks(progress, where, next_report, next_poll)) {
        fail(res, interrupted_failure(integrator, t, wall), "interrupted");
        break;
      }
    }
    if (max_steps > 0 || wall > 0) {
      if (std::string why = budget_failure(integrator, sys, t, t_end, xs, max_steps, max_wall, wall, chatter);
          !why.empty()) {
        fail(res, std::move(why), "budget");
        break;
      }
    }
    const bool output_now = !before(t, output_time(), t_end) &&
                            k_out * output_interval <= t_end + output_interval - time_tolerance(t_end);
    // Time events due here: the one stopped at, or (late events) every one
    // passed since the last output.
    const bool time_event_now = !before(t, t_event, t_end) && (stop_at_events || !before(t, output_time(), t_end));
    if (!output_now && !time_event_now && o.status != Outcome::kRoot) continue;
    x.assign(xs, xs + plant.size());
    if (apply_events(plant, integrator, o, t, t_end, time_event_now, t_event, x.data(), res)) {
      PUMASIM_PROFILE_CONTEXT(kEvents);
      restart(integrator, sys, t, x);
    }
    if (output_now) {
      PUMASIM_PROFILE_CONTEXT(kOutput);
      if (observe) observe(t, x.data());
      ++k_out;
    }
  }
  res.t_final = t;
  res.wall_time = seconds(Clock::now() - start);
  write_profile();
  return res;
}

}  // namespace pumasim
