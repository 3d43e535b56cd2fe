// The `pumasim` command line, as a function so that tests can run it in-process.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace pumasim {

// Exit statuses: 0 success, 1 internal error, 2 bad input (usage, values, files).
inline constexpr int kExitOk = 0;
inline constexpr int kExitInternal = 1;
inline constexpr int kExitBadInput = 2;

// args excludes the program name: {"dynamics", "--robot", "puma560", ...};
// program is argv[0], which meta.json's command line starts with.
int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
            const std::string& program = "pumasim");

}  // namespace pumasim
