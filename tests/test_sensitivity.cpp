// Forward sensitivities by CVODES (integrators/sensitivity.hpp) against
// closed forms: a scalar linear ODE with time-dependent forcing, and the DC
// motor's two-state linear model, whose sensitivity to its resistance is a
// block of one matrix exponential (Van Loan, "Computing integrals involving
// the matrix exponential", IEEE TAC 23(3), 1978), computed by Eigen's Pade
// scaling and squaring, independently of the integrator.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <unsupported/Eigen/MatrixFunctions>

#include "integrators/sensitivity.hpp"
#include "models/plant/plant.hpp"
#include "simulation/run.hpp"
#include "simulation/sensitivity.hpp"
#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

// x' = -a x + b cos t, x(0) = x0; p = (a, b).
class ForcedDecay final : public SensitivitySystem {
 public:
  ForcedDecay(double a, double b) : a_(a), b_(b) {}
  int size() const override { return 1; }
  int parameters() const override { return 2; }
  void rhs(double t, const double* x, double* f) override { f[0] = -a_ * x[0] + b_ * std::cos(t); }
  void jacobian(double, const double*, Eigen::MatrixXd& J) override { J(0, 0) = -a_; }
  bool has_exact_jacobian() const override { return true; }
  void parameter_derivatives(double t, const double* x, double* dfdp) override {
    dfdp[0] = -x[0], dfdp[1] = std::cos(t);
  }
  double parameter_scale(int k) const override { return k == 0 ? a_ : b_; }

 private:
  double a_, b_;
};

// x(t) = (x0 - b a / (1 + a^2)) e^{-a t} + b (a cos t + sin t) / (1 + a^2),
// and its derivatives in a and b, by hand.
struct ForcedDecayExact {
  double a, b, x0;
  double x(double t) const {
    const double k = 1 + a * a;
    return (x0 - b * a / k) * std::exp(-a * t) + b * (a * std::cos(t) + std::sin(t)) / k;
  }
  double dx_da(double t) const {
    const double k = 1 + a * a, e = std::exp(-a * t);
    return -b * (1 - a * a) / (k * k) * e - t * (x0 - b * a / k) * e +
           b * (std::cos(t) * k - 2 * a * (a * std::cos(t) + std::sin(t))) / (k * k);
  }
  double dx_db(double t) const {
    const double k = 1 + a * a;
    return -a / k * std::exp(-a * t) + (a * std::cos(t) + std::sin(t)) / k;
  }
};

TEST(Sensitivity, ScalarLinearOdeWithForcingMatchesItsClosedForm) {
  const ForcedDecayExact exact{0.7, 1.3, 2.0};
  ForcedDecay sys(exact.a, exact.b);
  const std::vector<double> outputs = {0.5, 1.0, 2.0, 5.0, 10.0};
  const SensitivityRun run = sensitivity_run(sys, 0.0, &exact.x0, outputs, {.rtol = 1e-10, .atol = 1e-12});
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.t.size(), outputs.size());
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const double t = outputs[i];
    EXPECT_DOUBLE_EQ(run.t[i], t);
    // Global errors of a 1e-10 tolerance, with margin for their accumulation over 10 s.
    EXPECT_NEAR(run.x[i][0], exact.x(t), 1e-8) << t;
    EXPECT_NEAR(run.s[i](0, 0), exact.dx_da(t), 1e-7) << t;
    EXPECT_NEAR(run.s[i](0, 1), exact.dx_db(t), 1e-7) << t;
  }
  EXPECT_GT(run.sensitivity_rhs, 0);
}

// The DC motor: L di/dt = V - R i - Ke w, Jm dw/dt = Kt i - B w, a constant
// voltage; p = (R, Kt).
class DcMotor final : public SensitivitySystem {
 public:
  double L = 2e-3, R = 1.6, Ke = 0.19, Kt = 0.19, Jm = 2e-4, B = 1e-4, V = 12.0;
  int size() const override { return 2; }
  int parameters() const override { return 2; }
  void rhs(double, const double* x, double* f) override {
    f[0] = (V - R * x[0] - Ke * x[1]) / L;
    f[1] = (Kt * x[0] - B * x[1]) / Jm;
  }
  void jacobian(double, const double*, Eigen::MatrixXd& J) override { J = A(); }
  bool has_exact_jacobian() const override { return true; }
  void parameter_derivatives(double, const double* x, double* dfdp) override {
    dfdp[0] = -x[0] / L, dfdp[1] = 0.0;  // d/dR
    dfdp[2] = 0.0, dfdp[3] = x[0] / Jm;  // d/dKt
  }
  double parameter_scale(int k) const override { return k == 0 ? R : Kt; }
  Eigen::Matrix2d A() const {
    Eigen::Matrix2d a;
    a << -R / L, -Ke / L, Kt / Jm, -B / Jm;
    return a;
  }
};

