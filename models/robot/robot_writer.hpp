// A robot as a robot file (the TOML that robot_file.hpp reads): what
// `pumasim robot --random N` prints, so that a random chain of any length
// can be the robot of a scene (tests, benchmarks, a user's first look at a
// long arm). Every number is written as the shortest text that reads back as
// the same double, so load_robot_file(write(m)) gives m's parameters exactly.
#pragma once

#include <string>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

// std::invalid_argument if the model has what a robot file cannot say: a
// base or tool transform other than the identity (a URDF robot's).
std::string robot_file_text(const RobotModel& model, const std::string& header_comment = "");

}  // namespace pumasim
