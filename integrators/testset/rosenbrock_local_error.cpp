// Diagnostic: the error estimate of odeint's rosenbrock4 stepper against its
// true local error, one step from the exact solution of the test set's
// Prothero-Robinson problem (y0' = lambda (y0 - sin t) + cos t, y1' = y0 - y1;
// closed form, exact Jacobian and df/dt), for step sizes halving from 0.5 s,
// with each coefficient set of the registry (integrators/rosenbrock_coefficients.hpp):
// odeint-rosenbrock4 (Hairer's RODAS table) and odeint-rodas4p (Steinebach's).
//
//   rosenbrock_local_error [LAMBDA] [T0]      (defaults -1e4 and 1)
//
// Prints, per method and h: h * |lambda|, the estimate and the true local error of each
// component, and the ratio of their max norms. Where the two fall alike with h
// the estimate is faithful; their slope is the local order the controller sees.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <boost/numeric/odeint.hpp>

#include "integrators/rosenbrock_coefficients.hpp"
#include "integrators/testset/problems.hpp"

namespace odeint = boost::numeric::odeint;
using Vec = boost::numeric::ublas::vector<double>;
using Mat = boost::numeric::ublas::matrix<double>;

template <class Coefficients>
void one_step_errors(const char* name, double lambda, double t0) {
  auto p = pumasim::testset::prothero_robinson(lambda);
  Eigen::MatrixXd Jd;
  double f1[2], ft[2];
  auto f = [&](const Vec& y, Vec& dy, double t) {
    const double x[2] = {y[0], y[1]};
    p->rhs(t, x, f1);
    dy.resize(2);
    dy[0] = f1[0], dy[1] = f1[1];
  };
  auto jac = [&](const Vec& y, Mat& J, double t, Vec& dfdt) {
    const double x[2] = {y[0], y[1]};
    p->jacobian(t, x, Jd);
    p->time_derivative(t, x, ft);
    J.resize(2, 2);
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) J(r, c) = Jd(r, c);
    dfdt.resize(2);
    dfdt[0] = ft[0], dfdt[1] = ft[1];
  };
  odeint::rosenbrock4<double, Coefficients> stepper;
  for (double h = 0.5; h > 2e-5; h /= 2) {
    double e0[2], e1[2];
    p->exact_solution(t0, e0);
    p->exact_solution(t0 + h, e1);
    Vec y(2), out(2), err(2);
    y[0] = e0[0], y[1] = e0[1];
    stepper.do_step(std::make_pair(f, jac), y, t0, out, h, err);
    const double true0 = std::abs(out[0] - e1[0]), true1 = std::abs(out[1] - e1[1]);
    const double est = std::max(std::abs(err[0]), std::abs(err[1])), tru = std::max(true0, true1);
    std::printf("%s\t%.4g\t%.4g\t%.3g\t%.3g\t%.3g\t%.3g\t%.3g\n", name, h, h * std::abs(lambda), std::abs(err[0]),
                true0, std::abs(err[1]), true1, tru > 0 ? est / tru : INFINITY);
  }
}

int main(int argc, char** argv) {
  char* end = nullptr;
  const double lambda = argc > 1 ? std::strtod(argv[1], &end) : -1e4;
  if (argc > 1 && (*end != '\0' || !(lambda < 0))) {
    std::fprintf(stderr, "rosenbrock_local_error: expected LAMBDA < 0, got '%s'\n", argv[1]);
    return 2;
  }
  const double t0 = argc > 2 ? std::strtod(argv[2], &end) : 1.0;
  if (argc > 2 && (*end != '\0' || !std::isfinite(t0))) {
    std::fprintf(stderr, "rosenbrock_local_error: expected a number T0, got '%s'\n", argv[2]);
    return 2;
  }
  std::printf("# odeint's rosenbrock4 stepper on Prothero-Robinson, lambda = %g, one step from the exact y(%g)\n",
              lambda, t0);
  std::printf("method\th\th*|lambda|\testimate_y0\ttrue_y0\testimate_y1\ttrue_y1\testimate/true\n");
  one_step_errors<pumasim::ConsistentRosenbrockCoefficients<double>>("odeint-rosenbrock4", lambda, t0);
  one_step_errors<pumasim::Rodas4PCoefficients<double>>("odeint-rodas4p", lambda, t0);
  return 0;
}
