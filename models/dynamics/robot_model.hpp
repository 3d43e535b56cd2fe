// Robot parameters: a serial chain of revolute joints described by DH rows.
//
// A RobotModel is plain, immutable data in SI units. It is loaded from a robot
// file (robot_file.hpp), generated at random (random_chain.hpp), or derived
// from another model (lock_joints, without_rotor_inertia). The dynamics
// algorithms never read it directly: they read a Chain (chain.hpp), the same
// data converted once to joint frames and to the algorithm's scalar type.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace pumasim {

enum class DhConvention {
  // Standard (distal) DH, Paul / Corke: A_j = Rz(theta_j) Tz(d_j) Tx(a_j) Rx(alpha_j);
  // link j's frame sits at the distal end of link j, on joint j+1's axis.
  kStandard,
  // Modified (proximal) DH, Craig: A_j = Rx(alpha_{j-1}) Tx(a_{j-1}) Rz(theta_j) Tz(d_j);
  // row j stores a_{j-1} and alpha_{j-1}; link j's frame sits on joint j's axis.
  kModified,
};

const char* to_string(DhConvention c);

struct JointParams {
  // Kinematics (meaning per DhConvention above); theta_j = q_j + offset.
  double a = 0.0;       // link length [m]
  double alpha = 0.0;   // link twist [rad]
  double d = 0.0;       // link offset [m]
  double offset = 0.0;  // joint angle offset [rad]
  // Link inertial parameters, in link j's DH frame.
  double mass = 0.0;                                       // [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();           // centre of mass [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();       // about the centre of mass [kg m^2]
  // Drive (motor side of the gearbox).
  double rotor_inertia = 0.0;  // Im, motor rotor inertia [kg m^2], motor side
  double gear_ratio = 1.0;     // Z = motor angle / joint angle [-]; link-side inertia Z^2 Im
  // Joint range (link side).
  double q_min = -3.141592653589793;  // [rad]
  double q_max = 3.141592653589793;   // [rad]
};

struct NamedPose {
  std::string name;
  Eigen::VectorXd q;  // [rad], one entry per joint
};

struct RobotModel {
  std::string name;
  std::string source;  // file it was loaded from, or how it was generated
  DhConvention convention = DhConvention::kStandard;
  std::vector<JointParams> joints;
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  // gravitational acceleration, base frame [m/s^2]
  std::vector<NamedPose> poses;

  int dof() const { return static_cast<int>(joints.size()); }
  // The pose called `name`, or nullptr.
  const NamedPose* pose(const std::string& pose_name) const;
};

// Homogeneous transform of DH row j (0-based) at joint angle q: frame j-1 -> frame j.
Eigen::Matrix4d dh_transform(const RobotModel& model, int j, double q);

// Potential energy of gravity V(q) = -sum_j m_j g . p_cj(q) [J] (a rotor turns
// about its own axis: no potential of its own).
double potential_energy(const RobotModel& model, const Eigen::VectorXd& q);

// The same model with every rotor inertia set to zero (rigid links only).
RobotModel without_rotor_inertia(RobotModel model);

// The first n_active joints of `model`; joints n_active..dof-1 are held at the
// angles q_full[n_active..] and their links are merged, as one rigid body, into
// link n_active-1 (their mass and inertia still count, their rotors do not turn).
// Poses are truncated to the active joints.
RobotModel lock_joints(const RobotModel& model, int n_active, const Eigen::VectorXd& q_full);

// Joint-frame form shared by every algorithm (see chain.hpp): joint frame j has
// its z axis on joint j and is obtained from joint frame j-1 by the fixed
// transform (E_j, p_j) followed by Rz(q_j). Inertial data are moved into these
// frames; `E_tool, p_tool` place the last DH frame (the flange) in joint frame n.
struct JointFrameData {
  std::vector<Eigen::Matrix3d> E;        // fixed rotation, joint frame j-1 -> j (before Rz(q_j))
  std::vector<Eigen::Vector3d> p;        // origin of joint frame j in joint frame j-1 [m]
  std::vector<double> mass;              // [kg]
  std::vector<Eigen::Vector3d> com;      // centre of mass in joint frame j [m]
  std::vector<Eigen::Matrix3d> I_com;    // inertia about the COM, joint frame j axes [kg m^2]
  std::vector<double> armature;          // Z^2 Im, link side [kg m^2]
  Eigen::Matrix3d E_tool = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_tool = Eigen::Vector3d::Zero();
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
};

JointFrameData joint_frames(const RobotModel& model);

}  // namespace pumasim
