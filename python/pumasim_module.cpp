// The Python module `pumasim` (pybind11): the dynamics back-ends, a scene's
// plant as f(t, x) and its Jacobian for any ODE solver (scipy's solve_ivp),
// and `pumasim run` with its statistics, numpy arrays in and out. Thin: every
// computation and every check is a library call that the command line makes
// too (models/robot/dynamics_query, experiments/simulation/run_request), and
// bad input raises ValueError with the message the command line prints after
// "pumasim: ".
#include <atomic>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "experiments/simulation/driver.hpp"
#include "experiments/simulation/run_folder.hpp"
#include "experiments/simulation/run_request.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/dynamics_query.hpp"
#include "models/scene/scene.hpp"

namespace py = pybind11;

namespace pumasim {
namespace {

// ---------------------------------------------------------------- arguments

// A path given as str or os.PathLike.
std::string path_arg(const py::handle& p) { return py::module_::import("os").attr("fspath")(p).cast<std::string>(); }

// A 1-D array of numbers (list, tuple, numpy array), as float64.
Eigen::VectorXd vector_arg(const py::handle& v, const std::string& what) {
  py::object a;
  try {
    a = py::module_::import("numpy").attr("asarray")(v, py::arg("dtype") = "float64");
  } catch (py::error_already_set& e) {
    throw std::invalid_argument(what + ": expected an array of numbers (" + std::string(py::str(e.value())) + ")");
  }
  const int ndim = a.attr("ndim").cast<int>();
  if (ndim != 1) {
    throw std::invalid_argument(what + ": expected a 1-D array of numbers, got an array of shape " +
                                std::string(py::str(a.attr("shape"))));
  }
  return a.cast<Eigen::VectorXd>();
}

// A Python value as a TOML value, for a scene override ("section.key=value",
// as the command line's --set): bool, int, float (inf and nan as TOML
// spells them), str, a dict (inline table) or a sequence (array) of these.
std::string toml_literal(const py::handle& v, const std::string& key) {
  const py::module_ np = py::module_::import("numpy");
  if (py::isinstance<py::bool_>(v) || py::isinstance(v, np.attr("bool_"))) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(v)) {
    std::string out = "\"";
    for (const char c : v.cast<std::string>()) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '"' || c == '\\') {
        out += '\\', out += c;
      } else if (u < 0x20 || u == 0x7f) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\u%04x", u);
        out += buf;
      } else {
        out += c;
      }
    }
    return out + "\"";
  }
  if (py::hasattr(v, "__index__")) return std::string(py::str(py::int_(py::reinterpret_borrow<py::object>(v))));
  if (py::isinstance<py::float_>(v) || py::hasattr(v, "__float__")) {
    const double x = v.cast<double>();
    if (std::isnan(x)) return "nan";
    if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
    char buf[32];
    std::string s(buf, std::to_chars(buf, buf + sizeof buf, x).ptr);  // the shortest text that reads back as x
    if (s.find_first_of(".e") == std::string::npos) s += ".0";       // a float, not an integer
    return s;
  }
  if (py::isinstance<py::dict>(v)) {
    std::string out = "{";
    for (const auto& kv : v.cast<py::dict>()) {
      out += (out.size() > 1 ? ", " : "") + std::string(py::str(kv.first)) + " = " + toml_literal(kv.second, key);
    }
    return out + "}";
  }
  if (py::isinstance<py::iterable>(v) && !py::isinstance<py::bytes>(v)) {
    std::string out = "[";
    for (const py::handle item : v) out += (out.size() > 1 ? ", " : "") + toml_literal(item, key);
    return out + "]";
  }
  throw std::invalid_argument("--set " + key + ": expected a bool, a number, a string, a dict or a list of these, "
                              "got a " + std::string(py::str(py::type::of(v).attr("__name__"))));
}

