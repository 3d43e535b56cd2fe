// The joint-torque regressor (models/dynamics/regressor.hpp) and the base
// parameters (models/robot/base_parameters.hpp): Y pi against every
// back-end's inverse dynamics, the two ways to Y against each other, the
// friction columns against their closed form, and the base-parameter counts
// against Khalil's grouping rules worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/regressor.hpp"
#include "models/robot/base_parameters.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "tests/helpers.hpp"

namespace pumasim {
namespace {

// The PUMA 560, the Panda, and random chains with prismatic joints in both DH conventions.
std::vector<RobotModel> regressor_arms() {
  return {load_robot("puma560"), load_robot("panda"), random_chain(5, 11, DhConvention::kStandard, "RP"),
          random_chain(7, 12, DhConvention::kModified, "RRP")};
}

struct State {
  Eigen::VectorXd q, qd, qdd;
};

State random_state(Rng& rng, int n) {
  return {rng.uniform_vector(n, -2.0, 2.0), rng.uniform_vector(n, -3.0, 3.0), rng.uniform_vector(n, -5.0, 5.0)};
}

TEST(Regressor, TimesTheModelsParametersIsEveryBackendsInverseDynamics) {
  for (const RobotModel& arm : regressor_arms()) {
    JointTorqueRegressor regressor(arm, {.rotor = true, .friction = false});
    const Eigen::VectorXd pi = regressor.parameters_of(arm);
    Eigen::MatrixXd Y(arm.dof(), regressor.parameters());
    Rng rng(3);
    for (int s = 0; s < 4; ++s) {
      const State x = random_state(rng, arm.dof());
      regressor.compute(x.q, x.qd, x.qdd, Y);
      const Eigen::VectorXd tau_y = Y * pi;
      for (const BackendInfo& info : testing::supported(arm)) {
        auto backend = info.make(arm);
        Eigen::VectorXd tau(arm.dof());
        backend->inverse_dynamics(x.q, x.qd, x.qdd, tau);
        // The bound: 1e-12 of the largest joint torque.
        EXPECT_LE((tau_y - tau).cwiseAbs().maxCoeff(), 1e-12 * tau.cwiseAbs().maxCoeff())
            << arm.name << ", back-end " << info.name << ", state " << s;
      }
    }
  }
}

TEST(Regressor, ProbingTheRneaWithUnitParametersGivesTheDirectRegressor) {
  for (const RobotModel& arm : regressor_arms()) {
    JointTorqueRegressor regressor(arm);
    Eigen::MatrixXd direct(arm.dof(), regressor.parameters()), probed(arm.dof(), regressor.parameters());
    Rng rng(5);
    for (int s = 0; s < 3; ++s) {
      const State x = random_state(rng, arm.dof());
      regressor.compute(x.q, x.qd, x.qdd, direct);
      regressor.compute_by_probing(x.q, x.qd, x.qdd, probed);
      EXPECT_LE((direct - probed).cwiseAbs().maxCoeff(), 1e-12 * direct.cwiseAbs().maxCoeff()) << arm.name;
    }
  }
}

// with_parameters inverts parameters_of: the links' values back in their DH
// frames (an identity on each arm), and a moved pi put into a model is that
// model's pi and its back-ends' inverse dynamics is Y pi (the frames'
// transforms undone correctly, in both DH conventions and for a URDF's).
TEST(Regressor, WithParametersPutsAParameterVectorIntoTheModel) {
  for (const RobotModel& arm : regressor_arms()) {
    JointTorqueRegressor regressor(arm);
    const Eigen::VectorXd pi = regressor.parameters_of(arm);
    const RobotModel same = regressor.with_parameters(arm, pi);
    for (int j = 0; j < arm.dof(); ++j) {
      const JointParams &a = arm.joints[static_cast<std::size_t>(j)], &b = same.joints[static_cast<std::size_t>(j)];
      EXPECT_NEAR(b.mass, a.mass, 1e-12 * a.mass) << arm.name << " link " << j + 1;
      EXPECT_LE((b.com - a.com).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + a.com.norm())) << arm.name << " link " << j + 1;
      EXPECT_LE((b.inertia - a.inertia).cwiseAbs().maxCoeff(), 1e-10 * (1e-3 + a.inertia.norm()))
          << arm.name << " link " << j + 1;
      EXPECT_NEAR(b.rotor_inertia, a.rotor_inertia, 1e-12 * (1e-6 + a.rotor_inertia)) << arm.name;
    }
    // Moved: 1.3 times each mass and first moment, inertias grown so that the
    // link stays a body (2x about the origin), rotors and friction moved.
    Eigen::VectorXd moved = pi;
    for (int j = 0; j < arm.dof(); ++j) {
      double* p = moved.data() + static_cast<std::ptrdiff_t>(j) * regressor.per_joint();
      for (int k = 0; k < 6; ++k) p[k] *= 2.0;
      for (int k = 6; k < 10; ++k) p[k] *= 1.3;
      p[10] = 0.5 * p[10] + 0.01;        // Ia
      p[11] = 0.2 + j, p[12] = 0.1 * j;  // Fv, Fc
      p[13] = 0.0;                       // Fo: not in a model
    }
    const RobotModel other = regressor.with_parameters(arm, moved);
    const Eigen::VectorXd back = regressor.parameters_of(other);
    EXPECT_LE((back - moved).cwiseAbs().maxCoeff(), 1e-10 * moved.cwiseAbs().maxCoeff()) << arm.name;
    JointTorqueRegressor no_friction(arm, {.rotor = true, .friction = false});
    const Eigen::VectorXd pi_links = no_friction.parameters_of(other);
    Eigen::MatrixXd Y(arm.dof(), no_friction.parameters());
    Rng rng(9);
    const State x = random_state(rng, arm.dof());
    no_friction.compute(x.q, x.qd, x.qdd, Y);
    auto backend = testing::supported(other).front().make(other);
    Eigen::VectorXd tau(arm.dof());
    backend->inverse_dynamics(x.q, x.qd, x.qdd, tau);
    EXPECT_LE((Y * pi_links - tau).cwiseAbs().maxCoeff(), 1e-12 * tau.cwiseAbs().maxCoeff()) << arm.name;
  }
  JointTorqueRegressor regressor(load_robot("puma560"));
  Eigen::VectorXd pi = regressor.parameters_of(load_robot("puma560"));
  pi[9 + regressor.per_joint()] = -1.0;  // M2
  EXPECT_THROW(regressor.with_parameters(load_robot("puma560"), pi), std::invalid_argument);
}

TEST(Regressor, FrictionColumnsAreViscousCoulombAndOffset) {
  const RobotModel arm = load_robot("puma560");
  JointTorqueRegressor with(arm), without(arm, {.rotor = true, .friction = false});
  Eigen::VectorXd pi = with.parameters_of(arm);
  const Eigen::VectorXd pi_rigid = without.parameters_of(arm);
  const int n = arm.dof();
  Eigen::VectorXd fv(n), fc(n), fo(n);
  for (int j = 0; j < n; ++j) {
    fv[j] = 0.5 + j, fc[j] = 2.0 - 0.1 * j, fo[j] = 0.3 * (j - 2);
    const int at = j * with.per_joint() + JointTorqueRegressor::kLinkParameters + 1;
    pi[at] = fv[j], pi[at + 1] = fc[j], pi[at + 2] = fo[j];
  }
  Eigen::MatrixXd Y(n, with.parameters()), Yr(n, without.parameters());
  Eigen::VectorXd qd = Eigen::VectorXd::LinSpaced(n, -1.0, 1.5);
  qd[2] = 0.0;  // sign(0) = 0: no Coulomb term at rest
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(n, 0.4), qdd = Eigen::VectorXd::Constant(n, -0.7);
  with.compute(q, qd, qdd, Y);
  without.compute(q, qd, qdd, Yr);
  for (int j = 0; j < n; ++j) {
    const double sign = qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0);
    const double expected = (Yr * pi_rigid)[j] + fv[j] * qd[j] + fc[j] * sign + fo[j];
    EXPECT_NEAR((Y * pi)[j], expected, 1e-12 * std::abs(expected)) << "joint " << j + 1;
  }
  EXPECT_EQ(with.parameter_name(JointTorqueRegressor::kLinkParameters), "Ia1");
  EXPECT_EQ(with.parameter_name(with.per_joint() + JointTorqueRegressor::kLinkParameters + 2), "Fc2");
}

