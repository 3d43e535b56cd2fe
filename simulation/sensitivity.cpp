#include "simulation/sensitivity.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>
#include <nlohmann/json.hpp>

#include "models/plant/controller/piv.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/toml_writer.hpp"
#include "simulation/run.hpp"

namespace pumasim {

namespace {

// A key's value in the resolved scene: a real number, or an array of equal
// real numbers (a per-joint key given one value for every joint, as --set
// and the ensembles take it), moved as one shared value. std::invalid_argument otherwise.
struct KeyValue {
  double p = 0;
  bool shared = false;  // an array of equal values
};

KeyValue scene_number(const toml::table& resolved, const std::string& key) {
  const std::string section = key.substr(0, key.find_first_of(".["));
  if (section == "integrator" || section == "scene" || section == "output") {
    throw std::invalid_argument("--sensitivity: '" + key +
                                "' sets how the scene is run, not the plant: its "
                                "sensitivities are zero; expected a key of the plant, such as motor.resistance");
  }
  const toml::node_view<const toml::node> node = resolved.at_path(key);
  if (!node) throw std::invalid_argument("--sensitivity: the scene has no key '" + key + "'");
  if (node.is_floating_point()) return {node.value<double>().value(), false};
  const toml::array* a = node.as_array();
  if (a && !a->empty() && a->is_homogeneous(toml::node_type::floating_point)) {
    const double first = a->front().value<double>().value();
    for (const toml::node& e : *a) {
      if (e.value<double>().value() != first) {
        throw std::invalid_argument("--sensitivity: '" + key + "' has different values: name one element, " + key +
                                    "[0] for the first (or give them one value with --set)");
      }
    }
    return {first, true};
  }
  throw std::invalid_argument("--sensitivity: '" + key + "' is not a real number in the scene (" +
                              std::string(node.is_integer() ? "an integer" : "not a number") +
                              "): expected a key such as motor.resistance");
}

// The resolved scene with `key` at `value` (for a shared key, one value for
// every joint), as text; `written` is the value as the text holds it (read
// back, so that the difference quotient divides by the step actually taken).
std::string moved_scene(const toml::table& resolved, const std::string& key, bool shared, double value,
                        double& written) {
  toml::table t = resolved;
  if (shared) {  // every element moved: an array of the same length
    for (toml::node& e : *t.at_path(key).as_array()) *e.as_floating_point() = value;
  } else {
    *t.at_path(key).as_floating_point() = value;
  }
  const std::string text = write_toml(t);  // not toml++'s formatter (models/robot/toml_writer.hpp: UB on arrays)
  const toml::table back = toml::parse(text);
  const toml::node_view<const toml::node> node = back.at_path(key);
  written = shared ? node.as_array()->front().value<double>().value() : node.value<double>().value();
  return text;
}

// The plant of the scene with `key` at `value`; std::invalid_argument naming
// the key and the value when the scene reader refuses it (a value at the
// key's range bound moved past it) or its states differ from the scene's.
std::unique_ptr<Plant> moved_plant(const Scene& scene, const toml::table& resolved, const std::string& key, bool shared,
                                   double value, double& written) {
  const std::string text = moved_scene(resolved, key, shared, value, written);
  std::unique_ptr<Plant> plant;
  try {
    plant = std::make_unique<Plant>(load_checked_scene_text(text, scene.file).plant);
  } catch (const std::exception& e) {
    char v[32];
    std::snprintf(v, sizeof v, "%.17g", written);
    throw std::invalid_argument("--sensitivity: '" + key + "' moved to " + v +
                                " for its difference is refused by the scene reader (" + e.what() +
                                "): a value at its range's bound has no two-sided difference");
  }
  return plant;
}

// The moved plant's time events (the reference's breakpoints, where f may
// jump in t) must be the scene's: sensitivities continue across a
// breakpoint that does not move with p, and jump by (f+ - f-) dtau/dp
// across one that does, which this does not apply.
void check_same_events(double duration, const Plant& base, const Plant& moved, const std::string& key) {
  if (moved.size() != base.size() || moved.layout().names != base.layout().names) {
    throw std::invalid_argument("--sensitivity: '" + key + "' changes the plant's states");
  }
  for (double t = 0.0, u = 0.0; t < duration || u < duration;) {
    t = base.next_time_event(t), u = moved.next_time_event(u);
    if (t != u && (t < duration || u < duration)) {
      char at[48];
      std::snprintf(at, sizeof at, "%.9g s against %.9g s", t, u);
      throw std::invalid_argument("--sensitivity: '" + key + "' moves the reference's breakpoints (" + at +
                                  "), where the right-hand side may jump in time: the sensitivities jump there "
                                  "too, by a condition this does not apply");
    }
  }
}

// The scene's plant, and a pair of plants per key with the key moved.
class PlantSensitivity final : public SensitivitySystem {
 public:
  PlantSensitivity(const Scene& scene, const std::vector<std::string>& keys, double relative_step,
                   SceneSensitivities& out)
      : base_(scene.plant), f_plus_(base_.size()), f_minus_(base_.size()), x_copy_(base_.size()) {
    const toml::table resolved = toml::parse(resolved_toml(scene));
    for (const std::string& key : keys) {
      const KeyValue v = scene_number(resolved, key);
      const double p = v.p;
      const double h = relative_step * (p != 0.0 ? std::abs(p) : 1.0);
      double up = 0, down = 0;
      plus_.push_back(moved_plant(scene, resolved, key, v.shared, p + h, up));
      minus_.push_back(moved_plant(scene, resolved, key, v.shared, p - h, down));
      for (const Plant* moved : {plus_.back().get(), minus_.back().get()})
        check_same_events(scene.duration, base_, *moved, key);
      width_.push_back(up - down), scale_.push_back(p != 0.0 ? std::abs(p) : 1.0);
      out.keys.push_back(key), out.values.push_back(p), out.steps.push_back(0.5 * (up - down));
    }
  }

