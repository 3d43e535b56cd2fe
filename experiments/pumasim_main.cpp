// pumasim: the project's command line (see `pumasim help`).
#include <cstdio>
#include <iostream>

#include "experiments/cli.hpp"

int main(int argc, char** argv) {
  std::ios::sync_with_stdio(false);
  int status = pumasim::run_cli(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr,
                                argc > 0 ? argv[0] : "pumasim");
  // What went to standard output must have reached it: a full disk or a
  // closed pipe is a failure naming the output, not an empty file and exit 0.
  std::cout.flush();
  if (!std::cout || std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::cerr << "pumasim: standard output: expected to write the command's output, got a write error (a full "
                 "disk, a closed pipe or a read-only file?)\n";
    if (status == pumasim::kExitOk) status = pumasim::kExitBadInput;
  }
  return status;
}
