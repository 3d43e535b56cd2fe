// Internal invariants. PUMASIM_DEMAND(condition, what) is checked in every
// build, as Drake's DRAKE_DEMAND: a false condition is a bug in pumasim, not
// bad input (bad input is a ConfigError naming the file, line and key, exit
// status 2). It throws pumasim::InternalError naming the condition, `what`,
// the file and the line, which the command line reports with exit status 1
// (kExitInternal). For checks cheap enough to keep off the hot paths' loops;
// none of the right-hand side's per-joint work uses it.
#pragma once

#include <string>

#include "core/errors.hpp"

namespace pumasim {

namespace detail {
[[noreturn]] inline void invariant_failed(const char* condition, const std::string& what, const char* file,
                                          int line) {
  throw InternalError(std::string("a bug in pumasim (please report it): ") + what + " [" +
                      condition + " is false at " + file + ":" + std::to_string(line) + "]");
}
}  // namespace detail

}  // namespace pumasim

#define PUMASIM_DEMAND(condition, what)                                                      \
  do {                                                                                       \
    if (!(condition)) ::pumasim::detail::invariant_failed(#condition, (what), __FILE__, __LINE__); \
  } while (false)
