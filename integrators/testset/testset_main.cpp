// testset: every registry integrator on every problem of the standard test
// set (integrators/testset/problems.hpp), over a tolerance ladder (adaptive
// methods: rtol, with atol = rtol * the problem's scale per component) or a
// step ladder (fixed-step methods: the problem's dt ladder), each run with a
// step budget and a wall-clock budget so that nothing hangs. Prints CSV to
// stdout, one row per run; the error is measured at the end point against the
// published reference value.
//
//   testset [--reduced] [--problem NAME]... [--integrator NAME]...
//           [--max-steps N] [--max-seconds S] [--list-problems]
//
// A run that cannot finish is a row with ok = 0 and the failure's message,
// never a missing row. Once a method has exhausted a budget on a problem, its
// runs that would need more work (tighter rtol, smaller dt) are reported as
// not run, with the reason, rather than spent against the same budget again.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "integrators/integrator.hpp"
#include "integrators/registry.hpp"
#include "integrators/testset/problems.hpp"

namespace {

using pumasim::Integrator;
using pumasim::IntegratorOptions;
using pumasim::OdeSystem;
using pumasim::Outcome;
using pumasim::testset::Problem;
using Clock = std::chrono::steady_clock;

struct BudgetExceeded : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Forwards to the problem, counts the right-hand sides the integrator asks
// for, and ends the run (by an exception, which every adapter passes on)
// once its wall-clock budget is spent. Only rhs and jacobian are checked, so
// the integrator's own sequence of steps is untouched.
class Guarded final : public OdeSystem {
 public:
  Guarded(Problem& p, double seconds) : p_(p), seconds_(seconds), start_(Clock::now()) {}
  int size() const override { return p_.size(); }
  void rhs(double t, const double* x, double* f) override {
    if ((++calls_ & 255) == 0) check();
    p_.rhs(t, x, f);
  }
  void jacobian(double t, const double* x, Eigen::MatrixXd& J) override {
    check();
    p_.jacobian(t, x, J);
  }
  bool has_exact_jacobian() const override { return p_.has_exact_jacobian(); }
  int time_derivative(double t, const double* x, double* dfdt) override { return p_.time_derivative(t, x, dfdt); }
  void rhs_split(double t, const double* x, double* fe, double* fi) override { p_.rhs_split(t, x, fe, fi); }
  void linear_diagonal(double* lambda) const override { p_.linear_diagonal(lambda); }
  std::string state_name(int i) const override { return p_.state_name(i); }
  double tolerance_scale(int i) const override { return p_.tolerance_scale(i); }
  long calls() const { return calls_; }

