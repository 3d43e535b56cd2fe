// The documents of a run folder besides the trajectory: stats.json (one
// schema: the run's settings, the integrator's statistics, the recorder's
// figures) and meta.json (how the run was asked for, how the program was
// built, fixed at build time, and the machine it ran on). Written with nlohmann-json, keys in order; a
// number that is not finite is null.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "simulation/scene_run.hpp"

namespace pumasim {

std::string stats_json(const Scene& scene, const RunControls& controls, const SceneRun& run);

// What meta.json records about one run besides the build.
struct RunContext {
  std::string command_line;       // the program and its arguments, shell-quoted (shell_quoted)
  std::string working_directory;  // where it was run
  std::string started_utc;        // ISO 8601, "2024-05-01T12:00:00Z"
  std::string robot_file;         // the robot file the scene loaded, absolute
  std::string robot_fnv1a64;      // FNV-1a 64 of its bytes as loaded, 16 hex digits
  std::vector<InputFile> inputs;  // every file the scene's load read (Scene::inputs), by content
};

// The context of a run starting now: argv (the program first), the working
// directory, the time, and the files the scene's load read with their hashes
// (of the bytes it parsed: no second read).
RunContext run_context(const std::vector<std::string>& argv, const Scene& scene);

// The run's context (command line, working directory, start time, robot file
// and its hash, every input file with its size and hash), then the git revision (with "-dirty" when the tree had
// changes) and whether it was dirty, compiler, flags and build type (from the
// build: cmake/build_info.cmake), the libraries' versions, the machine, its
// CPU count and CPU model.
std::string meta_json(const RunContext& context);

// The arguments joined by spaces, each quoted for a POSIX shell where it needs
// it ('it'\''s'), so that the line pastes back into a shell as the same argv.
std::string shell_quoted(const std::vector<std::string>& argv);


// "pumasim 161cd97 (GNU 12.2.0, -O3 -DNDEBUG -march=native, Release)": the
// build information of meta.json on one line (pumasim --version).
std::string version_text();

// /proc/cpuinfo's first "model name", or "unknown".
std::string cpu_model();

}  // namespace pumasim
