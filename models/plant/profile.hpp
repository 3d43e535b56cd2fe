// Cost breakdown timers, compiled in only with the CMake option
// PUMASIM_PROFILE (the preset "profile"); in every other build the macros
// below expand to nothing, so the right-hand side carries no timer.
//
// Exclusive wall-clock time per (context, part): a context is what the driver
// or the integrator asked for (the integrator's own work between calls, one
// f, the exact Jacobian, the root functions, the discrete events, the
// output), a part what the plant's evaluation is doing (reference, controller,
// drive, friction, dynamics, the rest). Entering a context or a part charges
// the time since the last mark to the one being left, so the table's entries
// add up to the time between the first and the last mark. A context entered
// inside another one (f inside the root functions) does not replace it.
// Counts: how many times each context was entered at the top.
//
// The timers read the steady clock twice per scope (a read's cost on this
// kind of machine: commit 1f6fa6a): a profiled run is slower than a normal
// one, which experiments/cost_breakdown.py reports beside the normal build's
// wall time.
#pragma once

#ifdef PUMASIM_PROFILE
#include <chrono>
#include <cstdio>

namespace pumasim::profile {

enum Context { kLoop, kRhs, kJacobian, kRoots, kEvents, kOutput, kContexts };
enum Part { kOwn, kReference, kController, kDrive, kFriction, kDynamics, kParts };
inline constexpr const char* kContextNames[kContexts] = {"loop", "rhs", "jacobian", "roots", "events", "output"};
inline constexpr const char* kPartNames[kParts] = {"own", "reference", "controller", "drive", "friction", "dynamics"};

struct Table {
  double ns[kContexts][kParts] = {};
  long calls[kContexts] = {};
  Context context = kLoop;
  Part part = kOwn;
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
  void mark() {
    const auto now = std::chrono::steady_clock::now();
    ns[context][part] += std::chrono::duration<double, std::nano>(now - last).count();
    last = now;
  }
};
inline Table& table() {
  static Table t;
  return t;
}

// The time spent in part p until the end of the scope.
class PartScope {
 public:
  explicit PartScope(Part p) : saved_(table().part) {
    table().mark();
    table().part = p;
  }
  ~PartScope() {
    table().mark();
    table().part = saved_;
  }
  PartScope(const PartScope&) = delete;
  PartScope& operator=(const PartScope&) = delete;

 private:
  Part saved_;
};

// Context c until the end of the scope, unless already inside a context
// other than the loop's.
class ContextScope {
 public:
  explicit ContextScope(Context c) : active_(table().context == kLoop) {
    if (!active_) return;
    table().mark();
    table().context = c;
    table().part = kOwn;
    ++table().calls[c];
  }
  ~ContextScope() {
    if (!active_) return;
    table().mark();
    table().context = kLoop;
    table().part = kOwn;
  }
  ContextScope(const ContextScope&) = delete;
  ContextScope& operator=(const ContextScope&) = delete;

 private:
  bool active_;
};

// Zeroes the table (at the start of a run).
inline void reset() { table() = Table{}; }

// "context part ns" lines, then "calls context n" lines.
inline void write(std::FILE* f) {
  table().mark();
  for (int c = 0; c < kContexts; ++c) {
    for (int p = 0; p < kParts; ++p) std::fprintf(f, "%s %s %.0f\n", kContextNames[c], kPartNames[p], table().ns[c][p]);
    std::fprintf(f, "calls %s %ld\n", kContextNames[c], table().calls[c]);
  }
}

}  // namespace pumasim::profile

#define PUMASIM_PROFILE_CAT2(a, b) a##b
#define PUMASIM_PROFILE_CAT(a, b) PUMASIM_PROFILE_CAT2(a, b)
#define PUMASIM_PROFILE_PART(p) \
  const ::pumasim::profile::PartScope PUMASIM_PROFILE_CAT(pumasim_part_, __LINE__)(::pumasim::profile::p)
#define PUMASIM_PROFILE_CONTEXT(c) \
  const ::pumasim::profile::ContextScope PUMASIM_PROFILE_CAT(pumasim_context_, __LINE__)(::pumasim::profile::c)
#else
#define PUMASIM_PROFILE_PART(p) static_cast<void>(0)
#define PUMASIM_PROFILE_CONTEXT(c) static_cast<void>(0)
#endif
