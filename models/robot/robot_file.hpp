// Robot files: a RobotModel in TOML (format documented in models/robots/README.md).
#pragma once

#include <string>

#include "models/dynamics/robot_model.hpp"
#include "models/robot/strict_toml.hpp"

namespace pumasim {

// Loads and checks a robot file; ConfigError naming file, line and key otherwise.
RobotModel load_robot_file(const std::string& path);

// The first joint (0-based) whose motion carries no inertia at pose q -- the
// joint-space inertia H(q), rotor inertia included, is singular there -- or
// -1 when H(q) is positive definite (to 1e-12 of its largest diagonal entry).
int joint_without_inertia(const RobotModel& model, const Eigen::VectorXd& q);

// `name_or_path` is a path when it contains '/' or ends in ".toml" or ".urdf"
// (is_robot_path); otherwise the shipped robot file <robots dir>/<name>.toml
// ("puma560"), or the shipped URDF file <robots dir>/<name>.urdf when there
// is no robot file of that name. A path ending in ".urdf" is a URDF file
// (urdf_file.hpp), any other a robot file.
RobotModel load_robot(const std::string& name_or_path);
bool is_robot_path(const std::string& name_or_path);

// The directory of the shipped robot files: $PUMASIM_ROBOTS_DIR if set, else
// the source tree's models/robots.
std::string robots_dir();

}  // namespace pumasim
