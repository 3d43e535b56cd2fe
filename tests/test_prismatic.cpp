// Prismatic joints: closed forms that every back-end must reproduce (a slider
// under gravity, the polar R-P arm), the flange's forward kinematics of the
// polar arm, the closed-form back-ends' refusal, and the model-level checks
// (a prismatic joint's d and a revolute joint's theta are the joint variable).
// The agreement of the back-ends on random chains mixing both kinds is in
// tests/test_backends.cpp, the identities on them in tests/test_identities.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "models/dynamics/backend.hpp"
#include "models/robot/kinematics.hpp"
#include "models/robot/robot_file.hpp"
#include "simulation/run_recorder.hpp"
#include "tests/helpers.hpp"

#ifndef PUMASIM_TEST_ROBOTS_DIR
#error "PUMASIM_TEST_ROBOTS_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

using testing::evaluate;
using testing::Quantities;
using testing::rel_err;

// Closed form against a back-end: a few hundred roundings of O(1..10) numbers.
constexpr double kPrismaticClosedForm = 1e-12;

// One prismatic joint, link of mass m, rotor Im behind a screw of ratio Z.
RobotModel slider(DhConvention convention, double alpha, const Eigen::Vector3d& gravity) {
  RobotModel m;
  m.name = std::string("slider (") + to_string(convention) + ")";
  m.convention = convention;
  m.gravity = gravity;
  JointParams J;
  J.type = JointType::kPrismatic;
  J.a = 0.2;  // only places the link's frame: no effect on a pure translation
  J.alpha = alpha;
  J.theta = 0.7;
  J.offset = -0.05;
  J.mass = 2.5;
  J.com = Eigen::Vector3d(0.1, -0.2, 0.05);
  J.inertia = Eigen::Vector3d(0.3, 0.2, 0.4).asDiagonal();
  J.rotor_inertia = 3e-5;
  J.gear_ratio = 400.0;  // [rad/m]
  m.joints.push_back(J);
  return m;
}

// A body that only translates along the unit axis z: Newton's second law
// along z, m qdd = tau_link + m g.z, with the screw's armature Z^2 Im on the
// motor side: tau = (m + Z^2 Im) qdd - m g.z, for any speed (no velocity term).
void expect_slider_law(const RobotModel& m, const Eigen::Vector3d& z) {
  const JointParams& J = m.joints[0];
  const double mass = J.mass, arm = J.gear_ratio * J.gear_ratio * J.rotor_inertia;
  for (const auto& info : testing::supported(m)) {
    auto b = info.make(m);
    Rng rng(11);
    for (int s = 0; s < 5; ++s) {
      const Eigen::VectorXd q = rng.uniform_vector(1, -1, 1), qd = rng.uniform_vector(1, -2, 2);
      const Eigen::VectorXd qdd = rng.uniform_vector(1, -5, 5), tau = rng.uniform_vector(1, -50, 50);
      const Quantities r = evaluate(*b, q, qd, qdd, tau);
      const double gz = m.gravity.dot(z);
      const Eigen::VectorXd weight = Eigen::VectorXd::Constant(1, -mass * gz);
      const std::string who = std::string(info.name) + " " + m.name;
      EXPECT_LT(rel_err(r.H, Eigen::MatrixXd::Constant(1, 1, mass + arm)), kPrismaticClosedForm) << who;
      EXPECT_LT(rel_err(r.g, weight), kPrismaticClosedForm) << who;
      EXPECT_LT(rel_err(r.h, weight), kPrismaticClosedForm) << who;
      EXPECT_LT(rel_err(r.tau, (mass + arm) * qdd + weight), kPrismaticClosedForm) << who;
      EXPECT_LT(rel_err(r.qdd, (tau - weight) / (mass + arm)), kPrismaticClosedForm) << who;
    }
  }
}

TEST(Prismatic, SliderAlongGravityIsNewtonsSecondLaw) {
  // Standard DH: joint 1 slides along the base z axis, here along gravity:
  // tau = (m + Z^2 Im) qdd + m 9.81.
  expect_slider_law(slider(DhConvention::kStandard, 0.4, {0, 0, -9.81}), Eigen::Vector3d::UnitZ());
  // Gravity with components across the axis: only g.z enters.
  expect_slider_law(slider(DhConvention::kStandard, 0.4, {3, -2, -9.81}), Eigen::Vector3d::UnitZ());
  // Modified DH: the axis is Rx(alpha) z = (0, -sin alpha, cos alpha).
  const double alpha = 0.4;
  expect_slider_law(slider(DhConvention::kModified, alpha, {3, -2, -9.81}),
                    Eigen::Vector3d(0, -std::sin(alpha), std::cos(alpha)));
}