 private:
  void check() const {
    if (std::chrono::duration<double>(Clock::now() - start_).count() > seconds_) {
      char b[96];
      std::snprintf(b, sizeof b, "wall-clock budget of %g s exhausted", seconds_);
      throw BudgetExceeded(b);
    }
  }
  Problem& p_;
  double seconds_;
  Clock::time_point start_;
  long calls_ = 0;
};

struct Config {
  bool reduced = false;
  std::vector<std::string> problems, integrators;
  long max_steps = 0;     // 0: the mode's default
  double max_seconds = 0;  // 0: the mode's default
};

struct Row {
  std::string problem, integrator, kind, jacobian;
  double setting = 0;
  bool ok = false;
  std::string message;
  double mixed = NAN, absolute = NAN, scd = NAN;
  long steps = 0, rhs = 0, rhs_counted = 0, jac = 0, lin = 0, rejected = 0;
  double wall = 0;
};

std::string csv_text(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return q + "\"";
}

std::string num(double v) {
  if (std::isnan(v)) return "";
  char b[40];
  std::snprintf(b, sizeof b, "%.6e", v);
  return b;
}

void print_header() {
  std::cout << "problem,integrator,kind,setting,ok,message,mixed_error,abs_error,scd,steps,rhs_evaluations,"
               "jacobian_evaluations,rejected_steps,wall_time_s,linear_solves,rhs_calls_counted,jacobian\n";
}

void print(const Row& r) {
  std::cout << r.problem << ',' << r.integrator << ',' << r.kind << ',' << num(r.setting) << ',' << (r.ok ? 1 : 0)
            << ',' << csv_text(r.message) << ',' << num(r.mixed) << ',' << num(r.absolute) << ',' << num(r.scd)
            << ',' << r.steps << ',' << r.rhs << ',' << r.jac << ',' << r.rejected << ',' << num(r.wall) << ','
            << r.lin << ',' << r.rhs_counted << ',' << r.jacobian << '\n';
  std::cout.flush();
}

// One run of `name` on `p` with options `o`, within the budgets.
Row run(Problem& p, const pumasim::IntegratorInfo& info, bool adaptive, double setting, long max_steps,
        double max_seconds) {
  Row r;
  r.problem = p.name();
  r.integrator = info.name;
  r.kind = adaptive ? "adaptive" : "fixed";
  r.setting = setting;
  IntegratorOptions o;
  o.max_steps = max_steps;
  if (adaptive) {
    o.rtol = setting;
    o.atol = setting;  // times the problem's tolerance_scale(i)
  } else {
    o.dt = setting;
  }
  std::unique_ptr<Integrator> integ;
  Guarded sys(p, max_seconds);
  const auto start = Clock::now();
  try {
    integ = info.make(o);
    // Every problem has its exact Jacobian; the methods that can take it do
    // (IntegratorOptions' default), arkode-imex forms its own differences.
    r.jacobian = jacobian_used(integ->capabilities(), o);
    integ->reset(sys, p.t0(), p.initial_value().data());
    const Outcome out = integ->advance_to(p.t_end());
    if (out.status == Outcome::kFailed) {
      r.message = out.message;
    } else if (out.status == Outcome::kRoot || integ->time() != p.t_end()) {
      r.message = "stopped at t = " + num(integ->time()) + " before the end " + num(p.t_end());
    } else {
      const auto e = pumasim::testset::end_error(p, integ->state());
      if (!std::isfinite(e.mixed)) {
        r.message = "non-finite state at the end: " + p.state_name(e.worst) + " = " + num(integ->state()[e.worst]);
      } else {
        r.ok = true;
        r.mixed = e.mixed, r.absolute = e.absolute, r.scd = e.scd;
      }
    }
  } catch (const std::exception& ex) {
    r.message = ex.what();
  }
  r.wall = std::chrono::duration<double>(Clock::now() - start).count();
  if (integ) {
    const auto& s = integ->stats();
    r.steps = s.steps, r.rhs = s.rhs_evaluations, r.jac = s.jacobian_evaluations;
    r.lin = s.linear_solves, r.rejected = s.rejected_steps;
  }
  r.rhs_counted = sys.calls();
  return r;
}

bool budget_failure(const Row& r) {
  const auto has = [&](const char* s) { return r.message.find(s) != std::string::npos; };
  return !r.ok && (has("budget") || has("too many steps") || has("TOO_MUCH_WORK") || has("mxstep"));
}

std::vector<double> reduce(const std::vector<double>& v) {
  if (v.size() <= 2) return v;
  const std::size_t i = v.size() / 2 - 1;  // the two in the middle of the ladder
  return {v[i], v[i + 1]};
}

int usage(const char* why) {
  std::cerr << "testset: " << why << "\n"
            << "usage: testset [--reduced] [--problem NAME]... [--integrator NAME]... [--max-steps N] "
               "[--max-seconds S] [--list-problems]\n"
            << "problems: " << pumasim::testset::problem_names() << "\n"
            << "integrators: " << pumasim::integrator_names() << "\n";
  return 2;
}

// Values separated by spaces, at full precision (17 significant digits) when `exact`.
template <class Values>
std::string spaced(const Values& v, bool exact) {
  std::string s;
  char buf[32];
  for (double d : v) {
    if (!s.empty()) s += ' ';
    if (exact) {
      std::snprintf(buf, sizeof buf, "%.17g", d);
      s += buf;
    } else {
      s += num(d);
    }
  }
  return s;
}

// The problems, with their initial values and references at full precision
// (experiments/radau_scipy.py reads them, to run scipy on the same problems).
void list_problems() {
  std::cout << "problem,equations,stiff,t_end,atol_per_rtol,fixed_steps,description,reference_source,initial_value,"
               "reference\n";
  for (const auto& p : pumasim::testset::make_problems()) {
    const Eigen::VectorXd& y0 = p->initial_value();
    const Eigen::VectorXd& yr = p->reference();
    std::cout << p->name() << ',' << p->size() << ',' << (p->stiff() ? 1 : 0) << ',' << num(p->t_end()) << ','
              << num(p->tolerance_scale(0)) << ',' << spaced(p->fixed_steps(), false) << ','
              << csv_text(p->description()) << ',' << csv_text(p->reference_source()) << ','
              << spaced(std::vector<double>(y0.data(), y0.data() + y0.size()), true) << ','
              << spaced(std::vector<double>(yr.data(), yr.data() + yr.size()), true) << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  Config cfg;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument("expected a value after " + a);
        return argv[++i];
      };
      if (a == "--reduced") {
        cfg.reduced = true;
      } else if (a == "--problem") {
        cfg.problems.push_back(pumasim::testset::make_problem(value())->name());
      } else if (a == "--integrator") {
        cfg.integrators.push_back(pumasim::find_integrator(value()).name);
      } else if (a == "--max-steps") {
        cfg.max_steps = std::stol(value());
        if (cfg.max_steps <= 0) throw std::invalid_argument("expected --max-steps > 0");
      } else if (a == "--max-seconds") {
        cfg.max_seconds = std::stod(value());
        if (!(cfg.max_seconds > 0)) throw std::invalid_argument("expected --max-seconds > 0");
      } else if (a == "--list-problems") {
        list_problems();
        return 0;
      } else if (a == "--help" || a == "-h") {
        usage("the standard ODE test set over the integrator registry; CSV on stdout");
        return 0;
      } else {
        throw std::invalid_argument("unknown option '" + a + "'");
      }
    }
  } catch (const std::exception& e) {
    return usage(e.what());
  }

  // Budgets per run. Steps: 1e7 for the adaptive methods, 1e8 for the fixed
  // ones (every ladder step at which a method is stable fits in it, ROBER's
  // 4e14 do not); the reduced set (CI) a tenth. Wall clock: a guard against
  // hangs, 60 s (reduced 2 s), not the limit that decides a run.
  const long adaptive_steps = cfg.max_steps > 0 ? cfg.max_steps : cfg.reduced ? 1'000'000 : 10'000'000;
  const long fixed_steps = cfg.max_steps > 0 ? cfg.max_steps : cfg.reduced ? 10'000'000 : 100'000'000;
  const double max_seconds = cfg.max_seconds > 0 ? cfg.max_seconds : cfg.reduced ? 2.0 : 60.0;
  const std::vector<double> rtols = cfg.reduced ? std::vector<double>{1e-4, 1e-7}
                                                : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  const auto selected = [](const std::vector<std::string>& chosen, const std::string& name) {
    if (chosen.empty()) return true;
    for (const auto& c : chosen)
      if (c == name) return true;
    return false;
  };

  print_header();
  for (auto& p : pumasim::testset::make_problems()) {
    if (!selected(cfg.problems, p->name())) continue;
    for (const auto& info : pumasim::integrators()) {
      if (!selected(cfg.integrators, info.name)) continue;
      if (info.conservative_only) continue;  // the test set's problems are no mechanical systems
      const bool adaptive = info.kind == pumasim::IntegratorKind::kAdaptive;
      const std::vector<double> settings = adaptive ? rtols : cfg.reduced ? reduce(p->fixed_steps()) : p->fixed_steps();
      std::string exhausted;  // the setting at which a budget ran out
      for (double s : settings) {
        Row r;
        if (!exhausted.empty()) {
          r.problem = p->name(), r.integrator = info.name, r.kind = adaptive ? "adaptive" : "fixed";
          r.setting = s;
          r.jacobian = "";
          r.message = "not run: the budget ran out at the looser setting " + exhausted;
        } else {
          r = run(*p, info, adaptive, s, adaptive ? adaptive_steps : fixed_steps, max_seconds);
          if (budget_failure(r)) exhausted = num(s);
        }
        print(r);
        std::cerr << p->name() << ' ' << info.name << ' ' << num(s) << (r.ok ? " ok " : " FAILED ") << num(r.wall)
                  << " s\n";
      }
    }
  }
  return 0;
}
