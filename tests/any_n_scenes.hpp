// Scenes on random chains of any length, written into the tests' scratch
// folder (tests/scratch.hpp): shared by tests/test_any_n.cpp and the
// allocation tests (tests/test_no_alloc.cpp, its own binary).
#pragma once

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <Eigen/Core>

#include "models/robot/kinematics.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_writer.hpp"
#include "tests/scratch.hpp"

namespace pumasim::testing {

inline std::string write_scratch_file(const std::string& name, const std::string& text) {
  const std::filesystem::path p = scratch_root() / name;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p.string();
}

// x as %.17g (read back exactly), and "[a, b, ...]" so.
inline std::string toml_number(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}
inline std::string toml_numbers(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += (i ? ", " : "") + toml_number(v[i]);
  return s + "]";
}

inline std::string random_robot_file(int n, std::uint64_t seed, const std::string& types = "R") {
  return write_scratch_file("any_n/random" + std::to_string(n) + "_" + std::to_string(seed) + types + ".toml",
                            robot_file_text(random_chain(n, seed, DhConvention::kStandard, types)));
}

// A random chain of n joints (seed 500 + n) following a line and an arc from
// the flange's pose at q_g (random in [-1, 1], seed 11) with that orientation
// held, by the numerical inverse kinematics (redundant for n > 6: the rule's
// rest pose is q_g), under computed torque (kp = 400, kd = 40) with the
// reduced drive (La = 0) and viscous friction B on each motor shaft.
inline std::string random_tracking_scene_file(int n, double B) {
  const std::string robot = random_robot_file(n, 500 + static_cast<std::uint64_t>(n));
  const RobotModel m = random_chain(n, 500 + static_cast<std::uint64_t>(n));
  Rng rng(11);
  const Eigen::VectorXd q_g = rng.uniform_vector(n, -1, 1);
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  forward_kinematics<double>(m, q_g, R, p);
  std::string orient = "[";
  for (int i = 0; i < 3; ++i) orient += (i ? ", " : "") + toml_numbers(R.row(i).transpose());
  orient += "]";
  const std::string text =
      "[scene]\nname = \"random" + std::to_string(n) + "_tracking\"\nrobot = \"" + robot + "\"\njoints = " +
      std::to_string(n) + "\nbackend = \"crba\"\nduration = 2.5\noutput_interval = 0.01\n\n"
      "[integrator]\nname = \"cvode-bdf\"\nrtol = 1e-9\natol = 1e-11\n\n"
      "[amplifier]\ngain = 10.0\noutput_resistance = 0.0\nvoltage_limit = 1e6\n\n"
      "[motor]\ninductance = 0.0\nresistance = 0.5\ntorque_constant = 0.5\n\n"
      "[friction]\nmodel = \"viscous\"\nviscous = " + toml_numbers(Eigen::VectorXd::Constant(n, B)) + "\n\n"
      "[controller]\nlaw = \"computed_torque\"\nmode = \"continuous\"\nkp = 400.0\nkd = 40.0\n\n"
      "[reference]\nik = \"numerical\"\nik_guess = " + toml_numbers(q_g) + "\nstart = " +
      toml_numbers(p.head<2>()) + "\nheight = " + toml_number(p.z()) +
      "\nheading = 0.0\norientation = " + orient +
      "\nsegments = [ { line = 0.05 }, { arc_radius = 0.03, turn_degrees = 90.0 } ]\n"
      "timing = \"quintic\"\ntraversal_time = 2.0\n";
  return write_scratch_file("any_n/random" + std::to_string(n) + "_tracking.toml", text);
}

}  // namespace pumasim::testing
