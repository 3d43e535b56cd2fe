// The published PUMA 560 parameter sets side by side (issue 35, the literature
// spread): the AKB86 set as the Robotics Toolbox gives it (mdl_puma560akb.m,
// modified DH: models/robots/puma560_akb.toml) against the toolbox's standard
// model (mdl_puma560.m: models/robots/puma560.toml). Every expected value comes
// from the published tables (models/robots/puma560_sources.md, sections 1-3)
// or from closed forms derived from them (section 8: the joint-angle map
// q_akb = q_rtb + (pi, -pi, pi, 0, 0, 0) between the two conventions), never
// from the program's own output:
// - the AKB file holds the table of section 2, its joint limits are Wang &
//   Chen's (section 1) through the map, and both sets weigh 23.45 kg;
// - the wrist centre of each file is the closed form of its DH rows, and the
//   two differ under the map by exactly the documented offsets,
//   (d2 + d3 - d3_rtb) = 0.00005 m along the shoulder axis and
//   (d4 - d4_rtb) = 0.0013 m along the forearm axis (so by their hypotenuse);
// - every joint axis is the same in both files under the map, and the flanges
//   differ by the constant Rz(pi);
// - the centres of mass are the same points but for those offsets, except link
//   4's, which the two sets put on opposite sides of the wrist centre;
// - gravity torque and two diagonal entries of H at the AKB file's qz, each a
//   sum over the table's links by hand, and H - H(no rotors) = diag(Jm G^2)
//   with Jm and G from the tables (section 3 prints RTB's Jm G^2).
//
// Tolerances: the closed forms are a few dozen roundings of O(1) numbers:
// 1e-12 m for positions and unit vectors; 1e-9 (the bound of
// tests/test_reference_values.cpp) for torques and inertias, over every
// back-end that describes the arm.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/robot_model.hpp"
#include "models/robot/kinematics.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "tests/helpers.hpp"

#ifndef PUMASIM_SCENES_DIR
#error "PUMASIM_SCENES_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

constexpr double kLitGeometry = 1e-12;  // [m] or [-]
constexpr double kLitDynamics = 1e-9;   // [N m] or [kg m^2]
constexpr double kLitG = 9.81;          // |g| of both files [m/s^2]

// The shipped robot file models/robots/<name>.toml, by its path in the source tree.
RobotModel lit_load(const std::string& name) {
  return load_robot_file(std::string(PUMASIM_SCENES_DIR) + "/../../models/robots/" + name + ".toml");
}

// Section 2's table (RTB-M mdl_puma560akb.m): d_j, a_{j-1}, alpha_{j-1}, m,
// r (centre of mass in link frame j), [Ixx Iyy Izz] (products 0), Jm, G.
struct LitAkbRow {
  double d, a, alpha, m;
  double r[3], I[3];
  double Jm, G;
};
const LitAkbRow kLitAkb[6] = {
    {0.0, 0.0, 0.0, 0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.35}, 291e-6, -62.6111},
    {0.2435, 0.0, -M_PI / 2, 17.4, {0.068, 0.006, -0.016}, {0.13, 0.524, 0.539}, 409e-6, 107.815},
    {-0.0934, 0.4318, 0.0, 4.8, {0.0, -0.070, 0.014}, {0.066, 0.0125, 0.066}, 299e-6, -53.7063},
    {0.4331, -0.0203, M_PI / 2, 0.82, {0.0, 0.0, -0.019}, {1.8e-3, 1.8e-3, 1.3e-3}, 35e-6, 76.0364},
    {0.0, 0.0, -M_PI / 2, 0.34, {0.0, 0.0, 0.0}, {0.3e-3, 0.3e-3, 0.4e-3}, 35e-6, 71.923},
    {0.0, 0.0, M_PI / 2, 0.09, {0.0, 0.0, 0.032}, {0.15e-3, 0.15e-3, 0.04e-3}, 35e-6, 76.686},
};
// Section 1 and 3 (RTB-M mdl_puma560.m): the lengths the wrist centre depends
// on, Jm and G, and the printed column Jm G^2 (6 significant digits).
constexpr double kLitRtbA2 = 0.4318, kLitRtbD3 = 0.15005, kLitRtbA3 = 0.0203, kLitRtbD4 = 0.4318;
const double kLitRtbJm[6] = {200e-6, 200e-6, 200e-6, 33e-6, 33e-6, 33e-6};
const double kLitRtbG[6] = {-62.6111, 107.815, -53.7063, 76.0364, 71.923, 76.686};
const double kLitRtbJmG2[6] = {0.78403, 2.32481, 0.576873, 0.190791, 0.170706, 0.194065};

