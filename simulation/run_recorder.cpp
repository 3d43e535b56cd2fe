#include "simulation/run_recorder.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <sstream>
#include <system_error>
#include <thread>

#include <Eigen/Geometry>

namespace pumasim {

namespace {
// Joint k (1-based) from a state name "<prefix>k", if the robot has it and it is prismatic.
bool prismatic_state(const std::string& state, std::size_t prefix, const RobotModel* robot) {
  if (robot == nullptr || state.size() <= prefix) return false;
  const std::string digits = state.substr(prefix);
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  const int k = std::stoi(digits);
  return k >= 1 && k <= robot->dof() && robot->joints[static_cast<std::size_t>(k - 1)].prismatic();
}
}  // namespace

std::string unit_of_state(const std::string& state, const RobotModel* robot) {
  if (state.rfind("qd", 0) == 0) return prismatic_state(state, 2, robot) ? "m/s" : "rad/s";
  if (state.rfind("q", 0) == 0) return prismatic_state(state, 1, robot) ? "m" : "rad";
  if (state.rfind("i_motor", 0) == 0) return "A";
  if (state.rfind("z_piv", 0) == 0) return "rad s";
  if (state.rfind("z_fric", 0) == 0) return "rad";
  if (state.rfind("e_", 0) == 0) return "J";
  return "-";
}

// Each number as the shortest text that reads back to the same double
// (std::to_chars without a precision: Ryu-style, no locale), so a reader gets
// every bit of the run; %.17g gave the same doubles in up to 24 characters and
// was a third of a short run's process time (perf, the 6-joint hybrid scene).
struct RunRecorder::Csv {
  std::string text;  // the chunk's rows
  bool on = false;   // text is wanted
  char buf[32];      // the longest shortest form of a double is 24 characters
  void put(double v) {
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v);
    text.append(buf, static_cast<std::size_t>(r.ptr - buf));
  }
  void first(double v) {
    if (on) put(v);
  }
  void num(double v) {
    if (on) text.push_back(','), put(v);
  }
};

struct RunRecorder::Sums {
  double sum_sq = 0, sum_sq_dev = 0;  // [m^2] path error and deviation, squared
  double E0 = 0;                      // [J] E_mech + E_mag at the first row
  std::vector<long> saturated;        // per joint: rows at a limit
  ReferenceSample ref;                // the reference at the row's time
  int nearest_piece = 0;              // the path's piece nearest the last row's flange (deviation's hint)
};

struct RunRecorder::Writer {
  struct Chunk {
    std::vector<double> saved, signals;  // rows [t, x...] and their drive signals, as the run filled them
  };
  std::mutex lock;
  std::condition_variable wake;  // the thread: a chunk or the end; the run: a spare chunk
  std::deque<Chunk> full;        // handed over, in the run's order
  std::vector<Chunk> spare;      // free (all but the run's at the start), their capacity kept
  bool done = false;             // no chunk will follow
  std::exception_ptr error;      // the first the formatting threw (the run rethrows it at its next hand-over)
  bool stream_failed = false;    // the stream went bad (a full disk): the rest is only recycled, the folder's
                                 // commit reports it
  std::thread thread;
};

RunRecorder::RunRecorder(Plant& plant, std::ostream* text, bool keep_rows, std::size_t expected_rows)
    : plant_(plant),
      rows_plant_(plant.shared_model()),
      cfg_(plant.config()),
      m_(plant.size()),
      n_(plant.layout().n),
      drive_(plant.config().drive),
      text_(text),
      keep_rows_(keep_rows),
      now_(static_cast<std::size_t>(plant.layout().n)),
      csv_(std::make_unique<Csv>()),
      sums_(std::make_unique<Sums>()) {
  const bool threaded = text != nullptr && !keep_rows;
  if (keep_rows) saved_.reserve((expected_rows + 1) * static_cast<std::size_t>(m_ + 1));
  reserve_chunk(saved_, signals_, threaded ? kWriterChunkValues : kChunkValues);
  if (keep_rows && cfg_.reference) path_error_.reserve(expected_rows + 1), path_deviation_.reserve(expected_rows + 1);
  csv_->on = text_ != nullptr;
  if (text_) *text_ << header(plant_);
  fig_.ledger = plant_.layout().e >= 0;
  fig_.peak_u.assign(n_, 0.0), fig_.peak_ea.assign(n_, 0.0), fig_.peak_i.assign(n_, 0.0);
  sums_->saturated.assign(n_, 0);
  if (threaded) {
    writer_ = std::make_unique<Writer>();
    writer_->spare.reserve(kWriterChunks);  // all come back at the end: no allocation on the writer's thread
    writer_->spare.resize(kWriterChunks - 1);
    for (Writer::Chunk& c : writer_->spare) reserve_chunk(c.saved, c.signals, kWriterChunkValues);
    try {
      writer_->thread = std::thread([this] { writer_loop(); });
    } catch (const std::system_error&) {  // no thread to be had (a process limit): the run's thread formats
      writer_.reset();
      reserve_chunk(saved_, signals_, kChunkValues);
    }
  }
}