// z = (x, dx/dR, dx/dKt, 1): z' = M z with M = [A 0 0 b; dA/dR A 0 0;
// dA/dKt 0 A 0; 0 0 0 0], so z(t) = exp(M t) z(0).
Eigen::VectorXd motor_closed_form(const DcMotor& m, double t) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(7, 7);
  const Eigen::Matrix2d A = m.A();
  Eigen::Matrix2d dA_dR = Eigen::Matrix2d::Zero(), dA_dKt = Eigen::Matrix2d::Zero();
  dA_dR(0, 0) = -1 / m.L;
  dA_dKt(1, 0) = 1 / m.Jm;
  M.block<2, 2>(0, 0) = A, M.block<2, 2>(2, 2) = A, M.block<2, 2>(4, 4) = A;
  M.block<2, 2>(2, 0) = dA_dR, M.block<2, 2>(4, 0) = dA_dKt;
  M(0, 6) = m.V / m.L;
  Eigen::VectorXd z0 = Eigen::VectorXd::Zero(7);
  z0[6] = 1;
  return (M * t).exp() * z0;
}

TEST(Sensitivity, DcMotorMatchesTheMatrixExponential) {
  DcMotor motor;
  const double x0[2] = {0.0, 0.0};
  const std::vector<double> outputs = {1e-3, 5e-3, 0.02, 0.1, 0.5};
  const SensitivityRun run = sensitivity_run(motor, 0.0, x0, outputs, {.rtol = 1e-10, .atol = 1e-12});
  ASSERT_TRUE(run.ok) << run.failure;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const Eigen::VectorXd z = motor_closed_form(motor, outputs[i]);
    const Eigen::Vector2d x = z.head<2>(), dR = z.segment<2>(2), dKt = z.segment<2>(4);
    EXPECT_LE((run.x[i] - x).norm(), 1e-8 * x.norm()) << outputs[i];
    EXPECT_LE((run.s[i].col(0) - dR).norm(), 1e-7 * dR.norm()) << outputs[i];
    EXPECT_LE((run.s[i].col(1) - dKt).norm(), 1e-7 * dKt.norm()) << outputs[i];
  }
}

// The forced decay with its forcing switched off at a stop: f jumps in t
// there (b cos t to 0) at a time that does not depend on p, so s stays
// continuous, and the closed form continues from the stop with b = 0.
class SwitchedDecay final : public SensitivitySystem {
 public:
  double a = 0.7, b = 1.3, t_off = 1.5;
  bool on = true;
  int size() const override { return 1; }
  int parameters() const override { return 1; }
  void rhs(double t, const double* x, double* f) override { f[0] = -a * x[0] + (on ? b * std::cos(t) : 0.0); }
  void jacobian(double, const double*, Eigen::MatrixXd& J) override { J(0, 0) = -a; }
  bool has_exact_jacobian() const override { return true; }
  void parameter_derivatives(double t, const double*, double* dfdp) override {
    dfdp[0] = on ? std::cos(t) : 0.0;  // p = b
  }
  double next_stop(double t) const override { return t < t_off ? t_off : std::numeric_limits<double>::infinity(); }
  void on_stop(double, double*) override { on = false; }
};

TEST(Sensitivity, RestartsAtAStopWhereTheRightHandSideKinks) {
  SwitchedDecay sys;
  const double x0 = 2.0;
  const SensitivityRun run = sensitivity_run(sys, 0.0, &x0, {3.0}, {.rtol = 1e-10, .atol = 1e-12});
  ASSERT_TRUE(run.ok) << run.failure;
  EXPECT_EQ(run.stats.restarts, 1);
  // Past the stop, x' = -a x: x(3) = x(t_off) e^{-a (3 - t_off)}, and so its derivative in b.
  const ForcedDecayExact before{sys.a, sys.b, x0};
  const double decay = std::exp(-sys.a * (3.0 - sys.t_off));
  EXPECT_NEAR(run.x[0][0], before.x(sys.t_off) * decay, 1e-8);
  EXPECT_NEAR(run.s[0](0, 0), before.dx_db(sys.t_off) * decay, 1e-7);
}

