// Shared by tests/test_ensemble.cpp and tests/test_threads.cpp: a small
// ensemble of the paper's viscous scene, and the bitwise comparison of two
// samples' results (every field but the wall-clock times).
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "simulation/ensemble.hpp"

namespace pumasim::testing {

// Three drive parameters varied, 0.1 s of the run with cvode-bdf (the tsan
// build has the crba back-end, the scene's).
inline EnsembleSpec small_ensemble(const std::string& scenes_dir, long samples) {
  EnsembleSpec s;
  s.scene = scenes_dir + "/paper_slow_viscous.toml";
  s.samples = samples;
  s.seed = 35;
  s.options.integrator = "cvode-bdf";
  s.options.rtol = 1e-6;
  s.options.t_end = 0.1;
  s.factors.push_back({.key = "motor.resistance", .kind = EnsembleFactor::Kind::kNormal, .a = 2.0, .b = 0.2});
  s.factors.push_back({.key = "motor.inductance", .kind = EnsembleFactor::Kind::kLogUniform, .a = 1e-3, .b = 4e-3});
  s.factors.push_back({.key = "amplifier.gain", .kind = EnsembleFactor::Kind::kUniform, .a = 3.5, .b = 4.5});
  return s;
}

inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

inline bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!same_bits(a[i], b[i])) return false;
  }
  return true;
}

// Every field of the two results but the wall-clock times, bit for bit.
inline void expect_same_result(const SampleResult& a, const SampleResult& b, const std::string& what) {
  SCOPED_TRACE(what + ", sample " + std::to_string(a.sample.index));
  EXPECT_EQ(a.sample.index, b.sample.index);
  EXPECT_EQ(a.sample.seed, b.sample.seed);
  EXPECT_EQ(a.sample.values, b.sample.values);
  EXPECT_EQ(a.ok, b.ok);
  EXPECT_EQ(a.failure_kind, b.failure_kind);
  EXPECT_EQ(a.failure, b.failure);
  EXPECT_TRUE(same_bits(a.t_final, b.t_final));
  EXPECT_EQ(a.stats.steps, b.stats.steps);
  EXPECT_EQ(a.stats.rhs_evaluations, b.stats.rhs_evaluations);
  EXPECT_EQ(a.stats.jacobian_evaluations, b.stats.jacobian_evaluations);
  EXPECT_EQ(a.stats.rejected_steps, b.stats.rejected_steps);
  EXPECT_EQ(a.stats.nonlinear_iterations, b.stats.nonlinear_iterations);
  const RunFigures &f = a.figures, &g = b.figures;
  EXPECT_EQ(f.rows, g.rows);
  EXPECT_TRUE(same_bits(f.max_path_error, g.max_path_error));
  EXPECT_TRUE(same_bits(f.rms_path_error, g.rms_path_error));
  EXPECT_TRUE(same_bits(f.max_path_deviation, g.max_path_deviation));
  EXPECT_TRUE(same_bits(f.rms_path_deviation, g.rms_path_deviation));
  EXPECT_TRUE(same_bits(f.peak_u, g.peak_u));
  EXPECT_TRUE(same_bits(f.peak_i, g.peak_i));
  EXPECT_TRUE(same_bits(f.saturated_fraction, g.saturated_fraction));
  EXPECT_FALSE(f.final_state.empty());
  EXPECT_TRUE(same_bits(f.final_state, g.final_state));
}

}  // namespace pumasim::testing
