// Exact Jacobians through the multi-tangent dual number (DualN) and the
// analytical derivatives of the dynamics (DynamicsDerivatives, TangentBackend;
// Carpentier & Mansard 2018): each against an independent computation, the
// single-tangent Dual through the back-end's own algorithm (one pass per
// direction) and central differences.
//
// Tolerances: two exact computations of the same derivative differ by rounding
// only, about eps times the condition number of H (below 1e4 for these arms)
// times the row's largest entry: 1e-9 of the row's scale leaves a factor 1000
// beyond that. Central differences with step d carry a truncation error
// O(d^2 f''') and a rounding error O(eps |f| / d): at d = 1e-5 both are near
// 1e-10 of the scale; 1e-6 is the bound.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/dual_n.hpp"
#include "models/dynamics/dynamics_derivatives.hpp"
#include "models/dynamics/rnea.hpp"
#include "models/dynamics/rnea_derivatives.hpp"
#include "models/dynamics/tangent_backend.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "tests/helpers.hpp"
#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

// max over entries of |a - b| / (the scale of b's row, floor 1)
double row_rel_err(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  double worst = 0;
  for (int r = 0; r < b.rows(); ++r) {
    const double scale = std::max(1.0, b.row(r).cwiseAbs().maxCoeff());
    worst = std::max(worst, (a.row(r) - b.row(r)).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

// f(x, y) = sin(x) y / sqrt(x) + tanh(x y) - cos(y) and its gradient in closed form.
TEST(DualN, ArithmeticAndFunctionsMatchClosedForms) {
  const double x = 0.7, y = -1.3;
  const DualN<3> X(x, 0), Y(y, 2);
  const DualN<3> f = sin(X) * Y / sqrt(X) + tanh(X * Y) - cos(Y);
  const double th = std::tanh(x * y);
  EXPECT_NEAR(f.value(), std::sin(x) * y / std::sqrt(x) + th - std::cos(y), 1e-15);
  const double dfdx = std::cos(x) * y / std::sqrt(x) - 0.5 * std::sin(x) * y * std::pow(x, -1.5) + (1 - th * th) * y;
  const double dfdy = std::sin(x) / std::sqrt(x) + (1 - th * th) * x + std::sin(y);
  EXPECT_NEAR(f.deriv(0), dfdx, 1e-14);
  EXPECT_EQ(f.deriv(1), 0.0);
  EXPECT_NEAR(f.deriv(2), dfdy, 1e-14);
  EXPECT_EQ(abs(-X).deriv(0), 1.0);
  // exp, on both dual types: d/dx x exp(-x^2) = (1 - 2 x^2) exp(-x^2).
  const DualN<3> g = X * exp(-(X * X));
  EXPECT_NEAR(g.value(), x * std::exp(-x * x), 1e-15);
  EXPECT_NEAR(g.deriv(0), (1 - 2 * x * x) * std::exp(-x * x), 1e-15);
  EXPECT_EQ(g.deriv(1), 0.0);
  const Dual d = Dual(x, 1.0) * exp(-(Dual(x, 1.0) * Dual(x, 1.0)));
  EXPECT_NEAR(d.value(), x * std::exp(-x * x), 1e-15);
  EXPECT_NEAR(d.deriv(), (1 - 2 * x * x) * std::exp(-x * x), 1e-15);
  // log: d/dx x log x = log x + 1.
  EXPECT_NEAR((X * log(X)).deriv(0), std::log(x) + 1, 1e-15);
  EXPECT_NEAR((Dual(x, 1.0) * log(Dual(x, 1.0))).deriv(), std::log(x) + 1, 1e-15);
}

std::vector<RobotModel> arms() {
  const RobotModel puma = load_robot("puma560");
  // puma 6, puma with the wrist held (the paper's 3 joints), a 7-joint chain
  // with prismatic joints (two partial passes: 14 directions > 12).
  return {puma, lock_joints(puma, 3, Eigen::VectorXd::Zero(6)),
          random_chain(7, 11, DhConvention::kModified, "RPRRPRR")};
}

// [dqdd/dq dqdd/dqd dqdd/dtau] by the back-end's own algorithm on Dual.
Eigen::MatrixXd fd_jacobian_per_column(const BackendInfo& info, const RobotModel& m, const Eigen::VectorXd& q,
                                       const Eigen::VectorXd& qd, const Eigen::VectorXd& tau) {
  const int n = m.dof();
  auto b = info.make_dual(m);
  Eigen::MatrixXd J(n, 3 * n);
  Eigen::Matrix<Dual, Eigen::Dynamic, 1> Q(n), Qd(n), T(n), out(n);
  for (int k = 0; k < 3 * n; ++k) {
    for (int j = 0; j < n; ++j) {
      Q[j] = Dual(q[j], k == j ? 1.0 : 0.0);
      Qd[j] = Dual(qd[j], k == n + j ? 1.0 : 0.0);
      T[j] = Dual(tau[j], k == 2 * n + j ? 1.0 : 0.0);
    }
    b->forward_dynamics(Q, Qd, T, out);
    for (int i = 0; i < n; ++i) J(i, k) = out[i].deriv();
  }
  return J;
}

TEST(DynamicsDerivatives, ForwardDynamicsMatchesDualColumnsAndCentralDifferences) {
  for (const RobotModel& m : arms()) {
    const int n = m.dof();
    Rng rng(5);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -10, 10);
    for (const auto& info : testing::supported(m)) {
      SCOPED_TRACE(std::string(info.name) + " n=" + std::to_string(n));
      DynamicsDerivatives d(m, info.make(m));
      Eigen::VectorXd qdd(n);
      Eigen::MatrixXd Dq(n, n), Dqd(n, n), Dt(n, n), J(n, 3 * n);
      d.forward_dynamics(q, qd, tau, qdd, Dq, Dqd, Dt);
      J << Dq, Dqd, Dt;
      EXPECT_LT(row_rel_err(J, fd_jacobian_per_column(info, m, q, qd, tau)), 1e-9);
      // Central differences of the back-end's forward dynamics (double).
      auto b = info.make(m);
      Eigen::MatrixXd C(n, 3 * n);
      Eigen::VectorXd qdd0(n), qp(n), qm(n);
      b->forward_dynamics(q, qd, tau, qdd0);
      EXPECT_LT((qdd - qdd0).norm(), 1e-10 * std::max(1.0, qdd0.norm()));
      constexpr double step = 1e-5;
      for (int k = 0; k < 3 * n; ++k) {
        Eigen::VectorXd x(3 * n);
        x << q, qd, tau;
        x[k] += step;
        b->forward_dynamics(x.head(n), x.segment(n, n), x.tail(n), qp);
        x[k] -= 2 * step;
        b->forward_dynamics(x.head(n), x.segment(n, n), x.tail(n), qm);
        C.col(k) = (qp - qm) / (2 * step);
      }
      EXPECT_LT(row_rel_err(J, C), 1e-6);
    }
  }
}

// The analytical partials of inverse dynamics (rnea_derivatives.hpp) against
// the RNEA itself on the single-tangent Dual, one pass per direction, with
// and without gravity, and the value of ID against the RNEA in double; the
// arms above and random chains of 12 and 48 joints (revolute and prismatic).
TEST(RneaDerivatives, MatchDualRneaPerDirection) {
  std::vector<RobotModel> models = arms();
  models.push_back(random_chain(12, 3, DhConvention::kStandard, "RRPRRRPRRRRP"));
  models.push_back(random_chain(48, 4, DhConvention::kModified));
  for (const RobotModel& m : models) {
    const int n = m.dof();
    SCOPED_TRACE("n=" + std::to_string(n));
    Rng rng(21);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd qdd = rng.uniform_vector(n, -5, 5);
    RneaDerivatives rd(m);
    const Chain<Dual, Eigen::Dynamic> chain(m);
    JointTransforms<Dual, Eigen::Dynamic> rot(n);
    RneaPass<Dual, Eigen::Dynamic> rnea(n);
    Eigen::Matrix<Dual, Eigen::Dynamic, 1> Q(n), Qd(n), Qdd(n), tau(n);
    for (bool gravity : {true, false}) {
      Eigen::MatrixXd dq(n, n), dqd(n, n), ref(n, 2 * n);
      Eigen::VectorXd t(n), t_ref(n);
      rd.compute(q.data(), qd.data(), qdd.data(), gravity, dq, dqd, t.data());
      for (int k = 0; k < 2 * n; ++k) {
        for (int j = 0; j < n; ++j) {
          Q[j] = Dual(q[j], k == j ? 1.0 : 0.0);
          Qd[j] = Dual(qd[j], k == n + j ? 1.0 : 0.0);
          Qdd[j] = Dual(qdd[j]);
        }
        rot.compute(chain, Q);
        rnea.run(chain, rot, Qd, Qdd, gravity, tau);
        for (int i = 0; i < n; ++i) ref(i, k) = tau[i].deriv(), t_ref[i] = tau[i].value();
      }
      Eigen::MatrixXd got(n, 2 * n);
      got << dq, dqd;
      EXPECT_LT(row_rel_err(got, ref), 1e-9) << "gravity " << gravity;
      EXPECT_LT((t - t_ref).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, t_ref.cwiseAbs().maxCoeff()));
    }
  }
}

// Above 12 joints the partials' assembly goes to matrix products
// (RneaDerivatives::compute): the same oracle on 13 and 48. dFD/dtau is H^-1
// formed from the Cholesky factor (Cholesky::inverse), on every n: its
// residual H X - I is within the forward-error bound of an inverse computed
// from a Cholesky factor, c n u cond(H) (Higham, Accuracy and Stability of
// Numerical Algorithms, 2nd ed., sec. 14.1; c = 10 is this test's margin).
TEST(DynamicsDerivatives, TheTorqueColumnsAreTheInverseOfH) {
  for (const RobotModel& m :
       {load_robot("puma560"), random_chain(13, 8, DhConvention::kModified, "RRRPRRRRRRRRR"), random_chain(48, 9)}) {
    const int n = m.dof();
    Rng rng(7);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -10, 10);
    DynamicsDerivatives d(m, find_backend("crba").make(m));
    Eigen::VectorXd qdd(n);
    Eigen::MatrixXd Dq(n, n), Dqd(n, n), Dt(n, n);
    d.forward_dynamics(q, qd, tau, qdd, Dq, Dqd, Dt);
    const Eigen::MatrixXd& H = d.mass_matrix();
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues();
    const double bound = 10.0 * n * std::numeric_limits<double>::epsilon() * ev.maxCoeff() / ev.minCoeff();
    EXPECT_LT((H * Dt - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), bound) << m.name;
  }
}

