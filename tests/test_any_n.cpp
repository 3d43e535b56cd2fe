// Arms of any length (issue 34): random chains of 7, 9, 12 and 16 joints as
// robot files, through the kinematics, the redundant inverse kinematics, and
// every integrator of the registry on a passive scene with the energy ledger.
//
//  - A robot file written by robot_file_text reads back to the same model,
//    every parameter bitwise (the writer's shortest round-trip text).
//  - The geometric Jacobian of a 12-joint chain (revolute and prismatic)
//    against central differences of the forward kinematics.
//  - The redundancy rule (models/reference/numerical_ik.hpp): its solution
//    reaches the task, q - q_r has no component in J's null space, nearby
//    poses on the task's manifold are no nearer q_r (a local minimum, as the
//    rule promises), and the solution does not depend on the warm start.
//  - task_rates against central differences of the rule's solution along a
//    moving task: qd and qdd are the derivatives of q(t).
//  - Every integrator on the passive random chains: its observed order
//    (fixed step) or tolerance proportionality (adaptive), as the
//    conformance tests check on the PUMA; and the passive model's energy:
//    the ledger's balance E(T) - E(0) = -e_friction(T) holds for the ODE
//    (the tight reference run, to 1e-9 of the energy dissipated), which
//    loses energy (E(T) < E(0)) and dissipates some (e_friction(T) > 0).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "integrators/integrator.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/jet2.hpp"
#include "models/plant/plant.hpp"
#include "models/reference/numerical_ik.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/kinematics.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/robot_writer.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "tests/any_n_scenes.hpp"
#include "tests/integrator_helpers.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

using testing::random_robot_file;
using testing::write_scratch_file;

TEST(RobotWriter, ARandomChainReadsBackBitwise) {
  // The PUMA's file (poses, limits) reads back as it was.
  const RobotModel puma = load_robot("puma560");
  const RobotModel back = load_robot_file(write_scratch_file("any_n/puma.toml", robot_file_text(puma)));
  ASSERT_EQ(back.poses.size(), puma.poses.size());
  for (std::size_t k = 0; k < puma.poses.size(); ++k) {
    EXPECT_EQ(back.poses[k].name, puma.poses[k].name);
    EXPECT_EQ(back.poses[k].q, puma.poses[k].q);
  }
  for (const auto& [n, types, conv] : {std::tuple{7, "R", DhConvention::kStandard},
                                       std::tuple{12, "RRP", DhConvention::kModified},
                                       std::tuple{16, "RP", DhConvention::kStandard}}) {
    const RobotModel m = random_chain(n, 40 + n, conv, types);
    const std::string file = write_scratch_file("any_n/readback" + std::to_string(n) + ".toml", robot_file_text(m));
    const RobotModel r = load_robot_file(file);
    ASSERT_EQ(r.dof(), n);
    EXPECT_EQ(r.convention, m.convention);
    EXPECT_EQ(r.gravity, m.gravity);
    for (int j = 0; j < n; ++j) {
      const JointParams &a = m.joints[j], &b = r.joints[j];
      EXPECT_EQ(a.type, b.type) << j;
      EXPECT_EQ(a.a, b.a) << j;
      EXPECT_EQ(a.alpha, b.alpha) << j;
      EXPECT_EQ(a.d, b.d) << j;
      EXPECT_EQ(a.theta, b.theta) << j;
      EXPECT_EQ(a.offset, b.offset) << j;
      EXPECT_EQ(a.mass, b.mass) << j;
      EXPECT_EQ(a.com, b.com) << j;
      // The file holds the six numbers of the upper triangle (random_chain's
      // R diag(I) R^T may differ from its transpose by rounding).
      for (auto [r, k] : {std::pair{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}}) {
        EXPECT_EQ(a.inertia(r, k), b.inertia(r, k)) << j;
        EXPECT_EQ(b.inertia(k, r), b.inertia(r, k)) << j;
      }
      EXPECT_EQ(a.rotor_inertia, b.rotor_inertia) << j;
      EXPECT_EQ(a.gear_ratio, b.gear_ratio) << j;
      EXPECT_EQ(a.q_min, b.q_min) << j;
      EXPECT_EQ(a.q_max, b.q_max) << j;
    }
  }
}