// Scene overrides: a dict {"section.key": value} or a list of the command
// line's "section.key=value" strings (TOML values).
std::vector<std::string> override_args(const py::handle& overrides) {
  std::vector<std::string> sets;
  if (overrides.is_none()) return sets;
  if (py::isinstance<py::dict>(overrides)) {
    for (const auto& kv : overrides.cast<py::dict>()) {
      const std::string key = py::str(kv.first);
      sets.push_back(key + "=" + toml_literal(kv.second, key));
    }
    return sets;
  }
  if (py::isinstance<py::str>(overrides)) {
    throw std::invalid_argument("overrides: expected a dict {\"section.key\": value} or a list of "
                                "\"section.key=value\" strings, got a str");
  }
  for (const py::handle item : overrides) sets.push_back(item.cast<std::string>());
  return sets;
}

// ---------------------------------------------------------------- dynamics

py::array_t<double> to_numpy(const Eigen::VectorXd& v) { return py::cast(v); }

py::dict dynamics(const py::object& robot, const std::string& backend, const py::object& q_in, const py::object& qd_in,
                  const py::object& qdd_in, const py::object& tau_in, bool rotor_inertia) {
  const RobotDynamics rd = robot_dynamics(path_arg(robot), backend, rotor_inertia);
  const int n = rd.model.dof();
  const Eigen::VectorXd q =
      py::isinstance<py::str>(q_in) ? pose_angles(rd.model, q_in.cast<std::string>(), "q") : vector_arg(q_in, "q");
  const Eigen::VectorXd qd = qd_in.is_none() ? Eigen::VectorXd::Zero(n) : vector_arg(qd_in, "qd");
  std::optional<Eigen::VectorXd> qdd, tau;
  if (!qdd_in.is_none()) qdd = vector_arg(qdd_in, "qdd");
  if (!tau_in.is_none()) tau = vector_arg(tau_in, "tau");
  const DynamicsValues v = evaluate_dynamics(*rd.backend, q, qd, qdd, tau);
  // The keys and their order of `pumasim dynamics`'s JSON object.
  py::dict d;
  d["backend"] = rd.backend->name();
  d["robot"] = rd.model.name;
  d["n"] = n;
  d["rotor_inertia_included"] = rd.rotor_inertia;
  d["q"] = to_numpy(q);
  d["qd"] = to_numpy(qd);
  d["mass_matrix"] = py::cast(v.mass_matrix);
  d["bias"] = to_numpy(v.bias);
  d["gravity"] = to_numpy(v.gravity);
  if (qdd) {
    d["qdd_in"] = to_numpy(*qdd);
    d["tau"] = to_numpy(*v.tau);
  }
  if (tau) {
    d["tau_in"] = to_numpy(*tau);
    d["qdd"] = to_numpy(*v.qdd);
  }
  return d;
}

// ---------------------------------------------------------------- scenes

// A loaded scene and its plant, at the plant's initial discrete state.
class PyScene {
 public:
  PyScene(const std::string& path, const std::vector<std::string>& overrides, const std::vector<std::string>& unset)
      : scene_(load_checked_scene(path, overrides, unset)),
        discrete_(discrete_state(scene_)),
        plant_(std::make_unique<Plant>(scene_.plant)),
        system_(std::make_unique<PlantSystem>(*plant_)) {
    initial_state();  // the discrete state at t = 0 (a held pose's set-point, ...)
  }

  const Scene& scene() const { return scene_; }
  const Plant& plant() const { return *plant_; }
  const std::string& discrete() const { return discrete_; }

  Eigen::VectorXd initial_state() {
    Eigen::VectorXd x(plant_->size());
    plant_->initial_state(x.data());
    return x;
  }

  Eigen::VectorXd rhs(double t, const py::handle& x_in) {
    const Eigen::VectorXd x = state_arg(x_in);
    warn_discontinuous();
    Eigen::VectorXd f(x.size());
    plant_->rhs(t, x.data(), f.data());
    return f;
  }

