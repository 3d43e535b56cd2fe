// A scene's forward sensitivities with respect to named scene keys
// ("motor.resistance", "controller.kp", any numeric key of the resolved
// scene): dx/dp along the run at its output times, by CVODES
// (integrators/sensitivity.hpp) on the scene's plant with its exact
// Jacobian. df/dp_k comes from central differences of the plant's f between
// two plants built from the scene with p_k moved by +-h_k (h_k =
// `relative_step` |p_k|, or `relative_step` where p_k = 0): every key the
// scene reader takes, at the cost of two f per key per sensitivity
// right-hand side; the initial state's dx0/dp_k the same way. Verified
// against central differences of whole runs (tests/test_sensitivity.cpp).
//
// Only scenes whose f is continuous in (t, x): a scene with discrete state
// (a sampled controller, a held set-point, the hybrid friction's modes) or
// a friction law discontinuous without events is refused with the reason
// (its sensitivities jump at the switches, by a saltation matrix this does
// not apply). The reference's breakpoints, where f only kinks, are stops.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "integrators/sensitivity.hpp"
#include "models/scene/scene.hpp"
#include "simulation/scene_run.hpp"

namespace pumasim {

struct SceneSensitivities {
  std::vector<std::string> keys;
  std::vector<double> values;  // p_k in the scene
  std::vector<double> steps;   // h_k of df/dp_k's differences
  std::vector<std::string> state_names;
  SensitivityRun run;
  // With a reference, over the rows the run's figures take (t = 0 and every
  // output): the path error's maximum and RMS [m] and their derivatives in
  // each key [m per unit of the key]; empty without one.
  double max_path_error = 0, rms_path_error = 0;
  std::vector<double> d_max_path_error, d_rms_path_error;
};

// Why the scene's sensitivities cannot be integrated ("" when they can).
std::string sensitivity_refusal(const Scene& scene);

// The sensitivities' set-up, made before the run so that every refusal
// costs nothing: the scene's plant and the moved plants (two per key).
struct SensitivityPlan;

// std::invalid_argument for a refused scene, no keys, a key that is not a
// real number of the resolved scene, one of [integrator], [scene] or
// [output], one whose moved value the scene reader refuses, or one that
// moves the reference's breakpoints.
std::shared_ptr<SensitivityPlan> plan_sensitivities(const Scene& scene, const std::vector<std::string>& keys,
                                                    double relative_step = 1e-6);

// The scene's run (its duration, output interval and the controls' rtol and
// atol, --max-steps in all) with the plan's sensitivities; a failure is a
// result (run.ok false).
SceneSensitivities scene_sensitivities(SensitivityPlan& plan, const Scene& scene, const RunControls& controls);

// "t,<state>,...,d<state>/d<key>,..." then a row per output time, numbers
// with 17 significant digits: the state, then each key's sensitivities.
std::string sensitivity_csv(const SceneSensitivities& s);

// stats.json's "sensitivity" object: the keys, their values and steps, the
// final state's sensitivities per key, the run's counts (steps, f, the
// sensitivities' right-hand sides, Jacobians) and wall time; ok and the
// failure when it failed.
std::string sensitivity_json(const SceneSensitivities& s, double rtol, double atol);

}  // namespace pumasim
