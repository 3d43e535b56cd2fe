// The coefficient sets handed to odeint's rosenbrock4 stepper
// (integrators/rosenbrock_coefficients.hpp), checked against the order
// conditions of Rosenbrock methods rather than against digits copied back:
// a misread or mistyped coefficient breaks an identity below.
//
// odeint steps the transformed form of Hairer & Wanner II, Sec. IV.7, (7.25):
// u_i = sum_j gamma_ij k_j, C = diag(1/gamma) - Gamma^-1, the a_ij of the
// table = alpha Gamma^-1, and stages 5 and 6 at t + h with the stage-6 point
// (a51..a54, 1) and the solutions y1 = y0 + (a51..a54, 1, 1) u (order 4) and
// the embedded (a51..a54, 1, 0) u (order 3). Back to the standard form:
// Gamma = (I/gamma - C)^-1, alpha = A Gamma, b = m Gamma. Order conditions:
// Hairer & Wanner II, Table IV.7.1 (beta_ij = alpha_ij + gamma_ij,
// beta'_i = sum_{j<i} beta_ij); non-autonomous problems also need the d_i of
// h df/dt equal to gamma_i = sum_j gamma_ij (7.4) and c_i = alpha_i.
// Compiled as C++17 like odeint.cpp (Boost 1.74's uBLAS).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include <boost/numeric/odeint.hpp>

#include "integrators/rosenbrock_coefficients.hpp"

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

struct StandardForm {
  double gamma = 0;
  Mat6 Gamma, alpha;
  Vec6 m, d2, d3;       // odeint's weights of u: the solution, and the dense output's (d2j, d3j)
  Vec6 b, bhat;         // order 4 and the embedded order 3
  double d[4], c[3];    // as the table gives them
};

template <class T>
StandardForm standard_form(const T& k) {
  Mat6 C = Mat6::Zero(), A = Mat6::Zero();
  C(1, 0) = k.c21;
  C(2, 0) = k.c31, C(2, 1) = k.c32;
  C(3, 0) = k.c41, C(3, 1) = k.c42, C(3, 2) = k.c43;
  C(4, 0) = k.c51, C(4, 1) = k.c52, C(4, 2) = k.c53, C(4, 3) = k.c54;
  C(5, 0) = k.c61, C(5, 1) = k.c62, C(5, 2) = k.c63, C(5, 3) = k.c64, C(5, 4) = k.c65;
  A(1, 0) = k.a21;
  A(2, 0) = k.a31, A(2, 1) = k.a32;
  A(3, 0) = k.a41, A(3, 1) = k.a42, A(3, 2) = k.a43;
  A(4, 0) = k.a51, A(4, 1) = k.a52, A(4, 2) = k.a53, A(4, 3) = k.a54;
  A.row(5) = A.row(4);
  A(5, 4) = 1;
  Vec6 m, mhat;
  m << k.a51, k.a52, k.a53, k.a54, 1, 1;
  mhat << k.a51, k.a52, k.a53, k.a54, 1, 0;
  StandardForm s;
  s.gamma = k.gamma;
  s.Gamma = (Mat6::Identity() / k.gamma - C).inverse();
  s.alpha = A * s.Gamma;
  s.m = m;
  s.d2 << k.d21, k.d22, k.d23, k.d24, k.d25, 0;
  s.d3 << k.d31, k.d32, k.d33, k.d34, k.d35, 0;
  s.b = s.Gamma.transpose() * m;
  s.bhat = s.Gamma.transpose() * mhat;
  const double d[4] = {k.d1, k.d2, k.d3, k.d4}, c[3] = {k.c2, k.c3, k.c4};
  std::copy(d, d + 4, s.d);
  std::copy(c, c + 3, s.c);
  return s;
}