  Eigen::MatrixXd jacobian(double t, const py::handle& x_in, bool exact) {
    const Eigen::VectorXd x = state_arg(x_in);
    warn_discontinuous();
    Eigen::MatrixXd J;
    if (exact) {
      plant_->jacobian_exact(t, x.data(), J);
    } else {
      system_->OdeSystem::jacobian(t, x.data(), J);  // the integrators' forward differences
    }
    return J;
  }

  // The times in (0, t_end] where the driver stops because f changes.
  // t_end is checked as pumasim run checks --t-end, and the count is bounded
  // by the default step budget (each event is a stop) before it is listed.
  std::vector<double> time_events(std::optional<double> t_end) const {
    if (t_end && !(std::isfinite(*t_end) && *t_end > 0)) {
      throw std::invalid_argument("t_end: expected a number > 0, got " + std::to_string(*t_end));
    }
    const double end = t_end.value_or(scene_.duration);
    std::vector<double> times;
    for (double t = plant_->next_time_event(0.0); t <= end; t = plant_->next_time_event(t)) {
      if (static_cast<long>(times.size()) >= kDefaultStepBudget) {
        throw std::invalid_argument("t_end: expected at most " + std::to_string(kDefaultStepBudget) +
                                    " time events before it (the default step budget), got more by t = " +
                                    std::to_string(t) + " s");
      }
      times.push_back(t);
    }
    return times;
  }

 private:
  // An ODE solver given rhs meets the friction's jump without a word
  // (scipy's BDF then fails obscurely): a RuntimeWarning, once per scene.
  void warn_discontinuous() {
    if (warned_) return;
    warned_ = true;
    if (const std::string note = discontinuity_note(scene_); !note.empty()) {
      const std::string msg = scene_.file + ": rhs(t, x) is not smooth: " + note +
                              "; a solver of your own meets the same (pumasim.run(scene, integrator=\"ab2\", "
                              "dt=5e-4) integrates it as the paper did)";
      if (PyErr_WarnEx(PyExc_RuntimeWarning, msg.c_str(), 1) != 0) throw py::error_already_set();
    }
  }

  Eigen::VectorXd state_arg(const py::handle& x_in) const {
    if (!discrete_.empty()) {
      throw std::invalid_argument(scene_.file + ": rhs(t, x) and jacobian(t, x) are the continuous right-hand side "
                                  "alone, and this scene has discrete state that changes at events: " + discrete_ +
                                  "; pumasim.run integrates it with its events");
    }
    Eigen::VectorXd x = vector_arg(x_in, "x");
    if (x.size() != plant_->size()) {
      throw std::invalid_argument("x: expected " + std::to_string(plant_->size()) + " values (the scene's state), got " +
                                  std::to_string(x.size()));
    }
    return x;
  }

  Scene scene_;
  std::string discrete_;
  std::unique_ptr<Plant> plant_;
  std::unique_ptr<PlantSystem> system_;
  bool warned_ = false;
};

// ---------------------------------------------------------------- interrupts

// Ctrl-C during pumasim.run. The run releases the GIL, so that other Python
// threads go on; but Python runs its signal handlers only on the main thread
// and with the GIL, so a run used to notice Ctrl-C only when it ended (never,
// with max_wall=0). The simplest design found that reaches every run:
// - The driver reads each run's cancel flag at every clock read (every few
//   ms) and calls the run's poll about every 50 ms (driver.hpp, ProgressHook).
// - g_interrupts counts the process's interrupts. A run notes it when it
//   starts, and its poll sets the run's flag once it has moved (an atomic
//   load: no GIL), so one interrupt stops every run in progress, on any
//   thread.
// - On the main thread the poll also takes the GIL for a moment and calls
//   PyErr_CheckSignals, which runs the Python handlers of the signals
//   received, as Python itself would between two bytecodes. When a handler
//   raises, the run keeps the exception and ends; a KeyboardInterrupt (the
//   default handler's) moves the count, so runs on other threads stop too.
// - When the main thread is in no run (it waits in Thread.join() for the
//   threads that run), nothing of ours runs there: a SIGINT handler of ours,
//   chained before Python's, moves the count itself (an atomic increment,
//   which a signal handler may do) and calls Python's. It is put in place
//   when a run starts, and only while Python's SIGINT handler is
//   signal.default_int_handler (Ctrl-C means KeyboardInterrupt);
//   signal.signal() replaces it, and a later run puts it back only then.
// An interrupted run writes no run folder and raises: on the main thread the
// handler's exception (KeyboardInterrupt) with a note saying where the run
// stopped, on another thread KeyboardInterrupt saying so.
std::atomic<unsigned long> g_interrupts{0};
std::atomic<void (*)(int)> g_python_sigint{nullptr};  // the handler ours calls
static_assert(std::atomic<unsigned long>::is_always_lock_free && std::atomic<void (*)(int)>::is_always_lock_free,
              "used in a signal handler");