// The joint-angle map (section 8): the AKB file's angles of the pose RTB's
// file has at q_rtb.
Eigen::VectorXd lit_to_akb(const Eigen::VectorXd& q_rtb) {
  Eigen::VectorXd q = q_rtb;
  q(0) += M_PI;
  q(1) -= M_PI;
  q(2) += M_PI;
  return q;
}

// RTB's standard DH rows (section 1) multiplied out at RTB angles q: the
// shoulder axis z2 (frame 1's z, also the elbow's), the upper arm's
// direction u2 (frame 2's x), the forearm's u3 (frame 3's x) and the forearm
// axis z4 (frame 3's z, joint 4's axis). z2 is orthogonal to u2, u3 and z4.
struct LitArm {
  Eigen::Vector3d z2, u2, u3, z4;
};
LitArm lit_arm(const Eigen::VectorXd& q) {
  const double c1 = std::cos(q(0)), s1 = std::sin(q(0)), c2 = std::cos(q(1)), s2 = std::sin(q(1));
  const double c23 = std::cos(q(1) + q(2)), s23 = std::sin(q(1) + q(2));
  return {Eigen::Vector3d(s1, -c1, 0.0), Eigen::Vector3d(c1 * c2, s1 * c2, s2),
          Eigen::Vector3d(c1 * c23, s1 * c23, s23), Eigen::Vector3d(-c1 * s23, -s1 * s23, c23)};
}

// The wrist centre a2 u2 + d3 z2 + a3 u3 + d4 z4. RTB's file: its own a2, d3,
// a3, d4. The AKB file at lit_to_akb(q): its a2 (row 3), d2 + d3 along the
// same axis (rows 2 and 3: alpha2 = 0), -a3 (row 4: its x3 is -u3 under the
// map) and its d4 (row 4), by the same multiplication of its modified rows.
Eigen::Vector3d lit_wrist(const LitArm& x, double a2, double d3, double a3, double d4) {
  return a2 * x.u2 + d3 * x.z2 + a3 * x.u3 + d4 * x.z4;
}
Eigen::Vector3d lit_wrist_rtb(const LitArm& x) { return lit_wrist(x, kLitRtbA2, kLitRtbD3, kLitRtbA3, kLitRtbD4); }
Eigen::Vector3d lit_wrist_akb(const LitArm& x) {
  return lit_wrist(x, kLitAkb[2].a, kLitAkb[1].d + kLitAkb[2].d, -kLitAkb[3].a, kLitAkb[3].d);
}

// Random RTB angles and RTB's named poses.
std::vector<Eigen::VectorXd> lit_poses(const RobotModel& rtb) {
  std::vector<Eigen::VectorXd> poses;
  for (const NamedPose& p : rtb.poses) poses.push_back(p.q);
  Rng rng(35);
  for (int k = 0; k < 20; ++k) poses.push_back(rng.uniform_vector(6, -M_PI, M_PI));
  return poses;
}

// The flange's pose (count < 0) or DH frame `count`'s.
void lit_frame(const RobotModel& m, const Eigen::VectorXd& q, int count, Eigen::Matrix3d& R, Eigen::Vector3d& p) {
  forward_kinematics(m, q, R, p, count);
}

