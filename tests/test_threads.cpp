// One const model, many threads (models/plant/plant_model.hpp): f evaluated
// from 8 threads, each with its own context and evaluators on one shared
// PlantModel, is bitwise the serial result; so are whole runs of the
// discrete state (time events, root functions, the friction modes). The
// sanitizer that checks these for data races is ThreadSanitizer (preset
// tsan, which builds this binary alone); the release build runs them too.
// Also here: loading a scene builds no plant and no back-end; and an
// ensemble (simulation/ensemble.hpp) on 1, 2 and 8 threads, each sample's
// result bitwise the serial one; and the run recorder's writer thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "models/dynamics/backend.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"
#include "simulation/ensemble.hpp"
#include "simulation/run.hpp"
#include "simulation/run_recorder.hpp"
#include "simulation/scene_run.hpp"
#include "tests/ensemble_helpers.hpp"

namespace pumasim {
namespace {

const std::string kScenes = PUMASIM_SCENES_DIR;
constexpr int kThreads = 8;

// The shipped scenes that cover the model's kinds: the paper's chain on a
// Cartesian path (tabulated reference, filled lazily by whichever thread
// first asks), the hybrid friction's events, a sampled controller, an
// open-loop input, a joint-space CSV reference, a passive arm.
const std::vector<std::string> kSceneNames = {
    "paper_slow_6dof",  "paper_slow_6dof_hybrid", "sampled_control", "open_loop_voltage",
    "joint_space_csv",  "stanford_passive",       "stick_slip",
};

struct Point {
  double t;
  std::vector<double> x;
};

// Points about the scene's start state, spread over its duration:
// deterministic perturbations scaled by each component's typical magnitude.
std::vector<Point> sample_points(Plant& plant, double duration, int count) {
  std::vector<double> x0(static_cast<std::size_t>(plant.size()));
  plant.initial_state(x0.data());
  std::vector<Point> pts;
  for (int k = 0; k < count; ++k) {
    Point p{duration * (k + 0.5) / count, x0};
    for (int i = 0; i < plant.size(); ++i) {
      p.x[static_cast<std::size_t>(i)] += 1e-2 * plant.tolerance_scale(i) * std::sin(1.7 * k + 0.3 * i);
    }
    pts.push_back(std::move(p));
  }
  return pts;
}

std::vector<double> evaluate_all(Plant& plant, const std::vector<Point>& pts, int rotate) {
  const int m = plant.size(), count = static_cast<int>(pts.size());
  std::vector<double> out(static_cast<std::size_t>(m) * count);
  std::vector<double> x0(static_cast<std::size_t>(m));
  plant.initial_state(x0.data());
  for (int s = 0; s < count; ++s) {  // each thread in its own order
    const int k = (s + rotate) % count;
    plant.rhs(pts[k].t, pts[k].x.data(), out.data() + static_cast<std::ptrdiff_t>(k) * m);
  }
  return out;
}

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(ConstModel, FFromEightThreadsIsBitwiseTheSerialResult) {
  for (const std::string& name : kSceneNames) {
    const Scene sc = load_scene(kScenes + "/" + name + ".toml");
    Plant serial(sc.plant);
    const std::vector<Point> pts = sample_points(serial, sc.duration, 64);
    const std::vector<double> expected = evaluate_all(serial, pts, 0);
    // A fresh model, so that its reference table is filled by the threads.
    const auto shared = std::make_shared<const PlantModel>(sc.plant);
    std::vector<std::vector<double>> got(kThreads);
    std::vector<std::thread> threads;
    for (int i = 0; i < kThreads; ++i) {
      threads.emplace_back([&, i] {
        Plant mine(shared);
        got[static_cast<std::size_t>(i)] = evaluate_all(mine, pts, 7 * i);
      });
    }
    for (auto& th : threads) th.join();
    for (int i = 0; i < kThreads; ++i) {
      EXPECT_TRUE(bitwise_equal(got[static_cast<std::size_t>(i)], expected)) << name << ", thread " << i;
    }
  }
}

// A run: classical RK4 at a fixed step with the discrete updates between
// steps (time events when one is due, root functions at every step, a mode
// switch where one changed sign). Not an integrator of the library: the same
// sequence of calls in every thread, so that the end state and the mode log
// must agree to the bit.
struct RunEnd {
  std::vector<double> x;
  std::vector<ModeChange> modes;
};

RunEnd run(Plant& p, double t_end, double h) {
  const int m = p.size(), r = p.num_roots();
  std::vector<double> x(static_cast<std::size_t>(m)), k1(x), k2(x), k3(x), k4(x), y(x);
  std::vector<double> g0(static_cast<std::size_t>(r)), g1(g0);
  p.initial_state(x.data());
  double t = 0, next = p.next_time_event(0.0);
  if (r > 0) p.roots(t, x.data(), g0.data());
  const auto stage = [&](double ts, const std::vector<double>& base, const std::vector<double>& k, double a,
                         std::vector<double>& out) {
    for (int i = 0; i < m; ++i) y[i] = base[i] + a * k[i];
    p.rhs(ts, y.data(), out.data());
  };
  while (t < t_end) {
    p.rhs(t, x.data(), k1.data());
    stage(t + h / 2, x, k1, h / 2, k2);
    stage(t + h / 2, x, k2, h / 2, k3);
    stage(t + h, x, k3, h, k4);
    for (int i = 0; i < m; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    t += h;
    if (t >= next) {
      p.on_time_event(t, x.data());
      next = p.next_time_event(t);
    }
    if (r == 0) continue;
    p.roots(t, x.data(), g1.data());
    for (int j = 0; j < r; ++j) {
      if ((g0[j] > 0) != (g1[j] > 0)) p.on_root(j, t, x.data());
    }
    p.roots(t, x.data(), g0.data());
  }
  return {x, p.mode_changes()};
}

bool same_modes(const std::vector<ModeChange>& a, const std::vector<ModeChange>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (std::memcmp(&a[k].t, &b[k].t, sizeof(double)) != 0 || a[k].joint != b[k].joint || a[k].mode != b[k].mode ||
        std::memcmp(&a[k].applied, &b[k].applied, sizeof(double)) != 0) {
      return false;
    }
  }
  return true;
}

TEST(ConstModel, RunsFromEightThreadsOnOneModelAreBitwiseTheSerialRun) {
  for (const std::string name : {"paper_slow_6dof_hybrid", "sampled_control", "stick_slip"}) {
    const Scene sc = load_scene(kScenes + "/" + name + ".toml");
    const double t_end = std::min(sc.duration, 0.01), h = 2.5e-5;  // 400 steps: seconds under TSan at -O0
    Plant serial(sc.plant);
    const RunEnd expected = run(serial, t_end, h);
    const auto shared = std::make_shared<const PlantModel>(sc.plant);
    std::vector<RunEnd> got(kThreads);
    std::vector<std::thread> threads;
    for (int i = 0; i < kThreads; ++i) {
      threads.emplace_back([&, i] {
        Plant mine(shared);
        got[static_cast<std::size_t>(i)] = run(mine, t_end, h);
      });
    }
    for (auto& th : threads) th.join();
    for (int i = 0; i < kThreads; ++i) {
      const RunEnd& g = got[static_cast<std::size_t>(i)];
      EXPECT_TRUE(bitwise_equal(g.x, expected.x)) << name << ", thread " << i;
      EXPECT_TRUE(same_modes(g.modes, expected.modes)) << name << ", thread " << i;
    }
    if (std::string(name) != "sampled_control") {
      EXPECT_GE(expected.modes.size(), 1u) << name << ": the run exercised the mode log";
    }
  }
}

// Loading a scene validates the plant without building one: no back-end is
// made (the counter counts every registry make and make_dual). A plant then
// builds its double evaluator's back-end, and the Jacobian its own.
TEST(ConstModel, LoadingASceneBuildsNoBackend) {
  for (const std::string& name : kSceneNames) {
    const long before = backends_built();
    const Scene sc = load_scene(kScenes + "/" + name + ".toml");
    EXPECT_EQ(backends_built(), before) << name;
    const long model_start = backends_built();
    const auto model = std::make_shared<const PlantModel>(sc.plant);
    // A passive arm's speed bound needs H at its start pose: one back-end.
    const long expected_model = sc.plant.controller == ControllerMode::kNone ? 1 : 0;
    EXPECT_EQ(backends_built() - model_start, expected_model) << name;
    const long plant_start = backends_built();
    Plant plant(model);
    EXPECT_EQ(backends_built() - plant_start, 1) << name << ": the double evaluator";
    std::vector<double> x(static_cast<std::size_t>(plant.size()));
    plant.initial_state(x.data());
    Eigen::MatrixXd J;
    plant.jacobian_exact(0.0, x.data(), J);
    EXPECT_EQ(backends_built() - plant_start, 2) << name << ": and the exact Jacobian's, at its first use";
  }
}

// Two parameter sets on one reference share its table (the immutable part),
// and each model's f is its own parameters'.
TEST(ConstModel, AParameterSetMakesItsOwnModelSharingTheReferenceTable) {
  const Scene sc = load_scene(kScenes + "/paper_slow_6dof.toml");
  const auto base = std::make_shared<const PlantModel>(sc.plant);
  PlantConfig heavier = sc.plant;
  heavier.robot.joints[1].mass *= 1.5;
  const auto varied = std::make_shared<const PlantModel>(heavier, *base);
  ASSERT_NE(base->reference_table(), nullptr);
  EXPECT_EQ(varied->reference_table(), base->reference_table());
  Plant a(base), b(varied), c(heavier);
  EXPECT_NE(c.model().reference_table(), base->reference_table()) << "a model of its own makes its own";
  std::vector<double> x(static_cast<std::size_t>(a.size())), fa(x), fb(x), fc(x);
  a.initial_state(x.data());
  // Moving (out of any law's stick band), so that the link's mass shows in qdd.
  for (int j = 0; j < a.layout().n; ++j) x[static_cast<std::size_t>(a.layout().qd + j)] = 0.5;
  a.rhs(0.3, x.data(), fa.data());
  b.rhs(0.3, x.data(), fb.data());
  c.rhs(0.3, x.data(), fc.data());
  EXPECT_FALSE(bitwise_equal(fa, fb)) << "the heavier link changes f";
  EXPECT_TRUE(bitwise_equal(fb, fc)) << "a shared table gives the values of the model's own";
}

// The same ensemble on 1, 2 and 8 threads: every sample's result is the
// serial one, bit for bit (all but the wall-clock times), in the samples'
// order; under ThreadSanitizer, with no data race between the runs.
TEST(Ensemble, OneTwoAndEightThreadsGiveTheSerialResultsBitForBit) {
  const EnsembleSpec s = testing::small_ensemble(kScenes, 8);
  const std::vector<EnsembleSample> samples = draw_samples(s);
  const std::vector<SampleResult> serial = run_ensemble(s, samples, 1);
  ASSERT_EQ(serial.size(), samples.size());
  for (const SampleResult& r : serial) ASSERT_TRUE(r.ok) << r.failure;
  for (int threads : {2, 8}) {
    const std::vector<SampleResult> par = run_ensemble(s, samples, threads);
    ASSERT_EQ(par.size(), serial.size());
    for (std::size_t k = 0; k < par.size(); ++k) {
      testing::expect_same_result(par[k], serial[k], std::to_string(threads) + " threads");
    }
  }
}

// The run recorder's writer thread (simulation/run_recorder.hpp): with
// trajectory text and no rows kept, the rows are formatted on a thread of
// their own, chunk by chunk, while the run goes on; with the rows kept, on
// the run's thread. The same code runs on the same rows in the same order, so
// the text must be byte for byte the same and so must every figure -- here
// over many more chunks than can be in flight, so that the run also waits
// for a spare one.
TEST(RunRecorder, TheWriterThreadWritesWhatTheRunsThreadWrites) {
  const double t_end = 0.01, interval = 2e-6;
  const RunPlan plan =
      plan_run(load_scene(kScenes + "/paper_slow_6dof_hybrid.toml"), {.t_end = t_end, .output_interval = interval});
  std::ostringstream on_writer, on_run;
  const SceneRun a = simulate_scene(plan.scene, plan.controls, {.trajectory = &on_writer});
  const SceneRun b = simulate_scene(plan.scene, plan.controls, {.keep_rows = true, .trajectory = &on_run});
  ASSERT_TRUE(a.result.ok) << a.result.failure;
  ASSERT_TRUE(b.result.ok) << b.result.failure;
  EXPECT_EQ(a.figures.rows, std::lround(t_end / interval) + 1);  // an output at 0 and at every interval
  const std::size_t values = static_cast<std::size_t>(a.figures.rows) * (a.state_names.size() + 1);
  EXPECT_GT(values, 4 * RunRecorder::kWriterChunks * RunRecorder::kWriterChunkValues);
  EXPECT_TRUE(on_writer.str() == on_run.str()) << "the texts differ";
  EXPECT_EQ(a.figures.rows, b.figures.rows);
  const auto same = [](const std::vector<double>& u, const std::vector<double>& v) { return bitwise_equal(u, v); };
  EXPECT_TRUE(same({a.figures.max_path_error, a.figures.rms_path_error, a.figures.max_path_deviation,
                    a.figures.rms_path_deviation, a.figures.max_ledger_residual, a.figures.ledger_energy_scale},
                   {b.figures.max_path_error, b.figures.rms_path_error, b.figures.max_path_deviation,
                    b.figures.rms_path_deviation, b.figures.max_ledger_residual, b.figures.ledger_energy_scale}));
  EXPECT_TRUE(same(a.figures.peak_u, b.figures.peak_u) && same(a.figures.peak_ea, b.figures.peak_ea) &&
              same(a.figures.peak_i, b.figures.peak_i) &&
              same(a.figures.saturated_fraction, b.figures.saturated_fraction));
  EXPECT_TRUE(same(a.figures.final_state, b.figures.final_state));
}

// A stream that takes its time (2 ms a write, a chunk's text each, so that the run waits
// for spare chunks), or that fails after `fail_after` bytes: by throwing,
// or by returning short (the stream's badbit, as a full disk does).
class SlowBuffer final : public std::stringbuf {
 public:
  enum class Fail { kNever, kThrow, kShort };
  SlowBuffer(Fail fail = Fail::kNever, std::size_t fail_after = 0) : fail_(fail), fail_after_(fail_after) {}

