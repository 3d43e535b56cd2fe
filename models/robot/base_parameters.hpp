// Base parameters: the identifiable combinations of a regressor's columns.
//
// The columns of Y(q, qd, qdd) (models/dynamics/regressor.hpp) are linearly
// dependent: some parameters never act (a vertical first joint's link feels
// only its ZZ), others act only together (a link's mass, its MZ and its YY
// with the previous link's). The base parameters are a largest independent
// set of columns, each carrying the dependent ones with it:
//     Y pi = Y_b pi_b,   pi_b = pi[base] + beta pi[grouped]
// (Gautier 1991, "Numerical calculation of the base inertial parameters of
// robots", J. Robotic Systems 8(4); Khalil & Dombre 2002, sec. 9.5.3).
//
// Numerically: Y is evaluated at `samples` random states (q uniform in the
// joint ranges, or in [-pi, pi] rad, [-0.5, 0.5] m for a joint without two
// finite limits; qd, qdd uniform in [-2, 2]), stacked into W. A column at
// rounding level of the largest (100 eps sqrt(rows) of it) has no effect;
// each other is scaled to unit norm. The rank is the number of singular
// values of the scaled W above `tolerance` times the largest; the gap (last
// kept over first dropped) says how clear that choice is. The columns are
// then taken in the regressor's order, each kept when its distance from the
// span of those kept before it (Gram-Schmidt, twice, against the kept
// columns) exceeds the same threshold: a later link's parameters are
// regrouped onto the earlier ones they act with, as in Khalil's rules. The
// regrouping beta solves the scaled base columns against the grouped ones;
// entries at rounding level (1e3 eps sqrt(columns), dimensionless) are set
// to zero before it is unscaled into the parameters' units.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/dynamics/regressor.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

struct BaseParameters {
  std::vector<std::string> names;   // the regressor's columns
  std::vector<int> base;            // the columns kept, in order
  std::vector<int> grouped;         // the others, in order
  Eigen::MatrixXd beta;             // base.size() x grouped.size()
  std::vector<int> no_effect;       // grouped columns that are zero (their beta columns are zero)
  Eigen::VectorXd singular_values;  // of the scaled stacked regressor, largest first
  double tolerance = 0.0;
  int samples = 0;
  std::string warning;  // a gap below 1e6: the rank is not clear ("" otherwise)

  int rank() const { return static_cast<int>(base.size()); }
  // sigma_r / sigma_(r+1) (1-based): the largest singular value dropped
  // against the smallest kept, as a ratio >= 1; infinite if none is dropped
  // or the dropped one is exactly zero.
  double gap() const;
  // pi_b of a standard parameter vector pi.
  Eigen::VectorXd values(const Eigen::VectorXd& pi) const;
  // Y_b: the base columns of a regressor (any number of stacked rows).
  Eigen::MatrixXd columns(const Eigen::MatrixXd& Y) const;
  // Base parameter i's name: its own column's, with R when others regroup onto it ("ZZ1R").
  std::string label(int i) const;
  // What it stands for: "ZZ1 + Ia1 + YY2 + 0.186 M3 ..." (coefficients in SI
  // units, every nonzero one of beta), or the column alone.
  std::string definition(int i) const;
  // One line per base parameter, "ZZ1R = ZZ1 + Ia1 + ...", then those with no effect.
  std::string regrouping() const;
};

// std::invalid_argument for a tolerance outside (0, 1), fewer rows than
// columns, or a sequential choice that disagrees with the SVD's rank (the
// tolerance sits in no gap: the message names the widest gap and a
// tolerance in it).
BaseParameters base_parameters(JointTorqueRegressor& regressor, const RobotModel& model, int samples = 40,
                               std::uint64_t seed = 1, double tolerance = 1e-8);

}  // namespace pumasim
