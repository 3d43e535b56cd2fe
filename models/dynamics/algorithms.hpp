// Every dynamics algorithm, and what the registry and the tests need to know
// about them generically: whether one can describe a given chain.
#pragma once

#include <string>

#include "models/dynamics/aba.hpp"
#include "models/dynamics/chain.hpp"
#include "models/dynamics/crba.hpp"
#include "models/dynamics/lagrange_euler.hpp"
#include "models/dynamics/lagrange_symbolic.hpp"
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

}  // namespace pumasim
