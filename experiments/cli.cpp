#include "experiments/cli.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <chrono>

#include "integrators/rk4_driver.hpp"
#include "models/backend.hpp"
#include "models/robot_file.hpp"
#include "models/scene.hpp"

namespace pumasim {
namespace {

// Bad command-line input; becomes one line on stderr and exit status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr const char* kUsage =
    "usage: pumasim <command> [options]\n"
    "commands:\n"
    "  dynamics --robot <name-or-file> --backend <name> --q=<csv|pose> [--qd=<csv>]\n"
    "           [--qdd=<csv>] [--tau=<csv>] [--no-rotor-inertia]\n"
    "      prints H, h, g (and tau from qdd, qdd from tau) as one JSON object\n"
    "  backends   lists the dynamics back-ends\n"
    "  check <scene.toml>\n"
    "      checks a scene; prints it resolved (every default filled in), its state\n"
    "      layout and initial state\n"
    "  simulate <scene.toml> [--dt X] [--t-end X]\n"
    "      runs the scene with fixed-step RK4 (stopping at every controller sample and\n"
    "      set-point update) and prints a JSON summary with the path error\n"
    "  help       prints this text\n";

// --key=value, --key value, or a bare --flag; values may start with '-'.
struct Options {
  std::map<std::string, std::string> values;
  std::map<std::string, bool> flags;

  static Options parse(const std::vector<std::string>& args, std::size_t first,
                       const std::vector<std::string>& valued,
                       const std::vector<std::string>& flag_names) {
    auto is_in = [](const std::vector<std::string>& v, const std::string& s) {
      for (const auto& x : v) if (x == s) return true;
      return false;
    };
    Options o;
    for (std::size_t i = first; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + a + "'; expected --option");
      const auto eq = a.find('=');
      const std::string key = a.substr(2, eq == std::string::npos ? std::string::npos : eq - 2);
      if (is_in(flag_names, key)) {
        if (eq != std::string::npos) throw UsageError("--" + key + " takes no value");
        o.flags[key] = true;
      } else if (is_in(valued, key)) {
        if (eq != std::string::npos) {
          o.values[key] = a.substr(eq + 1);
        } else if (i + 1 < args.size()) {
          o.values[key] = args[++i];
        } else {
          throw UsageError("--" + key + " expects a value");
        }
      } else {
        std::string known;
        for (const auto& k : valued) known += " --" + k;
        for (const auto& k : flag_names) known += " --" + k;
        throw UsageError("unknown option '--" + key + "'; expected one of:" + known);
      }
    }
    return o;
  }

  std::optional<std::string> get(const std::string& key) const {
    const auto it = values.find(key);
    if (it == values.end()) return std::nullopt;
    return it->second;
  }
  std::string require(const std::string& key, const std::string& what) const {
    auto v = get(key);
    if (!v) throw UsageError("missing --" + key + "; expected " + what);
    return *v;
  }
};

double parse_double(const std::string& s, const std::string& what) {
  double x = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  while (b < e && *b == ' ') ++b;
  while (e > b && e[-1] == ' ') --e;
  if (b < e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, x);
  if (b == e || r.ec != std::errc() || r.ptr != e || !std::isfinite(x)) {
    throw UsageError(what + ": expected a finite number, got '" + s + "'");
  }
  return x;
}

// "0.1,-0.2,..." with exactly n entries, or the name of one of the robot's poses.
Eigen::VectorXd parse_vector(const std::string& text, int n, const std::string& what,
                             const RobotModel* poses_from = nullptr) {
  if (poses_from) {
    if (const NamedPose* p = poses_from->pose(text)) return p->q;
  }
  std::vector<double> v;
  std::size_t start = 0;
  while (true) {
    const auto comma = text.find(',', start);
    v.push_back(parse_double(text.substr(start, comma - start), what));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (static_cast<int>(v.size()) != n) {
    std::string poses;
    if (poses_from) {
      for (const auto& p : poses_from->poses) poses += (poses.empty() ? "" : ", ") + p.name;
    }
    throw UsageError(what + ": expected " + std::to_string(n) + " comma-separated numbers" +
                     (poses.empty() ? "" : " or a pose name (" + poses + ")") + ", got " +
                     std::to_string(v.size()) + " values");
  }
  return Eigen::Map<Eigen::VectorXd>(v.data(), n);
}

void json_number(std::ostream& o, double x) {
  if (!std::isfinite(x)) {
    o << "null";
    return;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  o << buf;
}

void json_vector(std::ostream& o, const Eigen::VectorXd& v) {
  o << '[';
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (i) o << ", ";
    json_number(o, v[i]);
  }
  o << ']';
}

std::string json_string(const std::string& s) {
  std::string r = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') r += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      r += buf;
      continue;
    }
    r += c;
  }
  return r + "\"";
}