TEST(LiteratureSets, AkbFileHoldsTheTableOfMdlPuma560akb) {
  const RobotModel akb = lit_load("puma560_akb");
  ASSERT_EQ(akb.dof(), 6);
  EXPECT_EQ(akb.convention, DhConvention::kModified);
  EXPECT_TRUE(has_identity_base_and_tool(akb));
  EXPECT_DOUBLE_EQ(akb.gravity.z(), -kLitG);
  double total = 0;
  for (int j = 0; j < 6; ++j) {
    const JointParams& J = akb.joints[j];
    const LitAkbRow& t = kLitAkb[j];
    EXPECT_FALSE(J.prismatic()) << j;
    EXPECT_DOUBLE_EQ(J.d, t.d) << j;
    EXPECT_DOUBLE_EQ(J.a, t.a) << j;
    EXPECT_DOUBLE_EQ(J.alpha, t.alpha) << j;
    EXPECT_EQ(J.offset, 0.0) << j;
    EXPECT_DOUBLE_EQ(J.mass, t.m) << j;
    for (int k = 0; k < 3; ++k) {
      EXPECT_DOUBLE_EQ(J.com(k), t.r[k]) << j << " r" << k;
      EXPECT_DOUBLE_EQ(J.inertia(k, k), t.I[k]) << j << " I" << k;
    }
    EXPECT_EQ(J.inertia(0, 1), 0.0) << j;
    EXPECT_EQ(J.inertia(1, 2), 0.0) << j;
    EXPECT_EQ(J.inertia(0, 2), 0.0) << j;
    EXPECT_DOUBLE_EQ(J.rotor_inertia, t.Jm) << j;
    EXPECT_DOUBLE_EQ(J.gear_ratio, t.G) << j;
    total += J.mass;
  }
  // 0 + 17.4 + 4.8 + 0.82 + 0.34 + 0.09: the same masses in both tables.
  EXPECT_NEAR(total, 23.45, 1e-12);
  const RobotModel rtb = lit_load("puma560");
  double total_rtb = 0;
  for (const JointParams& J : rtb.joints) total_rtb += J.mass;
  EXPECT_NEAR(total_rtb, 23.45, 1e-12);
}

// Wang & Chen's limits (section 1, as puma560.toml has them) moved by the map:
// the same physical range in the AKB file's angles; the wrist's unchanged.
// RTB-M's qn through the map is inside every range (its q3 taken mod 2 pi).
TEST(LiteratureSets, AkbLimitsAreWangAndChensThroughTheMap) {
  const RobotModel akb = lit_load("puma560_akb"), rtb = lit_load("puma560");
  const Eigen::VectorXd lo = lit_to_akb(Eigen::VectorXd::Zero(6));
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(akb.joints[j].q_min, rtb.joints[j].q_min + lo(j), 1e-12) << j;
    EXPECT_NEAR(akb.joints[j].q_max, rtb.joints[j].q_max + lo(j), 1e-12) << j;
  }
  const Eigen::VectorXd qn = lit_to_akb(rtb.pose("qn")->q);
  ASSERT_NE(akb.pose("qn"), nullptr);
  for (int j = 0; j < 6; ++j) {
    const double turns = (akb.pose("qn")->q(j) - qn(j)) / (2 * M_PI);
    EXPECT_NEAR(turns, std::round(turns), 1e-12) << j;
    EXPECT_GE(akb.pose("qn")->q(j), akb.joints[j].q_min) << j;
    EXPECT_LE(akb.pose("qn")->q(j), akb.joints[j].q_max) << j;
  }
  // RTB-AKB's own poses (section 2): q2, q3 are RTB's ready pose's through the map.
  const Eigen::VectorXd qr = lit_to_akb(rtb.pose("qr")->q);
  ASSERT_NE(akb.pose("qr"), nullptr);
  EXPECT_NEAR(akb.pose("qr")->q(1), qr(1), 1e-15);
  EXPECT_NEAR(akb.pose("qr")->q(2), qr(2), 1e-15);
}

TEST(LiteratureSets, WristCentresAreTheClosedFormsAndDifferByTheDocumentedOffsets) {
  const RobotModel akb = lit_load("puma560_akb"), rtb = lit_load("puma560");
  const double d23 = kLitAkb[1].d + kLitAkb[2].d - kLitRtbD3;  // 0.1501 - 0.15005
  const double d4 = kLitAkb[3].d - kLitRtbD4;                  // 0.4331 - 0.4318
  EXPECT_NEAR(d23, 0.00005, 1e-15);
  EXPECT_NEAR(d4, 0.0013, 1e-15);
  for (const Eigen::VectorXd& q : lit_poses(rtb)) {
    const LitArm x = lit_arm(q);
    Eigen::Matrix3d R;
    Eigen::Vector3d p_rtb, p_akb;
    lit_frame(rtb, q, -1, R, p_rtb);
    lit_frame(akb, lit_to_akb(q), -1, R, p_akb);
    EXPECT_LT((p_rtb - lit_wrist_rtb(x)).norm(), kLitGeometry) << q.transpose();
    EXPECT_LT((p_akb - lit_wrist_akb(x)).norm(), kLitGeometry) << q.transpose();
    const Eigen::Vector3d diff = p_akb - p_rtb;
    EXPECT_LT((diff - (d23 * x.z2 + d4 * x.z4)).norm(), kLitGeometry) << q.transpose();
    // z2 is orthogonal to z4: the distance is the hypotenuse, at every pose.
    EXPECT_NEAR(diff.norm(), std::hypot(d23, d4), kLitGeometry) << q.transpose();
    EXPECT_LE(diff.norm(), std::abs(d23) + std::abs(d4) + kLitGeometry);
  }
}

