// Published and closed-form values, for every back-end.
#include <gtest/gtest.h>

#include <cmath>

#include "models/dynamics/backend.hpp"
#include "models/robot/robot_file.hpp"
#include "tests/helpers.hpp"

namespace pumasim {
namespace {

// The reference sheet prints 10 decimals: agreement to 1e-9 absolute.
constexpr double kPrinted = 1e-9;

void expect_near(const Eigen::MatrixXd& got, const Eigen::MatrixXd& want, double tol,
                 const std::string& who) {
  ASSERT_EQ(got.rows(), want.rows());
  ASSERT_EQ(got.cols(), want.cols());
  for (Eigen::Index i = 0; i < got.rows(); ++i)
    for (Eigen::Index j = 0; j < got.cols(); ++j)
      EXPECT_NEAR(got(i, j), want(i, j), tol) << who << " (" << i << "," << j << ")";
}

// Source: models/robots/puma560_sources.md (copied from the project's PUMA 560
// reference sheet, section 6), "gravload(q)" for the Robotics Toolbox PUMA 560
// (mdl_puma560.m, Corke & Armstrong-Helouvry 1994 parameters, g = 9.81),
// computed by a Newton-Euler code that reproduces the toolbox's own unit-test
// values to < 5e-5.
TEST(PublishedValues, Puma560GravityTorqueAtNamedPoses) {
  const RobotModel puma = load_robot("puma560");
  struct Case { const char* pose; Eigen::Matrix<double, 6, 1> g; };
  const Case cases[] = {
      {"qz", (Eigen::Matrix<double, 6, 1>() << 0, 37.4836666500, 0.2489287500, 0, 0, 0).finished()},
      {"qr", (Eigen::Matrix<double, 6, 1>() << 0, -0.7752352500, 0.2489287500, 0, 0, 0).finished()},
      {"qs", (Eigen::Matrix<double, 6, 1>() << 0, 46.0069380000, 8.7722001000, 0, 0.0282528000, 0).finished()},
  };
  for (const auto& info : testing::supported(puma)) {
    auto b = info.make(puma);
    for (const Case& c : cases) {
      Eigen::VectorXd g(6);
      b->gravity(puma.pose(c.pose)->q, g);
      expect_near(g, c.g, kPrinted, std::string(info.name) + " gravload(" + c.pose + ")");
    }
  }
}

// Source: models/robots/puma560_sources.md (the reference sheet's section 6),
// "inertia(qz)" and "inertia(qr)" (with Jm G^2 on the diagonal), and the
// rigid-body diagonal at qz.
TEST(PublishedValues, Puma560MassMatrixAtQzAndQr) {
  const RobotModel puma = load_robot("puma560");
  Eigen::Matrix<double, 6, 6> Hqz, Hqr;
  Hqz << 3.9611261043, -0.1626648105, -0.1389138105, 0.0016400000, -0.0004321440, 0.0000400000,
      -0.1626648105, 4.4566220955, 0.3727363235, 0, 0.0018857440, 0,
      -0.1389138105, 0.3727363235, 0.9386527304, 0, 0.0018857440, 0,
      0.0016400000, 0, 0, 0.1924306261, 0, 0.0000400000,
      -0.0004321440, 0.0018857440, 0.0018857440, 0, 0.1713484517, 0,
      0.0000400000, 0, 0, 0.0000400000, 0, 0.1941045057;
  Hqr << 2.3373510523, -0.8293051540, -0.1389138105, 0.0016400000, -0.0004321440, 0.0000400000,
      -0.8293051540, 5.2069480015, 0.7478992765, 0, 0.0031293280, 0,
      -0.1389138105, 0.7478992765, 0.9386527304, 0, 0.0018857440, 0,
      0.0016400000, 0, 0, 0.1924306261, 0, 0.0000400000,
      -0.0004321440, 0.0031293280, 0.0018857440, 0, 0.1713484517, 0,
      0.0000400000, 0, 0, 0.0000400000, 0, 0.1941045057;
  Eigen::Matrix<double, 6, 1> rigid_diag_qz;
  rigid_diag_qz << 3.1770961356, 2.1318072505, 0.3617793985, 0.0016400000, 0.0006421600, 0.0000400000;
  const RobotModel rigid = without_rotor_inertia(puma);
  for (const auto& info : testing::supported(puma)) {
    Eigen::MatrixXd H(6, 6);
    auto b = info.make(puma);
    b->mass_matrix(puma.pose("qz")->q, H);
    expect_near(H, Hqz, kPrinted, std::string(info.name) + " inertia(qz)");
    b->mass_matrix(puma.pose("qr")->q, H);
    expect_near(H, Hqr, kPrinted, std::string(info.name) + " inertia(qr)");
    if (!info.why_unsupported(rigid).empty()) continue;  // folded for the file's rotor inertias
    info.make(rigid)->mass_matrix(puma.pose("qz")->q, H);
    expect_near(H.diagonal(), rigid_diag_qz, kPrinted, std::string(info.name) + " rigid diag(qz)");
  }
}

// Closed form: the planar two-link arm (Spong, Hutchinson & Vidyasagar, Robot
// Modeling and Control, 2006, sec. 7.4.1): links of length l_i with centre of
// mass at lc_i along the link, inertia I_i about the centre of mass, joints
// about z, gravity along -y of the base.
TEST(ClosedForm, PlanarTwoLinkArm) {
  const double m1 = 2.3, m2 = 1.7, l1 = 0.6, l2 = 0.45, lc1 = 0.28, lc2 = 0.2, I1 = 0.07, I2 = 0.04;
  const double Jm1 = 3e-4, Jm2 = 2e-4, Z1 = 50, Z2 = -30, gr = 9.81;
  RobotModel m;
  m.name = "planar2";
  m.convention = DhConvention::kStandard;
  m.gravity = Eigen::Vector3d(0, -gr, 0);
  for (int j = 0; j < 2; ++j) {
    JointParams J;
    J.a = j == 0 ? l1 : l2;
    J.mass = j == 0 ? m1 : m2;
    // The standard DH frame of link j is at its distal end.
    J.com = Eigen::Vector3d(-(J.a - (j == 0 ? lc1 : lc2)), 0, 0);
    J.inertia = Eigen::Vector3d(0.01, 0.02, j == 0 ? I1 : I2).asDiagonal();
    J.rotor_inertia = j == 0 ? Jm1 : Jm2;
    J.gear_ratio = j == 0 ? Z1 : Z2;
    m.joints.push_back(J);
  }
  const double q1 = 0.7, q2 = -1.1, qd1 = 0.9, qd2 = -1.6, qdd1 = 2.0, qdd2 = -0.5;
  const double c2 = std::cos(q2), s2 = std::sin(q2), c1 = std::cos(q1), c12 = std::cos(q1 + q2);
  const double d11 = m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2 * l1 * lc2 * c2) + I1 + I2 + Z1 * Z1 * Jm1;
  const double d12 = m2 * (lc2 * lc2 + l1 * lc2 * c2) + I2;
  const double d22 = m2 * lc2 * lc2 + I2 + Z2 * Z2 * Jm2;
  const double hh = -m2 * l1 * lc2 * s2;
  const double g1 = (m1 * lc1 + m2 * l1) * gr * c1 + m2 * lc2 * gr * c12;
  const double g2 = m2 * lc2 * gr * c12;
  const double b1 = hh * (2 * qd1 * qd2 + qd2 * qd2) + g1;
  const double b2 = -hh * qd1 * qd1 + g2;
  const Eigen::Vector2d q(q1, q2), qd(qd1, qd2), qdd(qdd1, qdd2);
  Eigen::Matrix2d H_ref;
  H_ref << d11, d12, d12, d22;
  const Eigen::Vector2d h_ref(b1, b2), g_ref(g1, g2);
  const Eigen::Vector2d tau_ref = H_ref * qdd + h_ref;
  for (const auto& info : testing::supported(m)) {
    auto b = info.make(m);
    Eigen::MatrixXd H(2, 2);
    Eigen::VectorXd h(2), g(2), tau(2), acc(2);
    b->mass_matrix(q, H);
    b->bias(q, qd, h);
    b->gravity(q, g);
    b->inverse_dynamics(q, qd, qdd, tau);
    b->forward_dynamics(q, qd, tau_ref, acc);
    const std::string who = info.name;
    expect_near(H, H_ref, 1e-12, who + " H");
    expect_near(h, h_ref, 1e-12, who + " h");
    expect_near(g, g_ref, 1e-12, who + " g");
    expect_near(tau, tau_ref, 1e-12, who + " tau");
    expect_near(acc, qdd, 1e-12, who + " qdd");
  }
}

}  // namespace
}  // namespace pumasim