// Columns of the geometric Jacobian against central differences of the
// forward kinematics: the flange origin's velocity (rows 0-2) and the
// angular velocity from R(q + h e_k) R(q - h e_k)^T = exp(2 h [w]x) + O(h^3).
TEST(AnyN, GeometricJacobianOfATwelveJointChainMatchesDifferences) {
  const RobotModel m = random_chain(12, 7, DhConvention::kModified, "RRP");
  Rng rng(3);
  const Eigen::VectorXd q = rng.uniform_vector(12, -1, 1);
  Eigen::Matrix<double, 6, Eigen::Dynamic> J;
  geometric_jacobian(m, q, 12, J);
  const double h = 1e-6;
  for (int k = 0; k < 12; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h, qm[k] -= h;
    Eigen::Matrix3d Rp, Rm;
    Eigen::Vector3d pp, pm;
    forward_kinematics<double>(m, qp, Rp, pp);
    forward_kinematics<double>(m, qm, Rm, pm);
    const Eigen::AngleAxisd aa(Eigen::Matrix3d(Rp * Rm.transpose()));
    const Eigen::Vector3d w = aa.angle() * aa.axis() / (2 * h);
    EXPECT_LT((J.block<3, 1>(0, k) - (pp - pm) / (2 * h)).norm(), 1e-8) << k;
    EXPECT_LT((J.block<3, 1>(3, k) - w).norm(), 1e-8) << k;
  }
  Eigen::Matrix<double, 6, Eigen::Dynamic> J5;  // the first 5 columns; the others zero
  geometric_jacobian(m, q, 5, J5);
  EXPECT_EQ(J5.leftCols(5), J.leftCols(5));
  EXPECT_EQ(J5.rightCols(7).norm(), 0.0);
}

struct AnyNRuleCase {
  int n;
  bool orientation;
};

// The rule's residual: J's null-space part of q - q_r (the first n joints).
double any_n_null_space_part(const RobotModel& m, int n, int rows, const Eigen::VectorXd& q, const Eigen::VectorXd& rest) {
  Eigen::Matrix<double, 6, Eigen::Dynamic> J;
  geometric_jacobian(m, q, n, J);
  const Eigen::MatrixXd Jt = J.topLeftCorner(rows, n);
  const Eigen::VectorXd d = (q - rest).head(n);
  return (d - Jt.transpose() * (Jt * Jt.transpose()).ldlt().solve(Jt * d)).norm();
}

