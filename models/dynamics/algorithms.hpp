// Every dynamics algorithm, and what the registry and the tests need to know
// about them generically: whether one can describe a given chain, and whether
// its forward dynamics solves with H.
#pragma once

#include <string>

#include "models/dynamics/aba.hpp"
#include "models/dynamics/chain.hpp"
#include "models/dynamics/crba.hpp"
#include "models/dynamics/crba_world.hpp"
#include "models/dynamics/lagrange_euler.hpp"
#include "models/dynamics/lagrange_symbolic.hpp"
#include "models/dynamics/recursive_symbolic.hpp"
#include "models/dynamics/rnea_probing.hpp"

namespace pumasim {

// Empty if Algo can handle the model, else the reason. General algorithms
// handle every chain; generated ones declare `why_unsupported(chain)`.
template <template <class, int> class Algo>
std::string why_unsupported(const RobotModel& model) {
  if constexpr (requires(const Chain<double, Eigen::Dynamic>& c) {
                  Algo<double, Eigen::Dynamic>::why_unsupported(c);
                }) {
    return Algo<double, Eigen::Dynamic>::why_unsupported(Chain<double, Eigen::Dynamic>(model));
  } else {
    (void)model;
    return "";
  }
}

// Whether Algo's forward dynamics forms H and solves with it (Cholesky).
// Every algorithm here does but the ABA, which declares kFactorsMassMatrix.
template <template <class, int> class Algo>
constexpr bool factors_mass_matrix() {
  if constexpr (requires { Algo<double, Eigen::Dynamic>::kFactorsMassMatrix; }) {
    return Algo<double, Eigen::Dynamic>::kFactorsMassMatrix;
  } else {
    return true;
  }
}

}  // namespace pumasim