int cmd_dynamics(const std::vector<std::string>& args, std::ostream& final_out) {
  const Options opt = Options::parse(args, 1, {"robot", "backend", "q", "qd", "qdd", "tau"},
                                     {"no-rotor-inertia"});
  RobotModel model = load_robot(opt.require("robot", "a robot name (puma560) or a robot file path"));
  const bool rotor = !opt.flags.count("no-rotor-inertia");
  if (!rotor) model = without_rotor_inertia(model);
  const std::string backend_name = opt.require("backend", "one of: " + backend_names());
  auto backend = make_backend(backend_name, model);  // unknown name: invalid_argument
  const int n = model.dof();
  const Eigen::VectorXd q =
      parse_vector(opt.require("q", std::to_string(n) + " joint angles [rad] or a pose name"), n,
                   "--q", &model);
  const Eigen::VectorXd qd =
      opt.get("qd") ? parse_vector(*opt.get("qd"), n, "--qd") : Eigen::VectorXd::Zero(n);
  std::optional<Eigen::VectorXd> qdd_in, tau_in;
  if (auto s = opt.get("qdd")) qdd_in = parse_vector(*s, n, "--qdd");
  if (auto s = opt.get("tau")) tau_in = parse_vector(*s, n, "--tau");
  // Everything is checked before anything is printed: nothing half-written.
  std::ostringstream out;

  Eigen::MatrixXd H(n, n);
  Eigen::VectorXd h(n), g(n);
  backend->mass_matrix(q, H);
  backend->bias(q, qd, h);
  backend->gravity(q, g);

  out << "{\n  \"backend\": " << json_string(backend->name()) << ",\n";
  out << "  \"robot\": " << json_string(model.name) << ",\n";
  out << "  \"n\": " << n << ",\n";
  out << "  \"rotor_inertia_included\": " << (rotor ? "true" : "false") << ",\n";
  out << "  \"q\": ";
  json_vector(out, q);
  out << ",\n  \"qd\": ";
  json_vector(out, qd);
  out << ",\n  \"mass_matrix\": [";
  for (int i = 0; i < n; ++i) {
    out << (i ? ",\n    " : "\n    ");
    json_vector(out, H.row(i).transpose());
  }
  out << "\n  ],\n  \"bias\": ";
  json_vector(out, h);
  out << ",\n  \"gravity\": ";
  json_vector(out, g);
  if (qdd_in) {
    const Eigen::VectorXd& qdd = *qdd_in;
    Eigen::VectorXd tau(n);
    backend->inverse_dynamics(q, qd, qdd, tau);
    out << ",\n  \"qdd_in\": ";
    json_vector(out, qdd);
    out << ",\n  \"tau\": ";
    json_vector(out, tau);
  }
  if (tau_in) {
    const Eigen::VectorXd& tau = *tau_in;
    Eigen::VectorXd qdd(n);
    backend->forward_dynamics(q, qd, tau, qdd);
    out << ",\n  \"tau_in\": ";
    json_vector(out, tau);
    out << ",\n  \"qdd\": ";
    json_vector(out, qdd);
  }
  out << "\n}\n";
  final_out << out.str();
  return kExitOk;
}

Scene scene_argument(const std::vector<std::string>& args) {
  if (args.size() < 2 || args[1].rfind("--", 0) == 0) {
    throw UsageError(args[0] + ": expected a scene file, e.g. experiments/scenes/paper_slow.toml");
  }
  return load_scene(args[1]);
}