TEST(AnyN, TheRedundancyRuleFindsTheNearestPoseToTheRest) {
  for (const AnyNRuleCase c : {AnyNRuleCase{4, false}, AnyNRuleCase{7, false}, AnyNRuleCase{7, true}, AnyNRuleCase{9, true},
                           AnyNRuleCase{16, true}}) {
    const int rows = c.orientation ? 6 : 3;
    const RobotModel m = random_chain(c.n, 100 + c.n);
    Rng rng(5);
    // A reachable task: the flange at a random pose q_t; the rest pose near it.
    const Eigen::VectorXd q_t = rng.uniform_vector(c.n, -1, 1);
    const Eigen::VectorXd rest = q_t + rng.uniform_vector(c.n, -0.3, 0.3);
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    forward_kinematics<double>(m, q_t, R, p);
    IkWorkspace ws(c.n, c.n, rows);
    Eigen::VectorXd q = rest;
    const IkSolveResult res = dls_ik(m, c.n, p, c.orientation ? &R : nullptr, q, ws, &rest);
    ASSERT_TRUE(res.converged) << c.n << " error " << res.error;
    Eigen::Matrix3d Rq;
    Eigen::Vector3d pq;
    forward_kinematics<double>(m, q, Rq, pq);
    EXPECT_LT((pq - p).norm(), 1e-11) << c.n;
    if (c.orientation) {
      EXPECT_LT((Rq - R).norm(), 1e-11) << c.n;
    }
    EXPECT_LT(any_n_null_space_part(m, c.n, rows, q, rest), 1e-10) << c.n;
    // From another warm start on the same branch: the same pose.
    Eigen::VectorXd q2 = q + rng.uniform_vector(c.n, -0.05, 0.05);
    ASSERT_TRUE(dls_ik(m, c.n, p, c.orientation ? &R : nullptr, q2, ws, &rest).converged);
    EXPECT_LT((q2 - q).norm(), 1e-9) << c.n;
    // Poses of the manifold near q (a null-space step, then back onto the
    // task by damped least squares alone) are no nearer the rest pose.
    Eigen::Matrix<double, 6, Eigen::Dynamic> J;
    geometric_jacobian(m, q, c.n, J);
    const Eigen::MatrixXd Jt = J.topLeftCorner(rows, c.n);
    const Eigen::MatrixXd N = Eigen::MatrixXd::Identity(c.n, c.n) -
                              Jt.transpose() * (Jt * Jt.transpose()).ldlt().solve(Jt);
    const double d0 = (q - rest).squaredNorm();
    for (int k = 0; k < 10; ++k) {
      Eigen::VectorXd qn = q + 1e-3 * N * rng.uniform_vector(c.n, -1, 1);
      ASSERT_TRUE(dls_ik(m, c.n, p, c.orientation ? &R : nullptr, qn, ws, nullptr).converged);
      EXPECT_GE((qn - rest).squaredNorm(), d0 - 1e-12) << c.n << " sample " << k;
    }
  }
}

// The task moves: p(t) = p0 + r (cos wt - 1, sin wt, 0.5 sin wt), the
// orientation fixed. The rule's q(t) at t and t +- h (converged to rounding,
// each warm-started from the last) gives central differences that task_rates'
// qd and qdd must match: O(h^2) truncation (|q'''| h^2 / 6) and rounding
// 1e-15 / h^2 in qdd.
TEST(AnyN, TaskRatesAreTheDerivativesOfTheRulesSolution) {
  for (const AnyNRuleCase c : {AnyNRuleCase{3, false}, AnyNRuleCase{5, false}, AnyNRuleCase{6, true},
                           AnyNRuleCase{7, true}, AnyNRuleCase{12, true}}) {
    const int rows = c.orientation ? 6 : 3;
    const RobotModel m = random_chain(c.n, 200 + c.n);
    Rng rng(9);
    // The task starts at the pose q_t, some 0.5 to 1 rad from the rest pose:
    // the rule's mu and its curvature terms (M, J''^T mu) are then sizeable.
    const Eigen::VectorXd rest = rng.uniform_vector(c.n, -1, 1);
    const Eigen::VectorXd q_t = rest + rng.uniform_vector(c.n, -0.6, 0.6);
    Eigen::Matrix3d R;
    Eigen::Vector3d p0;
    forward_kinematics<double>(m, q_t, R, p0);
    const double r = 0.02, w = 1.3, t0 = 0.4;
    const auto task = [&](double t, Eigen::Vector3d& p, Eigen::Vector3d& v, Eigen::Vector3d& a) {
      const Eigen::Vector3d u(std::cos(w * t) - 1, std::sin(w * t), 0.5 * std::sin(w * t));
      const Eigen::Vector3d du(-w * std::sin(w * t), w * std::cos(w * t), 0.5 * w * std::cos(w * t));
      const Eigen::Vector3d ddu(-w * w * std::cos(w * t), -w * w * std::sin(w * t), -0.5 * w * w * std::sin(w * t));
      p = p0 + r * u, v = r * du, a = r * ddu;
    };
    IkWorkspace ws(c.n, c.n, rows);
    const bool redundant = c.n > rows;
    Eigen::VectorXd q = q_t;
    const double h = 1e-3;
    std::map<int, Eigen::VectorXd> sol;  // q(t0 + i h)
    Eigen::Vector3d p, v, a;
    for (int i : {-2, -1, 0, 1, 2}) {
      task(t0 + i * h, p, v, a);
      ASSERT_TRUE(dls_ik(m, c.n, p, c.orientation ? &R : nullptr, q, ws, redundant ? &rest : nullptr).converged)
          << c.n;
      sol[i] = q;
    }
    Eigen::VectorXd qd(c.n), qdd(c.n);
    task(t0, p, v, a);
    task_rates(m, c.n, c.orientation, sol[0], redundant ? &rest : nullptr, v, a, qd, qdd, ws);
    // Central differences with steps 2h and h: their errors against exact
    // rates fall as step^2 (by about 4 when the step halves), down to rounding.
    const auto qd_err = [&](int k) { return (qd - (sol[k] - sol[-k]) / (2 * k * h)).norm(); };
    const auto qdd_err = [&](int k) {
      return (qdd - (sol[k] - 2 * sol[0] + sol[-k]) / (k * k * h * h)).norm();
    };
    const double d1 = qd_err(2), d2 = qd_err(1), a1 = qdd_err(2), a2 = qdd_err(1);
    EXPECT_LT(d2, 1e-4 * (1 + qd.norm())) << c.n;
    EXPECT_LT(a2, 1e-3 * (1 + qdd.norm())) << c.n;
    if (d2 > 1e-9 * (1 + qd.norm())) {
      EXPECT_GT(d1 / d2, 3.0) << c.n << ": qd differences' errors " << d1 << " " << d2;
    }
    if (a2 > 1e-7 * (1 + qdd.norm())) {
      EXPECT_GT(a1 / a2, 3.0) << c.n << ": qdd differences' errors " << a1 << " " << a2;
    }
    if (redundant) {
      EXPECT_GT((sol[0] - rest).norm(), 0.3) << c.n;  // the rule is away from its rest pose
    }
  }
}