void count_sigint(int sig) {
  g_interrupts.fetch_add(1, std::memory_order_relaxed);
  if (void (*next)(int) = g_python_sigint.load(std::memory_order_relaxed)) next(sig);
}

// With the GIL (which also keeps two threads from doing this at once).
void chain_sigint_handler() {
  const py::module_ signal = py::module_::import("signal");
  if (!signal.attr("getsignal")(SIGINT).is(signal.attr("default_int_handler"))) return;
  struct sigaction current {};
  if (sigaction(SIGINT, nullptr, &current) != 0 || (current.sa_flags & SA_SIGINFO) != 0) return;
  if (current.sa_handler == count_sigint || current.sa_handler == SIG_DFL || current.sa_handler == SIG_IGN) return;
  g_python_sigint.store(current.sa_handler);
  struct sigaction mine = current;  // the same flags and mask
  mine.sa_handler = count_sigint;
  sigaction(SIGINT, &mine, nullptr);
}

// One run's side of the above: made and raised with the GIL, polled without.
class RunInterrupts {
 public:
  RunInterrupts()
      : start_(g_interrupts.load()),
        main_(py::module_::import("threading").attr("current_thread")().is(
            py::module_::import("threading").attr("main_thread")())) {
    chain_sigint_handler();
  }
  ~RunInterrupts() {  // an exception kept and not raised (the run failed otherwise)
    Py_XDECREF(type_);
    Py_XDECREF(value_);
    Py_XDECREF(trace_);
  }
  RunInterrupts(const RunInterrupts&) = delete;
  RunInterrupts& operator=(const RunInterrupts&) = delete;

  const std::atomic<bool>* flag() const { return &cancel_; }

  // From the driver's thread, without the GIL.
  void poll() {
    if (g_interrupts.load(std::memory_order_relaxed) != start_) {
      cancel_.store(true, std::memory_order_relaxed);
      return;
    }
    if (!main_) return;
    const PyGILState_STATE gil = PyGILState_Ensure();
    if (PyErr_CheckSignals() != 0) {
      if (PyErr_ExceptionMatches(PyExc_KeyboardInterrupt)) g_interrupts.fetch_add(1);
      PyErr_Fetch(&type_, &value_, &trace_);
      cancel_.store(true, std::memory_order_relaxed);
    }
    PyGILState_Release(gil);
  }

  // With the GIL, after an interrupted run: what interrupted it, saying where.
  [[noreturn]] void raise(const std::string& where) {
    if (type_) {
      PyErr_Restore(type_, value_, trace_);  // the reference passed on
      type_ = value_ = trace_ = nullptr;
    } else if (!(main_ && PyErr_CheckSignals() != 0)) {  // the handler not yet run (the count moved first)
      PyErr_SetString(PyExc_KeyboardInterrupt, where.c_str());
      throw py::error_already_set();
    }
    py::error_already_set e;
    if (py::hasattr(e.value(), "add_note")) e.value().attr("add_note")(where);  // Python 3.11
    throw e;
  }