// The polar arm of tests/robots/rp_polar.toml: joint 1 turns about the
// vertical axis, joint 2 slides along the horizontal z1, r = q2 + offset is
// the distance of link 2's centre of mass from the axis (its com is on the
// slide's axis, 3 cm above it). With J1 and J2 the links' moments of inertia
// about the vertical axis (y1 = y2 in the links' frames), the kinetic energy is
//   T = 1/2 (J1 + J2 + m2 r^2) qd1^2 + 1/2 m2 rd^2  (+ 1/2 Z_j^2 Im_j qd_j^2)
// (link 2's centre moves with rd along z1 and r qd1 across it), the potential
// is constant (both links move in horizontal planes), and Lagrange's equations
// give
//   tau1 = (J1 + J2 + m2 r^2 + Z1^2 Im1) qdd1 + 2 m2 r rd qd1
//   f2   = (m2 + Z2^2 Im2) rdd - m2 r qd1^2
// the RP manipulator of Craig, Introduction to Robotics (3rd ed., 2005),
// sec. 6.10, laid in a horizontal plane (there it is vertical, with gravity
// terms): centrifugal force -m2 r qd1^2 on the slide, Coriolis torque
// 2 m2 r rd qd1 on the turning joint.
TEST(Prismatic, PolarArmHasTheTextbookClosedForm) {
  const RobotModel m = load_robot(std::string(PUMASIM_TEST_ROBOTS_DIR) + "/rp_polar.toml");
  ASSERT_EQ(m.dof(), 2);
  ASSERT_TRUE(m.joints[1].prismatic());
  const JointParams &L1 = m.joints[0], &L2 = m.joints[1];
  const double J1 = L1.inertia(1, 1) + L1.mass * (L1.com.x() * L1.com.x() + L1.com.z() * L1.com.z());
  const double J2 = L2.inertia(1, 1), m2 = L2.mass;
  const double arm1 = L1.gear_ratio * L1.gear_ratio * L1.rotor_inertia;
  const double arm2 = L2.gear_ratio * L2.gear_ratio * L2.rotor_inertia;
  int backends = 0;
  for (const auto& info : testing::supported(m)) {
    ++backends;
    auto b = info.make(m);
    Rng rng(13);
    for (int s = 0; s < 5; ++s) {
      const Eigen::VectorXd q = rng.uniform_vector(2, -1, 1), qd = rng.uniform_vector(2, -2, 2);
      const Eigen::VectorXd qdd = rng.uniform_vector(2, -5, 5), tau = rng.uniform_vector(2, -5, 5);
      const Quantities r = evaluate(*b, q, qd, qdd, tau);
      const double rad = q[1] + L2.offset;
      Eigen::Matrix2d H;
      H << J1 + J2 + m2 * rad * rad + arm1, 0, 0, m2 + arm2;
      const Eigen::Vector2d h(2 * m2 * rad * qd[1] * qd[0], -m2 * rad * qd[0] * qd[0]);
      const std::string who = std::string(info.name) + " state " + std::to_string(s);
      EXPECT_LT(rel_err(r.H, H), kPrismaticClosedForm) << who;
      EXPECT_LT(rel_err(r.h, h), kPrismaticClosedForm) << who;
      EXPECT_LT(r.g.norm(), 1e-12) << who;  // vertical axis, horizontal slide
      EXPECT_LT(rel_err(r.tau, H * qdd + h), kPrismaticClosedForm) << who;
      EXPECT_LT(rel_err(r.qdd, H.inverse() * (tau - h)), kPrismaticClosedForm) << who;
    }
  }
  EXPECT_EQ(backends, 6);  // all but the generated ones made for the PUMA 560
  // The flange (link 2's DH frame) is at radius r along z1 = (sin q1, -cos q1, 0), height d1.
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  const Eigen::Vector2d q(0.3, 0.25);
  forward_kinematics<double>(m, q, R, p);
  const double rad = q[1] + L2.offset;
  EXPECT_LT((p - Eigen::Vector3d(rad * std::sin(q[0]), -rad * std::cos(q[0]), L1.d)).norm(), 1e-14);
}

