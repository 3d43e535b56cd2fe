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

// The forced decay with its forcing switched off at a stop: f kinks there
// (b cos t to 0), s stays continuous, and the closed form continues from
// the stop with the same formula at b = 0.
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

}  // namespace
}  // namespace pumasim
