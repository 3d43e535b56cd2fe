#include "models/robot/link_inertia.hpp"

#include <algorithm>
#include <cstdio>

#include <Eigen/Eigenvalues>

namespace pumasim {
namespace {

std::string str(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

}  // namespace

InertiaProblem inertia_problem(const JointParams& J) {
  const Eigen::Vector3d principal =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(J.inertia, Eigen::EigenvaluesOnly).eigenvalues();
  const double min_eig = principal.minCoeff();
  if (min_eig < -1e-12 * std::max(1.0, J.inertia.norm())) {
    return {"inertia", "a positive semi-definite inertia", "a matrix with eigenvalue " + std::to_string(min_eig),
            false};
  }
  if (J.mass == 0) {
    if (!J.inertia.isZero(0)) {
      return {"inertia", "zero inertia on a link of mass 0 (a body without mass has none)", "a non-zero inertia"};
    }
    if (!J.com.isZero(0)) {
      return {"com", "[0, 0, 0] on a link of mass 0 (a body without mass has no centre of mass)",
              "[" + str(J.com.x()) + ", " + str(J.com.y()) + ", " + str(J.com.z()) + "]"};
    }
    return {};
  }
  const double tol = 1e-12 * std::max(1.0, principal.sum());
  for (int i = 0; i < 3; ++i) {
    const double others = principal.sum() - principal[i];
    if (principal[i] > others + tol) {
      return {"inertia",
              "principal moments about the centre of mass that obey the triangle inequalities, each at most the "
              "sum of the other two (a rigid body's; Wensing, Kim & Slotine 2017)",
              str(principal[i]) + " > " + str(others) + " (principal moments " + str(principal[0]) + ", " +
                  str(principal[1]) + ", " + str(principal[2]) + " kg m^2)"};
    }
  }
  return {};
}

}  // namespace pumasim