// A PUMA 560 with its elbow made a slide: the back-ends generated for the PUMA
// (closed form, unrolled RNEA and CRBA) describe revolute joints only and say so.
TEST(Prismatic, ClosedFormBackEndsRefuseAPrismaticJoint) {
  RobotModel m = load_robot("puma560");
  JointParams& J = m.joints[2];
  J.type = JointType::kPrismatic;
  J.offset = J.d;
  J.d = 0.0;
  for (const char* name : {"lagrange-symbolic", "lagrange-symbolic-puma560", "crba-symbolic",
                           "crba-symbolic-puma560", "rnea-probing-symbolic",
                           "rnea-probing-symbolic-puma560"}) {
    const std::string why = find_backend(name).why_unsupported(m);
    EXPECT_NE(why.find("joint 3 is prismatic"), std::string::npos) << name << ": " << why;
    EXPECT_THROW(make_backend(name, m), std::invalid_argument) << name;
  }
  EXPECT_NE(puma_ik_unsupported(m).find("prismatic"), std::string::npos);
  EXPECT_NO_THROW(make_backend("crba", m));
}

// The parameter a joint variable replaces must be zero: a prismatic joint's d
// (d = q + offset) and a revolute joint's theta (theta = q + offset).
TEST(Prismatic, TheReplacedParameterMustBeZero) {
  RobotModel m = random_chain(3, 5, DhConvention::kStandard, "RPR");
  m.joints[1].d = 0.2;
  try {
    make_backend("crba", m);
    FAIL() << "accepted d on a prismatic joint";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 2 is prismatic: its d is the joint variable"),
              std::string::npos)
        << e.what();
  }
  m = random_chain(3, 5, DhConvention::kModified, "RPR");
  m.joints[2].theta = 0.1;
  EXPECT_THROW(make_backend("aba", m), std::invalid_argument);
}

// random_chain's pattern: "R" is the all-revolute chain itself (the
// benchmark's and the older tests' chains do not change), and a prismatic
// joint leaves every other joint as it was.
TEST(Prismatic, RandomChainPatternKeepsTheOtherJoints) {
  for (DhConvention c : {DhConvention::kStandard, DhConvention::kModified}) {
    const RobotModel r = random_chain(7, 42, c), rr = random_chain(7, 42, c, "R");
    const RobotModel mixed = random_chain(7, 42, c, "RRP");
    ASSERT_EQ(mixed.dof(), 7);
    for (int j = 0; j < 7; ++j) {
      const JointParams &a = r.joints[j], &b = rr.joints[j], &x = mixed.joints[j];
      EXPECT_EQ(a.a, b.a);
      EXPECT_EQ(a.offset, b.offset);
      EXPECT_EQ(b.type, JointType::kRevolute);
      EXPECT_EQ(x.prismatic(), j % 3 == 2) << j;
      EXPECT_EQ(a.mass, x.mass);
      EXPECT_EQ(a.alpha, x.alpha);
      if (!x.prismatic()) { EXPECT_EQ(a.d, x.d); }
      if (x.prismatic()) {  // the drawn angle is its theta, the drawn length its offset
        EXPECT_EQ(x.d, 0.0);
        EXPECT_EQ(x.theta, a.offset);
        EXPECT_EQ(x.offset, a.d);
      }
    }
  }
  EXPECT_THROW(random_chain(3, 1, DhConvention::kStandard, "RX"), std::invalid_argument);
}

}  // namespace
}  // namespace pumasim

namespace pumasim {
namespace {

// trajectory.csv's units follow the joint type: the Stanford arm's boom
// (joint 3, prismatic) in m and m/s, its revolute joints in rad and rad/s,
// every PIV integral motor-side (rad s).
TEST(Prismatic, TrajectoryUnitsFollowTheJointType) {
  const RobotModel stanford = load_robot("stanford");
  ASSERT_TRUE(stanford.joints[2].prismatic());
  EXPECT_EQ(unit_of_state("q3", &stanford), "m");
  EXPECT_EQ(unit_of_state("qd3", &stanford), "m/s");
  EXPECT_EQ(unit_of_state("q2", &stanford), "rad");
  EXPECT_EQ(unit_of_state("qd4", &stanford), "rad/s");
  EXPECT_EQ(unit_of_state("z_piv3", &stanford), "rad s");
  EXPECT_EQ(unit_of_state("q3"), "rad");  // without the robot: the revolute default
}

}  // namespace
}  // namespace pumasim