int cmd_check(const std::vector<std::string>& args, std::ostream& out) {
  Options::parse(args, 2, {}, {});
  const Scene sc = scene_argument(args);
  Plant plant(sc.plant);
  std::vector<double> x(plant.size());
  plant.initial_state(x.data());
  std::ostringstream o;
  o << resolved_toml(sc);
  o << "# state (" << plant.size() << "):";
  for (const auto& name : plant.layout().names) o << " " << name;
  o << "\n# initial state:";
  char buf[32];
  for (double v : x) std::snprintf(buf, sizeof buf, " %.10g", v), o << buf;
  o << "\n";
  out << o.str();
  return kExitOk;
}

int cmd_simulate(const std::vector<std::string>& args, std::ostream& out) {
  const Options opt = Options::parse(args, 2, {"dt", "t-end"}, {});
  const Scene sc = scene_argument(args);
  const double dt = opt.get("dt") ? parse_double(*opt.get("dt"), "--dt") : sc.integrator.dt;
  const double t_end = opt.get("t-end") ? parse_double(*opt.get("t-end"), "--t-end") : sc.duration;
  if (!(dt > 0) || !(t_end > 0)) throw UsageError("--dt and --t-end: expected numbers > 0");
  Plant plant(sc.plant);
  double max_err = 0, sum_sq = 0;
  long samples = 0;
  bool finite = true;
  ReferenceSample ref;
  const auto start = std::chrono::steady_clock::now();
  const Rk4Stats st = integrate_rk4(plant, t_end, dt, sc.output_interval,
                                    [&](double t, const double* x) {
    for (int i = 0; i < plant.size(); ++i) finite &= std::isfinite(x[i]);
    if (!sc.plant.reference) return;
    sc.plant.reference->eval(std::min(t, sc.plant.reference->profile().duration()), ref);
    const double e = (plant.tool_position(x) - ref.p).norm();
    max_err = std::max(max_err, e);
    sum_sq += e * e;
    ++samples;
  });
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::ostringstream o;
  o << "{\n  \"scene\": " << json_string(sc.name) << ",\n  \"integrator\": \"rk4\",\n  \"dt\": ";
  json_number(o, dt);
  o << ",\n  \"t_end\": ";
  json_number(o, t_end);
  o << ",\n  \"steps\": " << st.steps << ",\n  \"rhs_evaluations\": " << st.rhs_evaluations
    << ",\n  \"time_events\": " << st.time_events << ",\n  \"wall_time_s\": ";
  json_number(o, wall);
  o << ",\n  \"finite\": " << (finite ? "true" : "false");
  if (samples > 0) {
    o << ",\n  \"max_path_error_mm\": ";
    json_number(o, 1e3 * max_err);
    o << ",\n  \"rms_path_error_mm\": ";
    json_number(o, 1e3 * std::sqrt(sum_sq / samples));
  }
  o << "\n}\n";
  out << o.str();
  return kExitOk;
}

int cmd_backends(std::ostream& out) {
  for (const auto& b : backends()) out << b.name << "\t" << b.summary << "\n";
  return kExitOk;
}

}  // namespace

int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    if (args.empty()) throw UsageError("missing command; expected dynamics, backends, check, simulate or help");
    const std::string& cmd = args[0];
    if (cmd == "dynamics") return cmd_dynamics(args, out);
    if (cmd == "backends") return cmd_backends(out);
    if (cmd == "check") return cmd_check(args, out);
    if (cmd == "simulate") return cmd_simulate(args, out);
    if (cmd == "help" || cmd == "--help" || cmd == "-h") {
      out << kUsage;
      return kExitOk;
    }
    throw UsageError("unknown command '" + cmd + "'; expected dynamics, backends, check, simulate or help");
  } catch (const UsageError& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const ConfigError& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const std::invalid_argument& e) {
    err << "pumasim: " << e.what() << "\n";
  } catch (const std::exception& e) {
    err << "pumasim: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
  return kExitBadInput;
}

}  // namespace pumasim
