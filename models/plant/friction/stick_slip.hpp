// The friction modes as discrete state: the hybrid model's root functions
// and mode switches, the coupled stick solve at events, the mode log, the
// classification of the laws without modes, and the set-valued directions
// that time-stepping (moreau-jean) solves with. It changes the context
// (PlantContext::modes) and x at events, never inside f.
//
// Root functions (hybrid friction, one per joint): zero at a slipping joint's
// speed reversal and at a stuck joint's break-away. on_root switches the
// joint's mode (a slipping joint's speed is set to exactly zero in x, and
// it is stuck), then the coupled stick solve (stick_solve.hpp) sets the modes
// of every joint at rest at once: the stuck ones, and a joint at its
// break-away, which may only slip. settle does that solve alone (after a
// controller sample, or at the start). The problem is at acceleration level,
// on the motor side: W = Z (H^-1)_CC Z over the joints C at rest,
// b = W tau_applied,C (the torques their friction resists when all of them
// are held; then a_C = b + W r, r the friction torque on the joints), levels
// max(Fs, Fk) and Fk. After it each stuck joint's root function is >= 0
// (when Fs >= Fk) and each slipping joint at rest accelerates in its slip
// direction (or not at all).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "models/plant/friction/stick_solve.hpp"
#include "models/plant/plant_model.hpp"

namespace pumasim {

// One change of a joint's friction mode (simulation/mode_log.hpp
// writes them as events.csv): at time t, joint (0-based) entered `mode`;
// `applied` is the applied torque that decided it [N m, motor side] (the
// hybrid model: the constraint torque holding the joint after a stick, or the
// one that reached Fs before a release; the laws without modes: K i - h_j / Z
// at the step classified, NaN for a law that does not read it).
struct ModeChange {
  double t = 0;
  int joint = 0;
  SlipMode mode = SlipMode::kStuck;
  double applied = 0;
};

class StickSlip {
 public:
  // The hybrid model's coupled mode solves so far: how many, their PGS
  // sweeps in all, how many missed PGS's stopping rule or its exact check
  // (the enumeration then answered, when k <= 8), the worst relative residual.
  struct Stats {
    long solves = 0, iterations = 0, unconverged = 0;
    double worst_residual = 0.0;
  };

  // The model must outlive this.
  explicit StickSlip(const PlantModel& model);

  int num_roots() const;
  // Only a stuck joint's function needs f's work: its applied torque, from
  // the constrained dynamics at (t, x) (the last f's in w when that was at
  // the same (t, x) under the same modes); a slipping joint's is its speed.
  void roots(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, double* g);
  void on_root(PlantContext& c, PlantWorkspace<double>& w, int joint, double t, double* x);
  // The coupled solve over the joints at rest (see above).
  void settle(PlantContext& c, PlantWorkspace<double>& w, double t, double* x) { solve_modes(c, w, t, x, -1); }

  // The mode log: start() records the modes at t = 0 (one entry per joint
  // with events), record() each net change since (after a discrete update):
  // a joint stuck at a speed reversal and released again at the same instant
  // shows as one change, from slipping one way to the other. Outside f (it
  // may allocate).
  void start_log(const PlantContext& c, const PlantWorkspace<double>& w, double t);
  void record(const PlantContext& c, const PlantWorkspace<double>& w, double t);
  void clear_log() { logged_.clear(); }
  const std::vector<ModeChange>& mode_changes() const { return log_; }

  // Friction modes for laws without them (Plant::classify_modes).
  void classify(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, double stick_speed,
                SlipMode* mode, double* applied, bool always_applied, bool speed_only);

  // B_c at x, column-major (size x set-valued joints): a unit friction
  // torque on joint c's shaft changes qdd by H^-1 e_c Z_c, nothing else.
  void set_valued_directions(PlantWorkspace<double>& w, const double* x, double* B);

  const StickResult& last_solve() const { return result_; }
  const Stats& stats() const { return stats_; }
  StickResult solve(const StickProblem& p, double* r, int* mode) { return solver_.solve(p, r, mode); }

 private:
  void solve_modes(PlantContext& c, PlantWorkspace<double>& w, double t, double* x, int breaking);
  void stick_operator(PlantWorkspace<double>& w, int k);
  // f at (t, x) into w (its applied torques and H), unless w holds it already.
  void evaluate(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x);

  const PlantModel& m_;
  std::vector<double> f_;  // f's output, unused
  StickSolver solver_;
  StickResult result_;
  Stats stats_;
  std::vector<int> candidates_, candidate_mode_;  // the joints at rest in a mode solve, their modes
  // The solve's W (row-major), b, static and kinetic levels, r.
  std::vector<double> coupling_, free_accel_, static_level_, kinetic_level_, friction_;
  std::unique_ptr<bool[]> may_stick_;
  Eigen::VectorXd column_;            // a column of H^-1
  std::vector<ModeChange> log_;
  FrictionModes logged_;               // the modes the log last recorded
  std::vector<double> released_;       // per joint: the applied torque at its last release [N m]
};

}  // namespace pumasim