TEST(DynamicsDerivatives, LargeChainsMatchDualColumns) {
  for (const RobotModel& m : {random_chain(13, 8, DhConvention::kModified, "RRRPRRRRRRRRR"), random_chain(48, 9)}) {
    const int n = m.dof();
    Rng rng(6);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -10, 10);
    for (const char* name : {"aba", "crba"}) {
      SCOPED_TRACE(std::string(name) + " n=" + std::to_string(n));
      const BackendInfo& info = find_backend(name);
      DynamicsDerivatives d(m, info.make(m));
      Eigen::VectorXd qdd(n);
      Eigen::MatrixXd Dq(n, n), Dqd(n, n), Dt(n, n), J(n, 3 * n);
      d.forward_dynamics(q, qd, tau, qdd, Dq, Dqd, Dt);
      J << Dq, Dqd, Dt;
      EXPECT_LT(row_rel_err(J, fd_jacobian_per_column(info, m, q, qd, tau)), 1e-9);
    }
  }
}

// Every entry of the tangent back-end, along N random directions at once,
// against the back-end's own algorithm on Dual along each direction.
TEST(TangentBackend, EveryQuantityMatchesDualDirections) {
  constexpr int N = 4;
  using T = DualN<N>;
  for (const RobotModel& m : arms()) {
    const int n = m.dof();
    Rng rng(9);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1.5, 1.5), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd a = rng.uniform_vector(n, -5, 5);
    const Eigen::MatrixXd dirs = rng.uniform_vector(3 * n * N, -1, 1).reshaped(3 * n, N);
    for (const auto& info : testing::supported(m)) {
      SCOPED_TRACE(std::string(info.name) + " n=" + std::to_string(n));
      TangentBackend<N> tb(m, info.make(m));
      auto db = info.make_dual(m);
      Eigen::Matrix<T, Eigen::Dynamic, 1> Q(n), Qd(n), A(n), out(n);
      Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> H(n, n);
      for (int j = 0; j < n; ++j) {
        Q[j] = T(q[j]), Qd[j] = T(qd[j]), A[j] = T(a[j]);
        for (int k = 0; k < N; ++k) {
          Q[j].deriv(k) = dirs(j, k), Qd[j].deriv(k) = dirs(n + j, k), A[j].deriv(k) = dirs(2 * n + j, k);
        }
      }
      Eigen::Matrix<Dual, Eigen::Dynamic, 1> q1(n), qd1(n), a1(n), o1(n);
      Eigen::Matrix<Dual, Eigen::Dynamic, Eigen::Dynamic> H1(n, n);
      for (int k = 0; k < N; ++k) {
        for (int j = 0; j < n; ++j) {
          q1[j] = Dual(q[j], dirs(j, k)), qd1[j] = Dual(qd[j], dirs(n + j, k)), a1[j] = Dual(a[j], dirs(2 * n + j, k));
        }
        auto compare = [&](const char* what) {
          Eigen::MatrixXd x(n, 2), y(n, 2);
          for (int i = 0; i < n; ++i) x(i, 0) = out[i].value(), x(i, 1) = out[i].deriv(k);
          for (int i = 0; i < n; ++i) y(i, 0) = o1[i].value(), y(i, 1) = o1[i].deriv();
          EXPECT_LT(row_rel_err(x, y), 1e-9) << what << " direction " << k;
        };
        tb.forward_dynamics(Q, Qd, A, out), db->forward_dynamics(q1, qd1, a1, o1), compare("fd");
        tb.inverse_dynamics(Q, Qd, A, out), db->inverse_dynamics(q1, qd1, a1, o1), compare("id");
        tb.bias(Q, Qd, out), db->bias(q1, qd1, o1), compare("bias");
        tb.gravity(Q, out), db->gravity(q1, o1), compare("gravity");
        tb.mass_matrix(Q, H), db->mass_matrix(q1, H1);
        for (int c = 0; c < n; ++c) {
          for (int i = 0; i < n; ++i) out[i] = H(i, c), o1[i] = H1(i, c);
          compare("H");
        }
      }
    }
  }
}