  Plant& plant() { return base_; }
  int size() const override { return base_.size(); }
  void rhs(double t, const double* x, double* f) override { base_.rhs(t, x, f); }
  void jacobian(double t, const double* x, Eigen::MatrixXd& J) override { base_.jacobian_exact(t, x, J); }
  bool has_exact_jacobian() const override { return true; }
  std::string state_name(int i) const override { return base_.layout().names[static_cast<std::size_t>(i)]; }
  double tolerance_scale(int i) const override { return base_.tolerance_scale(i); }
  int num_roots() const override { return base_.num_roots(); }
  int parameters() const override { return static_cast<int>(plus_.size()); }
  double parameter_scale(int k) const override { return scale_[static_cast<std::size_t>(k)]; }

  void parameter_derivatives(double t, const double* x, double* dfdp) override {
    const int m = size();
    for (std::size_t k = 0; k < plus_.size(); ++k) {
      plus_[k]->rhs(t, x, f_plus_.data());
      minus_[k]->rhs(t, x, f_minus_.data());
      for (int i = 0; i < m; ++i) dfdp[k * static_cast<std::size_t>(m) + i] = (f_plus_[i] - f_minus_[i]) / width_[k];
    }
  }
  void initial_sensitivities(double* s0) const override {
    const int m = size();
    std::vector<double> up(static_cast<std::size_t>(m)), down(static_cast<std::size_t>(m));
    for (std::size_t k = 0; k < plus_.size(); ++k) {
      plus_[k]->initial_state(up.data());
      minus_[k]->initial_state(down.data());
      for (int i = 0; i < m; ++i) s0[k * static_cast<std::size_t>(m) + i] = (up[i] - down[i]) / width_[k];
    }
  }
  // The path error e = |p(q) - p_ref(t)| at (t, x) [m] and de/dp_k, from s
  // (dx/dp at t): the flange's motion along s_k by central differences of
  // the forward kinematics (step 1e-6 rad of the largest joint change), the
  // reference point's dp_ref/dp_k by the moved plants' references.
  double path_error(double t, const double* x, const Eigen::MatrixXd& s, Eigen::VectorXd& de) const {
    const std::shared_ptr<const Reference>& ref = base_.config().reference;
    const int m = size();
    ReferenceSample sample;
    const auto ref_point = [&](const Plant& p) {
      return p.config().reference->point(std::min(t, p.config().reference->timing().duration()), sample);
    };
    Eigen::Matrix3d R;
    Eigen::Vector3d flange, up, down;
    base_.tool_pose(x, R, flange);
    const Eigen::Vector3d diff = flange - ref_point(base_);
    const double e = diff.norm();
    de.setZero(parameters());
    if (!ref || e == 0.0) return e;
    std::vector<double> moved(x, x + m);
    for (int k = 0; k < parameters(); ++k) {
      const double largest = s.col(k).cwiseAbs().maxCoeff();
      Eigen::Vector3d dflange = Eigen::Vector3d::Zero();
      if (largest > 0) {
        const double eps = 1e-6 / largest;
        for (int i = 0; i < m; ++i) moved[static_cast<std::size_t>(i)] = x[i] + eps * s(i, k);
        base_.tool_pose(moved.data(), R, up);
        for (int i = 0; i < m; ++i) moved[static_cast<std::size_t>(i)] = x[i] - eps * s(i, k);
        base_.tool_pose(moved.data(), R, down);
        dflange = (up - down) / (2 * eps);
      }
      const std::size_t kk = static_cast<std::size_t>(k);
      const Eigen::Vector3d dref = (ref_point(*plus_[kk]) - ref_point(*minus_[kk])) / width_[kk];
      de[k] = diff.dot(dflange - dref) / e;
    }
    return e;
  }
  bool has_reference() const { return base_.config().reference != nullptr; }

