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

#include "experiments/simulation/scene_run.hpp"

namespace pumasim {

std::string stats_json(const Scene& scene, const RunControls& controls, const SceneRun& run);

// What meta.json records about one run besides the build.
struct RunContext {
  std::string command_line;       // the program and its arguments, shell-quoted (shell_quoted)
  std::string working_directory;  // where it was run
  std::string started_utc;        // ISO 8601, "2024-05-01T12:00:00Z"
  std::string robot_file;         // the robot file the scene loaded, absolute
  std::string robot_fnv1a64;      // FNV-1a 64 of its bytes, 16 hex digits; "" if it could not be read
  // A URDF robot's side file (its rotor inertias, gear ratios, ...), absolute,
  // and its hash; both "" when the robot is no URDF file or it has none.
  std::string robot_side_file;
  std::string robot_side_fnv1a64;
};

// The context of a run starting now: argv (the program first), the working
// directory, the time, the scene's robot file and its hash (read now), and a
// URDF robot's side file and its hash.
RunContext run_context(const std::vector<std::string>& argv, const Scene& scene);

// The run's context (command line, working directory, start time, robot file
// and its hash; robot_side_file too for a URDF robot with a side file), then the git revision (with "-dirty" when the tree had
// changes) and whether it was dirty, compiler, flags and build type (from the
// build: cmake/build_info.cmake), the libraries' versions, the machine, its
// CPU count and CPU model.
std::string meta_json(const RunContext& context);

// The arguments joined by spaces, each quoted for a POSIX shell where it needs
// it ('it'\''s'), so that the line pastes back into a shell as the same argv.
std::string shell_quoted(const std::vector<std::string>& argv);

// FNV-1a, 64 bits (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
std::uint64_t fnv1a64(std::string_view bytes);

// "pumasim 161cd97 (GNU 12.2.0, -O3 -DNDEBUG -march=native, Release)": the
// build information of meta.json on one line (pumasim --version).
std::string version_text();

// /proc/cpuinfo's first "model name", or "unknown".
std::string cpu_model();

}  // namespace pumasim
