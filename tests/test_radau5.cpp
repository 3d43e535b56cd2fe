// Radau IIA of order 5 (integrators/radau5.cpp) checked against closed forms:
// its coefficients against Hairer & Wanner, Solving ODEs II, Sec. IV.5
// (Table 5.6, the simplifying conditions B(5), C(3)) and Sec. IV.8 (A^-1's
// eigenvalues, the error estimate's weights); one step on y' = lambda y
// against the method's stability function, the (2,3) Pade approximant of
// exp (Sec. IV.5: Radau IIA with s stages has the (s-1, s) Pade
// approximant as its stability function); its order 5
// at a constant step on Prothero-Robinson, whose solution is known; the
// dense output exact on a cubic solution (collocation of degree 3); and the
// adaptive method ending within 10 rtol on stiff Prothero-Robinson. The
// registry-wide suites (conformance, with the error proportional to the
// tolerance; roots; the plant scenes) run it as every other method.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "integrators/radau5.hpp"
#include "integrators/registry.hpp"
#include "integrators/testset/problems.hpp"

namespace pumasim {
namespace {

// Sum_j a_ij c_j^(k-1) = c_i^k / k for k = 1..3 (C(3), stage order 3), and
// sum_i b_i c_i^(k-1) = 1/k for k = 1..5 (B(5), quadrature order 5), b the
// last row of A: Hairer & Wanner II, Sec. IV.5, (5.3) and Thm. 5.3.
TEST(Radau5Tableau, SatisfiesTheSimplifyingConditions) {
  const Radau5Tableau& t = radau5_tableau();
  for (int k = 1; k <= 3; ++k) {
    for (int i = 0; i < 3; ++i) {
      double s = 0;
      for (int j = 0; j < 3; ++j) s += t.A(i, j) * std::pow(t.c(j), k - 1);
      EXPECT_NEAR(s, std::pow(t.c(i), k) / k, 1e-15) << "C(3), k = " << k << ", row " << i;
    }
  }
  for (int k = 1; k <= 5; ++k) {
    double s = 0;
    for (int j = 0; j < 3; ++j) s += t.A(2, j) * std::pow(t.c(j), k - 1);
    EXPECT_NEAR(s, 1.0 / k, 1e-15) << "B(5), k = " << k;
  }
  // B(6) fails: the order is 5, not more.
  double s6 = 0;
  for (int j = 0; j < 3; ++j) s6 += t.A(2, j) * std::pow(t.c(j), 5);
  EXPECT_GT(std::abs(s6 - 1.0 / 6), 1e-4);
}

// A's eigenvalues in closed form, as RADAU5 computes them (Hairer & Wanner
// II, Sec. IV.8): 1/gamma = (6 + 81^(1/3) - 9^(1/3)) / 30 and the pair
// (12 - 81^(1/3) + 9^(1/3)) / 60 +- i sqrt 3 (81^(1/3) + 9^(1/3)) / 60;
// A^-1's are their inverses. T^-1 A^-1 T is the block form the Newton
// systems rely on, and the error weights are gamma (b^ - b)^T A^-1 =
// (-(13 + 7 sqrt 6)/3, (-13 + 7 sqrt 6)/3, -1/3) (Sec. IV.8, (8.20), with
// gamma0 = 1/gamma).
TEST(Radau5Tableau, TransformationAndErrorWeightsMatchTheClosedForms) {
  const Radau5Tableau& t = radau5_tableau();
  const double c81 = std::cbrt(81.0), c9 = std::cbrt(9.0);
  const double u1 = (6 + c81 - c9) / 30;
  const std::complex<double> pair((12 - c81 + c9) / 60, (c81 + c9) * std::sqrt(3.0) / 60);
  const std::complex<double> inv = 1.0 / pair;
  EXPECT_NEAR(t.gamma, 1 / u1, 1e-13);
  EXPECT_NEAR(t.alpha, inv.real(), 1e-13);
  EXPECT_NEAR(t.beta, std::abs(inv.imag()), 1e-13);
  Eigen::Matrix3d lambda = Eigen::Matrix3d::Zero();
  lambda(0, 0) = t.gamma;
  lambda(1, 1) = lambda(2, 2) = t.alpha;
  lambda(1, 2) = -t.beta;
  lambda(2, 1) = t.beta;
  EXPECT_LT((t.T_inv * t.A_inv * t.T - lambda).cwiseAbs().maxCoeff(), 1e-13);
  const double s6 = std::sqrt(6.0);
  EXPECT_NEAR(t.dd(0), -(13 + 7 * s6) / 3, 1e-12);
  EXPECT_NEAR(t.dd(1), (-13 + 7 * s6) / 3, 1e-12);
  EXPECT_NEAR(t.dd(2), -1.0 / 3, 1e-12);
}

// y' = L y with L = [a -b; b a] (eigenvalues a +- i b): one step of size h
// maps y0 to R(h lambda) y0, lambda = a + i b, where R is Radau IIA(5)'s
// stability function, the (2,3) Pade approximant of exp,
// R(z) = (1 + 2z/5 + z^2/20) / (1 - 3z/5 + 3z^2/20 - z^3/60)
// (Hairer & Wanner II, Sec. IV.3, the Pade approximations R_kj with k = 2,
// j = 3; Sec. IV.5: Radau IIA's is the (s-1, s) one). Checks the real and
// complex Newton systems and their transformation: the problem is linear,
// so the iteration's first correction is exact. The last case, h lambda =
// -1e8, is L-stability: R(-inf) = 0.
class Rotation : public OdeSystem {
 public:
  Rotation(double a, double b) : a_(a), b_(b) {}
  int size() const override { return 2; }
  void rhs(double, const double* x, double* f) override {
    f[0] = a_ * x[0] - b_ * x[1];
    f[1] = b_ * x[0] + a_ * x[1];
  }
  bool has_exact_jacobian() const override { return true; }
  void jacobian(double, const double*, Eigen::MatrixXd& J) override {
    J.resize(2, 2);
    J << a_, -b_, b_, a_;
  }

