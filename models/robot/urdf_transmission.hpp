// A URDF's <transmission> elements: the gear ratio and rotor inertia of the
// joints they drive (internal to models/robot: urdf_file.cpp uses it).
//
// urdfdom has no transmission model, so this is a second read of the same
// text with TinyXML 2.6.2 (the XML parser urdfdom is built with on Debian
// 12), after the URDF pre-scan (urdf_file.hpp) has bounded its size, depth,
// attributes and markup: the parse sees only text the first read accepted.
//
// What is read, in the two forms ROS descriptions use (ros_control's
// transmission_interface and the older pr2_mechanism_model one):
//
//   <transmission name="t1">
//     <type>transmission_interface/SimpleTransmission</type>
//     <joint name="j1"><hardwareInterface>...</hardwareInterface></joint>
//     <actuator name="m1">
//       <mechanicalReduction>50</mechanicalReduction>   gear ratio Z [-] (or [rad/m])
//       <motorInertia>2e-4</motorInertia>               rotor inertia [kg m^2], motor side
//     </actuator>
//   </transmission>
//
// <mechanicalReduction> may also stand directly in <transmission> (the older
// form). A transmission with one joint and one actuator is a simple
// reduction; one that couples several joints or actuators (a differential
// wrist) has no gear ratio per joint, and is listed as not read, as is one on
// a joint off the chain (urdf_file.cpp); one naming no joint of the URDF is
// refused. Only <transmission> elements directly inside <robot> are read:
// ROS 2's <ros2_control> blocks (their <transmission> with
// <mechanical_reduction>) are not, and give no gear ratio.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pumasim {

struct UrdfTransmission {
  std::string name;           // the <transmission>'s name attribute
  int line = 0;               // its start tag's line
  std::optional<double> gear_ratio;     // <mechanicalReduction>
  std::optional<double> rotor_inertia;  // <motorInertia> [kg m^2]
};

struct UrdfTransmissions {
  std::map<std::string, UrdfTransmission> by_joint;  // simple reductions, by joint name
  // Transmissions coupling several joints or actuators: "'t' (joints a, b; 2 actuators)".
  std::vector<std::string> coupled;
};

// The transmissions in `text` (a URDF the pre-scan accepted, read from
// `path` for messages). ConfigError naming the file and line for a value
// that is not a finite number, a zero reduction, a negative motor inertia,
// or two simple transmissions on one joint.
UrdfTransmissions read_urdf_transmissions(const std::string& path, const std::string& text);

}  // namespace pumasim