// The joint axes are the Jacobian's angular rows (kinematics.hpp: [z_i x (p -
// o_i); z_i]). At q_rtb = 0 the closed forms give RTB's flange R = I (its twists
// pi/2, 0, -pi/2, pi/2, -pi/2, 0 add up to 0) and the AKB file's, at (pi, -pi,
// pi, 0, 0, 0), Rz(pi) Rx(-pi/2) Rz(-pi) Rz(pi) Rx(pi/2) Rx(-pi/2) Rx(pi/2) =
// Rz(pi); with the same axes turning the same way, that offset holds at every pose.
TEST(LiteratureSets, JointAxesAgreeAndFlangesDifferByAHalfTurn) {
  const RobotModel akb = lit_load("puma560_akb"), rtb = lit_load("puma560");
  const Eigen::Matrix3d half_turn = Eigen::Vector3d(-1.0, -1.0, 1.0).asDiagonal();
  for (const Eigen::VectorXd& q : lit_poses(rtb)) {
    Eigen::MatrixXd J_rtb(6, 6), J_akb(6, 6);
    geometric_jacobian(rtb, q, 6, J_rtb);
    geometric_jacobian(akb, lit_to_akb(q), 6, J_akb);
    EXPECT_LT((J_akb.bottomRows(3) - J_rtb.bottomRows(3)).cwiseAbs().maxCoeff(), kLitGeometry) << q.transpose();
    Eigen::Matrix3d R_rtb, R_akb;
    Eigen::Vector3d p;
    lit_frame(rtb, q, -1, R_rtb, p);
    lit_frame(akb, lit_to_akb(q), -1, R_akb, p);
    EXPECT_LT((R_akb - R_rtb * half_turn).cwiseAbs().maxCoeff(), kLitGeometry) << q.transpose();
  }
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  lit_frame(rtb, Eigen::VectorXd::Zero(6), -1, R, p);
  EXPECT_LT((R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), kLitGeometry);
}

// Centres of mass, each the frame's origin plus R r with the table's r (in
// link j's frame: distal for RTB, proximal for AKB). Under the map (section 8):
// links 1 and 2 at the same point; link 3 along the shoulder axis at d2 + d3 +
// r_z (AKB) against d3 - r_y (RTB: its y3 is -z2), 0.1641 against 0.16415 m;
// links 5 and 6 shifted with the wrist centre; link 4 along the forearm axis at
// d4 + r_z (AKB: 0.4331 - 0.019) against d4 + r_y (RTB: its y4 is z4; 0.4318
// + 0.019): the sets disagree there by 0.038 m less the 0.0013 m of d4.
TEST(LiteratureSets, CentresOfMassAgreeButLinkFours) {
  const RobotModel akb = lit_load("puma560_akb"), rtb = lit_load("puma560");
  const double d23 = kLitAkb[1].d + kLitAkb[2].d - kLitRtbD3, d4 = kLitAkb[3].d - kLitRtbD4;
  const double link3 = (kLitAkb[1].d + kLitAkb[2].d + kLitAkb[2].r[2]) - (kLitRtbD3 - (-0.0141));
  const double link4 = (kLitAkb[3].d + kLitAkb[3].r[2]) - (kLitRtbD4 + 0.019);
  EXPECT_NEAR(link3, -0.00005, 1e-15);
  EXPECT_NEAR(link4, 0.0013 - 0.038, 1e-15);
  for (const Eigen::VectorXd& q : lit_poses(rtb)) {
    const LitArm x = lit_arm(q);
    const Eigen::Vector3d want[6] = {Eigen::Vector3d::Zero(),   Eigen::Vector3d::Zero(), link3 * x.z2,
                                     d23 * x.z2 + link4 * x.z4, d23 * x.z2 + d4 * x.z4,  d23 * x.z2 + d4 * x.z4};
    for (int j = 0; j < 6; ++j) {
      Eigen::Matrix3d R_rtb, R_akb;
      Eigen::Vector3d o_rtb, o_akb;
      lit_frame(rtb, q, j + 1, R_rtb, o_rtb);
      lit_frame(akb, lit_to_akb(q), j + 1, R_akb, o_akb);
      const Eigen::Vector3d c_rtb = o_rtb + R_rtb * rtb.joints[j].com, c_akb = o_akb + R_akb * akb.joints[j].com;
      EXPECT_LT((c_akb - c_rtb - want[j]).norm(), kLitGeometry) << "link " << j + 1 << " at " << q.transpose();
    }
  }
}

