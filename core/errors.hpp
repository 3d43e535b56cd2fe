// The error types every layer throws. ConfigError: bad user input (a file, an
// override, a name), its message naming the file, line and key with what was
// expected; the command line turns it into exit status 2, the Python module
// into ValueError. InternalError: a bug in pumasim, a broken invariant
// (core/invariant.hpp's PUMASIM_DEMAND); exit status 1. A numerical failure
// (divergence, step-size underflow) is neither: it is a run's reported
// outcome (simulation/driver.hpp), not an exception.
#pragma once

#include <stdexcept>

namespace pumasim {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct InternalError : std::logic_error {
  using std::logic_error::logic_error;
};

}  // namespace pumasim
