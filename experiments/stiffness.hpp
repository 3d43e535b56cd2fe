// Stiffness diagnosis of a scene: the eigenvalues of the plant Jacobian along
// a trajectory (spectral radius, stiffness ratio, fastest and slowest time
// constants with the state that participates most), and for each explicit
// fixed-step integrator the largest stable step its stability region predicts
// beside the largest found by bisection on the scene itself.
#pragma once

#include <string>
#include <vector>

#include "models/scene/scene.hpp"

namespace pumasim {

struct ModeInfo {
  double re = 0, im = 0;  // eigenvalue [1/s]
  std::string state;      // the state with the largest participation factor
};

struct StiffnessSample {
  double t = 0;
  double spectral_radius = 0;  // max |lambda|
  double stiffness_ratio = 0;  // max |Re lambda| / min |Re lambda| over decaying modes
  ModeInfo fastest, slowest;   // decaying modes with the largest / smallest |Re lambda|
  int unstable_modes = 0;      // Re lambda > 0 (a physically growing mode)
};

struct StepBound {
  std::string integrator;
  double predicted = 0;  // min over samples of the region's bound [s]
  double measured = 0;   // largest stable dt found by bisection [s] (0: not measured)
  std::string note;
};

struct StiffnessReport {
  std::vector<StiffnessSample> samples;
  std::vector<StepBound> steps;
};

// samples: Jacobians at that many equally spaced times of a run over
// [0, t_end] with the scene's own integrator and settings. bisect: also
// measure each explicit method's largest stable step (stable: the run over
// [0, t_end] succeeds and ends within 10 % (relative, per state, floor 1) of
// that run's final state).
StiffnessReport analyse_stiffness(const Scene& scene, double t_end, int samples, bool bisect);

// Conditioning along a scene's reference: at each sample (q, qd, qdd) of the
// reference for the simulated joints, cond(H) = its largest over smallest
// eigenvalue, and each supported back-end's forward dynamics of the torque
// tau = ID(q, qd, qdd) (CRBA's RNEA) against qdd: max_j |qdd_b - qdd| /
// max(max_j |qdd|, 1 rad/s^2) -- the back-ends' agreement where H is
// ill-conditioned.
struct ConditioningSample {
  double t = 0;
  std::vector<double> q;
  double cond_H = 0, min_eig_H = 0;
  std::vector<double> qdd_error;  // per back-end, in the order of `backends`
};

struct ConditioningReport {
  std::vector<std::string> backends;
  std::vector<ConditioningSample> samples;
};

ConditioningReport analyse_conditioning(const Scene& scene, int samples);

// The reports as CSV text (what `pumasim stiffness --csv` and `--steps-csv`,
// and `pumasim conditioning --csv`, write): a header row of column names with
// units, then one row per sample (per method), numbers at full precision.
// Stiffness samples: t [s], spectral_radius [1/s], stiffness_ratio [-], then
// for the fastest and the slowest decaying mode its time constant
// tau = -1/Re lambda [s] (0: no decaying mode), Re and Im lambda [1/s] and the
// state that participates most, then unstable_modes [-].
std::string stiffness_samples_csv(const StiffnessReport& report);
// Step bounds: integrator, predicted_step [s], measured_step [s] (0: not
// measured), note.
std::string step_bounds_csv(const StiffnessReport& report);
// Conditioning: t [s], q1 [rad]..., cond_H [-], min_eig_H [kg m^2], and
// qdd_error_<back-end> [-] for each back-end.
std::string conditioning_csv(const ConditioningReport& report);

}  // namespace pumasim
