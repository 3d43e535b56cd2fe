// The Python module `pumasim` (pybind11): the dynamics back-ends, a scene's
// plant as f(t, x) and its Jacobian for any ODE solver (scipy's solve_ivp),
// and `pumasim run` with its statistics, numpy arrays in and out. Thin: every
// computation and every check is a library call that the command line makes
// too (models/robot/dynamics_query, simulation/run), and
// bad input raises ValueError with the message the command line prints after
// "pumasim: "; the module itself converts the arguments ("arguments" below:
// a wrong type is a TypeError naming the argument).
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/regressor.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/base_parameters.hpp"
#include "models/robot/dynamics_query.hpp"
#include "models/robot/link_inertia.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/robot_writer.hpp"
#include "models/robot/strict_toml.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "simulation/ensemble.hpp"
#include "simulation/run.hpp"
#include "simulation/run_folder.hpp"

namespace py = pybind11;

namespace pumasim {
namespace {

// ---------------------------------------------------------------- arguments

// Every argument is taken as a Python object and converted here, so that a
// value of the wrong type or out of range is a TypeError or ValueError naming
// the argument (pybind11's own conversions say "incompatible function
// arguments" or "Unable to cast Python instance", naming none), and texts are
// bounded before anything echoes them (tests/test_python_hostile.py).

// The longest name or path taken (PATH_MAX), and the longest override, in
// characters: the longest argument a Linux command line can pass to --set
// (MAX_ARG_STRLEN, 128 KiB).
constexpr std::size_t kMaxText = 4096;
constexpr std::size_t kMaxOverride = 131072;
// How deep an override's lists and tables may nest (TOML itself needs two or three).
constexpr int kMaxNesting = 32;

std::string type_name(const py::handle& v) { return py::str(py::type::of(v).attr("__name__")); }

[[noreturn]] void wrong_type(const std::string& what, const std::string& expected, const py::handle& v) {
  throw py::type_error(what + ": expected " + expected + ", got a " + type_name(v));
}

// A str as UTF-8 (a lone surrogate is refused, naming the argument).
std::string utf8(const py::handle& v, const std::string& what) {
  Py_ssize_t size = 0;
  const char* data = PyUnicode_AsUTF8AndSize(v.ptr(), &size);
  if (!data) {
    PyErr_Clear();
    throw std::invalid_argument(what + ": expected text that UTF-8 can encode (no lone surrogates)");
  }
  return std::string(data, static_cast<std::size_t>(size));
}

// A name (integrator, back-end, pose, ...): a str of at most kMaxText characters.
std::string text_arg(const py::handle& v, const std::string& what) {
  if (!py::isinstance<py::str>(v)) wrong_type(what, "a str", v);
  std::string s = utf8(v, what);
  if (s.size() > kMaxText) {
    throw std::invalid_argument(what + ": expected at most " + std::to_string(kMaxText) + " characters, got " +
                                std::to_string(s.size()));
  }
  return s;
}

std::optional<std::string> optional_text(const py::handle& v, const std::string& what) {
  if (v.is_none()) return std::nullopt;
  return text_arg(v, what);
}

// A path given as str, bytes or os.PathLike, as the file system's bytes
// (os.fsencode): not empty, without a NUL (which would end it early: the
// file opened would be another) and at most kMaxText bytes.
std::string path_arg(const py::handle& p, const std::string& what) {
  if (!(py::isinstance<py::str>(p) || py::isinstance<py::bytes>(p) || py::hasattr(p, "__fspath__"))) {
    wrong_type(what, "a path (str, bytes or os.PathLike)", p);
  }
  std::string path;
  try {
    path = py::module_::import("os").attr("fsencode")(p).cast<py::bytes>();
  } catch (py::error_already_set& e) {
    throw py::type_error(what + ": expected a path (str, bytes or os.PathLike): " + std::string(py::str(e.value())));
  }
  if (path.empty()) throw std::invalid_argument(what + ": expected a path, got an empty one");
  if (path.find('\0') != std::string::npos) throw std::invalid_argument(what + ": a path with a NUL character");
  if (path.size() > kMaxText) {
    throw std::invalid_argument(what + ": expected a path of at most " + std::to_string(kMaxText) + " bytes, got " +
                                std::to_string(path.size()));
  }
  return path;
}

bool is_bool(const py::handle& v) {
  return py::isinstance<py::bool_>(v) || py::isinstance(v, py::module_::import("numpy").attr("bool_"));
}

// A flag: True or False (also numpy's), not any value with a truth (None, nan, "no").
bool flag_arg(const py::handle& v, const std::string& what) {
  if (!is_bool(v)) wrong_type(what, "True or False", v);
  return v.cast<bool>();
}

// A number: an int, a float, or any scalar that converts to a float (numpy's);
// not a bool, not a str. Its range is the caller's to check.
double number_arg(const py::handle& v, const std::string& what) {
  if (is_bool(v) || py::isinstance<py::str>(v) || py::isinstance<py::bytes>(v) ||
      !(PyIndex_Check(v.ptr()) || PyFloat_Check(v.ptr()) || py::hasattr(v, "__float__"))) {
    wrong_type(what, "a number", v);
  }
  const double x = PyFloat_AsDouble(v.ptr());  // int, float, __float__, __index__
  if (x == -1.0 && PyErr_Occurred()) {
    const bool overflow = PyErr_ExceptionMatches(PyExc_OverflowError) != 0;
    py::error_already_set e;
    if (overflow) throw std::invalid_argument(what + ": expected a number, got an integer beyond a float's range");
    throw py::type_error(what + ": expected a number, got a " + type_name(v) + " (" + std::string(py::str(e.value())) +
                         ")");
  }
  return x;
}

std::optional<double> optional_number(const py::handle& v, const std::string& what) {
  if (v.is_none()) return std::nullopt;
  return number_arg(v, what);
}

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
// spells them), str, a dict (inline table) or a sequence (array: a list, a
// tuple, a numpy array) of these. Refused, naming the key: another type, an
// integer beyond TOML's 64 bits, nesting deeper than kMaxNesting (a list
// that holds itself), a text longer than kMaxOverride (checked as it grows).
class TomlLiteral {
 public:
  explicit TomlLiteral(const std::string& key) : key_(key) {}
  std::string operator()(const py::handle& v) {
    value(v, 0);
    return std::move(out_);
  }