// Jet2 carries value, first and second derivative exactly: along x(s) = t + s
// (seed (t, 1, 0)), x^3 gives 3 t^2 and 6 t; sin(x)/x gives the closed forms
// (t cos t - sin t)/t^2 and -sin t/t - 2 cos t/t^2 + 2 sin t/t^3; cos(x)^2
// + sin(x)^2 stays 1 with zero derivatives; and a curved seed (t, v, a)
// follows the chain rule: y(x(s)) has y' v and y'' v^2 + y' a.
TEST(Jet2, CarriesExactFirstAndSecondDerivatives) {
  for (const double t : {0.3, 1.7, -2.4}) {
    const Jet2 x(t, 1.0, 0.0);
    const Jet2 cube = x * x * x;
    EXPECT_NEAR(cube.d1(), 3 * t * t, 1e-14 * (1 + t * t));
    EXPECT_NEAR(cube.d2(), 6 * t, 1e-14 * (1 + std::abs(t)));
    const Jet2 sinc = sin(x) / x;
    EXPECT_NEAR(sinc.value(), std::sin(t) / t, 1e-15);
    EXPECT_NEAR(sinc.d1(), (t * std::cos(t) - std::sin(t)) / (t * t), 1e-14);
    EXPECT_NEAR(sinc.d2(), -std::sin(t) / t - 2 * std::cos(t) / (t * t) + 2 * std::sin(t) / (t * t * t), 1e-13);
    const Jet2 one = cos(x) * cos(x) + sin(x) * sin(x);
    EXPECT_NEAR(one.value(), 1.0, 1e-15);
    EXPECT_NEAR(one.d1(), 0.0, 1e-15);
    EXPECT_NEAR(one.d2(), 0.0, 1e-14);
    const double v = 0.7, a = -1.3;
    const Jet2 c = cos(Jet2(t, v, a));
    EXPECT_NEAR(c.d1(), -std::sin(t) * v, 1e-15);
    EXPECT_NEAR(c.d2(), -std::cos(t) * v * v - std::sin(t) * a, 1e-15);
    const Jet2 q = Jet2(1.0, 0.0, 0.0) / Jet2(t, v, a);  // 1/x: -x'/x^2, 2 x'^2/x^3 - x''/x^2
    EXPECT_NEAR(q.d1(), -v / (t * t), 1e-14);
    EXPECT_NEAR(q.d2(), 2 * v * v / (t * t * t) - a / (t * t), 1e-13);
  }
}