class WithRoots final : public SensitivitySystem {
 public:
  int size() const override { return 1; }
  int parameters() const override { return 1; }
  int num_roots() const override { return 1; }
  void rhs(double, const double* x, double* f) override { f[0] = -x[0]; }
  void parameter_derivatives(double, const double*, double* dfdp) override { dfdp[0] = 0.0; }
};

TEST(Sensitivity, RefusesASystemWithEventsAndSaysWhy) {
  WithRoots sys;
  const double x0 = 1.0;
  const SensitivityRun run = sensitivity_run(sys, 0.0, &x0, {1.0}, {});
  EXPECT_FALSE(run.ok);
  EXPECT_NE(run.failure.find("saltation"), std::string::npos) << run.failure;
}

// A plain run's final state (rtol 1e-10) with `key` set to `value`.
std::vector<double> final_state(const std::string& scene, const std::string& key, double value, double t_end) {
  RunRequest r;
  r.file = test::scene_path(scene);
  char set[96];
  std::snprintf(set, sizeof set, "%s=%.17g", key.c_str(), value);
  r.sets = {set};
  r.options.integrator = "cvode-bdf";
  r.options.rtol = 1e-10, r.options.atol = 1e-12, r.options.t_end = t_end;
  r.stats = false;
  const RunRecord rec = run(r);
  EXPECT_TRUE(rec.run.result.ok) << rec.run.result.failure;
  return rec.run.figures.final_state;
}

// The scene's sensitivities against central differences of whole runs,
// (x(T; p + d) - x(T; p - d)) / 2d with d = 1e-2 |p|, compared as p s_i /
// scale_i (the change of x_i in units of its typical magnitude, the
// integrators' own scale, per relative change of p), over 2.5 s: across the
// reference's first breakpoint (1.92 s), a restart of both. The differences'
// error in that measure: the runs' integration errors (rtol 1e-10, atol 1e-12
// of the scale) over 2d / |p| = 0.02, about 5e-9 (|x_i| / scale_i + 1);
// their truncation, O((d/p)^2) = 1e-4 of the third derivative (a tenfold
// smaller d moved the comparison by less than it moved the noise); the
// sensitivities' own at rtol 1e-9, about 1e-9. The bound: that budget with
// the largest |x_i| / scale_i here, about 10, i.e. 5e-8, and at most 1e-3 of
// the key's largest sensitivity, so that a small one is held to its size.
TEST(SceneSensitivity, MatchesCentralDifferencesOfWholeRuns) {
  const double t_end = 2.5;
  RunRequest r;
  r.file = test::scene_path("paper_slow_viscous");
  r.options.integrator = "cvode-bdf";
  r.options.rtol = 1e-9, r.options.atol = 1e-11, r.options.t_end = t_end;
  r.options.sensitivity = {"motor.resistance", "motor.inductance"};
  r.stats = false;
  const RunRecord rec = run(r);
  ASSERT_TRUE(rec.sensitivities.has_value());
  const SceneSensitivities& s = *rec.sensitivities;
  ASSERT_TRUE(s.run.ok) << s.run.failure;
  EXPECT_DOUBLE_EQ(s.run.t.back(), t_end);
  EXPECT_GE(s.run.stats.restarts, 1);  // the breakpoint
  Plant plant(load_checked_scene(test::scene_path("paper_slow_viscous"), {}).plant);
  for (std::size_t k = 0; k < s.keys.size(); ++k) {
    const Eigen::VectorXd col = s.run.s.back().col(static_cast<Eigen::Index>(k));
    const double p = s.values[k], d = 1e-2 * std::abs(p);
    const std::vector<double> up = final_state("paper_slow_viscous", s.keys[k], p + d, t_end);
    const std::vector<double> down = final_state("paper_slow_viscous", s.keys[k], p - d, t_end);
    ASSERT_EQ(static_cast<std::size_t>(col.size()), up.size());
    double worst = 0, largest = 0;
    for (Eigen::Index i = 0; i < col.size(); ++i) {
      const double scale = plant.tolerance_scale(static_cast<int>(i)) / std::abs(p);
      worst = std::max(worst, std::abs(col[i] - (up[i] - down[i]) / (2 * d)) / scale);
      largest = std::max(largest, std::abs(col[i]) / scale);
    }
    EXPECT_LE(worst, std::min(5e-8, 1e-3 * largest)) << s.keys[k] << ": largest " << largest;
  }
}

