// The run recorder: what a run of the plant leaves behind, computed apart from
// the command line. Its observe() is the driver's observer: it copies the
// state at each output (and the drive signals, as the run applies them);
// when the copied rows reach a chunk (kChunkValues numbers)
// it formats them as trajectory.csv's rows into its text stream, computes
// their figures (path error and deviation, drive peaks and saturation, the
// energy ledger's residual) and lets them go. So its memory is bounded by the
// chunk, whatever the run's length (unless the rows are kept for the
// caller), and the time the run's thread spends on the output is counted
// apart (output_seconds) so that the run's wall time stays the simulation's.
// With text and without keep_rows (the command line's trajectory.csv), the
// formatting runs on a thread of its own while the run goes on: the run
// hands over chunks of kWriterChunkValues numbers, at most kWriterChunks at
// a time (it waits for a free one beyond that: the memory stays bounded),
// and that one thread formats them in order, so the text and the figures
// are the same as formatted on the run's thread. output_seconds then counts
// the run's thread's share alone (the drive signals, the hand-overs and
// their waits): the formatting itself runs beside the run, on a free core
// where there is one (where there is none, it slows the run's thread and
// lands in its wall time). A formatting error is rethrown at the run's next
// hand-over; a stream that goes bad stops the formatting, and the run
// folder's commit reports it. Without a thread to be had, the run's thread
// formats. The figures are read after finish().
#pragma once

#include <cstddef>
#include <memory>
#include <ostream>
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
  std::vector<double> final_state;    // the last output's state x
};

class RunRecorder {
 public:
  // The numbers (times and states) held before a chunk is formatted: 512 KiB.
  static constexpr std::size_t kChunkValues = std::size_t{1} << 16;
  // The writer thread's chunk (32 KiB of numbers, about a hundred rows of a
  // six-joint plant) and the chunks in flight, the one being filled included.
  static constexpr std::size_t kWriterChunkValues = std::size_t{1} << 12;
  static constexpr int kWriterChunks = 4;
  // text: where trajectory.csv's text goes (one header line, one row per
  // output), chunk by chunk; nullptr: no text, the figures only. keep_rows:
  // every row is also kept, for take_rows(), room reserved for expected_rows
  // (the caller bounds their number).
  RunRecorder(Plant& plant, std::ostream* text, bool keep_rows = false, std::size_t expected_rows = 0);
  ~RunRecorder();
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;
  // The driver's observer: the state at an output time.
  void observe(double t, const double* x);
  // Formats the rows left and completes the figures. Call once, after the run.
  void finish();
  const RunFigures& figures() const { return fig_; }
  // [s] of wall-clock time the run's thread spent taking the drive signals,
  // formatting rows and computing their figures (or, with the writer thread,
  // handing chunks over to it and waiting for a free one).
  double output_seconds() const { return output_seconds_; }
  // After finish(), with keep_rows: the observed rows, [t, x...] per output,
  // and each row's path error and deviation [m] (empty without a
  // reference), moved out.
  struct Rows {
    std::vector<double> rows;
    std::vector<double> path_error, path_deviation;
  };
  Rows take_rows();
  // trajectory.csv's header line for this plant, and its number of columns.
  static std::string header(const Plant& plant);
  static int columns(const Plant& plant);

 private:
  struct Csv;   // the text of a chunk of trajectory.csv, numbers at full precision
  struct Sums;  // what the figures accumulate over the rows
  struct Writer;  // the formatting thread and its chunks
  void format_pending();
  void format_rows(const double* saved, std::size_t rows, const double* signals);
  void reserve_chunk(std::vector<double>& saved, std::vector<double>& signals, std::size_t values) const;
  void hand_over(bool last);
  void writer_loop();
  void write_row(double t, const double* x, const double* signals);
  void path_columns(const Eigen::Vector3d& p);
  void drive_columns(const double* signals);
  void ledger_columns(const double* x, bool first);
  void summarise();
  // The run's plant: the drive signals at each output, as applied (they
  // depend on its discrete state then: a held set-point or controller
  // output, the reference's piece).
  Plant& plant_;
  // A twin of it that computes the rows' other columns as the run goes (the
  // flange's pose, the energies: functions of the state alone), so that the
  // run's plant sees no evaluation but the drive signals' between its steps;
  // it shares the run's model (its own context and workspaces only).
  Plant rows_plant_;
  const PlantConfig& cfg_;
  int m_, n_;
  bool drive_;                   // the drive signals are taken at each output
  std::ostream* text_;
  bool keep_rows_;
  std::vector<double> saved_;    // [t, x...] per output (from row `formatted_` on: not yet formatted)
  std::vector<double> signals_;  // [u, e_a, i] per joint per output not yet formatted (with a drive)
  std::size_t formatted_ = 0;    // rows of saved_ already formatted (with keep_rows; else 0)
  std::vector<DriveSignals> now_;
  std::vector<double> path_error_, path_deviation_;  // [m] per row (with a reference, keep_rows)
  std::unique_ptr<Csv> csv_;
  std::unique_ptr<Sums> sums_;
  RunFigures fig_;
  double output_seconds_ = 0;
  std::unique_ptr<Writer> writer_;  // last: its thread starts when everything else is made
};

// The unit of a state component, from its name (q1 rad, qd1 rad/s, ...);
// with the robot, a prismatic joint's q and qd in m and m/s (its PIV
// integral stays motor-side, rad s).
std::string unit_of_state(const std::string& name, const RobotModel* robot = nullptr);

}  // namespace pumasim