// ---- Every integrator on passive random chains -------------------------

// A passive random chain (no drive, no controller: zero joint torque) with
// viscous friction on the motor shafts and the energy ledger, released from
// rest at q0 in [-1, 1] rad: smooth in t and x, so every method shows its
// order. The friction B = 1e-4 N m s/rad (motor side; Z^2 B on the link,
// some 0.04 to 1.4 N m s/rad) dissipates a measurable part of the energy.
constexpr int kAnyNJoints[] = {7, 9, 12, 16};
constexpr double kAnyNT = 0.5;  // [s]


const Scene& any_n_passive_scene(int n) {
  static std::map<int, Scene> cache;
  if (auto it = cache.find(n); it != cache.end()) return it->second;
  const std::string robot = random_robot_file(n, 1000 + static_cast<std::uint64_t>(n));
  Rng rng(77 + static_cast<std::uint64_t>(n));
  const std::string scene =
      "[scene]\nname = \"random" + std::to_string(n) + "_passive\"\nrobot = \"" + robot + "\"\njoints = " +
      std::to_string(n) + "\nbackend = \"crba\"\nduration = " + std::to_string(kAnyNT) +
      "\noutput_interval = 0.05\nenergy_ledger = true\n\n[integrator]\nname = \"rk4\"\ndt = 0.001\n\n"
      "[friction]\nmodel = \"viscous\"\nviscous = " + testing::toml_numbers(Eigen::VectorXd::Constant(n, 1e-4)) +
      "\n\n[initial]\nq = " + testing::toml_numbers(rng.uniform_vector(n, -1, 1)) + "\n";
  const std::string file = write_scratch_file("any_n/random" + std::to_string(n) + "_passive.toml", scene);
  return cache.emplace(n, load_scene(file)).first->second;
}

std::vector<double> any_n_final_state(int n, const IntegratorInfo& info, const IntegratorOptions& o) {
  Plant plant(any_n_passive_scene(n).plant);
  auto integ = info.make(o);
  std::vector<double> x;
  const RunResult r =
      run_plant(plant, *integ, {.t_end = kAnyNT, .output_interval = kAnyNT, .observe = [&](double, const double* s) {
                                  x.assign(s, s + plant.size());
                                }});
  EXPECT_TRUE(r.ok) << info.name << " n = " << n << ": " << r.failure;
  return x;
}

// The reference: Dormand-Prince at rtol 1e-12, atol 1e-14 (as the PUMA's
// conformance tests, tests/test_conformance.cpp).
const std::vector<double>& any_n_reference(int n) {
  static std::map<int, std::vector<double>> cache;
  if (auto it = cache.find(n); it != cache.end()) return it->second;
  IntegratorOptions o;
  o.rtol = 1e-12, o.atol = 1e-14;
  return cache.emplace(n, any_n_final_state(n, find_integrator("odeint-dopri5"), o)).first->second;
}

// max over every state (the ledger's included) of |x - x_ref| / its typical magnitude.
double any_n_error(int n, const std::vector<double>& x) {
  Plant plant(any_n_passive_scene(n).plant);
  const std::vector<double>& ref = any_n_reference(n);
  double e = 0;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    e = std::max(e, std::abs(x[k] - ref[k]) / plant.tolerance_scale(static_cast<int>(k)));
  }
  return e;
}

