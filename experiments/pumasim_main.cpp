// pumasim: the project's command line (see `pumasim help`).
#include <iostream>

#include "experiments/cli.hpp"

int main(int argc, char** argv) {
  std::ios::sync_with_stdio(false);
  return pumasim::run_cli(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr,
                          argc > 0 ? argv[0] : "pumasim");
}