// Gravity at the AKB file's qz (q = 0, a left-handed L: upper arm along +x,
// forearm up), by hand from section 2's rows. Frames at q = 0: x2 = x3 = x4 = x
// (base), z2 = z3 = y (the shoulder and elbow axes), y2 = y3 = -z; y4 = y,
// z4 = z; y5 = -z, z5 = y; y6 = y, z6 = z. Origins: frame 2 at (0, d2, 0),
// frame 3 at (a2, d2 + d3, 0), frames 4-6 at the wrist centre (a2 + a3,
// d2 + d3, d4). Centres of mass x: link 2 r_x = 0.068, link 3 a2 + r_x = a2,
// links 4-6 a2 + a3 + r_x = 0.4115. Holding torque about +y through the
// origin (dV/dq2, V = |g| sum m z and dz/dq2 = -x): -|g| sum m x; about the
// elbow axis: -|g| sum_{j>=3} m (x - a2); the vertical joints 1, 4, 6 and
// joint 5 (its axis through the wrist centre, link 6's centre above it) carry
// none.
TEST(LiteratureSets, AkbGravityAtQzIsTheTablesSum) {
  const RobotModel akb = lit_load("puma560_akb");
  const LitAkbRow* t = kLitAkb;
  const double a2 = t[2].a, x_wrist = t[2].a + t[3].a;  // links 4-6 have r_x = 0
  const double m_wrist = t[3].m + t[4].m + t[5].m;
  const double g2 = -kLitG * (t[1].m * t[1].r[0] + t[2].m * (a2 + t[2].r[0]) + m_wrist * x_wrist);
  const double g3 = -kLitG * (t[2].m * t[2].r[0] + m_wrist * (x_wrist - a2));
  EXPECT_NEAR(g2, -36.98580915, 1e-8);  // by hand: 9.81 (17.4 0.068 + 4.8 0.4318 + 1.25 0.4115)
  EXPECT_NEAR(g3, 0.24892875, 1e-10);   // by hand: 9.81 1.25 0.0203
  Eigen::VectorXd want(6);
  want << 0.0, g2, g3, 0.0, 0.0, 0.0;
  const Eigen::VectorXd qz = akb.pose("qz")->q;
  for (const auto& info : testing::supported(akb)) {
    Eigen::VectorXd g(6);
    info.make(akb)->gravity(qz, g);
    EXPECT_LT((g - want).cwiseAbs().maxCoeff(), kLitDynamics) << info.name << ": " << g.transpose();
  }
}

