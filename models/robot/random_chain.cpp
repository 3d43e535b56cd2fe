#include "models/robot/random_chain.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace pumasim {

RobotModel random_chain(int n, std::uint64_t seed, DhConvention convention) {
  return random_chain(n, seed, convention, "R");
}

RobotModel random_chain(int n, std::uint64_t seed, DhConvention convention, std::string_view joint_types) {
  if (joint_types.empty() || joint_types.find_first_not_of("RP") != std::string_view::npos) {
    throw std::invalid_argument("random_chain: expected joint types as a pattern of 'R' and 'P', got '" +
                                std::string(joint_types) + "'");
  }
  const bool all_revolute = joint_types.find('P') == std::string_view::npos;
  Rng rng(seed);
  RobotModel m;
  m.name = "random" + std::to_string(n);
  m.source = "random_chain(n=" + std::to_string(n) + ", seed=" + std::to_string(seed) +
             (all_revolute ? "" : ", joints=" + std::string(joint_types)) + ")";
  m.convention = convention;
  for (int j = 0; j < n; ++j) {
    JointParams J;
    J.a = rng.uniform(0.0, 0.5);
    J.alpha = rng.uniform(-M_PI, M_PI);
    J.d = rng.uniform(-0.3, 0.3);
    J.offset = rng.uniform(-M_PI, M_PI);
    J.mass = rng.uniform(0.5, 10.0);
    J.com = Eigen::Vector3d(rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2));
    // Principal moments from a solid box with random sides: always a valid body.
    const double x = rng.uniform(0.05, 0.5), y = rng.uniform(0.05, 0.5), z = rng.uniform(0.05, 0.5);
    const Eigen::Vector3d principal =
        J.mass / 12.0 * Eigen::Vector3d(y * y + z * z, x * x + z * z, x * x + y * y);
    const Eigen::Quaterniond orient(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1),
                                    rng.uniform(-1, 1));
    const Eigen::Matrix3d R = orient.normalized().toRotationMatrix();
    J.inertia = R * principal.asDiagonal() * R.transpose();
    J.rotor_inertia = rng.uniform(1e-5, 5e-4);
    J.gear_ratio = rng.uniform(20.0, 120.0) * (rng.uniform() < 0.5 ? -1.0 : 1.0);
    if (joint_types[static_cast<std::size_t>(j) % joint_types.size()] == 'P') {
      // The same draws, so that the other joints do not change: the angle
      // drawn as offset becomes the fixed theta, the d drawn the offset [m].
      J.type = JointType::kPrismatic;
      J.theta = J.offset;
      J.offset = J.d;
      J.d = 0.0;
      J.q_min = -std::numeric_limits<double>::infinity();
      J.q_max = std::numeric_limits<double>::infinity();
    }
    m.joints.push_back(J);
  }
  return m;
}

}  // namespace pumasim
