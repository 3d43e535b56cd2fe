// Forward kinematics of a RobotModel on any scalar, its geometric Jacobian
// (exact, by dual numbers) and the closed-form inverse kinematics of the PUMA 560.
#pragma once

#include <array>
#include <cmath>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "models/dynamics/dual.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

// Pose in the base frame of DH frame `count`, or by default of the flange (the
// last DH frame, then the tool transform), for the joint variables q (angles
// [rad], or displacements [m] for prismatic joints). Allocation-free.
template <class S, class Q>
void forward_kinematics(const RobotModel& m, const Q& q, Eigen::Matrix<S, 3, 3>& R,
                        Eigen::Matrix<S, 3, 1>& p, int count = -1) {
  using std::cos;
  using std::sin;
  R = m.base_R.template cast<S>();
  p = m.base_p.template cast<S>();
  const int upto = count < 0 ? m.dof() : count;
  for (int j = 0; j < upto; ++j) {
    const JointParams& J = m.joints[j];
    const S th = J.dh_theta(S(q[j])), d = J.dh_d(S(q[j]));
    const S ct = cos(th), st = sin(th);
    const double ca = std::cos(J.alpha), sa = std::sin(J.alpha);
    Eigen::Matrix<S, 3, 3> Rz, Rx;
    Rz << ct, -st, S(0), st, ct, S(0), S(0), S(0), S(1);
    Rx << S(1), S(0), S(0), S(0), S(ca), S(-sa), S(0), S(sa), S(ca);
    if (m.convention == DhConvention::kStandard) {  // Rz(th) Tz(d) Tx(a) Rx(alpha)
      p += R * (Rz * Eigen::Matrix<S, 3, 1>(S(J.a), S(0), d));
      R = (R * Rz * Rx).eval();
    } else {  // Rx(alpha) Tx(a) Rz(th) Tz(d)
      p += R * Eigen::Matrix<S, 3, 1>(S(J.a), S(0), S(0));
      R = (R * Rx).eval();
      p += R * Eigen::Matrix<S, 3, 1>(S(0), S(0), d);
      R = (R * Rz).eval();
    }
  }
  if (count < 0) {  // the flange
    p += R * m.tool_p.template cast<S>();
    R = (R * m.tool_R.template cast<S>()).eval();
  }
}

// Geometric Jacobian of the flange (forward_kinematics' default frame) of a
// robot with 6 joints (rows: linear velocity of the flange's origin, angular
// velocity; base frame), for the first `columns` joints
// (the others zero): the closed form [z_i x (p_e - o_i); z_i] for a revolute
// joint and [z_i; 0] for a prismatic one (Siciliano et al. 2009, eq. 3.30)
// from one kinematic pass. Allocation-free.
// With S = Dual and q = Dual(q, qd), the derivative parts are dJ/dt exactly.
template <class S>
void geometric_jacobian(const RobotModel& m, const Eigen::Matrix<S, 6, 1>& q, int columns,
                        Eigen::Matrix<S, 6, 6>& J) {
  using std::cos;
  using std::sin;
  using V3 = Eigen::Matrix<S, 3, 1>;
  using M3 = Eigen::Matrix<S, 3, 3>;
  std::array<V3, 6> z, o;
  M3 R = m.base_R.template cast<S>();
  V3 p = m.base_p.template cast<S>();
  for (int j = 0; j < m.dof(); ++j) {
    const JointParams& P = m.joints[j];
    const S th = P.dh_theta(q[j]), d = P.dh_d(q[j]), ct = cos(th), st = sin(th);
    const double ca = std::cos(P.alpha), sa = std::sin(P.alpha);
    M3 Rz, Rx;
    Rz << ct, -st, S(0), st, ct, S(0), S(0), S(0), S(1);
    Rx << S(1), S(0), S(0), S(0), S(ca), S(-sa), S(0), S(sa), S(ca);
    if (m.convention == DhConvention::kStandard) {  // joint j turns about z of frame j-1
      z[j] = R.col(2), o[j] = p;
      p += R * (Rz * V3(S(P.a), S(0), d));
      R = (R * Rz * Rx).eval();
    } else {  // about z of frame j, after Rx(alpha) Tx(a)
      p += R * V3(S(P.a), S(0), S(0));
      R = (R * Rx).eval();
      z[j] = R.col(2), o[j] = p;
      p += R * V3(S(0), S(0), d);
      R = (R * Rz).eval();
    }
  }
  p += R * m.tool_p.template cast<S>();  // the flange's origin
  J.setZero();
  for (int k = 0; k < columns; ++k) {
    if (m.joints[k].prismatic()) {
      J.template block<3, 1>(0, k) = z[k];
      continue;
    }
    J.template block<3, 1>(0, k) = z[k].cross(p - o[k]);
    J.template block<3, 1>(3, k) = z[k];
  }
}

// PUMA 560 arm configuration for the closed-form inverse kinematics.
struct PumaConfig {
  bool right_arm = true;    // shoulder: right (X > 0 in the arm plane) or left
  bool elbow_up = true;     // elbow above or below the shoulder-wrist line
  bool wrist_flip = false;  // the second wrist solution (q4 + pi, -q5, q6 + pi)
};

// Closed-form inverse kinematics of a PUMA-structured arm (standard DH twists
// pi/2, 0, -pi/2, pi/2, -pi/2, 0; a1 = d2 = a4 = a5 = d5 = d6 = 0). The first
// three joints place the wrist centre at p; when R is given (6 joints) the last
// three set the flange orientation. Returns false if p is out of reach.
bool puma_ik_position(const RobotModel& m, const Eigen::Vector3d& p, const PumaConfig& c,
                      Eigen::Vector3d& q123);
bool puma_ik(const RobotModel& m, const Eigen::Vector3d& p, const Eigen::Matrix3d& R,
             const PumaConfig& c, Eigen::Matrix<double, 6, 1>& q);

// Empty if the model has the structure puma_ik needs, else why not.
std::string puma_ik_unsupported(const RobotModel& m);

}  // namespace pumasim
