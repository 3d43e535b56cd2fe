// The exponential integrators (integrators/exponential.cpp): exact on the
// linear part, their explicit parents without one, their order on a stiff
// problem where the parents are unstable, and the plant's linear part.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "integrators/registry.hpp"
#include "tests/integrator_helpers.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"

namespace pumasim {
namespace {

using testing::fixed_step;

// y' = lambda y + c, linear part lambda declared: y(t) = -c/lambda + (y0 + c/lambda) e^{lambda t}.
class ForcedDecay final : public OdeSystem {
 public:
  ForcedDecay(double lambda, double c) : lambda_(lambda), c_(c) {}
  int size() const override { return 1; }
  void rhs(double, const double* y, double* f) override { f[0] = lambda_ * y[0] + c_; }
  void linear_diagonal(double* l) const override { l[0] = lambda_; }
  double exact(double t, double y0) const { return -c_ / lambda_ + (y0 + c_ / lambda_) * std::exp(lambda_ * t); }

 private:
  double lambda_, c_;
};

// y0' = lambda y0 + (y1 - lambda sin t), y1' = -y0, y(0) = (0, 1): the
// solution is (sin t, cos t) for every lambda, and N = f - diag(lambda, 0) y
// depends on the state (y1), so the method's N extrapolation is exercised.
class StiffRotation final : public OdeSystem {
 public:
  explicit StiffRotation(double lambda) : lambda_(lambda) {}
  int size() const override { return 2; }
  void rhs(double t, const double* y, double* f) override {
    f[0] = lambda_ * y[0] + (y[1] - lambda_ * std::sin(t));
    f[1] = -y[0];
  }
  void linear_diagonal(double* l) const override {
    l[0] = lambda_;
    l[1] = 0.0;
  }

