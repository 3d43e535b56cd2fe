// A robot's dynamics at one state, as `pumasim dynamics` prints them and the
// Python module (python/) returns them: the robot (a shipped name or a file,
// rotor inertias kept or removed), a back-end from the registry, then H, h, g,
// and tau = ID(q, qd, qdd) when qdd is given, qdd = FD(q, qd, tau) when tau is.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

struct RobotDynamics {
  RobotModel model;            // as loaded, rotor inertias removed unless rotor_inertia
  bool rotor_inertia = true;
  std::unique_ptr<DynamicsBackend> backend;
};

// load_robot(robot) (ConfigError naming file, line and key), its rotor
// inertias removed unless rotor_inertia, and the back-end made for it
// (std::invalid_argument: an unknown name, listing the valid ones, or a
// back-end that cannot describe the robot, saying why).
RobotDynamics robot_dynamics(const std::string& robot, const std::string& backend, bool rotor_inertia);

// The angles of the robot file's pose `name`; std::invalid_argument naming
// `what` and the poses there are otherwise.
Eigen::VectorXd pose_angles(const RobotModel& model, const std::string& name, const std::string& what);

struct DynamicsValues {
  Eigen::MatrixXd mass_matrix;         // H(q), rotor inertia included when the model has it
  Eigen::VectorXd bias;                // h(q, qd)
  Eigen::VectorXd gravity;             // g(q)
  std::optional<Eigen::VectorXd> tau;  // ID(q, qd, qdd), when qdd is given
  std::optional<Eigen::VectorXd> qdd;  // FD(q, qd, tau), when tau is given
};

// Every vector has one entry per joint of the back-end's robot, or
// std::invalid_argument ("qd: expected 6 values (one per joint), got 3");
// so is a result that is not finite (finite arguments too large: "bias
// h(q, qd) is not finite (inf for joint 1): ...").
DynamicsValues evaluate_dynamics(DynamicsBackend& backend, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                 const std::optional<Eigen::VectorXd>& qdd, const std::optional<Eigen::VectorXd>& tau);

}  // namespace pumasim