// The plant's Jacobian (one DualN pass per 24 states) against the per-column
// Dual passes, and the hybrid friction's stuck and slipping joints seen
// along a run.
struct PlantCase {
  std::string scene;
  std::vector<std::string> sets;
};

void expect_plant_jacobians_agree(Plant& plant, double t, const double* x, const std::string& what) {
  Eigen::MatrixXd Ja, Jb;
  plant.jacobian_exact(t, x, Ja);
  plant.jacobian_per_column(t, x, Jb);
  EXPECT_LT(row_rel_err(Ja, Jb), 1e-9) << what << " t=" << t;
}

TEST(PlantJacobian, MultiTangentEqualsPerColumnInEveryKindOfScene) {
  const std::vector<PlantCase> cases = {
      {"paper_slow", {}},                                                               // the paper's rule
      {"stick_slip", {"friction.model=\"tanh\"", "friction.speed_scale=1e-2"}},         // tanh
      {"stick_slip", {"friction.model=\"stribeck\"", "friction.stribeck_speed=0.14"}},  // Stribeck (exp, tanh)
      {"stick_slip",
       {"friction.model=\"lugre\"", "friction.stribeck_speed=0.1", "friction.bristle_stiffness=100.0",
        "friction.bristle_damping=0.6"}},  // LuGre: a state per joint
      {"paper_slow_viscous",
       {"friction.model=\"dahl\"", "friction.kinetic_torque=0.124", "friction.bristle_stiffness=100.0",
        "friction.dahl_exponent=2.0"}},  // Dahl, alpha = 2 (exp, log)
      {"sampled_control", {}},           // sampled controller
      {"passive_arm", {}},               // no drive, no controller
      {"computed_torque", {}},           // a law calling inverse dynamics
      {"energy_long_time", {}},          // the ledger (more than 24 states)
      {"stanford_tracking", {}},         // a prismatic joint
      {"paper_slow_reduced", {}},        // no current states
      {"panda_tracking", {}},            // the sigmoid law, 7 joints, the redundancy rule's inverse kinematics
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.scene);
    const Scene sc = load_scene(test::scene_path(c.scene), c.sets);
    for (const char* backend : {"crba", "aba", "lagrange-euler"}) {
      Scene s = sc;
      s.plant.backend = backend;
      Plant plant(s.plant);
      std::vector<double> x(plant.size());
      plant.initial_state(x.data());
      const StateLayout& L = plant.layout();
      for (int j = 0; j < L.n; ++j) x[L.qd + j] = 0.1 * (j + 1) * (j % 2 ? -1 : 1);
      expect_plant_jacobians_agree(plant, 0.3, x.data(), backend);
    }
  }
}

