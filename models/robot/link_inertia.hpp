// What a link's mass, centre of mass and inertia lack to be a rigid body's,
// for the readers of robot files (robot_file.cpp) and URDF files (urdf_file.cpp).
#pragma once

#include <string>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

// The key at fault ("inertia" or "com"), what it should be and what it is;
// key empty: nothing. `excusable` is false for an inertia that is not positive
// semi-definite (no body has one), true for the rigid-body conditions below,
// which a published set may break (a robot file's inconsistent_inertia).
struct InertiaProblem {
  std::string key, expected, got;
  bool excusable = true;
};

// A body of no mass has no inertia and no centre of mass (a density >= 0
// whose integral is zero is zero). With mass, the principal moments about the
// centre of mass obey the triangle inequalities, each at most the sum of the
// other two: with m >= 0 that is the pseudo-inertia matrix being positive
// semi-definite (its 3 x 3 block about the centre of mass has eigenvalues
// (I_j + I_k - I_i) / 2), the physical-consistency condition of Wensing, Kim
// & Slotine, "Linear matrix inequalities for physically consistent inertial
// parameter identification", IEEE RA-L 3(1), 2017. It implies a positive
// semi-definite inertia (checked first, with its own message).
InertiaProblem inertia_problem(const JointParams& link);

}  // namespace pumasim