 private:
  double lambda_;
};

// A nonlinear system without a declared linear part (the pendulum).
class Pendulum final : public OdeSystem {
 public:
  int size() const override { return 2; }
  void rhs(double, const double* y, double* f) override {
    f[0] = y[1];
    f[1] = -std::sin(y[0]) - 0.3 * y[1];
  }
};

const std::vector<std::string> kExponential{"etd-ab2", "etd-ab3", "etd-ab4", "etd-rk4"};

std::string parent(const std::string& name) { return name.substr(4); }  // "etd-ab2" -> "ab2"

// With no linear part the exponential methods are their explicit parents:
// the same steps to rounding (the weights' series at z = 0 is beta_j).
TEST(Exponential, WithoutALinearPartEqualsItsExplicitParent) {
  for (const std::string& name : kExponential) {
    Pendulum a, b;
    const double y0[2] = {1.0, 0.0};
    auto e = make_integrator(name, fixed_step(0.01));
    auto p = make_integrator(parent(name), fixed_step(0.01));
    e->reset(a, 0.0, y0);
    p->reset(b, 0.0, y0);
    ASSERT_EQ(e->advance_to(3.0).status, Outcome::kReached) << name;
    ASSERT_EQ(p->advance_to(3.0).status, Outcome::kReached) << name;
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(e->state()[i], p->state()[i], 1e-13) << name << " component " << i;
    double de[2], dp[2];
    e->dense_state(2.9951, de);
    p->dense_state(2.9951, dp);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(de[i], dp[i], 1e-13) << name << " dense, component " << i;
  }
}

// N constant: every exponential method is exact, at steps far beyond any
// explicit method's stability (h lambda = -1e3) and at small h lambda
// (-1e-3), in the steps and in the dense output over the last step (the
// start-up steps and the multistep ones).
TEST(Exponential, ExactOnALinearDecayWithConstantForcing) {
  for (const std::string& name : kExponential) {
    for (const double lambda : {-1e5, -0.1}) {
      ForcedDecay sys(lambda, 3.0);
      const double y0 = 2.0;
      auto integ = make_integrator(name, fixed_step(0.01));
      integ->reset(sys, 0.0, &y0);
      for (const double t_stop : {0.01, 0.02, 0.03, 0.0475, 0.06, 0.1}) {
        ASSERT_EQ(integ->advance_to(t_stop).status, Outcome::kReached) << name;
        const double t = 0.5 * (integ->step_start() + integ->time());
        double y = 0;
        integ->dense_state(t, &y);
        EXPECT_NEAR(y, sys.exact(t, y0), 1e-13 * std::max(1.0, std::abs(sys.exact(t, y0)))) << name << " t " << t;
        EXPECT_NEAR(integ->state()[0], sys.exact(t_stop, y0), 1e-12) << name << " lambda " << lambda;
      }
    }
  }
}

// On the stiff problem (lambda = -1e4: h lambda = -200 at dt = 0.02) the
// explicit parents blow up and the exponential methods converge. Their
// observed order there (error ratio on halving dt) is bounded below by what
// their stage values allow: ETDRK4's midpoint stage for the stiff component,
// e^{z/2} y0 + h I_0 N, is the quasi-steady value at t_n, first-order
// accurate in h when z << 0 (its nonstiff order conditions no longer cancel
// the error), so the coupled component y1' = -y0 gains an O(h^2) local error
// per step: global order 1 (Hochbruck & Ostermann, SIAM J. Numer. Anal. 43
// (2005) 1069-1090, on ETDRK4's stiff order reduction). The exponential
// Adams methods use no stages: order k (Hochbruck & Ostermann, BIT 51 (2011)
// 889-908), except that their k - 1 ETDRK4 start-up steps add O(h^2) each,
// so etd-ab3 and etd-ab4 show at least order 2 here and at most their own.
TEST(Exponential, ConvergesWhereTheParentIsUnstable) {
  const auto error = [](const std::string& name, double dt) {
    StiffRotation sys(-1e4);
    const double y0[2] = {0.0, 1.0};
    auto integ = make_integrator(name, fixed_step(dt));
    integ->reset(sys, 0.0, y0);
    const Outcome o = integ->advance_to(2.0);
    if (o.status != Outcome::kReached) return std::numeric_limits<double>::infinity();
    return std::max(std::abs(integ->state()[0] - std::sin(2.0)), std::abs(integ->state()[1] - std::cos(2.0)));
  };
  for (const std::string& name : kExponential) {
    EXPECT_FALSE(error(parent(name), 0.02) < 1.0) << parent(name) << " should be unstable at h lambda = -200";
    const double e2 = error(name, 0.01), e3 = error(name, 0.005);
    const int order = find_integrator(name).order;
    const double lowest = name == "etd-rk4" ? 1 : std::min(order, 2);
    EXPECT_GE(std::log2(e2 / e3), lowest - 0.3) << name << " errors " << e2 << " " << e3;
    EXPECT_LE(std::log2(e2 / e3), order + 0.3) << name << " errors " << e2 << " " << e3;
  }
}

// --keep-history: a reset at the time reached, with the state unchanged,
// leaves a multistep method's run as if it had not happened (one
// RK4 start-up step in all: 20 steps of AB2 cost 20 + 3 right-hand sides);
// without it the history restarts (a second start-up step, 3 more).
TEST(KeepHistory, ACarriedHistoryIgnoresAResetAtTheTimeReached) {
  for (const char* name : {"ab2", "etd-ab3"}) {
    for (const bool keep : {true, false}) {
      Pendulum a, b;
      const double y0[2] = {1.0, 0.0};
      IntegratorOptions o = fixed_step(0.01);
      o.keep_history = keep;
      auto cut = make_integrator(name, o), whole = make_integrator(name, o);
      cut->reset(a, 0.0, y0);
      whole->reset(b, 0.0, y0);
      ASSERT_EQ(cut->advance_to(0.1).status, Outcome::kReached);
      const std::vector<double> x(cut->state(), cut->state() + 2);
      cut->reset(a, cut->time(), x.data());
      ASSERT_EQ(cut->advance_to(0.2).status, Outcome::kReached);
      ASSERT_EQ(whole->advance_to(0.2).status, Outcome::kReached);
      const int starts = keep ? 1 : 2, k = find_integrator(name).order;
      EXPECT_EQ(cut->stats().rhs_evaluations, 20 + starts * (k - 1) * 3) << name << " keep " << keep;
      // The step that lands on t = 0.1 is 0.1 - t_9, dt to rounding: the runs
      // agree to rounding with the history kept, and by far less without.
      const double gap = std::max(std::abs(cut->state()[0] - whole->state()[0]),
                                  std::abs(cut->state()[1] - whole->state()[1]));
      if (keep) {
        EXPECT_LT(gap, 1e-15) << name;
      } else {
        EXPECT_GT(gap, 1e-9) << name;
      }
    }
  }
}

// The plant's linear part is the diagonal of its exact Jacobian on the
// current states (di_j/dt is linear in i_j with slope -(R0 + R_j)/La_j) and
// 0 where it declares none.
TEST(Exponential, PlantLinearPartIsTheArmatureDecay) {
  const Scene sc = load_scene(std::string(PUMASIM_SCENES_DIR) + "/paper_slow.toml");
  Plant plant(sc.plant);
  const int m = plant.size();
  std::vector<double> x(static_cast<std::size_t>(m)), lambda(static_cast<std::size_t>(m));
  plant.initial_state(x.data());
  plant.linear_diagonal(lambda.data());
  Eigen::MatrixXd J;
  plant.jacobian_exact(0.3, x.data(), J);
  const int i0 = plant.layout().i;
  ASSERT_GE(i0, 0);
  for (int k = 0; k < m; ++k) {
    const bool current = k >= i0 && k < i0 + plant.layout().n;
    if (current) {
      const int j = k - i0;
      EXPECT_NEAR(lambda[static_cast<std::size_t>(k)], J(k, k), 1e-9 * std::abs(J(k, k))) << k;
      const double expected = -(sc.plant.amplifier[j].output_resistance + sc.plant.motor[j].resistance) / sc.plant.motor[j].inductance;
      EXPECT_NEAR(lambda[static_cast<std::size_t>(k)], expected, 1e-12 * std::abs(expected)) << k;
    } else {
      EXPECT_EQ(lambda[static_cast<std::size_t>(k)], 0.0) << k;
    }
  }
}

}  // namespace
}  // namespace pumasim