 private:
  double a_, b_;
};

std::complex<double> pade_23(std::complex<double> z) {
  return (1.0 + 2.0 * z / 5.0 + z * z / 20.0) / (1.0 - 3.0 * z / 5.0 + 3.0 * z * z / 20.0 - z * z * z / 60.0);
}

TEST(Radau5, OneStepIsTheStabilityFunction) {
  for (const auto& [a, b, h] : {std::tuple{-1.0, 0.5, 0.3}, std::tuple{-1e4, 5e3, 1e-3}, std::tuple{-2.0, 40.0, 0.1},
                                std::tuple{-1e8, 0.0, 1.0}}) {
    Rotation sys(a, b);
    auto integ = make_radau5_fixed_step(h);
    const double y0[2] = {1.0, 0.0};
    integ->reset(sys, 0.0, y0);
    ASSERT_EQ(integ->advance_to(h).status, Outcome::kReached);
    const std::complex<double> r = pade_23({h * a, h * b});  // y = Re/Im of R(z) (1 + 0 i)
    EXPECT_NEAR(integ->state()[0], r.real(), 1e-12 * std::max(1.0, std::abs(r))) << a << " " << b << " " << h;
    EXPECT_NEAR(integ->state()[1], r.imag(), 1e-12 * std::max(1.0, std::abs(r))) << a << " " << b << " " << h;
    EXPECT_EQ(integ->stats().steps, 1);
  }
}

// Order 5 at a constant step on the test set's Prothero-Robinson problem
// (closed form y0 = sin t, y1 = (sin t - cos t + exp(-t)) / 2), lambda = -5:
// halving h divides the end error by 2^5 (within 0.3 in log2).
TEST(Radau5, HasOrderFiveAtAConstantStepOnProtheroRobinson) {
  auto sys = testset::prothero_robinson(-5.0);
  const double T = 6.0;
  double exact[2];
  sys->exact_solution(T, exact);
  std::vector<double> errs;
  for (double h : {0.2, 0.1, 0.05}) {
    auto integ = make_radau5_fixed_step(h);
    integ->reset(*sys, 0.0, sys->initial_value().data());
    ASSERT_EQ(integ->advance_to(T).status, Outcome::kReached);
    errs.push_back(std::max(std::abs(integ->state()[0] - exact[0]), std::abs(integ->state()[1] - exact[1])));
  }
  EXPECT_NEAR(std::log2(errs[0] / errs[1]), 5.0, 0.3) << errs[0] << " " << errs[1];
  EXPECT_NEAR(std::log2(errs[1] / errs[2]), 5.0, 0.3) << errs[1] << " " << errs[2];
}

// y' = 3 t^2 + 2 t + 1 with y(0) = 0 has the cubic solution t^3 + t^2 + t;
// the collocation polynomial (degree 3, through y0 and the three stages) is
// that cubic, so the dense output is exact at every time, in every step.
class Cubic : public OdeSystem {
 public:
  int size() const override { return 1; }
  void rhs(double t, const double*, double* f) override { f[0] = 3 * t * t + 2 * t + 1; }
  bool has_exact_jacobian() const override { return true; }
  void jacobian(double, const double*, Eigen::MatrixXd& J) override { J.setZero(1, 1); }
};

TEST(Radau5, DenseOutputIsExactOnACubic) {
  Cubic sys;
  IntegratorOptions o;
  o.rtol = o.atol = 1e-6;
  auto integ = make_integrator("radau5", o);
  const double y0 = 0.0;
  integ->reset(sys, 0.0, &y0);
  double worst = 0;
  while (integ->time() < 3.0) {
    ASSERT_EQ(integ->step_toward(3.0).status, Outcome::kReached);
    const double a = integ->step_start(), b = integ->time();
    for (double f : {0.1, 0.37, 0.5, 0.81}) {
      const double t = a + f * (b - a);
      double y;
      integ->dense_state(t, &y);
      worst = std::max(worst, std::abs(y - (t * t * t + t * t + t)) / (1 + t * t * t));
    }
  }
  EXPECT_LT(worst, 1e-13);
}

// The adaptive method on stiff Prothero-Robinson (lambda = -1e6): ends within
// 10 rtol of the closed form at every tolerance, its steps far fewer than
// an explicit method's stability limit 2.8 / 1e6 s would allow (a stiff method).
TEST(Radau5, SolvesStiffProtheroRobinsonToItsTolerance) {
  auto sys = testset::prothero_robinson(-1e6);
  const double T = 10.0;
  double exact[2];
  sys->exact_solution(T, exact);
  for (double rtol : {1e-4, 1e-6, 1e-8}) {
    IntegratorOptions o;
    o.rtol = o.atol = rtol;
    auto integ = make_integrator("radau5", o);
    integ->reset(*sys, 0.0, sys->initial_value().data());
    ASSERT_EQ(integ->advance_to(T).status, Outcome::kReached);
    const double err = std::max(std::abs(integ->state()[0] - exact[0]), std::abs(integ->state()[1] - exact[1]));
    EXPECT_LT(err, 10 * rtol) << rtol;
    EXPECT_LT(integ->stats().steps, 10'000) << rtol;
    // One Jacobian serves many steps when the iteration contracts fast.
    EXPECT_LT(integ->stats().jacobian_evaluations, integ->stats().steps) << rtol;
  }
}

}  // namespace
}  // namespace pumasim
