// The end of every benchmark binary's main: the build that runs (revision,
// compiler, flags, build type; cmake/build_info.cmake) into the JSON's
// context, then Google Benchmark's own command line and run.
#pragma once

#include <benchmark/benchmark.h>

#include "pumasim_build_info.hpp"  // generated at build time

namespace pumasim {

inline int run_registered_benchmarks(int argc, char** argv) {
  benchmark::AddCustomContext("pumasim_git_revision", build_info::kGitRevision);
  benchmark::AddCustomContext("pumasim_compiler", build_info::kCompiler);
  benchmark::AddCustomContext("pumasim_flags", build_info::kFlags);
  benchmark::AddCustomContext("pumasim_build_type", build_info::kBuildType);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace pumasim