 private:
  unsigned long start_;
  bool main_;
  std::atomic<bool> cancel_{false};
  PyObject *type_ = nullptr, *value_ = nullptr, *trace_ = nullptr;
};

// ---------------------------------------------------------------- runs

struct PyRun {
  py::object t, x, state_names, stats, path_error_mm, path_deviation_mm, out;
  bool ok = true;
  std::string failure;
};

PyRun run(const py::object& scene_in, const RunRequest& request, const py::object& out, bool force) {
  Scene sc = py::isinstance<PyScene>(scene_in) ? scene_in.cast<const PyScene&>().scene()
                                               : load_checked_scene(path_arg(scene_in), {});
  const RunControls rc = run_controls(sc, request);
  // What `pumasim run` says on stderr before it starts, as Python warnings.
  for (const std::string& w : run_start_warnings(sc, rc)) {
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) != 0) throw py::error_already_set();
  }
  std::optional<std::filesystem::path> dir;
  if (!out.is_none()) dir = path_arg(out);
  CompletedRun done;
  RunInterrupts interrupts;
  ProgressHook hook;
  hook.cancel = interrupts.flag();
  hook.poll = [&interrupts] { interrupts.poll(); };
  {
    py::gil_scoped_release release;
    done = run_scene(sc, rc, dir, force, hook, nullptr, /*keep_rows=*/true);
  }
  const SceneRun& r = done.run;
  if (r.result.failure_kind == "interrupted") interrupts.raise("pumasim.run " + sc.name + ": " + r.result.failure);
  const auto m = static_cast<py::ssize_t>(r.state_names.size());
  const auto rows = static_cast<py::ssize_t>(r.rows.size()) / (m + 1);
  py::array_t<double> t(rows);
  py::array_t<double> x({rows, m});
  auto tt = t.mutable_unchecked<1>();
  auto xx = x.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < rows; ++i) {
    const double* row = r.rows.data() + i * (m + 1);
    tt(i) = row[0];
    for (py::ssize_t k = 0; k < m; ++k) xx(i, k) = row[k + 1];
  }
  const auto in_mm = [](const std::vector<double>& v) {
    py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
    auto aa = a.mutable_unchecked<1>();
    for (std::size_t i = 0; i < v.size(); ++i) aa(static_cast<py::ssize_t>(i)) = 1e3 * v[i];
    return a;
  };
  PyRun res;
  res.t = t;
  res.x = x;
  res.state_names = py::cast(r.state_names);
  res.stats = py::module_::import("json").attr("loads")(done.stats);
  res.path_error_mm = in_mm(r.path_error);
  res.path_deviation_mm = in_mm(r.path_deviation);
  res.out = dir ? py::object(py::str(dir->string())) : py::none();
  res.ok = r.result.ok;
  res.failure = r.result.failure;
  return res;
}

std::vector<std::string> backend_list() {
  std::vector<std::string> names;
  for (const BackendInfo& b : backends()) names.emplace_back(b.name);
  return names;
}

std::vector<std::string> integrator_list() {
  std::vector<std::string> names;
  for (const IntegratorInfo& i : integrators()) names.emplace_back(i.name);
  return names;
}

// The registries and the robot's dynamics.
void bind_dynamics(py::module_& m) {
  m.def("backends", &backend_list, "The dynamics back-ends' names (pumasim backends), sorted.");
  m.def("integrators", &integrator_list, "The integrators' names (pumasim integrators), sorted.");

  m.def("dynamics", &dynamics, py::kw_only(), py::arg("robot") = "puma560", py::arg("backend") = "crba", py::arg("q"),
        py::arg("qd") = py::none(), py::arg("qdd") = py::none(), py::arg("tau") = py::none(),
        py::arg("rotor_inertia") = true,
        "The robot's dynamics at (q, qd), as `pumasim dynamics` prints them: a dict with backend, robot, n,\n"
        "rotor_inertia_included, q, qd, mass_matrix (n x n), bias, gravity; with qdd also qdd_in and tau\n"
        "(inverse dynamics), with tau also tau_in and qdd (forward dynamics). robot: a shipped robot's name\n"
        "(models/robots/<name>.toml, else <name>.urdf) or a path (a robot file, or a URDF file *.urdf); q: n\n"
        "numbers or a pose name of the robot file; qd: default 0.");
}