RunRecorder::~RunRecorder() {
  if (!writer_ || !writer_->thread.joinable()) return;
  {  // left without finish() (the run threw): the rows not formatted are dropped
    const std::lock_guard<std::mutex> g(writer_->lock);
    writer_->full.clear();
    writer_->done = true;
  }
  writer_->wake.notify_all();
  writer_->thread.join();
}

void RunRecorder::observe(double t, const double* x) {
  saved_.push_back(t);
  saved_.insert(saved_.end(), x, x + m_);
  fig_.final_state.assign(x, x + m_);  // its size once, then no allocation
  if (drive_) {  // as the run applies them: its discrete state (set-point, held output, reference piece) is now
    const auto start = std::chrono::steady_clock::now();
    plant_.drive_signals(t, x, now_.data());
    for (const DriveSignals& d : now_) signals_.insert(signals_.end(), {d.u, d.ea, d.i});
    output_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  const std::size_t width = static_cast<std::size_t>(m_ + 1);
  if (writer_) {
    if (saved_.size() >= kWriterChunkValues) hand_over(false);
  } else if (saved_.size() - formatted_ * width >= kChunkValues) {
    format_pending();
  }
}

// Room for a chunk of `values` numbers of rows and their drive signals.
void RunRecorder::reserve_chunk(std::vector<double>& saved, std::vector<double>& signals, std::size_t values) const {
  const std::size_t width = static_cast<std::size_t>(m_ + 1);
  saved.reserve(values + width);
  if (drive_) signals.reserve((values / width + 1) * 3 * static_cast<std::size_t>(n_));
}

// The run's rows so far to the writer thread; unless they are the last, a
// spare chunk becomes the run's (waiting for one while all are in flight).
void RunRecorder::hand_over(bool last) {
  const auto start = std::chrono::steady_clock::now();
  Writer& w = *writer_;
  Writer::Chunk next;
  {
    std::unique_lock<std::mutex> g(w.lock);
    if (w.error) std::rethrow_exception(w.error);  // the formatting failed: the run stops here (the destructor joins)
    if (!last) {
      w.wake.wait(g, [&w] { return !w.spare.empty(); });
      next = std::move(w.spare.back());
      w.spare.pop_back();
    }
    w.full.push_back({std::move(saved_), std::move(signals_)});
    if (last) w.done = true;
  }
  w.wake.notify_all();
  saved_ = std::move(next.saved), signals_ = std::move(next.signals);
  output_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The writer thread: formats the chunks in the order handed over, until the last.
void RunRecorder::writer_loop() {
  Writer& w = *writer_;
  const std::size_t width = static_cast<std::size_t>(m_ + 1);
  for (;;) {
    Writer::Chunk c;
    bool skip = false;
    {
      std::unique_lock<std::mutex> g(w.lock);
      w.wake.wait(g, [&w] { return !w.full.empty() || w.done; });
      if (w.full.empty()) return;
      c = std::move(w.full.front());
      w.full.pop_front();
      skip = w.error || w.stream_failed;
    }
    std::exception_ptr failed;
    bool bad = false;
    if (!skip) {
      try {
        format_rows(c.saved.data(), c.saved.size() / width, c.signals.data());
        bad = text_ && !*text_;
      } catch (...) {
        failed = std::current_exception();
      }
    }
    c.saved.clear(), c.signals.clear();
    {
      const std::lock_guard<std::mutex> g(w.lock);
      if (failed && !w.error) w.error = failed;
      w.stream_failed = w.stream_failed || bad;
      w.spare.push_back(std::move(c));
    }
    w.wake.notify_all();
  }
}

std::string RunRecorder::header(const Plant& plant) {
  const PlantConfig& cfg = plant.config();
  const int n = plant.layout().n;
  std::ostringstream csv;
  csv << "t [s]";
  for (const auto& name : plant.layout().names) {
    csv << "," << name << " [" << unit_of_state(name, &cfg.robot) << "]";
  }
  if (cfg.reference) {
    for (int j = 0; j < n; ++j) csv << ",q_ref" << j + 1 << " [" << unit_of_state("q" + std::to_string(j + 1), &cfg.robot) << "]";
  }
  csv << ",x [m],y [m],z [m],tool_qw [-],tool_qx [-],tool_qy [-],tool_qz [-]";  // flange frame: position, unit quaternion
  if (cfg.reference) csv << ",x_ref [m],y_ref [m],z_ref [m],path_error [mm],path_deviation [mm]";
  if (cfg.drive) {
    for (int j = 0; j < n; ++j) csv << ",u" << j + 1 << " [V],e_a" << j + 1 << " [V]";
  }
  if (plant.layout().e >= 0) csv << ",E_mech [J],E_mag [J],ledger_residual [J]";
  csv << "\n";
  return csv.str();
}

int RunRecorder::columns(const Plant& plant) {
  const std::string h = header(plant);
  return static_cast<int>(std::count(h.begin(), h.end(), ',')) + 1;
}

// The rows not yet formatted, on the run's thread: their text to the stream,
// their figures, then (without keep_rows) they are let go.
void RunRecorder::format_pending() {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t width = static_cast<std::size_t>(m_ + 1);
  const std::size_t rows = saved_.size() / width;
  format_rows(saved_.data() + formatted_ * width, rows - formatted_, signals_.data());
  signals_.clear();
  if (keep_rows_) {
    formatted_ = rows;
  } else {
    saved_.clear();
  }
  output_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Rows [t, x...] and their drive signals (3 n per row, with a drive): their
// text to the stream and their figures.
void RunRecorder::format_rows(const double* saved, std::size_t rows, const double* signals) {
  const std::size_t width = static_cast<std::size_t>(m_ + 1), per_row = 3 * static_cast<std::size_t>(n_);
  csv_->text.clear();
  for (std::size_t row = 0; row < rows; ++row) {
    ++fig_.rows;
    write_row(saved[row * width], &saved[row * width + 1], drive_ ? signals + per_row * row : nullptr);
    if (csv_->on) csv_->text += '\n';
  }
  if (text_) text_->write(csv_->text.data(), static_cast<std::streamsize>(csv_->text.size()));
}

void RunRecorder::finish() {
  if (writer_) {
    hand_over(true);
    writer_->thread.join();
    if (writer_->error) std::rethrow_exception(writer_->error);  // joined: no other thread reads it
  } else {
    format_pending();
  }
  csv_->text = std::string();  // its memory back
  summarise();
  if (text_) text_->flush();
}

RunRecorder::Rows RunRecorder::take_rows() {
  Rows r{std::move(saved_), std::move(path_error_), std::move(path_deviation_)};
  saved_.clear(), path_error_.clear(), path_deviation_.clear();
  formatted_ = 0;
  return r;
}

// One row: time and state, the reference, the flange's pose, then the path,
// drive and ledger columns where the plant has them.
void RunRecorder::write_row(double t, const double* x, const double* signals) {
  Csv& csv = *csv_;
  csv.first(t);
  for (int i = 0; i < m_; ++i) csv.num(x[i]);
  Eigen::Matrix3d R_tool;
  Eigen::Vector3d p;
  rows_plant_.tool_pose(x, R_tool, p);
  if (cfg_.reference) {
    const double t_ref = std::min(t, cfg_.reference->timing().duration());
    if (csv.on) {  // q_ref's columns: the full evaluation
      cfg_.reference->eval(t_ref, sums_->ref);
      for (int j = 0; j < n_; ++j) csv.num(sums_->ref.q[j]);
    } else {  // the figures need only the point
      sums_->ref.p = cfg_.reference->point(t_ref, sums_->ref);
    }
  }
  csv.num(p.x()), csv.num(p.y()), csv.num(p.z());
  Eigen::Quaterniond quat(R_tool);
  if (quat.w() < 0) quat.coeffs() *= -1;  // one sign for one orientation
  csv.num(quat.w()), csv.num(quat.x()), csv.num(quat.y()), csv.num(quat.z());
  if (cfg_.reference) path_columns(p);
  if (cfg_.drive) drive_columns(signals);
  if (plant_.layout().e >= 0) ledger_columns(x, fig_.rows == 1);
}

void RunRecorder::path_columns(const Eigen::Vector3d& p) {
  Csv& csv = *csv_;
  Sums& sums = *sums_;
  const ReferenceSample& ref = sums.ref;
  const double e = (p - ref.p).norm();
  // Deviation: the distance to the geometric path, whatever the timing
  // (a joint-space interpolation leaves the path between via-points).
  const double dev = cfg_.reference->deviation(p, &sums.nearest_piece);
  csv.num(ref.p.x()), csv.num(ref.p.y()), csv.num(ref.p.z()), csv.num(1e3 * e), csv.num(1e3 * dev);
  if (keep_rows_) path_error_.push_back(e), path_deviation_.push_back(dev);
  fig_.max_path_error = std::max(fig_.max_path_error, e);
  sums.sum_sq += e * e;
  fig_.max_path_deviation = std::max(fig_.max_path_deviation, dev);
  sums.sum_sq_dev += dev * dev;
  ++fig_.samples;
}

void RunRecorder::drive_columns(const double* signals) {
  Csv& csv = *csv_;
  for (int j = 0; j < n_; ++j) {
    const DriveSignals d{signals[3 * j], signals[3 * j + 1], signals[3 * j + 2]};
    csv.num(d.u), csv.num(d.ea);
    fig_.peak_u[j] = std::max(fig_.peak_u[j], std::abs(d.u));
    fig_.peak_ea[j] = std::max(fig_.peak_ea[j], std::abs(d.ea));
    fig_.peak_i[j] = std::max(fig_.peak_i[j], std::abs(d.i));
    const double u_lim = controller_output_limit(cfg_.controller_params, j), v_lim = cfg_.amplifier[j].voltage_limit;
    if (std::abs(d.u) >= u_lim * (1 - 1e-12) || std::abs(cfg_.amplifier[j].gain * d.u) >= v_lim * (1 - 1e-12)) {
      ++sums_->saturated[j];
    }
  }
}

// (E_mech + E_mag)(t) - (E_mech + E_mag)(0) - (e_in - e_copper - e_friction)
void RunRecorder::ledger_columns(const double* x, bool first) {
  Csv& csv = *csv_;
  Sums& sums = *sums_;
  const int led = plant_.layout().e;
  double kin = 0;
  const double Em = rows_plant_.mechanical_energy(x, &kin), Eg = rows_plant_.magnetic_energy(x);
  if (first) sums.E0 = Em + Eg;
  const double res = (Em + Eg - sums.E0) - (x[led] - x[led + 1] - x[led + 2]);
  csv.num(Em), csv.num(Eg), csv.num(res);
  fig_.max_ledger_residual = std::max(fig_.max_ledger_residual, std::abs(res));
  fig_.ledger_energy_scale = std::max({fig_.ledger_energy_scale, kin, Eg, std::abs(Em + Eg - sums.E0),
                                       std::abs(x[led]), std::abs(x[led + 1]), std::abs(x[led + 2])});
}

void RunRecorder::summarise() {
  const Sums& sums = *sums_;
  if (fig_.samples) {
    fig_.rms_path_error = std::sqrt(sums.sum_sq / fig_.samples);
    fig_.rms_path_deviation = std::sqrt(sums.sum_sq_dev / fig_.samples);
  }
  fig_.saturated_fraction.assign(n_, 0.0);
  for (int j = 0; j < n_; ++j) {
    if (fig_.rows) fig_.saturated_fraction[j] = static_cast<double>(sums.saturated[j]) / fig_.rows;
  }
}

}  // namespace pumasim