// The base-parameter counts from Khalil's grouping rules (Gautier & Khalil,
// "Direct calculation of minimum set of inertial parameters of serial
// robots", IEEE TRA 6(3), 1990; Khalil & Dombre, "Modeling, identification
// and control of robots", 2002, sec. 9.5.2-9.5.3), for a chain of revolute
// joints whose first axis is vertical (parallel to gravity):
// - General rule, every link j: YYj, MZj and Mj act only together with link
//   j-1's parameters and regroup onto them (XXRj = XXj - YYj, ...), leaving
//   7 of the 10: XXRj, XYj, XZj, YZj, ZZRj, MXRj, MYRj.
// - Link 1 turns about the fixed vertical axis: its angular velocity has a
//   z component only and gravity lies along that axis, so of its 7 only ZZR1
//   acts (XXR1, XY1, XZ1, YZ1, MX1, MY1 have no effect; nor have the
//   M1R and MZ1R that link 2's M2 and MZ2 regroup into).
// - Every other joint axis of the PUMA and the Panda is perpendicular to the
//   one before it, except the PUMA's joints 2 and 3 (parallel, but joint 2
//   is not parallel to joint 1, so link 3 still turns about two directions
//   and keeps its 7): no further rule applies.
// Rigid links: 1 + 7 (n - 1), 36 for the PUMA (n = 6) and 43 for the Panda (n = 7).
// Rotors (Ia_j, a Z^2 Im qdd_j term on joint j only): Ia1 has ZZ1's column
// (link 1 turns with joint 1 alone) and regroups into ZZR1. Ia2 has ZZ2's:
// link 1 turns about the fixed z1 and z2 is perpendicular to it, so link
// 2's angular velocity is qd1 z1 + qd2 z2 with qd1 z1 normal to z2; ZZ2's
// moment ZZ2 (wd_z z2 + w_z w x z2) then has no component on z1
// (z1 . z2 = 0, z1 . (w x z2) = w . (z2 x z1) = 0) and gives joint 2
// ZZ2 qdd2 alone (Khalil & Dombre's rule for the rotor of the second link).
// (A first count here that missed this rule said 41 and 49; the SVD found 40
// and 48, and the regrouping it printed, ZZ2R = ZZ2 + Ia2 + ..., led to the
// rule.) Ia3..Ian stay: + (n - 2), 40 and 48. Friction (Fv, Fc, Fo per
// joint): their columns qd_j, sign(qd_j) and 1 on joint j alone are
// independent of the rest (the rigid columns are products of accelerations,
// velocity pairs or gravity terms that vary with q): + 3n, 58 and 69 with the
// rotors, 54 and 64 without. (Not on every arm: on a vertical prismatic
// joint the mass's gravity column is constant and meets the offset's.)
TEST(BaseParameters, CountsFollowKhalilsGroupingRules) {
  struct Case {
    const char* robot;
    bool rotor, friction;
    int expected;
  };
  const Case cases[] = {{"puma560", false, false, 36}, {"puma560", true, false, 40}, {"puma560", true, true, 58},
                        {"puma560", false, true, 54},  {"panda", false, false, 43},  {"panda", true, false, 48},
                        {"panda", true, true, 69},     {"panda", false, true, 64}};
  for (const Case& c : cases) {
    const RobotModel arm = load_robot(c.robot);
    JointTorqueRegressor regressor(arm, {.rotor = c.rotor, .friction = c.friction});
    const BaseParameters base = base_parameters(regressor, arm);
    EXPECT_EQ(base.rank(), c.expected) << c.robot << " rotor " << c.rotor << " friction " << c.friction << "\n"
                                       << base.regrouping();
    // A numerical rank worth the name: the dropped singular values sit many
    // orders of magnitude below the kept ones (rounding against O(1)).
    EXPECT_GT(base.gap(), 1e8) << c.robot;
  }
}