// Residuals of the order conditions of orders 1..4 (Table IV.7.1) for weights w.
std::vector<double> order_residuals(const StandardForm& s, const Vec6& w) {
  const double g = s.gamma;
  const Vec6 one = Vec6::Ones();
  const Vec6 a = s.alpha * one;                              // alpha_i
  Mat6 Bs = s.alpha + s.Gamma;                               // beta_ij
  Bs.diagonal().setZero();                                   // j < i only
  const Vec6 bp = Bs * one;                                  // beta'_i
  return {
      w.sum() - 1,                                                           // order 1
      w.dot(bp) - (0.5 - g),                                                 // order 2
      w.dot(a.cwiseProduct(a)) - 1.0 / 3,                                    // order 3
      w.dot(Bs * bp) - (1.0 / 6 - g + g * g),                                //
      w.dot(a.cwiseProduct(a).cwiseProduct(a)) - 0.25,                       // order 4
      w.dot(a.cwiseProduct(s.alpha * bp)) - (1.0 / 8 - g / 3),               //
      w.dot(Bs * a.cwiseProduct(a)) - (1.0 / 12 - g / 3),                    //
      w.dot(Bs * (Bs * bp)) - (1.0 / 24 - g / 2 + 1.5 * g * g - g * g * g),  //
  };
}

// odeint's dense output y(theta) = (1 - theta) y0 + theta y1 + theta (1 - theta)
// (cont3 + theta cont4), cont3 = sum_j d2j u_j, cont4 = sum_j d3j u_j, is
// sum_i b_i(theta) k_i with b(theta) = Gamma^T w(theta). Its order-3
// conditions are those of a step theta h taken with the stages of the step h:
// sum b = theta, sum b beta' = theta^2/2 - gamma theta, sum b alpha^2 =
// theta^3/3, sum b beta beta' = theta^3/6 - gamma theta^2 + gamma^2 theta
// (expanding k_i in h as for Table IV.7.1, with the exact solution at theta h).
std::vector<double> dense_residuals(const StandardForm& s, double th) {
  const double g = s.gamma;
  const Vec6 w = th * s.m + th * (1 - th) * (s.d2 + th * s.d3);
  const Vec6 b = s.Gamma.transpose() * w;
  const Vec6 one = Vec6::Ones(), a = s.alpha * one;
  Mat6 Bs = s.alpha + s.Gamma;
  Bs.diagonal().setZero();
  const Vec6 bp = Bs * one;
  return {b.sum() - th, b.dot(bp) - (th * th / 2 - g * th), b.dot(a.cwiseProduct(a)) - th * th * th / 3,
          b.dot(Bs * bp) - (th * th * th / 6 - g * th * th + g * g * th),
          b.dot(a.cwiseProduct(a).cwiseProduct(a)) - th * th * th * th / 4};  // the last: order 4, not required
}

// The stability function at infinity, R(inf) = 1 - w^T B^-1 1 with B = alpha + Gamma.
double r_infinity(const StandardForm& s, const Vec6& w) {
  const Mat6 B = s.alpha + s.Gamma;
  return 1 - w.dot(B.partialPivLu().solve(Vec6::Ones()));
}

template <class T>
void expect_rodas_form(const char* name) {
  const StandardForm s = standard_form(T{});
  const Vec6 gi = s.Gamma * Vec6::Ones(), ai = s.alpha * Vec6::Ones();
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(s.d[i], gi[i], 1e-12) << name << ": d" << i + 1 << " is not gamma_i";
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s.c[i], ai[i + 1], 1e-12) << name << ": c" << i + 2 << " is not alpha_i";
  // odeint gives stages 5 and 6 no h df/dt term and evaluates them at t + h.
  EXPECT_NEAR(gi[4], 0, 1e-12) << name;
  EXPECT_NEAR(gi[5], 0, 1e-12) << name;
  EXPECT_NEAR(ai[4], 1, 1e-12) << name;
  EXPECT_NEAR(ai[5], 1, 1e-12) << name;
  const auto r = order_residuals(s, s.b), rh = order_residuals(s, s.bhat);
  for (std::size_t k = 0; k < r.size(); ++k) EXPECT_NEAR(r[k], 0, 1e-12) << name << ": condition " << k;
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(rh[k], 0, 1e-12) << name << ": embedded, condition " << k;
  double worst = 0;  // the embedded method is of order 3 exactly: some order-4 condition fails
  for (std::size_t k = 4; k < rh.size(); ++k) worst = std::max(worst, std::abs(rh[k]));
  EXPECT_GT(worst, 1e-3) << name;
  // The dense output: order 3 at every theta (and not 4).
  for (const double th : {0.25, 0.5, 0.75}) {
    const auto dr = dense_residuals(s, th);
    for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(dr[k], 0, 1e-12) << name << ": dense output at " << th << ", condition " << k;
    EXPECT_GT(std::abs(dr[4]), 1e-4) << name << ": dense output at " << th;
  }
  // Stiffly accurate, both: L-stable (R(inf) = 0) when A-stable.
  EXPECT_NEAR(r_infinity(s, s.b), 0, 1e-12) << name;
  EXPECT_NEAR(r_infinity(s, s.bhat), 0, 1e-12) << name;
}