// The ledger at the end of a run: E(T) - E(0) + e_friction(T) (zero for the
// ODE: no input, no copper), and the energy dissipated.
struct AnyNLedger {
  double residual, dissipated, rise;
};
AnyNLedger any_n_ledger(int n, const std::vector<double>& x) {
  Plant plant(any_n_passive_scene(n).plant);
  std::vector<double> x0(plant.size());
  plant.initial_state(x0.data());
  const int e = plant.layout().e;
  const double E0 = plant.mechanical_energy(x0.data()), E1 = plant.mechanical_energy(x.data());
  return {E1 - E0 + x[static_cast<std::size_t>(e + 2)] - x[static_cast<std::size_t>(e)] +
              x[static_cast<std::size_t>(e + 1)],
          x[static_cast<std::size_t>(e + 2)], E1 - E0};
}

class AnyNIntegrators : public ::testing::TestWithParam<std::string> {};

// Fixed step: the error at T falls as dt^p from dt = 4 ms to 2 ms (within 0.35
// of the registry's order p). Adaptive: as the PUMA's conformance test, the
// error falls with rtol, log10 slope in [0.5, 1.5] over rtol 1e-5 ... 1e-8.
// The error measure sees every state, the ledger's energies included.
TEST_P(AnyNIntegrators, ConvergeAndKeepTheLedgerOnPassiveChains) {
  const IntegratorInfo& info = find_integrator(GetParam());
  for (int n : kAnyNJoints) {
    // The ODE itself keeps the ledger (the reference to 1e-9 of what it
    // dissipates) and loses energy: the model's bookkeeping for this n.
    const AnyNLedger l_ref = any_n_ledger(n, any_n_reference(n));
    EXPECT_GT(l_ref.dissipated, 0.0) << n;
    EXPECT_LT(l_ref.rise, 0.0) << n;
    EXPECT_LT(std::abs(l_ref.residual), 1e-9 * l_ref.dissipated) << "reference, n = " << n;
    if (info.kind == IntegratorKind::kFixedStep) {
      const double e1 = any_n_error(n, any_n_final_state(n, info, testing::fixed_step(4e-3)));
      const double e2 = any_n_error(n, any_n_final_state(n, info, testing::fixed_step(2e-3)));
      EXPECT_NEAR(std::log2(e1 / e2), info.order, 0.35) << info.name << " n = " << n << " errors " << e1 << " " << e2;
    } else {
      IntegratorOptions lo, hi;
      lo.rtol = lo.atol = 1e-5;
      hi.rtol = hi.atol = 1e-8;
      const double e_lo = any_n_error(n, any_n_final_state(n, info, lo));
      const double e_hi = any_n_error(n, any_n_final_state(n, info, hi));
      const double slope = (std::log10(e_hi) - std::log10(e_lo)) / (-8.0 + 5.0);
      EXPECT_GE(slope, 0.5) << info.name << " n = " << n << " errors " << e_lo << " " << e_hi;
      EXPECT_LE(slope, 1.5) << info.name << " n = " << n << " errors " << e_lo << " " << e_hi;
    }
  }
}

// ---- A long arm tracking a Cartesian pose path -------------------------