  double next_stop(double t) const override { return base_.next_time_event(t); }
  // A continuous PIV integral at its bound (|Ki z| = integral_limit): its
  // rate switches from e to 0 there, a jump in f that the sensitivities
  // would jump with (windup).
  std::string jump_at(double t, const double* x) const override {
    const auto* piv = std::get_if<LawParams<PivController>>(&base_.config().controller_params);
    const int z = base_.layout().z;
    if (!piv || z < 0) return {};
    for (std::size_t j = 0; j < piv->joints.size(); ++j) {
      const PivParams& P = piv->joints[j];
      if (P.ki == 0) continue;
      const double bound = piv_integral_bound(P), v = x[z + static_cast<int>(j)];
      if (std::abs(v) >= bound * (1 - 1e-9)) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "the PIV integral %s reached its bound %.6g (integral_limit / |Ki|) at t = %.9g s",
                      state_name(z + static_cast<int>(j)).c_str(), bound, t);
        return std::string(buf) +
               ": its rate switches to 0 there (windup), and the sensitivities jump with it, "
               "which this does not apply";
      }
    }
    return {};
  }
  void on_stop(double t, double* x) override {
    base_.on_time_event(t, x, false);
    for (std::size_t k = 0; k < plus_.size(); ++k) {
      for (Plant* p : {plus_[k].get(), minus_[k].get()}) {
        std::copy(x, x + size(), x_copy_.begin());
        p->on_time_event(t, x_copy_.data(), false);
      }
    }
  }

 private:
  Plant base_;
  std::vector<std::unique_ptr<Plant>> plus_, minus_;  // initial_state restarts their discrete state: mutable use
  std::vector<double> width_;                         // p+ - p- as written
  std::vector<double> scale_;                         // |p|, or 1 where p = 0 (CVODES' pbar)
  std::vector<double> f_plus_, f_minus_, x_copy_;
};

void append_number(std::string& s, double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17);
  s.append(buf, r.ptr);
}

}  // namespace

std::string sensitivity_refusal(const Scene& scene) {
  if (std::string why = why_no_ode_form(scene.plant); !why.empty()) return why;  // CVODES integrates ODEs
  const std::string discrete = discrete_state(scene);
  if (!discrete.empty()) {
    return "its right-hand side has discrete state (" + discrete +
           "): the sensitivities jump where it switches, by a saltation matrix this does not apply";
  }
  const std::string note = discontinuity_note(scene);
  if (!note.empty()) return "its right-hand side is discontinuous in the state without events: " + note;
  return {};
}

namespace {

// The run's path-error figures and their sensitivities, over the rows the
// run's own figures take (t = 0 and every output): the RMS's, d rms/dp =
// sum e de/dp / (rows rms), and the maximum's, de/dp at its row (a
// one-sided derivative where two rows tie).
void path_error_sensitivities(const PlantSensitivity& sys, const std::vector<double>& x0, SceneSensitivities& out) {
  const int p = sys.parameters();
  Eigen::MatrixXd s0(sys.size(), p);
  sys.initial_sensitivities(s0.data());
  Eigen::VectorXd de(p), sum = Eigen::VectorXd::Zero(p), at_max = Eigen::VectorXd::Zero(p);
  double sum_sq = 0, max = -1;
  const auto add = [&](double t, const double* x, const Eigen::MatrixXd& s) {
    const double e = sys.path_error(t, x, s, de);
    sum_sq += e * e, sum += e * de;
    if (e > max) max = e, at_max = de;
  };
  add(0.0, x0.data(), s0);
  for (std::size_t r = 0; r < out.run.t.size(); ++r) add(out.run.t[r], out.run.x[r].data(), out.run.s[r]);
  const double rows = static_cast<double>(out.run.t.size() + 1), rms = std::sqrt(sum_sq / rows);
  out.max_path_error = max, out.rms_path_error = rms;
  out.d_max_path_error = std::vector<double>(at_max.data(), at_max.data() + p);
  const Eigen::VectorXd d_rms = rms > 0 ? Eigen::VectorXd(sum / (rows * rms)) : Eigen::VectorXd::Zero(p);
  out.d_rms_path_error = std::vector<double>(d_rms.data(), d_rms.data() + p);
}

}  // namespace

struct SensitivityPlan {
  SceneSensitivities out;  // the keys, their values and steps, the state names
  std::unique_ptr<PlantSensitivity> sys;
};