TEST(RosenbrockTables, RodasAsShippedWithConsistentDIsOrderFourWithAnOrderThreeEstimate) {
  expect_rodas_form<pumasim::ConsistentRosenbrockCoefficients<double>>("RODAS (d recomputed)");
}

TEST(RosenbrockTables, Rodas4PIsOrderFourWithAnOrderThreeEstimate) {
  expect_rodas_form<pumasim::Rodas4PCoefficients<double>>("Rodas4P");
}

// What Rodas4P was built for: on the Prothero-Robinson problem y' = lambda (y -
// sin t) + cos t in the stiff limit (h |lambda| >> 1), fixed steps from y(0) =
// 0 to t = 1, a Rosenbrock method's global error falls like h^(q+1) rather
// than h^p unless extra conditions hold (J. Rang, "The Prothero and Robinson
// example: convergence studies for Runge-Kutta and Rosenbrock-Wanner
// methods", TU Braunschweig, Informatikbericht 2014-05): RODAS falls like h
// (ratio 2 per halving), Rodas4P like h^3 (ratio 8; G. Steinebach, TH
// Darmstadt Preprint 1741, 1995, designed it for order 3 there).
template <class Coefficients>
std::vector<double> stiff_prothero_robinson_ratios() {
  namespace odeint = boost::numeric::odeint;
  using Vec = boost::numeric::ublas::vector<double>;
  using Mat = boost::numeric::ublas::matrix<double>;
  const double lambda = -1e6;
  auto f = [lambda](const Vec& y, Vec& dy, double t) {
    dy.resize(1);
    dy[0] = lambda * (y[0] - std::sin(t)) + std::cos(t);
  };
  auto jac = [lambda](const Vec&, Mat& J, double t, Vec& dfdt) {
    J.resize(1, 1);
    J(0, 0) = lambda;
    dfdt.resize(1);
    dfdt[0] = -lambda * std::cos(t) - std::sin(t);
  };
  odeint::rosenbrock4<double, Coefficients> stepper;
  std::vector<double> err, ratios;
  for (int n = 8; n <= 64; n *= 2) {  // h |lambda| from 1.25e5 to 1.6e4
    Vec y(1);
    y[0] = 0;
    for (int k = 0; k < n; ++k) stepper.do_step(std::make_pair(f, jac), y, static_cast<double>(k) / n, 1.0 / n);
    err.push_back(std::abs(y[0] - std::sin(1.0)));
  }
  for (std::size_t k = 0; k + 1 < err.size(); ++k) ratios.push_back(err[k] / err[k + 1]);
  return ratios;
}

TEST(RosenbrockTables, OnStiffProtheroRobinsonRodasIsFirstOrderAndRodas4PThirdOrder) {
  for (double r : stiff_prothero_robinson_ratios<pumasim::ConsistentRosenbrockCoefficients<double>>()) {
    EXPECT_GT(r, 1.8) << "RODAS: order 1";
    EXPECT_LT(r, 2.4) << "RODAS: order 1";
  }
  for (double r : stiff_prothero_robinson_ratios<pumasim::Rodas4PCoefficients<double>>()) {
    EXPECT_GT(r, 7.0) << "Rodas4P: order 3";
    EXPECT_LT(r, 9.0) << "Rodas4P: order 3";
  }
}

// The defect the consistent set repairs: Boost 1.74's d4 is gamma_4 with the wrong sign.
TEST(RosenbrockTables, BoostsShippedD4IsNotGamma4) {
  const boost::numeric::odeint::default_rosenbrock_coefficients<double> shipped;
  const StandardForm s = standard_form(shipped);
  const double g4 = (s.Gamma * Vec6::Ones())[3];
  EXPECT_NEAR(s.d[3], -g4, 1e-12);
  EXPECT_GT(std::abs(s.d[3] - g4), 0.07);
}

}  // namespace