// The second rotor's rule needs z2 perpendicular to z1: with the PUMA's
// first twist alpha1 moved by 0.1 rad, ZZ2 acts on joint 1 too and Ia2
// stands alone (one more base parameter with the rotors); the rigid links'
// count is unchanged (link 1 still turns about the vertical, and joint
// frame 2's origin still lies on axis 1).
TEST(BaseParameters, TheSecondRotorsRuleNeedsPerpendicularFirstAxes) {
  RobotModel arm = load_robot("puma560");
  arm.joints[0].alpha += 0.1;
  const struct {
    bool rotor, friction;
    int expected;
  } cases[] = {{false, false, 36}, {true, false, 41}, {true, true, 59}};
  for (const auto& c : cases) {
    JointTorqueRegressor regressor(arm, {.rotor = c.rotor, .friction = c.friction});
    const BaseParameters base = base_parameters(regressor, arm);
    EXPECT_EQ(base.rank(), c.expected) << "rotor " << c.rotor << " friction " << c.friction << "\n"
                                       << base.regrouping();
    EXPECT_GT(base.gap(), 1e8);
  }
}

TEST(BaseParameters, RefusesABadToleranceOrTooFewSamples) {
  const RobotModel arm = load_robot("puma560");
  JointTorqueRegressor regressor(arm);
  for (double tol : {0.0, -1e-8, 1.0, std::nan("")}) {
    EXPECT_THROW(base_parameters(regressor, arm, 40, 1, tol), std::invalid_argument) << tol;
  }
  // 84 columns need at least 14 states of 6 rows.
  EXPECT_THROW(base_parameters(regressor, arm, 13), std::invalid_argument);
  EXPECT_EQ(base_parameters(regressor, arm, 14).rank(), 58);
}