// Scene: a scene file's plant as f(t, x) and its Jacobian.
void bind_scene(py::module_& m) {
  py::class_<PyScene>(m, "Scene",
                      "A scene file loaded as `pumasim check` loads it, with its plant at the initial discrete "
                      "state.\nrhs(t, x) is the continuous right-hand side f(t, x); a scene whose plant has "
                      "discrete state\n(a sampled controller, held set-points, hybrid stick-slip friction: see "
                      "discrete_state) refuses\nrhs and jacobian with ValueError: pumasim.run integrates it with its "
                      "events.")
      .def_static(
          "load",
          [](const py::object& path, const py::object& overrides, const std::vector<std::string>& unset) {
            return std::make_unique<PyScene>(path_arg(path), override_args(overrides), unset);
          },
          py::arg("path"), py::arg("overrides") = py::none(), py::arg("unset") = std::vector<std::string>{},
          "Loads a scene file. overrides: {\"section.key\": value} (bool, number, str, list), or a list of\n"
          "\"section.key=value\" strings in TOML syntax, as the command line's --set; unset: [\"section.key\"],\n"
          "keys removed from the file first, as --unset.")
      .def_property_readonly("name", [](const PyScene& s) { return s.scene().name; })
      .def_property_readonly("file", [](const PyScene& s) { return s.scene().file; })
      .def_property_readonly("size", [](const PyScene& s) { return s.plant().size(); }, "The state's length.")
      .def_property_readonly("state_names", [](const PyScene& s) { return s.plant().layout().names; })
      .def_property_readonly(
          "tolerance_scales",
          [](const PyScene& s) {
            Eigen::VectorXd v(s.plant().size());
            for (int i = 0; i < s.plant().size(); ++i) v[i] = s.plant().tolerance_scale(i);
            return v;
          },
          "Each state's typical magnitude: the integrators' absolute tolerance is atol times it.")
      .def_property_readonly("duration", [](const PyScene& s) { return s.scene().duration; }, "[s]")
      .def_property_readonly("output_interval", [](const PyScene& s) { return s.scene().output_interval; }, "[s]")
      .def_property_readonly("integrator", [](const PyScene& s) { return s.scene().integrator.name; })
      .def_property_readonly("backend", [](const PyScene& s) { return s.scene().plant.backend; })
      .def_property_readonly(
          "discrete_state",
          [](const PyScene& s) { return s.discrete().empty() ? py::object(py::none()) : py::str(s.discrete()); },
          "None when f(t, x) alone is the plant; otherwise what else it depends on (and the scene keys).")
      .def("time_events", &PyScene::time_events, py::arg("t_end") = py::none(),
           "The times in (0, t_end] (default: the duration) where the driver stops because f changes: the\n"
           "reference's breakpoints (where f has kinks), controller samples, set-point updates.")
      .def("initial_state", &PyScene::initial_state, "x(0); also restarts the plant's discrete state.")
      .def("rhs", &PyScene::rhs, py::arg("t"), py::arg("x"), "f(t, x), the plant's right-hand side.")
      .def("jacobian", &PyScene::jacobian, py::arg("t"), py::arg("x"), py::arg("exact") = true,
           "df/dx at (t, x): exact (dual numbers through the plant), or the integrators' forward differences.")
      .def("resolved_toml", [](const PyScene& s) { return resolved_toml(s.scene()); },
           "The scene with every default filled in (what scene.resolved.toml holds).")
      .def("__repr__", [](const PyScene& s) {
        return "<pumasim.Scene " + s.scene().name + " (" + s.scene().file + "): " + std::to_string(s.plant().size()) +
               " states>";
      });
}

