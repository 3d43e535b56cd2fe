// Random serial chains of any length, for tests and cost-versus-n benchmarks.
//
// Deterministic: the same (n, seed) gives the same chain on every platform
// (a 64-bit Mersenne Twister mapped to [0, 1) by hand, not through the
// implementation-defined std::uniform_real_distribution).
#pragma once

#include <cstdint>
#include <random>
#include <string_view>

#include <Eigen/Core>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  Eigen::VectorXd uniform_vector(int n, double lo, double hi) {
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v[i] = uniform(lo, hi);
    return v;
  }

 private:
  std::mt19937_64 engine_;
};

// A chain of n revolute joints with random DH rows (convention as given), link
// masses in [0.5, 10] kg, centres of mass within 0.2 m of the frame origin,
// physically valid inertias (principal moments obeying the triangle inequality,
// random principal axes), rotor inertias in [1e-5, 5e-4] kg m^2 and gear
// ratios of magnitude 20..120 with random sign; gravity -9.81 m/s^2 along z.
RobotModel random_chain(int n, std::uint64_t seed,
                        DhConvention convention = DhConvention::kStandard);

// The same with joint j prismatic where joint_types[j % size] is 'P' and
// revolute where it is 'R' ("RP": alternating, "RRP": every third). The random
// numbers drawn are the same as above, so every revolute joint is the one of
// random_chain(n, seed, convention), and "R" gives that chain exactly. A
// prismatic joint takes the angle drawn as offset for its fixed theta and the
// length drawn as d for its offset (d_j = q_j + offset, |offset| <= 0.3 m);
// its gear ratio is then in rad/m and its limits are none (+-inf).
RobotModel random_chain(int n, std::uint64_t seed, DhConvention convention, std::string_view joint_types);

}  // namespace pumasim
