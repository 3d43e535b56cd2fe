// Robot parameters: a serial chain of revolute and prismatic joints described
// by DH rows, between a base transform and a tool transform.
//
// A RobotModel is plain, immutable data in SI units. It is loaded from a robot
// file (robot_file.hpp) or a URDF file (urdf_file.hpp), generated at random
// (random_chain.hpp), or derived
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

// What joint j's variable q_j moves (the Robotics Toolbox's `Link` convention,
// Corke): a revolute joint turns about z, theta_j = q_j + offset with
// d_j = d fixed; a prismatic joint slides along z, d_j = q_j + offset with
// theta_j = theta fixed. The parameter the variable replaces is not used: a
// revolute joint's `theta` and a prismatic joint's `d` must be 0 (joint_frames
// refuses them otherwise, so that no value is silently ignored).
enum class JointType : unsigned char { kRevolute, kPrismatic };

const char* to_string(JointType t);

struct JointParams {
  // Kinematics (meaning per DhConvention and JointType above).
  JointType type = JointType::kRevolute;
  double a = 0.0;       // link length [m]
  double alpha = 0.0;   // link twist [rad]
  double d = 0.0;       // link offset [m]; revolute joints only (0 for prismatic)
  double theta = 0.0;   // joint angle [rad]; prismatic joints only (0 for revolute)
  double offset = 0.0;  // joint variable offset: [rad] revolute, [m] prismatic
  // Link inertial parameters, in link j's DH frame.
  double mass = 0.0;                                       // [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();           // centre of mass [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();       // about the centre of mass [kg m^2]
  // Drive (motor side of the gearbox).
  double rotor_inertia = 0.0;  // Im, motor rotor inertia [kg m^2], motor side
  // Z = motor angle / joint variable: [-] revolute, [rad/m] prismatic (a ball
  // screw); the link-side armature Z^2 Im is in [kg m^2] or [kg].
  double gear_ratio = 1.0;
  // Joint-side friction a robot file gives (a URDF's <dynamics damping
  // friction>): defaults for a scene's [friction], which moves them to the
  // motor side (models/scene). The dynamics algorithms never read them.
  double damping = 0.0;  // viscous [N m s/rad] revolute, [N s/m] prismatic, joint side
  double coulomb = 0.0;  // Coulomb level [N m] revolute, [N] prismatic, joint side
  // Joint range (link side): [rad] revolute, [m] prismatic.
  double q_min = -3.141592653589793;
  double q_max = 3.141592653589793;

  bool prismatic() const { return type == JointType::kPrismatic; }
  // The DH row's joint angle theta_j [rad] and offset d_j [m] at joint variable q.
  template <class S>
  S dh_theta(const S& q) const { return prismatic() ? S(theta) : S(q + S(offset)); }
  template <class S>
  S dh_d(const S& q) const { return prismatic() ? S(q + S(offset)) : S(d); }
};

struct NamedPose {
  std::string name;
  Eigen::VectorXd q;  // one entry per joint: [rad] revolute, [m] prismatic
};

struct RobotModel {
  std::string name;
  std::string source;  // file it was loaded from, or how it was generated
  DhConvention convention = DhConvention::kStandard;
  std::vector<JointParams> joints;
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  // gravitational acceleration, base frame [m/s^2]
  std::vector<NamedPose> poses;
  // The base frame is the frame of gravity and of every Cartesian quantity
  // (forward kinematics, Jacobian, inverse kinematics, Cartesian references).
  // DH frame 0 sits in it at (base_R, base_p), and the flange sits in the
  // last DH frame at (tool_R, tool_p): identity for a DH robot file (the base
  // is DH frame 0, the flange the last DH frame); a URDF file sets both (its
  // root link's frame is the base, its chain's last link the flange).
  Eigen::Matrix3d base_R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d base_p = Eigen::Vector3d::Zero();  // [m]
  Eigen::Matrix3d tool_R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d tool_p = Eigen::Vector3d::Zero();  // [m]
  // What the flange is and why, for messages (`pumasim check`, a path out
  // of reach): a URDF's link and the rule that chose it.
  std::string flange = "the last DH frame (a DH robot file)";
  // Where the values a robot file's format has no key for came from, one
  // line each, for `pumasim check` and `pumasim robot` (a URDF's drive
  // values: its side file, a <transmission> or none; its <dynamics>; the
  // links merged off the chain and the joint values they are held at).
  std::vector<std::string> provenance;

  int dof() const { return static_cast<int>(joints.size()); }
  // The pose called `name`, or nullptr.
  const NamedPose* pose(const std::string& pose_name) const;
};

// Homogeneous transform of DH row j (0-based) at joint variable q: frame j-1 -> frame j.
Eigen::Matrix4d dh_transform(const RobotModel& model, int j, double q);

// The base and tool transforms as homogeneous matrices: DH frame 0 in the
// base frame, and the flange in the last DH frame.
Eigen::Matrix4d base_transform(const RobotModel& model);
Eigen::Matrix4d tool_transform(const RobotModel& model);
// True when both are the identity (a DH robot file's).
bool has_identity_base_and_tool(const RobotModel& model);

// Potential energy of gravity V(q) = -sum_j m_j g . p_cj(q) [J], the centres
// of mass in the base frame (a rotor turns
// about its own axis: no potential of its own, for a ball-screw drive too).
double potential_energy(const RobotModel& model, const Eigen::VectorXd& q);

// The same model with every rotor inertia set to zero (rigid links only).
RobotModel without_rotor_inertia(RobotModel model);

// The first n_active joints of `model`; joints n_active..dof-1 are held at
// q_full[n_active..] (angles, or displacements for prismatic joints) and their
// links are merged, as one rigid body, into link n_active-1 (their mass and
// inertia still count, their rotors do not turn).
// Poses are truncated to the active joints. The base stays, and so does the
// flange: the tool transform becomes the held rows' transform at their values
// times the tool, so that the flange's pose is the full model's with the held
// joints at q_full (the same for both DH conventions, and for a URDF file).
RobotModel lock_joints(const RobotModel& model, int n_active, const Eigen::VectorXd& q_full);

// Joint-frame form shared by every algorithm (see chain.hpp): joint frame j has
// its z axis on joint j and is obtained from joint frame j-1 by the fixed
// transform (E_j, p_j) followed by Rz(q_j) (revolute) or Tz(q_j) (prismatic).
// Joint frame 0 is the base frame: the base transform is folded into (E_1, p_1),
// so gravity stays in the base frame. Inertial data are moved into these
// frames; `E_tool, p_tool` place the flange (the last DH frame, then the tool
// transform) in joint frame n. Throws std::invalid_argument for a
// revolute joint with theta != 0 or a prismatic one with d != 0.
struct JointFrameData {
  std::vector<JointType> type;
  std::vector<Eigen::Matrix3d> E;        // fixed rotation, joint frame j-1 -> j (before the joint)
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