// run(): `pumasim run`, and its result.
void bind_run(py::module_& m) {
  py::class_<PyRun>(m, "Run", "The result of pumasim.run: what `pumasim run` writes, as arrays.")
      .def_readonly("t", &PyRun::t, "Output times [s].")
      .def_readonly("x", &PyRun::x, "The state at each output time, one row per time.")
      .def_readonly("state_names", &PyRun::state_names)
      .def_readonly("stats", &PyRun::stats, "stats.json as a dict.")
      .def_readonly("path_error_mm", &PyRun::path_error_mm,
                    "The flange's distance to the reference point at each output [mm] (empty without a reference).")
      .def_readonly("path_deviation_mm", &PyRun::path_deviation_mm,
                    "The flange's distance to the geometric path at each output [mm] (empty without a reference).")
      .def_readonly("ok", &PyRun::ok, "False when the run failed (stats['failure'] says why).")
      .def_readonly("failure", &PyRun::failure)
      .def_readonly("out", &PyRun::out, "The run folder written, or None.")
      .def("__repr__", [](const PyRun& r) {
        return "<pumasim.Run " + std::string(py::str(r.stats["scene"])) + " with " +
               std::string(py::str(r.stats["integrator"])) + (r.ok ? ": ok" : ": failed") + ">";
      });

  m.def(
      "run",
      [](const py::object& scene, const std::optional<std::string>& integrator, std::optional<double> rtol,
         std::optional<double> atol, std::optional<double> dt, std::optional<double> t_end, const py::object& out,
         bool force, const std::optional<std::string>& backend, const std::optional<std::string>& jacobian,
         std::optional<double> max_steps,
         std::optional<double> max_wall, bool late_events, bool stop_at_outputs) {
        RunRequest r;
        r.integrator = integrator;
        r.backend = backend;
        r.rtol = rtol;
        r.atol = atol;
        r.dt = dt;
        r.t_end = t_end;
        r.max_steps = max_steps;
        r.max_wall = max_wall;
        r.jacobian = jacobian;
        r.late_events = late_events;
        r.stop_at_outputs = stop_at_outputs;
        return run(scene, r, out, force);
      },
      py::arg("scene"), py::kw_only(), py::arg("integrator") = py::none(), py::arg("rtol") = py::none(),
      py::arg("atol") = py::none(), py::arg("dt") = py::none(), py::arg("t_end") = py::none(),
      py::arg("out") = py::none(), py::arg("force") = false, py::arg("backend") = py::none(),
      py::arg("jacobian") = py::none(), py::arg("max_steps") = py::none(), py::arg("max_wall") = py::none(),
      py::arg("late_events") = false, py::arg("stop_at_outputs") = false,
      "`pumasim run` on a Scene (or a scene file's path): the same options (None: the scene's value or\n"
      "the command line's default), the same checks and messages, the same stats. Writes the run folder\n"
      "only when out is given (a new folder, or with force a pumasim run folder). A run that fails is a\n"
      "result (ok False, failure), as the command line's exit status 1.");
}

}  // namespace
}  // namespace pumasim

PYBIND11_MODULE(pumasim, m) {
  using namespace pumasim;

  m.doc() =
      "pumasim: the PUMA 560 as one stiff state-space ODE (README.md, \"Use it as a library\").\n\n"
      "backends(), integrators(): the registries' names; dynamics(...): H, h, g, and tau or qdd;\n"
      "Scene.load(path, overrides): a scene's plant as f(t, x) and its Jacobian; run(scene, ...): `pumasim run`.\n"
      "Bad input raises ValueError with the command line's message.";
  m.attr("__version__") = PUMASIM_VERSION;

  // The library's input errors: ValueError, as std::invalid_argument already is.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const RunFolderError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  bind_dynamics(m);
  bind_scene(m);
  bind_run(m);
}
