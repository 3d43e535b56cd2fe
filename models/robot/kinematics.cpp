#include "models/robot/kinematics.hpp"

#include <cmath>

namespace pumasim {

// Closed form from one kinematic pass: column i is [z_i x (p_e - o_i); z_i],
// with z_i the axis of joint i and o_i a point on it, in the base frame.
std::string puma_ik_unsupported(const RobotModel& m) {
  const double twist[6] = {M_PI / 2, 0, -M_PI / 2, M_PI / 2, -M_PI / 2, 0};
  if (m.convention != DhConvention::kStandard || m.dof() != 6) {
    return "the PUMA inverse kinematics needs a 6-joint standard-DH robot file";
  }
  if (!has_identity_base_and_tool(m)) {
    return "the PUMA inverse kinematics needs the base at DH frame 0 and the flange at the last DH frame "
           "(no base or tool transform, as in a DH robot file)";
  }
  for (int j = 0; j < 6; ++j) {
    const JointParams& J = m.joints[j];
    if (J.prismatic()) {
      return "the PUMA inverse kinematics needs revolute joints; joint " + std::to_string(j + 1) +
             " is prismatic";
    }
    if (std::abs(J.alpha - twist[j]) > 1e-9 || J.offset != 0.0) {
      return "the PUMA inverse kinematics needs the PUMA's twists and zero offsets; joint " +
             std::to_string(j + 1) + " differs";
    }
  }
  const auto& J = m.joints;
  if (J[0].a != 0 || J[1].d != 0 || J[3].a != 0 || J[4].a != 0 || J[4].d != 0 || J[5].a != 0 ||
      J[5].d != 0) {
    return "the PUMA inverse kinematics needs a1 = d2 = a4 = a5 = d5 = a6 = d6 = 0";
  }
  return "";
}

// Wrist centre in the base frame (derivation in the header's terms):
//   X = a2 c2 + a3 c23 - d4 s23,  Y = a2 s2 + a3 s23 + d4 c23   (arm plane)
//   p = (X c1 + d3 s1, X s1 - d3 c1, Y + d1)
bool puma_ik_position(const RobotModel& m, const Eigen::Vector3d& p, const PumaConfig& c,
                      Eigen::Vector3d& q) {
  const double d1 = m.joints[0].d, a2 = m.joints[1].a, a3 = m.joints[2].a, d3 = m.joints[2].d,
               d4 = m.joints[3].d;
  const double r2 = p.x() * p.x() + p.y() * p.y() - d3 * d3;
  if (r2 < 0) return false;
  const double X = (c.right_arm ? 1.0 : -1.0) * std::sqrt(r2);
  const double Y = p.z() - d1;
  q[0] = std::atan2(p.y(), p.x()) + std::atan2(d3, X);
  // Planar 2R: link a2, then L at angle q2 + q3 + gamma.
  const double L = std::hypot(a3, d4), gamma = std::atan2(d4, a3);
  const double D = (X * X + Y * Y - a2 * a2 - L * L) / (2 * a2 * L);
  if (D < -1.0 || D > 1.0) return false;
  // Elbow up is the solution with the elbow above the shoulder-wrist line, for the right arm.
  const double th = (c.elbow_up == c.right_arm ? -1.0 : 1.0) * std::acos(D);
  q[1] = std::atan2(Y, X) - std::atan2(L * std::sin(th), a2 + L * std::cos(th));
  q[2] = th - gamma;
  for (int k = 0; k < 3; ++k) q[k] = std::remainder(q[k], 2 * M_PI);
  return true;
}

bool puma_ik(const RobotModel& m, const Eigen::Vector3d& p, const Eigen::Matrix3d& R,
             const PumaConfig& c, Eigen::Ref<Eigen::VectorXd> q) {
  Eigen::Vector3d q123;
  if (!puma_ik_position(m, p, c, q123)) return false;
  q.head<3>() = q123;
  q.segment<3>(3).setZero();
  // R03 from the first three joints, then R36 = R03^T R = Rz(q4) Ry(-q5) Rz(q6).
  Eigen::Matrix3d R03;
  Eigen::Vector3d p3;
  forward_kinematics<double>(m, q123, R03, p3, 3);
  const Eigen::Matrix3d W = R03.transpose() * R;
  const double sb = std::sqrt(std::max(0.0, 1.0 - W(2, 2) * W(2, 2)));  // |sin q5|
  double q4, q5, q6;
  if (sb < 1e-12) {  // wrist singular (q5 = 0): q4 + q6 fixed, take q4 = 0
    q4 = 0;
    q5 = 0;
    q6 = std::atan2(W(1, 0), W(0, 0));
  } else {
    // Ry(b) with b = -q5 and sin b = +sb: r13 = c4 sb, r23 = s4 sb, r31 = -sb c6, r32 = sb s6.
    q4 = std::atan2(W(1, 2), W(0, 2));
    q5 = -std::atan2(sb, W(2, 2));
    q6 = std::atan2(W(2, 1), -W(2, 0));
  }
  if (c.wrist_flip) {
    q4 += M_PI;
    q5 = -q5;
    q6 += M_PI;
  }
  q[3] = std::remainder(q4, 2 * M_PI);
  q[4] = q5;
  q[5] = std::remainder(q6, 2 * M_PI);
  return true;
}

}  // namespace pumasim
