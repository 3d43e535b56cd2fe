// The run recorder: what a run of the plant leaves behind, computed apart from
// the command line. Its observe() is the driver's observer (it only copies the
// state at each output, and the drive signals where they depend on a
// discrete state, so the run's wall time is the simulation's); finish()
// then formats the trajectory rows, with reference and kinematics, and
// computes the run's figures: path error and deviation, drive peaks and
// saturation, and the energy ledger's residual.
#pragma once

#include <string>
#include <vector>

#include "models/plant/plant.hpp"

namespace pumasim {

struct RunFigures {
  long rows = 0;                      // output rows
  long samples = 0;                   // rows with a reference
  double max_path_error = 0;          // [m] flange to the reference point
  double rms_path_error = 0;          // [m]
  double max_path_deviation = 0;      // [m] flange to the geometric path, whatever the timing
  double rms_path_deviation = 0;      // [m]
  std::vector<double> peak_u, peak_ea, peak_i;  // per joint: controller output [V], amplifier voltage [V], current [A]
  std::vector<double> saturated_fraction;       // per joint: outputs at the DAC's or the amplifier's limit
  bool ledger = false;                // the energy ledger's figures below are set
  double max_ledger_residual = 0;     // [J]
  double ledger_energy_scale = 0;     // [J] the largest term seen, kinetic energy included
};

class RunRecorder {
 public:
  // Reserves room for duration / output_interval rows.
  RunRecorder(Plant& plant, double duration, double output_interval);
  // The driver's observer: the state at an output time.
  void observe(double t, const double* x);
  // Formats trajectory.csv (one header line, one row per output) and computes
  // the figures. Call once, after the run.
  std::string finish();
  const RunFigures& figures() const { return fig_; }
  // After finish(): the observed rows, [t, x...] per output, and each row's
  // path error and deviation [m] (empty without a reference), moved out.
  struct Rows {
    std::vector<double> rows;
    std::vector<double> path_error, path_deviation;
  };
  Rows take_rows();

 private:
  struct Csv;   // the text of trajectory.csv, numbers at full precision
  struct Sums;  // what finish() accumulates over the rows
  std::string header() const;
  void write_row(double t, const double* x, Csv& csv, Sums& sums);
  void path_columns(const Eigen::Vector3d& p, Csv& csv, Sums& sums);
  void drive_columns(double t, const double* x, Csv& csv, Sums& sums);
  void ledger_columns(const double* x, bool first, Csv& csv, Sums& sums);
  void summarise(const Sums& sums);
  Plant& plant_;
  const PlantConfig& cfg_;
  int m_, n_;
  bool held_;                    // drive signals depend on a discrete state: taken at each output
  std::vector<double> saved_;    // [t, x...] per output
  std::vector<double> signals_;  // [u, e_a, i] per joint per output (held_ only)
  std::vector<DriveSignals> now_;
  std::vector<double> path_error_, path_deviation_;  // [m] per row (with a reference)
  RunFigures fig_;
};

// The unit of a state component, from its name (q1 rad, qd1 rad/s, ...);
// with the robot, a prismatic joint's q and qd in m and m/s (its PIV
// integral stays motor-side, rad s).
std::string unit_of_state(const std::string& name, const RobotModel* robot = nullptr);

}  // namespace pumasim