TEST(PlantJacobian, HybridFrictionStuckAndSlippingJointsAlongARun) {
  // The 6-joint scene's wrist joints stick while the others slip; the
  // 3-joint stick_slip scene stops every joint half way (its dwell).
  for (const auto& [scene, t_end] : {std::pair{"paper_slow_6dof_hybrid", 1.5}, std::pair{"stick_slip", 6.0}}) {
    SCOPED_TRACE(scene);
    const Scene sc = load_scene(test::scene_path(scene));
    Plant plant(sc.plant);
    IntegratorOptions o;
    o.rtol = 1e-6, o.atol = 1e-8;
    auto integ = make_integrator("cvode-bdf", o);
    int mixed = 0, some_stuck = 0, some_slipping = 0;
    const RunResult r = run_plant(
        plant, *integ, {.t_end = t_end, .output_interval = t_end / 40, .observe = [&](double t, const double* x) {
                          const int n = plant.layout().n;
                          int stuck = 0;
                          for (int j = 0; j < n; ++j) stuck += plant.slip_mode(j) == SlipMode::kStuck;
                          mixed += stuck > 0 && stuck < n;
                          some_stuck += stuck > 0;
                          some_slipping += stuck < n;
                          expect_plant_jacobians_agree(plant, t, x, std::to_string(stuck) + " stuck");
                        }});
    EXPECT_TRUE(r.ok);
    EXPECT_GT(some_stuck, 0);
    EXPECT_GT(some_slipping, 0);
    if (std::string(scene) == "paper_slow_6dof_hybrid") { EXPECT_GT(mixed, 0) << "no sample with both modes"; }
  }
}

