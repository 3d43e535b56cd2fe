// Where a link's inertial data sit in the algorithms' joint frames: a robot
// file gives link j's centre of mass and inertia in its DH frame j; in joint
// frame j (models/dynamics/robot_model.hpp, JointFrameData) a point is
// R p + t of its DH-frame coordinates p. Standard DH: R = Rx(alpha_j),
// t = (a_j, 0, d_j) (d_j the fixed d after a revolute joint, 0 after a
// prismatic one, whose d moves the joint frame itself); modified DH: the two
// frames are one (R = 1, t = 0). joint_frames moves the data with it and
// JointTorqueRegressor::with_parameters moves them back.
#pragma once

#include <Eigen/Core>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

struct LinkInJointFrame {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

LinkInJointFrame link_in_joint_frame(const RobotModel& model, int j);

}  // namespace pumasim