std::shared_ptr<SensitivityPlan> plan_sensitivities(const Scene& scene, const std::vector<std::string>& keys,
                                                    double relative_step) {
  if (keys.empty()) throw std::invalid_argument("--sensitivity: expected at least one scene key");
  const std::string why = sensitivity_refusal(scene);
  if (!why.empty()) throw std::invalid_argument("--sensitivity: the scene is refused: " + why);
  auto plan = std::make_shared<SensitivityPlan>();
  plan->sys = std::make_unique<PlantSensitivity>(scene, keys, relative_step, plan->out);
  for (int i = 0; i < plan->sys->size(); ++i) plan->out.state_names.push_back(plan->sys->state_name(i));
  return plan;
}

SceneSensitivities scene_sensitivities(SensitivityPlan& plan, const Scene& scene, const RunControls& controls) {
  PlantSensitivity& sys = *plan.sys;
  SceneSensitivities out = plan.out;
  std::vector<double> x0(static_cast<std::size_t>(sys.size()));
  sys.plant().initial_state(x0.data());
  std::vector<double> outputs;
  const double dt = scene.output_interval, t_end = scene.duration;
  for (long k = 1; k * dt < t_end * (1 - 1e-12); ++k) outputs.push_back(k * dt);
  outputs.push_back(t_end);
  SensitivityOptions o;
  o.rtol = controls.options.rtol, o.atol = controls.options.atol;
  if (controls.max_steps > 0) o.max_steps = controls.max_steps;  // in all, as the run's budget
  out.run = sensitivity_run(sys, 0.0, x0.data(), outputs, o);
  if (sys.has_reference() && out.run.ok) path_error_sensitivities(sys, x0, out);
  return out;
}

std::string sensitivity_csv(const SceneSensitivities& s) {
  std::string text = "t";
  for (const std::string& n : s.state_names) text += "," + n;
  for (const std::string& k : s.keys) {
    for (const std::string& n : s.state_names) text += ",d" + n + "/d" + k;
  }
  text += "\n";
  for (std::size_t r = 0; r < s.run.t.size(); ++r) {
    append_number(text, s.run.t[r]);
    for (Eigen::Index i = 0; i < s.run.x[r].size(); ++i) text += ",", append_number(text, s.run.x[r][i]);
    const Eigen::MatrixXd& S = s.run.s[r];
    for (Eigen::Index k = 0; k < S.cols(); ++k) {
      for (Eigen::Index i = 0; i < S.rows(); ++i) text += ",", append_number(text, S(i, k));
    }
    text += "\n";
  }
  return text;
}

std::string sensitivity_json(const SceneSensitivities& s, double rtol, double atol) {
  nlohmann::ordered_json js;
  js["keys"] = s.keys;
  js["values"] = s.values;
  js["difference_steps"] = s.steps;
  js["method"] =
      "cvodes BDF, staggered corrector, sensitivities in the error test; the plant's exact Jacobian; "
      "df/dp by central differences of f";
  js["rtol"] = rtol, js["atol"] = atol;
  js["ok"] = s.run.ok;
  js["failure"] = s.run.failure;
  js["t_final"] = s.run.t.empty() ? 0.0 : s.run.t.back();
  if (!s.d_rms_path_error.empty()) {  // [mm] and [mm per unit of each key]
    js["max_path_error_mm"] = 1e3 * s.max_path_error, js["rms_path_error_mm"] = 1e3 * s.rms_path_error;
    nlohmann::ordered_json dmax = nlohmann::ordered_json::object(), drms = nlohmann::ordered_json::object();
    for (std::size_t k = 0; k < s.keys.size(); ++k) {
      dmax[s.keys[k]] = 1e3 * s.d_max_path_error[k], drms[s.keys[k]] = 1e3 * s.d_rms_path_error[k];
    }
    js["d_max_path_error_mm"] = std::move(dmax), js["d_rms_path_error_mm"] = std::move(drms);
  }
  js["final_state"] = nlohmann::ordered_json::object();
  if (!s.run.s.empty()) {
    for (std::size_t k = 0; k < s.keys.size(); ++k) {
      nlohmann::ordered_json col = nlohmann::ordered_json::object();
      for (std::size_t i = 0; i < s.state_names.size(); ++i) {
        const double v = s.run.s.back()(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
        col[s.state_names[i]] = std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
      }
      js["final_state"][s.keys[k]] = std::move(col);
    }
  }
  js["steps"] = s.run.stats.steps;
  js["rhs_evaluations"] = s.run.stats.rhs_evaluations;
  js["sensitivity_rhs_evaluations"] = s.run.sensitivity_rhs;
  js["jacobian_evaluations"] = s.run.stats.jacobian_evaluations;  // CVODES' Newton matrices
  js["sensitivity_rhs_jacobians"] = s.run.sensitivity_jacobians;  // the exact J in the sensitivities' rhs
  js["sensitivity_error_test_failures"] = s.run.sensitivity_error_test_failures;
  js["restarts"] = s.run.stats.restarts;
  js["wall_time_s"] = s.run.wall_time;
  return js.dump(2);
}

}  // namespace pumasim