// Against central differences of f, saturations lifted so that the states
// stay on one side of their kinks.
TEST(PlantJacobian, MatchesCentralDifferences) {
  struct Case {
    const char* scene;
    std::vector<std::string> sets;
    double qd;    // [rad/s] joint j's speed: qd (j + 1)
    double step;  // relative to each state's scale
  };
  // The Stribeck law at joint speeds whose motor speeds (gear ratios near
  // 60) straddle its peak, w_St / sqrt(2) = 0.1 rad/s: its exp term matters.
  // Its third derivative in w_m there, about sqrt(2e) (Fs - Fk) 6 / w_St^3
  // ~ 100 N m s^3/rad^3, makes the differences' truncation error (h^2 / 6
  // times it) at the others' step ~1e-5 relative: a tenth of the step, a
  // hundredth of the error.
  const std::vector<Case> cases = {
      {"paper_slow_6dof_hybrid", {}, 0.05, 1e-5},
      {"paper_slow", {}, 0.05, 1e-5},
      {"computed_torque", {}, 0.05, 1e-5},
      {"stick_slip", {"friction.model=\"stribeck\"", "friction.stribeck_speed=0.14"}, 0.001, 1e-6},
      {"stick_slip",
       {"friction.model=\"lugre\"", "friction.stribeck_speed=0.1", "friction.bristle_stiffness=100.0",
        "friction.bristle_damping=0.6"},
       0.001,
       1e-6},  // LuGre's G(w) as Stribeck's exp
      {"paper_slow_viscous",
       {"friction.model=\"dahl\"", "friction.kinetic_torque=0.124", "friction.bristle_stiffness=100.0",
        "friction.dahl_exponent=2.0"},
       0.001,
       1e-6},  // Dahl, alpha = 2
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene);
    std::vector<std::string> sets = {"amplifier.voltage_limit=1e9", "controller.output_limit=1e9"};
    sets.insert(sets.end(), c.sets.begin(), c.sets.end());
    const Scene sc = load_scene(test::scene_path(c.scene), sets);
    Plant plant(sc.plant);
    const int m = plant.size();
    std::vector<double> x(m), fp(m), fm(m);
    plant.initial_state(x.data());
    const StateLayout& L = plant.layout();
    for (int j = 0; j < L.n; ++j) x[L.qd + j] = c.qd * (j + 1);
    plant.settle_modes(0.3, x.data());
    Eigen::MatrixXd J, C(m, m);
    plant.jacobian_exact(0.3, x.data(), J);
    for (int k = 0; k < m; ++k) {
      const double step = c.step * std::max(1.0, plant.tolerance_scale(k));
      const double xk = x[k];
      x[k] = xk + step, plant.rhs(0.3, x.data(), fp.data());
      x[k] = xk - step, plant.rhs(0.3, x.data(), fm.data());
      x[k] = xk;
      for (int r = 0; r < m; ++r) C(r, k) = (fp[r] - fm[r]) / (2 * step);
    }
    EXPECT_LT(row_rel_err(J, C), 1e-6);
  }
}

}  // namespace
}  // namespace pumasim