// H11 and H22 at the AKB file's qz (frames as above): each link's moment about
// the joint's axis through its centre of mass (the table's diagonal entry on
// the link axis that lies along it) plus m times the squared distance of its
// centre of mass from the axis, plus Jm G^2. Joint 1 (axis z through the
// origin): link 1 Izz, links 2-3 Iyy (their y is -z), links 4 and 6 Izz, link 5
// Iyy (y5 = -z); distance^2 = x^2 + y^2. Joint 2 (axis y through the origin):
// links 2, 3, 5 Izz, links 4, 6 Iyy; distance^2 = x^2 + z^2.
// Centres of mass at qz, origin + r_x x_j + r_y y_j + r_z z_j: link 2 (0.068,
// d2 - 0.016, -0.006), link 3 (a2, d2 + d3 + 0.014, 0.070), links 4-6 at the
// wrist centre (a2 + a3, d2 + d3, d4) plus r (link 6: 0.032 up).
TEST(LiteratureSets, AkbInertiaAtQzIsTheTablesSum) {
  const RobotModel akb = lit_load("puma560_akb");
  const LitAkbRow* t = kLitAkb;
  const double y23 = t[1].d + t[2].d, xw = t[2].a + t[3].a;
  const Eigen::Vector3d c[6] = {
      Eigen::Vector3d::Zero(),
      Eigen::Vector3d(t[1].r[0], t[1].d + t[1].r[2], -t[1].r[1]),
      Eigen::Vector3d(t[2].a + t[2].r[0], y23 + t[2].r[2], -t[2].r[1]),
      Eigen::Vector3d(xw + t[3].r[0], y23 + t[3].r[1], t[3].d + t[3].r[2]),
      Eigen::Vector3d(xw + t[4].r[0], y23 + t[4].r[2], t[3].d - t[4].r[1]),
      Eigen::Vector3d(xw + t[5].r[0], y23 + t[5].r[1], t[3].d + t[5].r[2]),
  };
  const int axis1[6] = {2, 1, 1, 2, 1, 2}, axis2[6] = {0, 2, 2, 1, 2, 1};  // the link axis along z, along y
  double H11 = t[0].Jm * t[0].G * t[0].G, H22 = t[1].Jm * t[1].G * t[1].G;
  for (int j = 0; j < 6; ++j) {
    H11 += t[j].I[axis1[j]] + t[j].m * (c[j].x() * c[j].x() + c[j].y() * c[j].y());
    if (j >= 1) H22 += t[j].I[axis2[j]] + t[j].m * (c[j].x() * c[j].x() + c[j].z() * c[j].z());
  }
  const Eigen::VectorXd qz = akb.pose("qz")->q;
  for (const auto& info : testing::supported(akb)) {
    Eigen::MatrixXd H(6, 6);
    info.make(akb)->mass_matrix(qz, H);
    EXPECT_NEAR(H(0, 0), H11, kLitDynamics) << info.name;
    EXPECT_NEAR(H(1, 1), H22, kLitDynamics) << info.name;
  }
}

// The rotors' share of H is diag(Z^2 Jm) at every pose (robot_model.hpp), with
// each table's Jm and G: for AKB86 their product from section 2, for RTB the
// column section 3 prints (to its 6 significant digits).
TEST(LiteratureSets, RotorInertiaOnTheDiagonalIsJmTimesGSquared) {
  const RobotModel akb = lit_load("puma560_akb"), rtb = lit_load("puma560");
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(kLitRtbJm[j] * kLitRtbG[j] * kLitRtbG[j], kLitRtbJmG2[j], 5e-6 * kLitRtbJmG2[j]) << j;
  }
  struct Set {
    const RobotModel* model;
    Eigen::VectorXd jm_g2;
  };
  Eigen::VectorXd akb_jm_g2(6), rtb_jm_g2(6);
  for (int j = 0; j < 6; ++j) {
    akb_jm_g2(j) = kLitAkb[j].Jm * kLitAkb[j].G * kLitAkb[j].G;
    rtb_jm_g2(j) = kLitRtbJm[j] * kLitRtbG[j] * kLitRtbG[j];
  }
  const Set sets[] = {{&akb, akb_jm_g2}, {&rtb, rtb_jm_g2}};
  Rng rng(1986);
  for (const Set& s : sets) {
    const RobotModel rigid = without_rotor_inertia(*s.model);
    for (const auto& info : testing::supported(*s.model)) {
      if (!info.why_unsupported(rigid).empty()) continue;  // folded for the file's rotor inertias
      auto with = info.make(*s.model);
      auto without = info.make(rigid);
      for (int k = 0; k < 5; ++k) {
        const Eigen::VectorXd q = rng.uniform_vector(6, -M_PI, M_PI);
        Eigen::MatrixXd H(6, 6), H_rigid(6, 6);
        with->mass_matrix(q, H);
        without->mass_matrix(q, H_rigid);
        const Eigen::MatrixXd rotors = H - H_rigid;
        EXPECT_LT((rotors.diagonal() - s.jm_g2).cwiseAbs().maxCoeff(), kLitDynamics)
            << s.model->name << " " << info.name;
        EXPECT_LT((rotors - Eigen::MatrixXd(rotors.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), kLitDynamics)
            << s.model->name << " " << info.name;
      }
    }
  }
}

}  // namespace
}  // namespace pumasim