 protected:
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    written_ += static_cast<std::size_t>(n);
    if (fail_ != Fail::kNever && written_ > fail_after_) {
      if (fail_ == Fail::kThrow) throw std::runtime_error("the test's stream failed");
      return 0;
    }
    return std::stringbuf::xsputn(s, n);
  }

 private:
  Fail fail_;
  std::size_t fail_after_, written_ = 0;
};

// Around the chunk's size: one row short of a chunk, exactly one, one more,
// and an exact multiple (the last hand-over empty); on a plant with an energy
// ledger and no drive (the writer thread then computes the ledger's
// residuals), through a slow stream.
TEST(RunRecorder, TheWriterThreadAgreesAtTheChunksEdgesThroughASlowStream) {
  const std::string scene = kScenes + "/planar2_passive.toml";
  const int m = Plant(load_scene(scene).plant).size();
  const long chunk_rows = static_cast<long>((RunRecorder::kWriterChunkValues + static_cast<std::size_t>(m)) / (m + 1));
  for (const long rows : {chunk_rows - 1, chunk_rows, chunk_rows + 1, 5 * chunk_rows}) {
    const double interval = 1e-4;
    const RunPlan plan = plan_run(load_scene(scene), {.t_end = (rows - 1) * interval, .output_interval = interval});
    SlowBuffer slow;
    std::ostream on_writer(&slow);
    std::ostringstream on_run;
    const SceneRun a = simulate_scene(plan.scene, plan.controls, {.trajectory = &on_writer});
    const SceneRun b = simulate_scene(plan.scene, plan.controls, {.keep_rows = true, .trajectory = &on_run});
    ASSERT_TRUE(a.result.ok && b.result.ok) << a.result.failure << b.result.failure;
    EXPECT_EQ(a.figures.rows, rows);
    EXPECT_TRUE(slow.str() == on_run.str()) << rows << " rows: the texts differ";
    EXPECT_TRUE(bitwise_equal({a.figures.max_ledger_residual, a.figures.ledger_energy_scale},
                              {b.figures.max_ledger_residual, b.figures.ledger_energy_scale}))
        << rows << " rows";
  }
}

// A formatting error on the writer thread ends the run with it (rethrown at
// the run's next hand-over, not only at the end); a stream that goes bad
// stops the formatting and the run still ends, the stream's state telling.
TEST(RunRecorder, TheWriterThreadsFailuresEndTheRunOrReachTheStream) {
  const double t_end = 0.01, interval = 2e-6;
  const RunPlan plan =
      plan_run(load_scene(kScenes + "/paper_slow_6dof_hybrid.toml"), {.t_end = t_end, .output_interval = interval});
  SlowBuffer throwing(SlowBuffer::Fail::kThrow, 100000);
  std::ostream thrown(&throwing);
  thrown.exceptions(std::ios::badbit);
  EXPECT_THROW(simulate_scene(plan.scene, plan.controls, {.trajectory = &thrown}), std::runtime_error);
  SlowBuffer shorted(SlowBuffer::Fail::kShort, 100000);
  std::ostream bad(&shorted);
  const SceneRun r = simulate_scene(plan.scene, plan.controls, {.trajectory = &bad});
  EXPECT_TRUE(r.result.ok) << r.result.failure;
  EXPECT_TRUE(bad.bad());
}

}  // namespace
}  // namespace pumasim