// The path error's maximum and RMS over the run's rows, and their
// sensitivities, against central differences of whole runs' own figures
// (rtol 1e-10) with d = 1e-3 |p|: small enough that the row where the
// maximum falls stays the same (at d = 1e-2 it moved, and the difference
// of the maxima disagreed by 3 %). The differences' own error: truncation
// O((d/p)^2) = 1e-6 relative; the runs' errors in the figures (1e-10 of
// them) over 2d/p = 2e-3, about 5e-8 relative. Bound: 1e-4 of the
// derivative, as the chain rule's other terms (the flange's motion by
// differences of the kinematics, step 1e-6 rad) are far below it.
TEST(SceneSensitivity, PathErrorFiguresMatchCentralDifferencesOfWholeRuns) {
  const double t_end = 2.5;
  RunRequest r;
  r.file = test::scene_path("paper_slow_viscous");
  r.options.integrator = "cvode-bdf";
  r.options.rtol = 1e-9, r.options.atol = 1e-11, r.options.t_end = t_end;
  r.options.sensitivity = {"motor.resistance"};
  r.stats = false;
  const RunRecord rec = run(r);
  ASSERT_TRUE(rec.sensitivities && rec.sensitivities->run.ok);
  const SceneSensitivities& s = *rec.sensitivities;
  ASSERT_EQ(s.d_max_path_error.size(), 1u);
  // The figures themselves are the run's (the same rows, another integrator run at the same tolerance).
  EXPECT_NEAR(s.max_path_error, rec.run.figures.max_path_error, 1e-6 * rec.run.figures.max_path_error);
  EXPECT_NEAR(s.rms_path_error, rec.run.figures.rms_path_error, 1e-6 * rec.run.figures.rms_path_error);
  const double p = s.values[0], d = 1e-3 * p;
  const auto figures = [&](double value) {
    RunRequest q;
    q.file = test::scene_path("paper_slow_viscous");
    char set[64];
    std::snprintf(set, sizeof set, "motor.resistance=%.17g", value);
    q.sets = {set};
    q.options.integrator = "cvode-bdf";
    q.options.rtol = 1e-10, q.options.atol = 1e-12, q.options.t_end = t_end;
    q.stats = false;
    return run(q).run.figures;
  };
  const RunFigures up = figures(p + d), down = figures(p - d);
  const double dmax = (up.max_path_error - down.max_path_error) / (2 * d);
  const double drms = (up.rms_path_error - down.rms_path_error) / (2 * d);
  EXPECT_NEAR(s.d_max_path_error[0], dmax, 1e-4 * std::abs(dmax));
  EXPECT_NEAR(s.d_rms_path_error[0], drms, 1e-4 * std::abs(drms));
}

// A key that moves the reference's breakpoints (where f jumps in t) is
// refused before the run: its sensitivities would jump there.
TEST(SceneSensitivity, RefusesAKeyThatMovesTheBreakpoints) {
  RunRequest r;
  r.file = test::scene_path("paper_slow_viscous");
  r.options.sensitivity = {"reference.max_speed"};
  try {
    run(r);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("breakpoints"), std::string::npos) << e.what();
  }
}

// A PIV integral reaching its bound (windup: its rate switches to 0, a jump
// in f) ends the sensitivities as a reported failure naming the state.
TEST(SceneSensitivity, WindupEndsTheSensitivitiesAsANamedFailure) {
  RunRequest r;
  r.file = test::scene_path("paper_slow_viscous");
  r.sets = {"controller.integral_limit=[10.0, 0.68, 10.0]"};
  r.options.integrator = "cvode-bdf";
  r.options.t_end = 3.0;
  r.options.sensitivity = {"motor.resistance"};
  r.stats = false;
  const RunRecord rec = run(r);
  ASSERT_TRUE(rec.run.result.ok) << rec.run.result.failure;
  ASSERT_TRUE(rec.sensitivities.has_value());
  EXPECT_FALSE(rec.sensitivities->run.ok);
  EXPECT_NE(rec.sensitivities->run.failure.find("z_piv2"), std::string::npos) << rec.sensitivities->run.failure;
}

TEST(SceneSensitivity, RefusesASceneWithDiscreteStateBeforeItRuns) {
  RunRequest r;
  r.file = test::scene_path("paper_slow_6dof_hybrid");
  r.options.sensitivity = {"motor.resistance"};
  try {
    run(r);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("saltation"), std::string::npos) << e.what();
  }
}

TEST(SceneSensitivity, NamesAKeyThatIsNotARealNumber) {
  RunRequest r;
  r.file = test::scene_path("paper_slow_viscous");
  for (const char* key : {"motor.nonexistent", "reference.arm", "integrator.rtol"}) {
    r.options.sensitivity = {key};
    try {
      run(r);
      ADD_FAILURE() << "expected a refusal of " << key;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace pumasim
