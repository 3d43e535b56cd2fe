// The command line run in-process, its exit status and both streams captured
// (shared by the tests that drive run_cli).
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "experiments/cli.hpp"

namespace pumasim::testing {

struct CliResult {
  int status;
  std::string out, err;
};

inline CliResult cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int status = run_cli(args, out, err);
  return {status, out.str(), err.str()};
}

}  // namespace pumasim::testing