 private:
  void append(const std::string& s) {
    out_ += s;
    if (out_.size() > kMaxOverride) {
      throw std::invalid_argument("overrides " + key_ + ": expected a value of at most " +
                                  std::to_string(kMaxOverride) +
                                  " characters of TOML (the longest command-line argument), got more");
    }
  }

  void value(const py::handle& v, int depth) {
    if (depth > kMaxNesting) {
      throw std::invalid_argument("overrides " + key_ + ": expected lists and tables nested at most " +
                                  std::to_string(kMaxNesting) + " deep, got deeper (a list that holds itself?)");
    }
    const py::module_ np = py::module_::import("numpy");
    if (is_bool(v)) return append(v.cast<bool>() ? "true" : "false");
    if (py::isinstance<py::str>(v)) return append(toml_string(utf8(v, "overrides " + key_)));
    if (py::isinstance(v, np.attr("ndarray"))) return value(v.attr("tolist")(), depth);
    if (PyIndex_Check(v.ptr()) && !PyFloat_Check(v.ptr())) {  // int, numpy's integers
      PyObject* i = PyNumber_Index(v.ptr());
      int overflow = 0;
      const long long n = i ? PyLong_AsLongLongAndOverflow(i, &overflow) : 0;
      Py_XDECREF(i);
      if (PyErr_Occurred()) {
        py::error_already_set e;
        throw py::type_error("overrides " + key_ + ": expected an integer, got a " + type_name(v) + " (" +
                             std::string(py::str(e.value())) + ")");
      }
      if (overflow != 0) {
        throw std::invalid_argument("overrides " + key_ +
                                    ": expected an integer within +-2^63 (a TOML integer), "
                                    "got a larger one");
      }
      return append(std::to_string(n));
    }
    if (PyFloat_Check(v.ptr()) || py::hasattr(v, "__float__")) {
      const double x = number_arg(v, "overrides " + key_);
      if (std::isnan(x)) return append("nan");
      if (std::isinf(x)) return append(x > 0 ? "inf" : "-inf");
      char buf[32];
      std::string s(buf, std::to_chars(buf, buf + sizeof buf, x).ptr);  // the shortest text that reads back as x
      if (s.find_first_of(".e") == std::string::npos) s += ".0";       // a float, not an integer
      return append(s);
    }
    if (py::isinstance<py::dict>(v)) {
      append("{");
      bool first = true;
      for (const auto& kv : v.cast<py::dict>()) {
        if (!py::isinstance<py::str>(kv.first)) wrong_type("overrides " + key_, "str keys in a table", kv.first);
        const std::string k = utf8(kv.first, "overrides " + key_);
        const bool bare = !k.empty() && k.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                                            "0123456789_-") == std::string::npos;
        append(std::string(first ? "" : ", ") + (bare ? k : toml_string(k)) + " = ");
        value(kv.second, depth + 1);
        first = false;
      }
      return append("}");
    }
    if (py::isinstance<py::iterable>(v) && !py::isinstance<py::bytes>(v) && !PyByteArray_Check(v.ptr())) {
      append("[");
      bool first = true;
      for (const py::handle item : v) {
        if (!first) append(", ");
        value(item, depth + 1);
        first = false;
      }
      return append("]");
    }
    wrong_type("overrides " + key_, "a bool, a number, a string, a dict or a list of these", v);
  }

