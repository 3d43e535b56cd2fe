// The documents of a run folder besides the trajectory: stats.json (one
// schema: the run's settings, the integrator's statistics, the recorder's
// figures) and meta.json (how the program was built, fixed at build time,
// and the machine it ran on). Written with nlohmann-json, keys in order; a
// number that is not finite is null.
#pragma once

#include <string>

#include "experiments/simulation/scene_run.hpp"

namespace pumasim {

std::string stats_json(const Scene& scene, const RunControls& controls, const SceneRun& run);

// git revision (with "-dirty" when the tree had changes) and whether it was
// dirty, compiler, flags and build type (from the build: cmake/build_info.cmake),
// the libraries' versions, the machine and its CPU count.
std::string meta_json();

}  // namespace pumasim