// A random chain of n joints (6: the pose; 7, 12: redundant for the pose)
// follows a path of a line and an arc from the flange's pose at a random q_g, with
// its orientation held there (reference.orientation), by the numerical
// inverse kinematics and its redundancy rule (rest pose q_g), under computed
// torque with the reduced drive (La = 0) as planar2_tracking. The joint
// error then obeys e'' + kd e' + kp e = H^-1 Z^2 B q' (tests/check_arm_scenes.py
// derives it: the viscous friction is the only torque the law does not
// cancel), so with e(0) = e'(0) = 0 and critical damping
//   |e_j(t)| <= max_j(Z_j^2 B_j) / min_j(Z_j^2 Im_j) * max_t |q'(t)|_2 / kp,
// checked with the run's own speeds.
// On the same scenes (each costs a 2000-point branch table of the rule: one
// load each, which matters under the sanitizers): a sample made by another
// reference (a joint curve's: a 3-row workspace) is resized by the pose
// path's eval, which then gives what its own sample gives; and a plant
// refuses a reference for another joint count (the controllers read the
// reference's first n joints).
TEST(AnyN, ALongArmTracksAPosePathWithinTheComputedTorqueBound) {
  std::map<int, Scene> scenes;
  for (const int n : {6, 7, 12}) {
    const double kp = 400, B = 1e-5;  // the scene's kp [1/s^2] and viscous friction [N m s/rad]
    const RobotModel m = random_chain(n, 500 + static_cast<std::uint64_t>(n));
    const Scene& sc = scenes.emplace(n, load_scene(testing::random_tracking_scene_file(n, B))).first->second;
    Plant plant(sc.plant);
    IntegratorOptions o;
    o.rtol = 1e-9, o.atol = 1e-11;
    auto integ = find_integrator("cvode-bdf").make(o);
    double e_max = 0, qd_max = 0, moved = 0;
    const int q0 = plant.layout().q, v0 = plant.layout().qd;
    const Eigen::VectorXd q_start = plant.reference_at(0.0).q;
    const RunResult r =
        run_plant(plant, *integ, {.t_end = 2.5, .output_interval = 0.01, .observe = [&](double t, const double* x) {
                                    const Eigen::VectorXd q_ref =
                                        plant.reference_at(t).q;  // a copy: the plant's sample is reused
                                    double speed2 = 0;
                                    for (int j = 0; j < n; ++j) {
                                      e_max = std::max(e_max, std::abs(q_ref[j] - x[q0 + j]));
                                      speed2 += x[v0 + j] * x[v0 + j];
                                      moved = std::max(moved, std::abs(q_ref[j] - q_start[j]));
                                    }
                                    qd_max = std::max(qd_max, std::sqrt(speed2));
                                  }});
    ASSERT_TRUE(r.ok) << n << ": " << r.failure;
    double zb = 0, zi = std::numeric_limits<double>::infinity();
    for (const JointParams& J : m.joints) {
      zb = std::max(zb, J.gear_ratio * J.gear_ratio * B);
      zi = std::min(zi, J.gear_ratio * J.gear_ratio * J.rotor_inertia);
    }
    const double bound = zb / zi * qd_max / kp;
    EXPECT_GT(moved, 1e-3) << n;  // the reference moves the joints
    std::printf("n = %d: joint error %.3g rad, bound %.3g rad, reference moved %.3g rad\n", n, e_max, bound, moved);
    EXPECT_LE(e_max, bound * (1 + 1e-3) + 1e-7) << n << ": error " << e_max << " rad, bound " << bound;
  }
  const Scene& sc = scenes.at(7);
  const Reference& ref = *sc.plant.reference;
  const JointCurve curve({0.0, 1.0}, {Eigen::VectorXd::Zero(7), Eigen::VectorXd::Constant(7, 0.1)}, 7,
                         JointCurve::Kind::kCubic);
  const Reference joint_ref(sc.plant.robot, Eigen::VectorXd::Zero(7), curve, Timing::unit_speed(1.0));
  ReferenceSample foreign = joint_ref.sample(), own = ref.sample();
  ASSERT_FALSE(ref.fits(foreign));
  ref.eval(0.8, foreign);
  ref.eval(0.8, own);
  EXPECT_TRUE(ref.fits(foreign));
  EXPECT_EQ(foreign.q, own.q);
  EXPECT_EQ(foreign.qd, own.qd);
  EXPECT_EQ(foreign.qdd, own.qdd);
  PlantConfig mixed = sc.plant;
  mixed.reference = scenes.at(12).plant.reference;
  try {
    Plant plant(mixed);
    ADD_FAILURE() << "a 12-joint reference was accepted by a 7-joint plant";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the reference is for 12 of 12 joints, the plant simulates 7 of 7"),
              std::string::npos)
        << e.what();
  }
}

std::string any_n_test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s)
    if (c == '-') c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Registry, AnyNIntegrators, ::testing::ValuesIn(testing::integrator_names()),
                         any_n_test_name);

}  // namespace
}  // namespace pumasim
