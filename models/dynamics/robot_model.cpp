#include "models/dynamics/robot_model.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "models/dynamics/link_frame.hpp"

namespace pumasim {
namespace {

Eigen::Matrix3d rot_x(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d R;
  R << 1, 0, 0, 0, c, -s, 0, s, c;
  return R;
}

Eigen::Matrix3d rot_z(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

Eigen::Matrix4d homogeneous(const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = p;
  return T;
}

}  // namespace

const char* to_string(DhConvention c) {
  return c == DhConvention::kStandard ? "standard" : "modified";
}

const char* to_string(JointType t) { return t == JointType::kRevolute ? "revolute" : "prismatic"; }

const NamedPose* RobotModel::pose(const std::string& pose_name) const {
  for (const auto& p : poses) {
    if (p.name == pose_name) return &p;
  }
  return nullptr;
}

Eigen::Matrix4d dh_transform(const RobotModel& model, int j, double q) {
  const JointParams& J = model.joints.at(static_cast<std::size_t>(j));
  const double theta = J.dh_theta(q), d = J.dh_d(q);
  if (model.convention == DhConvention::kStandard) {
    // Rz(theta) Tz(d) Tx(a) Rx(alpha)
    return homogeneous(rot_z(theta), Eigen::Vector3d(0, 0, d)) *
           homogeneous(rot_x(J.alpha), Eigen::Vector3d(J.a, 0, 0));
  }
  // Rx(alpha) Tx(a) Rz(theta) Tz(d)
  return homogeneous(rot_x(J.alpha), Eigen::Vector3d(J.a, 0, 0)) *
         homogeneous(rot_z(theta), Eigen::Vector3d(0, 0, d));
}

Eigen::Matrix4d base_transform(const RobotModel& model) { return homogeneous(model.base_R, model.base_p); }

Eigen::Matrix4d tool_transform(const RobotModel& model) { return homogeneous(model.tool_R, model.tool_p); }

bool has_identity_base_and_tool(const RobotModel& model) {
  return model.base_R == Eigen::Matrix3d::Identity() && model.base_p.isZero(0) &&
         model.tool_R == Eigen::Matrix3d::Identity() && model.tool_p.isZero(0);
}

double potential_energy(const RobotModel& model, const Eigen::VectorXd& q) {
  Eigen::Matrix4d T = base_transform(model);
  double V = 0;
  for (int j = 0; j < model.dof(); ++j) {
    T = T * dh_transform(model, j, q[j]);
    const Eigen::Vector3d c = T.topLeftCorner<3, 3>() * model.joints[j].com + T.topRightCorner<3, 1>();
    V -= model.joints[j].mass * model.gravity.dot(c);
  }
  return V;
}

RobotModel without_rotor_inertia(RobotModel model) {
  for (auto& j : model.joints) j.rotor_inertia = 0.0;
  model.name += " (no rotor inertia)";
  return model;
}

RobotModel lock_joints(const RobotModel& model, int n_active, const Eigen::VectorXd& q_full) {
  const int n = model.dof();
  if (n_active < 1 || n_active > n) {
    throw std::invalid_argument("lock_joints: expected 1 <= n_active <= " + std::to_string(n) +
                                ", got " + std::to_string(n_active));
  }
  if (q_full.size() != n) {
    throw std::invalid_argument("lock_joints: expected " + std::to_string(n) +
                                " held joint angles, got " + std::to_string(q_full.size()));
  }
  RobotModel out = model;
  out.joints.resize(static_cast<std::size_t>(n_active));
  if (n_active < n) out.name += " (joints " + std::to_string(n_active + 1) + ".." +
                                std::to_string(n) + " held)";
  const int last = n_active - 1;
  // Merge the held links into link `last`, all in link last's DH frame.
  double m = model.joints[last].mass;
  Eigen::Vector3d mc = m * model.joints[last].com;
  struct Body { double m; Eigen::Vector3d c; Eigen::Matrix3d I; };
  std::vector<Body> bodies{{m, model.joints[last].com, model.joints[last].inertia}};
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (int i = n_active; i < n; ++i) {
    T = T * dh_transform(model, i, q_full[i]);
    const JointParams& L = model.joints[i];
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const Eigen::Vector3d c = R * L.com + T.topRightCorner<3, 1>();
    bodies.push_back({L.mass, c, R * L.inertia * R.transpose()});
    m += L.mass;
    mc += L.mass * c;
  }
  // The flange stays where the held joints put it: in DH frame n_active,
  // the held rows' transform T, then the tool.
  const Eigen::Matrix4d tool = T * tool_transform(model);
  out.tool_R = tool.topLeftCorner<3, 3>();
  out.tool_p = tool.topRightCorner<3, 1>();
  JointParams& J = out.joints[last];
  J.mass = m;
  J.com = m > 0 ? Eigen::Vector3d(mc / m) : Eigen::Vector3d::Zero();
  J.inertia.setZero();
  for (const Body& b : bodies) {  // parallel-axis theorem about the merged COM
    const Eigen::Vector3d d = b.c - J.com;
    J.inertia += b.I + b.m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  for (auto& p : out.poses) p.q = p.q.head(n_active).eval();
  return out;
}

namespace {

// A revolute joint's theta and a prismatic joint's d are replaced by the joint
// variable; a non-zero value there would be silently ignored, so it is refused.
void check_unused_parameter(const RobotModel& model, int j) {
  const JointParams& J = model.joints[j];
  const bool bad = J.prismatic() ? J.d != 0.0 : J.theta != 0.0;
  if (!bad) return;
  const std::string name = J.prismatic() ? "d" : "theta";
  throw std::invalid_argument(
      model.name + ": joint " + std::to_string(j + 1) + " is " + to_string(J.type) + ": its " + name +
      " is the joint variable q + offset, expected " + name + " = 0, got " +
      std::to_string(J.prismatic() ? J.d : J.theta) + " (put a constant part in offset)");
}

}  // namespace

LinkInJointFrame link_in_joint_frame(const RobotModel& model, int j) {
  LinkInJointFrame f;
  if (model.convention != DhConvention::kStandard) return f;
  const JointParams& J = model.joints[static_cast<std::size_t>(j)];
  f.R = rot_x(J.alpha);
  f.t = Eigen::Vector3d(J.a, 0, J.prismatic() ? 0.0 : J.d);
  return f;
}

JointFrameData joint_frames(const RobotModel& model) {
  const int n = model.dof();
  JointFrameData f;
  f.gravity = model.gravity;
  // The part of row j that the joint variable does not move: the angle about
  // z_j (offset or theta) and the translation along z_j (d or offset), and
  // the fixed d that standard DH puts after the joint (0 for a prismatic joint,
  // whose d moves the joint frame itself).
  const auto fixed_angle = [](const JointParams& J) { return J.prismatic() ? J.theta : J.offset; };
  const auto fixed_slide = [](const JointParams& J) { return J.prismatic() ? J.offset : J.d; };
  const auto distal_d = [](const JointParams& J) { return J.prismatic() ? 0.0 : J.d; };
  for (int j = 0; j < n; ++j) {
    check_unused_parameter(model, j);
    const JointParams& J = model.joints[j];
    Eigen::Matrix3d E;
    Eigen::Vector3d p;
    Eigen::Vector3d com = J.com;
    Eigen::Matrix3d I = J.inertia;
    if (model.convention == DhConvention::kStandard) {
      // Revolute: joint frame j = DH frame j-1 * Rz(offset_j) * Rz(q_j) and
      // DH frame j = joint frame j * Tz(d_j) Tx(a_j) Rx(alpha_j).
      // Prismatic: joint frame j = DH frame j-1 * Rz(theta_j) Tz(offset_j) * Tz(q_j)
      // and DH frame j = joint frame j * Tx(a_j) Rx(alpha_j).
      // DH frame j-1 = joint frame j-1 * Tz(distal d_{j-1}) Tx(a_{j-1}) Rx(alpha_{j-1}).
      if (j == 0) {
        E = rot_z(fixed_angle(J));
        p.setZero();
      } else {
        const JointParams& P = model.joints[j - 1];
        E = rot_x(P.alpha) * rot_z(fixed_angle(J));
        p = Eigen::Vector3d(P.a, 0, distal_d(P));
      }
      if (J.prismatic()) p += E.col(2) * J.offset;
      const LinkInJointFrame L = link_in_joint_frame(model, j);
      com = L.R * J.com + L.t;
      I = L.R * J.inertia * L.R.transpose();
    } else {
      // Joint frame j = DH frame j = DH frame j-1 * Rx(alpha) Tx(a) Tz(fixed slide)
      // Rz(fixed angle), then Rz(q) or Tz(q) (Rz and Tz commute).
      E = rot_x(J.alpha) * rot_z(fixed_angle(J));
      p = rot_x(J.alpha) * Eigen::Vector3d(J.a, 0, fixed_slide(J));
    }
    f.type.push_back(J.type);
    f.E.push_back(E);
    f.p.push_back(p);
    f.mass.push_back(J.mass);
    f.com.push_back(com);
    f.I_com.push_back(I);
    f.armature.push_back(J.gear_ratio * J.gear_ratio * J.rotor_inertia);
  }
  // Joint frame 0 is the base frame: DH frame 0 is placed in it by the base transform.
  if (n > 0) {
    f.p[0] = model.base_R * f.p[0] + model.base_p;
    f.E[0] = model.base_R * f.E[0];
  }
  // The flange: the last DH frame (joint frame n for modified DH, n's distal
  // frame for standard DH), then the tool transform.
  if (model.convention == DhConvention::kStandard && n > 0) {
    const JointParams& L = model.joints[n - 1];
    f.E_tool = rot_x(L.alpha);
    f.p_tool = Eigen::Vector3d(L.a, 0, distal_d(L));
  }
  f.p_tool += f.E_tool * model.tool_p;
  f.E_tool = f.E_tool * model.tool_R;
  return f;
}

}  // namespace pumasim
