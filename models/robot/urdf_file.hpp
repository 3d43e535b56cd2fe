// URDF robot files, read through urdfdom (Debian liburdfdom-dev).
//
// A serial chain of revolute, continuous and prismatic joints becomes a
// RobotModel in modified DH form (Craig) between a base and a tool transform
// (robot_model.hpp): DH frame j has its z axis on joint j's axis, pointing
// along the URDF axis, so q_j is the URDF joint variable (an axis (0, 0, -1)
// turns the other way), and its x axis on the common normal to joint j+1's
// axis (parallel axes: the normal through the previous frame's origin). The
// URDF root link's frame is the base frame (gravity, Cartesian quantities);
// the flange is the chain's last link. Fixed joints merge their child links
// into the parent body (mass, centre of mass, inertia by the parallel-axis
// theorem); links fixed to the root are ground and carry no dynamics. A link
// without <inertial> has no mass.
//
// Refused, each with a ConfigError naming the file, the line of the joint or
// link and what was expected: a tree (two moving joints leaving one rigid
// body), a closed loop (a link that is the child of two joints), links not
// connected to the root, floating and planar joints, mimic joints, joint
// damping or friction (friction belongs to the scene's drive), a zero axis,
// revolute or prismatic limits without lower < upper, non-finite numbers, a
// negative mass, and a body whose mass and inertia are no rigid body's
// (link_inertia.hpp) unless the side file says why. Ignored: visual and
// collision geometry, materials, calibration, safety controllers, transmissions,
// and the limits' effort and velocity.
//
// What URDF has no place for comes from an optional TOML side file next to it,
// the same path with ".toml" appended (puma560.urdf -> puma560.urdf.toml),
// read strictly (format in models/robots/README.md): per moving joint its
// rotor inertia and gear ratio (default: none and 1, a direct drive) and an
// inconsistent_inertia excuse; gravity in the root link's frame (default
// [0, 0, -9.81], z up as in ROS); the flange link; named poses.
#pragma once

#include <string>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

// True for a path ending in ".urdf".
bool is_urdf_path(const std::string& path);

// The side file of a URDF file: its path with ".toml" appended.
std::string urdf_side_file(const std::string& urdf_path);

// Loads a URDF file and its side file when there is one; ConfigError otherwise.
RobotModel load_urdf_file(const std::string& path);

}  // namespace pumasim
