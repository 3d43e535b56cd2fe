// Forward kinematics of a RobotModel on any scalar, its geometric Jacobian
// (exact, by dual numbers) and the closed-form inverse kinematics of the PUMA 560.
#pragma once

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

// Geometric Jacobian of the flange (forward_kinematics' default frame)
// (rows: linear velocity of the flange's origin, angular velocity; base
// frame) for the first `columns` joints, the others' columns zero: the
// closed form [z_i x (p_e - o_i); z_i] for a revolute joint and [z_i; 0] for
// a prismatic one (Siciliano et al. 2009, eq. 3.30) from one kinematic pass.
// q: any vector of at least dof entries; J: 6 rows and dof columns (a
// dynamic J is resized to that, which allocates only when its size changes).
// Allocation-free for a J of the right size: the axes z_i and points o_i
// wait in J's own columns until the pass has found p_e.
// With S = Dual and q = Dual(q, qd), the derivative parts are dJ/dt exactly
// (and with S = Jet2, the second derivative along qd too).
template <class QD, class JD>
void geometric_jacobian(const RobotModel& m, const Eigen::MatrixBase<QD>& q, int columns,
                        const Eigen::MatrixBase<JD>& J_out) {
  using S = typename JD::Scalar;
  using std::cos;
  using std::sin;
  using V3 = Eigen::Matrix<S, 3, 1>;
  using M3 = Eigen::Matrix<S, 3, 3>;
  auto& J = const_cast<Eigen::MatrixBase<JD>&>(J_out).derived();
  if (J.rows() != 6 || J.cols() != m.dof()) J.resize(6, m.dof());
  M3 R = m.base_R.template cast<S>();
  V3 p = m.base_p.template cast<S>();
  for (int j = 0; j < m.dof(); ++j) {
    const JointParams& P = m.joints[j];
    const S qj = S(q[j]);
    const S th = P.dh_theta(qj), d = P.dh_d(qj), ct = cos(th), st = sin(th);
    const double ca = std::cos(P.alpha), sa = std::sin(P.alpha);
    M3 Rz, Rx;
    Rz << ct, -st, S(0), st, ct, S(0), S(0), S(0), S(1);
    Rx << S(1), S(0), S(0), S(0), S(ca), S(-sa), S(0), S(sa), S(ca);
    if (m.convention == DhConvention::kStandard) {  // joint j turns about z of frame j-1
      J.template block<3, 1>(0, j) = p, J.template block<3, 1>(3, j) = R.col(2);
      p += R * (Rz * V3(S(P.a), S(0), d));
      R = (R * Rz * Rx).eval();
    } else {  // about z of frame j, after Rx(alpha) Tx(a)
      p += R * V3(S(P.a), S(0), S(0));
      R = (R * Rx).eval();
      J.template block<3, 1>(0, j) = p, J.template block<3, 1>(3, j) = R.col(2);
      p += R * V3(S(0), S(0), d);
      R = (R * Rz).eval();
    }
  }
  p += R * m.tool_p.template cast<S>();  // the flange's origin
  for (int k = 0; k < m.dof(); ++k) {
    if (k >= columns) {
      J.col(k).setZero();
      continue;
    }
    const V3 o = J.template block<3, 1>(0, k), z = J.template block<3, 1>(3, k);
    if (m.joints[k].prismatic()) {
      J.template block<3, 1>(0, k) = z;
      J.template block<3, 1>(3, k).setZero();
    } else {
      J.template block<3, 1>(0, k) = z.cross(p - o);
    }
  }
}

// PUMA 560 arm configuration for the closed-form inverse kinematics.
struct PumaConfig {
  bool right_arm = true;    // shoulder: right (X > 0 in the arm plane) or left
  bool elbow_up = true;     // elbow above or below the shoulder-wrist line
  bool wrist_flip = false;  // the second wrist solution (q4 + pi, -q5, q6 + pi)
  bool operator==(const PumaConfig&) const = default;
};

// Closed-form inverse kinematics of a PUMA-structured arm (standard DH twists
// pi/2, 0, -pi/2, pi/2, -pi/2, 0; a1 = d2 = a4 = a5 = d5 = d6 = 0). The first
// three joints place the wrist centre at p; when R is given (6 joints) the last
// three set the flange orientation. Returns false if p is out of reach.
bool puma_ik_position(const RobotModel& m, const Eigen::Vector3d& p, const PumaConfig& c,
                      Eigen::Vector3d& q123);
// q: 6 entries or more (the first six written).
bool puma_ik(const RobotModel& m, const Eigen::Vector3d& p, const Eigen::Matrix3d& R,
             const PumaConfig& c, Eigen::Ref<Eigen::VectorXd> q);

// Empty if the model has the structure puma_ik needs, else why not.
std::string puma_ik_unsupported(const RobotModel& m);

}  // namespace pumasim