TEST(BaseParameters, BaseColumnsTimesBaseValuesGiveTheTorquesAtNewStates) {
  for (const RobotModel& arm : regressor_arms()) {
    JointTorqueRegressor regressor(arm);
    const BaseParameters base = base_parameters(regressor, arm, 40, 7);
    Eigen::VectorXd pi = regressor.parameters_of(arm);
    Rng rng(9);
    for (Eigen::Index k = 0; k < pi.size(); ++k) pi[k] += rng.uniform(-1.0, 1.0);  // any pi, not only a physical one
    const Eigen::VectorXd pi_b = base.values(pi);
    Eigen::MatrixXd Y(arm.dof(), regressor.parameters());
    for (int s = 0; s < 3; ++s) {
      const State x = random_state(rng, arm.dof());
      regressor.compute(x.q, x.qd, x.qdd, Y);
      const Eigen::VectorXd tau = Y * pi, tau_b = base.columns(Y) * pi_b;
      EXPECT_LE((tau - tau_b).cwiseAbs().maxCoeff(), 1e-9 * tau.cwiseAbs().maxCoeff()) << arm.name;
    }
  }
}

TEST(BaseParameters, PumaRegroupsTheFirstLinkOntoZZ1) {
  const RobotModel arm = load_robot("puma560");
  JointTorqueRegressor regressor(arm, {.rotor = true, .friction = false});
  const BaseParameters base = base_parameters(regressor, arm);
  const std::string text = base.regrouping();
  // Link 1's only acting parameter, carrying its rotor: ZZR1 = ZZ1 + Ia1 + ...
  EXPECT_NE(text.find("ZZ1R = ZZ1 + Ia1"), std::string::npos) << text;
  // The second rotor's rule (CountsFollowKhalilsGroupingRules' comment).
  EXPECT_NE(text.find("ZZ2R = ZZ2 + Ia2"), std::string::npos) << text;
  std::vector<std::string> inert;
  for (int k : base.no_effect) inert.push_back(base.names[static_cast<std::size_t>(k)]);
  // The rest of link 1's: its own frame turns about z alone, with gravity
  // along that z. And link 2's M2 and MZ2: joint frame 2's origin lies on
  // axis 1 (the PUMA's a1 = d1 = 0), a fixed point, so a mass there neither
  // moves nor weighs on any joint, and a first moment along the horizontal
  // z2 enters neither the kinetic energy (v_o = 0) nor the potential (g . z2 = 0).
  const std::vector<std::string> expected = {"XX1", "XY1", "XZ1", "YY1", "YZ1", "MX1", "MY1", "MZ1", "M1", "MZ2", "M2"};
  EXPECT_EQ(inert, expected) << text;
}

}  // namespace
}  // namespace pumasim