  const std::string& key_;
  std::string out_;
};

// Scene overrides: a dict {"section.key": value} or a list of the command
// line's "section.key=value" strings (TOML values).
std::vector<std::string> override_args(const py::handle& overrides) {
  const std::string expected = "a dict {\"section.key\": value} or a list of \"section.key=value\" strings";
  std::vector<std::string> sets;
  if (overrides.is_none()) return sets;
  if (py::isinstance<py::dict>(overrides)) {
    for (const auto& kv : overrides.cast<py::dict>()) {
      if (!py::isinstance<py::str>(kv.first)) {
        wrong_type("overrides", "\"section.key\" strings as the dict's keys", kv.first);
      }
      const std::string key = text_arg(kv.first, "overrides");
      sets.push_back(key + "=" + TomlLiteral(key)(kv.second));
    }
    return sets;
  }
  if (py::isinstance<py::str>(overrides) || py::isinstance<py::bytes>(overrides) ||
      !py::isinstance<py::iterable>(overrides)) {
    wrong_type("overrides", expected, overrides);
  }
  for (const py::handle item : overrides) {
    if (!py::isinstance<py::str>(item)) {
      throw py::type_error("overrides: expected " + expected + ", got a " + type_name(overrides) + " holding a " +
                           type_name(item));
    }
    sets.push_back(utf8(item, "overrides"));
    if (sets.back().size() > kMaxOverride) {
      throw std::invalid_argument("overrides: expected \"section.key=value\" strings of at most " +
                                  std::to_string(kMaxOverride) + " characters (the longest command-line argument), "
                                  "got one of " + std::to_string(sets.back().size()));
    }
  }
  return sets;
}

// Keys to unset: a list of "section.key" strings (the command line's --unset).
std::vector<std::string> unset_args(const py::handle& unset) {
  std::vector<std::string> keys;
  if (unset.is_none()) return keys;
  if (py::isinstance<py::str>(unset) || py::isinstance<py::bytes>(unset) || !py::isinstance<py::iterable>(unset)) {
    wrong_type("unset", "a list of \"section.key\" strings", unset);
  }
  for (const py::handle item : unset) {
    if (!py::isinstance<py::str>(item)) {
      throw py::type_error("unset: expected a list of \"section.key\" strings, got a " + type_name(unset) +
                           " holding a " + type_name(item));
    }
    keys.push_back(text_arg(item, "unset"));
  }
  return keys;
}

// ---------------------------------------------------------------- dynamics

py::array_t<double> to_numpy(const Eigen::VectorXd& v) { return py::cast(v); }

py::dict dynamics(const py::object& robot, const py::object& backend, const py::object& q_in, const py::object& qd_in,
                  const py::object& qdd_in, const py::object& tau_in, const py::object& rotor_inertia) {
  const RobotDynamics rd = robot_dynamics(path_arg(robot, "robot"), text_arg(backend, "backend"),
                                          flag_arg(rotor_inertia, "rotor_inertia"));
  const int n = rd.model.dof();
  const Eigen::VectorXd q =
      py::isinstance<py::str>(q_in) ? pose_angles(rd.model, text_arg(q_in, "q"), "q") : vector_arg(q_in, "q");
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
      : PyScene(load_checked_scene(path, overrides, unset)) {}
  explicit PyScene(Scene scene)
      : scene_(std::move(scene)),
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

  // f(t, x), and its Jacobian: t and x finite, and so the result, or a
  // ValueError naming x (a state far beyond the plant's range overflows).
  Eigen::VectorXd rhs(const py::handle& t_in, const py::handle& x_in) {
    refuse_dae("rhs");
    const double t = time_arg(t_in);
    const Eigen::VectorXd x = state_arg(x_in);
    warn_discontinuous();
    Eigen::VectorXd f(x.size());
    plant_->rhs(t, x.data(), f.data());
    for (int i = 0; i < f.size(); ++i) {
      if (!std::isfinite(f[i])) not_finite("f(t, x)", "d(" + name(i) + ")/dt", f[i], x);
    }
    return f;
  }

  Eigen::MatrixXd jacobian(const py::handle& t_in, const py::handle& x_in, const py::handle& exact) {
    refuse_dae("jacobian");
    const double t = time_arg(t_in);
    const bool exact_jacobian = flag_arg(exact, "exact");
    const Eigen::VectorXd x = state_arg(x_in);
    warn_discontinuous();
    Eigen::MatrixXd J;
    if (exact_jacobian) {
      plant_->jacobian_exact(t, x.data(), J);
    } else {
      system_->OdeSystem::jacobian(t, x.data(), J);  // the integrators' forward differences
    }
    for (int j = 0; j < J.cols(); ++j) {
      for (int i = 0; i < J.rows(); ++i) {
        if (!std::isfinite(J(i, j))) not_finite("the Jacobian", "d(" + name(i) + "')/d(" + name(j) + ")", J(i, j), x);
      }
    }
    return J;
  }

  // The times in (0, t_end] where the driver stops because f changes.
  // t_end is checked as pumasim run checks --t-end, and the count is bounded
  // by the default step budget (each event is a stop) before it is listed.
  std::vector<double> time_events(const py::handle& t_end_in) const {
    const std::optional<double> t_end = optional_number(t_end_in, "t_end");
    if (t_end && !(std::isfinite(*t_end) && *t_end > 0)) {
      char got[32];
      std::snprintf(got, sizeof got, "%.9g", *t_end);
      throw std::invalid_argument(std::string("t_end: expected a number > 0, got ") + got);
    }
    const double end = t_end.value_or(scene_.duration);
    std::vector<double> times;
    for (double t = plant_->next_time_event(0.0); t <= end; t = plant_->next_time_event(t)) {
      if (static_cast<long>(times.size()) >= kDefaultStepBudget) {
        char by[32];
        std::snprintf(by, sizeof by, "%.9g", t);
        throw std::invalid_argument(std::string(t_end ? "t_end" : "the scene's duration") + ": expected at most " +
                                    std::to_string(kDefaultStepBudget) + " time events before it (the default step "
                                    "budget), got more by t = " + by + " s");
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

  std::string name(int i) const { return plant_->layout().names[static_cast<std::size_t>(i)]; }

  // A scene starts at t = 0: before it, a reference is not defined (its
  // extrapolated path leaves the workspace).
  static double time_arg(const py::handle& t_in) {
    const double t = number_arg(t_in, "t");
    if (!(std::isfinite(t) && t >= 0)) {
      char got[32];
      std::snprintf(got, sizeof got, "%.9g", t);
      throw std::invalid_argument(std::string("t: expected a finite time >= 0 (a scene starts at t = 0), got ") + got);
    }
    return t;
  }

  // `what` at x is not finite (its entry `entry` is `value`): a ValueError
  // naming x's largest entry.
  [[noreturn]] void not_finite(const char* what, const std::string& entry, double value,
                                const Eigen::VectorXd& x) const {
    Eigen::Index k = 0;
    x.cwiseAbs().maxCoeff(&k);
    char buf[160];
    std::snprintf(buf, sizeof buf, " = %g; its largest entry is %s = %g", value, name(static_cast<int>(k)).c_str(),
                  x[k]);
    throw std::invalid_argument(std::string("x: ") + what + " is not finite at this state (" + entry + buf +
                                "): the state is beyond what the plant's arithmetic holds");
  }

  // f and its Jacobian are an ODE's: a DAE's algebraic rows hold residuals (why_no_ode_form).
  void refuse_dae(const char* what) const {
    if (const std::string why = why_no_ode_form(scene_.plant); !why.empty())
      throw py::value_error(std::string(what) + ": " + why);
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
    for (int i = 0; i < x.size(); ++i) {
      if (!std::isfinite(x[i])) {
        throw std::invalid_argument(std::string("x: expected finite numbers, got ") +
                                    (std::isnan(x[i]) ? "nan" : x[i] > 0 ? "inf" : "-inf") + " for " + name(i));
      }
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
// and with the GIL, so by themselves they let a run notice Ctrl-C only when
// it ends (never, with max_wall=0; history: commit fa21494). The simplest
// design found that reaches every run:
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
  py::object sensitivity = py::none();  // with sensitivity=[keys]: a dict (keys, values, t, x, s, ok, failure)
  bool ok = true;
  std::string failure;
};

// The Python module's words for the options the library names neutrally
// (core/option_words.hpp): its keywords, "force=True" for a flag, and the
// list a scene's overrides are given in.
std::string python_words(std::string_view name) {
  if (name == "set") return "overrides";
  for (const char* flag : {"force", "late_events", "stop_at_outputs", "keep_history"}) {
    if (name == flag) return std::string(name) + "=True";
  }
  return std::string(name);
}

// None (none), or a list or tuple of scene keys.
std::vector<std::string> key_list(const py::object& v, const char* what) {
  std::vector<std::string> keys;
  if (v.is_none()) return keys;
  if (!py::isinstance<py::list>(v) && !py::isinstance<py::tuple>(v)) wrong_type(what, "a list of scene keys (str)", v);
  for (const py::handle& k : v) {
    if (!py::isinstance<py::str>(k)) wrong_type(what, "a list of scene keys (str)", v);
    keys.push_back(k.cast<std::string>());
  }
  return keys;
}

// A run's sensitivities as NumPy arrays: t (rows), x (rows x m) and s (rows
// x m x p, s[r, i, k] = dx_i/dp_k at t[r]), beside the keys and their values.
py::dict sensitivity_dict(const SceneSensitivities& sens) {
  const SensitivityRun& sr = sens.run;
  const auto rows = static_cast<py::ssize_t>(sr.t.size()), m = static_cast<py::ssize_t>(sens.state_names.size()),
             p = static_cast<py::ssize_t>(sens.keys.size());
  py::array_t<double> t(rows), x({rows, m}), s({rows, m, p});
  auto tt = t.mutable_unchecked<1>();
  auto xx = x.mutable_unchecked<2>();
  auto ss = s.mutable_unchecked<3>();
  for (py::ssize_t r = 0; r < rows; ++r) {
    tt(r) = sr.t[static_cast<std::size_t>(r)];
    for (py::ssize_t i = 0; i < m; ++i) {
      xx(r, i) = sr.x[static_cast<std::size_t>(r)][i];
      for (py::ssize_t k = 0; k < p; ++k) ss(r, i, k) = sr.s[static_cast<std::size_t>(r)](i, k);
    }
  }
  py::dict d;
  d["keys"] = py::cast(sens.keys);
  d["values"] = py::cast(sens.values);
  d["t"] = t, d["x"] = x, d["s"] = s;
  d["ok"] = sr.ok;
  d["failure"] = sr.failure;
  return d;
}

PyRun run(const py::object& scene_in, const RunOptions& options, const py::object& out, bool force) {
  RunRequest request;
  request.options = options;
  request.force = force;
  request.keep_rows = true;
  if (!out.is_none()) request.out = path_arg(out, "out");
  const bool is_scene = py::isinstance<PyScene>(scene_in);
  if (!is_scene && !(py::isinstance<py::str>(scene_in) || py::isinstance<py::bytes>(scene_in) ||
                     py::hasattr(scene_in, "__fspath__"))) {
    wrong_type("scene", "a pumasim.Scene or a scene file's path", scene_in);
  }
  if (is_scene)
    request.scene = &scene_in.cast<const PyScene&>().scene();
  else
    request.file = path_arg(scene_in, "scene");
  RunInterrupts interrupts;
  RunSinks sinks;
  sinks.words = python_words;
  // What `pumasim run` says on stderr before it starts, as Python warnings
  // (an error when the warnings filter makes them one: the run does not start).
  sinks.warning = [](const std::string& w) {
    const py::gil_scoped_acquire gil;
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) != 0) throw py::error_already_set();
  };
  sinks.progress.cancel = interrupts.flag();
  sinks.progress.poll = [&interrupts] { interrupts.poll(); };
  RunRecord done;
  {
    py::gil_scoped_release release;
    done = pumasim::run(request, sinks);
  }
  const Scene& sc = done.plan.scene;
  const std::optional<std::filesystem::path>& dir = done.plan.folder;
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
  if (done.sensitivities) res.sensitivity = sensitivity_dict(*done.sensitivities);
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

// One sample given from Python: {key: value}, each value as TOML text.
EnsembleSample given_sample(const py::handle& row, long index) {
  if (!py::isinstance<py::dict>(row)) wrong_type("samples[" + std::to_string(index) + "]", "a dict {key: value}", row);
  EnsembleSample s;
  s.index = index;
  for (const auto& kv : py::reinterpret_borrow<py::dict>(row)) {
    const std::string what = "samples[" + std::to_string(index) + "]";
    if (!py::isinstance<py::str>(kv.first)) wrong_type(what, "str keys (section.key)", kv.first);
    s.keys.push_back(kv.first.cast<std::string>());
    const py::handle v = kv.second;
    if (is_bool(v)) {
      s.values.emplace_back(v.cast<bool>() ? "true" : "false");
    } else if (py::isinstance<py::str>(v)) {
      s.values.push_back(toml_string(utf8(v, what)));
    } else {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", number_arg(v, what + "[" + s.keys.back() + "]"));
      s.values.emplace_back(buf);
    }
  }
  return s;
}

// pumasim.ensemble: the ensemble file's samples (or the given ones) on
// `threads` threads, the GIL released while they run; the table as text and
// its sidecar as a dict.
py::dict ensemble(const py::object& file, const py::object& threads, const py::object& samples,
                  const py::object& sample) {
  EnsembleSpec spec = read_ensemble_file(path_arg(file, "file"));
  std::vector<EnsembleSample> todo;
  if (!samples.is_none()) {
    if (!py::isinstance<py::list>(samples)) wrong_type("samples", "a list of dicts {key: value}", samples);
    long k = 0;
    for (const py::handle& row : samples) todo.push_back(given_sample(row, k++));
    spec.factors.clear();
  } else if (!sample.is_none()) {
    const std::optional<double> k = optional_number(sample, "sample");
    if (*k < 0 || *k != std::floor(*k) || *k >= static_cast<double>(spec.samples)) {
      throw std::invalid_argument("sample: expected a whole number in [0, " + std::to_string(spec.samples) + "), got " +
                                  py::str(sample).cast<std::string>());
    }
    todo.push_back(draw_sample(spec, static_cast<long>(*k)));
  } else {
    todo = draw_samples(spec);
  }
  const std::optional<double> n = optional_number(threads, "threads");
  if (n && (*n < 1 || *n > 1024 || *n != std::floor(*n))) {
    throw std::invalid_argument("threads: expected a whole number in [1, 1024], got " +
                                py::str(threads).cast<std::string>());
  }
  const int t = n ? static_cast<int>(*n) : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<SampleResult> results;
  double wall = 0;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    results = run_ensemble(spec, todo, t);
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  py::dict out;
  out["csv"] = ensemble_csv(results, spec.final_state);
  out["meta"] = py::module_::import("json").attr("loads")(ensemble_sidecar(spec, results, t, wall));
  return out;
}

// ---------------------------------------------------------------- identification

// Rows of n numbers: a 2-D array (rows x n) or one row (a 1-D array of n).
Eigen::MatrixXd rows_arg(const py::handle& v, const std::string& what, int n) {
  py::object a;
  try {
    a = py::module_::import("numpy").attr("asarray")(v, py::arg("dtype") = "float64");
  } catch (py::error_already_set& e) {
    throw std::invalid_argument(what + ": expected an array of numbers (" + std::string(py::str(e.value())) + ")");
  }
  if (a.attr("ndim").cast<int>() == 1) a = a.attr("reshape")(1, -1);
  const py::tuple shape = a.attr("shape");
  if (shape.size() != 2 || shape[1].cast<int>() != n) {
    throw std::invalid_argument(what + ": expected rows of " + std::to_string(n) +
                                " numbers (an array rows x n, or one row), got an array of shape " +
                                py::repr(shape).cast<std::string>());
  }
  return a.cast<Eigen::MatrixXd>();
}

RegressorColumns columns_arg(const py::object& rotor, const py::object& friction) {
  return {.rotor = flag_arg(rotor, "rotor"), .friction = flag_arg(friction, "friction")};
}

// pumasim.regressor: Y at each row of (q, qd, qdd), stacked sample by sample.
py::dict regressor(const py::object& robot, const py::object& q_in, const py::object& qd_in, const py::object& qdd_in,
                   const py::object& rotor, const py::object& friction) {
  const RobotModel model = load_robot(path_arg(robot, "robot"));
  JointTorqueRegressor Y(model, columns_arg(rotor, friction));
  const int n = model.dof();
  const Eigen::MatrixXd q = rows_arg(q_in, "q", n), qd = rows_arg(qd_in, "qd", n), qdd = rows_arg(qdd_in, "qdd", n);
  if (qd.rows() != q.rows() || qdd.rows() != q.rows()) {
    throw std::invalid_argument("qd, qdd: expected as many rows as q (" + std::to_string(q.rows()) + "), got " +
                                std::to_string(qd.rows()) + " and " + std::to_string(qdd.rows()));
  }
  Eigen::MatrixXd out(q.rows() * n, Y.parameters());
  {
    py::gil_scoped_release release;
    Eigen::MatrixXd block(n, Y.parameters());
    for (Eigen::Index s = 0; s < q.rows(); ++s) {
      Y.compute(q.row(s).transpose(), qd.row(s).transpose(), qdd.row(s).transpose(), block);
      out.middleRows(s * n, n) = block;
    }
  }
  Eigen::VectorXd gear(n);
  for (int j = 0; j < n; ++j) gear[j] = model.joints[static_cast<std::size_t>(j)].gear_ratio;
  py::dict d;
  d["robot"] = model.name;
  d["n"] = n;
  d["names"] = Y.parameter_names();
  d["Y"] = py::cast(out);
  d["pi"] = to_numpy(Y.parameters_of(model));
  d["gear_ratio"] = to_numpy(gear);
  return d;
}

// pumasim.base_parameters: `pumasim base-parameters` as a dict, with the
// projection K (rank x columns): pi_b = K pi.
py::dict base_parameters_dict(const py::object& robot, const py::object& rotor, const py::object& friction,
                              const py::object& samples, const py::object& seed, const py::object& tolerance) {
  const RobotModel model = load_robot(path_arg(robot, "robot"));
  JointTorqueRegressor Y(model, columns_arg(rotor, friction));
  const double ns = number_arg(samples, "samples"), sd = number_arg(seed, "seed");
  if (ns < 1 || ns > 1e6 || ns != std::floor(ns))
    throw std::invalid_argument("samples: expected a whole number in [1, 1e6]");
  if (sd < 0 || sd > 9e15 || sd != std::floor(sd)) throw std::invalid_argument("seed: expected a whole number >= 0");
  const BaseParameters b = base_parameters(Y, model, static_cast<int>(ns), static_cast<std::uint64_t>(sd),
                                           number_arg(tolerance, "tolerance"));
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(b.rank(), Y.parameters());
  std::vector<std::string> labels, definitions;
  for (int i = 0; i < b.rank(); ++i) {
    K(i, b.base[static_cast<std::size_t>(i)]) = 1.0;
    for (std::size_t g = 0; g < b.grouped.size(); ++g) K(i, b.grouped[g]) = b.beta(i, static_cast<Eigen::Index>(g));
    labels.push_back(b.label(i));
    definitions.push_back(b.definition(i));
  }
  py::dict d;
  d["robot"] = model.name;
  d["names"] = b.names;
  d["base"] = b.base;
  d["grouped"] = b.grouped;
  d["no_effect"] = b.no_effect;
  d["labels"] = labels;
  d["definitions"] = definitions;
  d["K"] = py::cast(K);
  d["values"] = to_numpy(b.values(Y.parameters_of(model)));
  d["singular_values"] = to_numpy(b.singular_values);
  d["gap"] = b.gap();
  d["tolerance"] = b.tolerance;
  d["warning"] = b.warning;
  return d;
}

// pumasim.robot_with_parameters: the robot with pi's values, as a robot
// file's text, and what keeps each link from being a rigid body.
py::dict robot_with_parameters(const py::object& robot, const py::object& pi_in, const py::object& rotor,
                               const py::object& friction, const py::object& comment) {
  const RobotModel model = load_robot(path_arg(robot, "robot"));
  JointTorqueRegressor Y(model, columns_arg(rotor, friction));
  const Eigen::VectorXd pi = vector_arg(pi_in, "pi");
  if (pi.size() != Y.parameters()) {
    throw std::invalid_argument("pi: expected " + std::to_string(Y.parameters()) +
                                " numbers (the regressor's columns), got " + std::to_string(pi.size()));
  }
  py::dict d;
  py::list problems;
  d["problems"] = problems;
  d["text"] = py::none();
  for (int j = 0; j < model.dof(); ++j) {
    const Eigen::Index at = static_cast<Eigen::Index>(j) * Y.per_joint();
    const double m = pi[at + 9];
    if (!(m > 0.0) && !(m == 0.0 && pi.segment(at + 6, 3).isZero(0.0))) {
      py::dict p;
      p["link"] = j + 1, p["key"] = "mass", p["expected"] = "> 0 (or 0 with a zero first moment)",
      p["got"] = std::to_string(m), p["excusable"] = false;
      problems.append(p);
    }
  }
  if (!problems.empty()) return d;
  RobotModel out = Y.with_parameters(model, pi);
  bool readable = true;
  for (int j = 0; j < out.dof(); ++j) {
    const InertiaProblem why = inertia_problem(out.joints[static_cast<std::size_t>(j)]);
    if (why.key.empty()) continue;
    readable = readable && why.excusable;
    py::dict p;
    p["link"] = j + 1, p["key"] = why.key, p["expected"] = why.expected, p["got"] = why.got,
    p["excusable"] = why.excusable;
    problems.append(p);
  }
  if (!readable) return d;  // no robot file reads an inertia that is not positive semi-definite
  out.source = "pumasim.robot_with_parameters";
  d["text"] = robot_file_text(out, text_arg(comment, "comment"));
  return d;
}

void bind_identification(py::module_& m) {
  m.def("regressor", &regressor, py::kw_only(), py::arg("robot") = "puma560", py::arg("q"), py::arg("qd"),
        py::arg("qdd"), py::arg("rotor") = true, py::arg("friction") = true,
        "The joint-torque regressor tau = Y(q, qd, qdd) pi (docs/user-guide/identification.md) at each row of\n"
        "q, qd, qdd (arrays rows x n, or one row): a dict with names (the columns), Y ((rows n) x columns,\n"
        "row s n + j is sample s's joint j), pi (the robot's own parameters) and gear_ratio.");
  m.def("base_parameters", &base_parameters_dict, py::kw_only(), py::arg("robot") = "puma560", py::arg("rotor") = true,
        py::arg("friction") = true, py::arg("samples") = 40, py::arg("seed") = 1, py::arg("tolerance") = 1e-8,
        "`pumasim base-parameters` as a dict: names, base and grouped (column indices), labels and definitions\n"
        "(the regrouping), K (rank x columns: pi_b = K pi), values (the robot's pi_b), singular_values, gap,\n"
        "tolerance, warning, no_effect.");
  m.def("robot_with_parameters", &robot_with_parameters, py::kw_only(), py::arg("robot") = "puma560", py::arg("pi"),
        py::arg("rotor") = true, py::arg("friction") = true, py::arg("comment") = "",
        "The robot with the regressor parameters pi (its kinematics kept): a dict with problems (per link, what\n"
        "keeps it from being a rigid body: link, key, expected, got, excusable; the triangle inequalities of\n"
        "Wensing et al. 2017) and text (a robot file, a published set's excuse written where it is excusable;\n"
        "None for such a mass or an inertia is not positive semi-definite). Fo has no place in a robot file and is "
        "dropped.");
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

// A Scene pickles as its resolved content (resolved_toml: every key, the
// overrides applied), not as its file's path: unpickled after the scene file
// changed, it is still the scene pickled. The other files it read (the robot
// file, an input CSV) are read again; one that changed since is refused
// (ValueError naming it), as the unpickled scene would not be the pickled one.
py::tuple scene_state(const PyScene& s) {
  py::list inputs;
  for (const InputFile& f : s.scene().inputs) inputs.append(py::make_tuple(f.path, f.fnv1a64, f.bytes));
  return py::make_tuple("pumasim.Scene", 1, resolved_toml(s.scene()), s.scene().file, inputs);
}

std::unique_ptr<PyScene> scene_from_state(const py::tuple& st) {
  if (st.size() != 5 || !py::isinstance<py::str>(st[0]) || st[0].cast<std::string>() != "pumasim.Scene" ||
      st[1].cast<int>() != 1) {
    throw py::value_error("pumasim.Scene: expected the state a pumasim.Scene pickles (version 1)");
  }
  Scene sc = load_checked_scene_text(st[2].cast<std::string>(), st[3].cast<std::string>());
  std::vector<InputFile> then;
  for (const py::handle& h : st[4].cast<py::list>()) {
    const auto [path, hash, bytes] = h.cast<std::tuple<std::string, std::uint64_t, std::size_t>>();
    then.push_back({path, bytes, hash});
  }
  for (const InputFile& now : sc.inputs) {
    const auto was = std::find_if(then.begin(), then.end(), [&](const InputFile& f) { return f.path == now.path; });
    if (was != then.end() && was->fnv1a64 == now.fnv1a64 && was->bytes == now.bytes) continue;
    throw py::value_error("pumasim.Scene: the pickled scene read " + now.path + ", which has changed since (" +
                          (was == then.end()
                               ? std::string("not read then")
                               : "fnv1a64 " + hex64(was->fnv1a64) + ", " + std::to_string(was->bytes) + " bytes then") +
                          "; fnv1a64 " + hex64(now.fnv1a64) + ", " + std::to_string(now.bytes) +
                          " bytes now): unpickled, it would not be the scene pickled");
  }
  sc.inputs = std::move(then);  // the scene file too, as it was read: the content the resolved text came from
  return std::make_unique<PyScene>(std::move(sc));
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
          [](const py::object& path, const py::object& overrides, const py::object& unset) {
            return std::make_unique<PyScene>(path_arg(path, "path"), override_args(overrides), unset_args(unset));
          },
          py::arg("path"), py::arg("overrides") = py::none(), py::arg("unset") = py::none(),
          "Loads a scene file. overrides: {\"section.key\": value} (bool, number, str, list), or a list of\n"
          "\"section.key=value\" strings in TOML syntax, as the command line's --set; unset: [\"section.key\"],\n"
          "keys removed from the file first, as --unset.")
      .def_property_readonly("name", [](const PyScene& s) { return s.scene().name; })
      .def_property_readonly("file", [](const PyScene& s) { return s.scene().file; })
      .def_property_readonly(
          "size", [](const PyScene& s) { return s.plant().size(); }, "The state's length.")
      .def_property_readonly("state_names", [](const PyScene& s) { return s.plant().layout().names; })
      .def_property_readonly(
          "tolerance_scales",
          [](const PyScene& s) {
            Eigen::VectorXd v(s.plant().size());
            for (int i = 0; i < s.plant().size(); ++i) v[i] = s.plant().tolerance_scale(i);
            return v;
          },
          "Each state's typical magnitude: the integrators' absolute tolerance is atol times it.")
      .def_property_readonly(
          "duration", [](const PyScene& s) { return s.scene().duration; }, "[s]")
      .def_property_readonly(
          "output_interval", [](const PyScene& s) { return s.scene().output_interval; }, "[s]")
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
      .def(
          "resolved_toml", [](const PyScene& s) { return resolved_toml(s.scene()); },
          "The scene with every default filled in (what scene.resolved.toml holds).")
      .def(py::pickle(&scene_state, &scene_from_state))
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
      .def_readonly("sensitivity", &PyRun::sensitivity,
                    "With sensitivity=[keys]: a dict with keys, values, t, x and s (s[r, i, k] = dx_i/dp_k at t[r]),\n"
                    "ok and failure (`pumasim run --sensitivity`); else None.")
      .def(py::pickle(
          [](const PyRun& r) {  // its values (the arrays pickle as numpy's)
            return py::make_tuple("pumasim.Run", 2, r.t, r.x, r.state_names, r.stats, r.path_error_mm,
                                  r.path_deviation_mm, r.out, r.ok, r.failure, r.sensitivity);
          },
          [](const py::tuple& st) {  // version 1 (before the sensitivities) still reads
            const int version = st.size() > 1 && py::isinstance<py::int_>(st[1]) ? st[1].cast<int>() : 0;
            if (!py::isinstance<py::str>(st[0]) || st[0].cast<std::string>() != "pumasim.Run" ||
                !((version == 1 && st.size() == 11) || (version == 2 && st.size() == 12))) {
              throw py::value_error("pumasim.Run: expected the state a pumasim.Run pickles (version 1 or 2)");
            }
            PyRun r;
            r.t = st[2], r.x = st[3], r.state_names = st[4], r.stats = st[5];
            r.path_error_mm = st[6], r.path_deviation_mm = st[7], r.out = st[8];
            r.ok = st[9].cast<bool>();
            r.failure = st[10].cast<std::string>();
            if (version == 2) r.sensitivity = st[11];
            return r;
          }))
      .def("__repr__", [](const PyRun& r) {
        return "<pumasim.Run " + std::string(py::str(r.stats["scene"])) + " with " +
               std::string(py::str(r.stats["integrator"])) + (r.ok ? ": ok" : ": failed") + ">";
      });

  m.def(
      "run",
      [](const py::object& scene, const py::object& integrator, const py::object& rtol, const py::object& atol,
         const py::object& dt, const py::object& t_end, const py::object& out, const py::object& force,
         const py::object& backend, const py::object& jacobian, const py::object& max_steps, const py::object& max_wall,
         const py::object& late_events, const py::object& stop_at_outputs, const py::object& sensitivity) {
        RunOptions r;  // each option's range is checked with the command line's (plan_run)
        r.integrator = optional_text(integrator, "integrator");
        r.backend = optional_text(backend, "backend");
        r.rtol = optional_number(rtol, "rtol");
        r.atol = optional_number(atol, "atol");
        r.dt = optional_number(dt, "dt");
        r.t_end = optional_number(t_end, "t_end");
        r.max_steps = optional_number(max_steps, "max_steps");
        r.max_wall = optional_number(max_wall, "max_wall");
        r.jacobian = optional_text(jacobian, "jacobian");
        r.late_events = flag_arg(late_events, "late_events");
        r.stop_at_outputs = flag_arg(stop_at_outputs, "stop_at_outputs");
        r.sensitivity = key_list(sensitivity, "sensitivity");
        return run(scene, r, out, flag_arg(force, "force"));
      },
      py::arg("scene"), py::kw_only(), py::arg("integrator") = py::none(), py::arg("rtol") = py::none(),
      py::arg("atol") = py::none(), py::arg("dt") = py::none(), py::arg("t_end") = py::none(),
      py::arg("out") = py::none(), py::arg("force") = false, py::arg("backend") = py::none(),
      py::arg("jacobian") = py::none(), py::arg("max_steps") = py::none(), py::arg("max_wall") = py::none(),
      py::arg("late_events") = false, py::arg("stop_at_outputs") = false, py::arg("sensitivity") = py::none(),
      "`pumasim run` on a Scene (or a scene file's path): the same options (None: the scene's value or\n"
      "the command line's default), the same checks and messages, the same stats. Writes the run folder\n"
      "only when out is given (a new folder, or with force a pumasim run folder). A run that fails is a\n"
      "result (ok False, failure), as the command line's exit status 1.");
  m.def("ensemble", &ensemble, py::arg("file"), py::kw_only(), py::arg("threads") = py::none(),
        py::arg("samples") = py::none(), py::arg("sample") = py::none(),
        "`pumasim ensemble` on an ensemble file: its samples (or sample k alone, or the given samples, a\n"
        "list of dicts {section.key: value} run instead of the file's draws) on `threads` threads (None: the\n"
        "machine's cores), the GIL released while they run. Returns {'csv': the table as text (pandas.read_csv\n"
        "or numpy.genfromtxt read it; 17 significant digits), 'meta': its sidecar (columns, units, spec)}.");
}

}  // namespace
}  // namespace pumasim

PYBIND11_MODULE(pumasim, m) {
  using namespace pumasim;

  m.doc() =
      "pumasim: the PUMA 560 as one stiff state-space ODE (docs/user-guide/python.md).\n\n"
      "backends(), integrators(): the registries' names; dynamics(...): H, h, g, and tau or qdd;\n"
      "Scene.load(path, overrides): a scene's plant as f(t, x) and its Jacobian; run(scene, ...): `pumasim run`.\n"
      "Bad input raises ValueError with the command line's message, a wrong type TypeError naming the argument.";
  m.attr("__version__") = PUMASIM_VERSION;

  // The library's input errors: ValueError, as std::invalid_argument already is.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, phrased(e.what(), python_words).c_str());
    } catch (const RunFolderError& e) {
      PyErr_SetString(PyExc_ValueError, phrased(e.what(), python_words).c_str());
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, phrased(e.what(), python_words).c_str());
    }
  });

  bind_dynamics(m);
  bind_identification(m);
  bind_scene(m);
  bind_run(m);
}
