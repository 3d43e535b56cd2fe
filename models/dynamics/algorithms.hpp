// Every dynamics algorithm, and what the registry and the tests need to know
// about them generically: whether one can describe a given chain, and whether
// its forward dynamics solves with H.
#pragma once

#include <concepts>
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

// What a dynamics algorithm is (a template on the scalar and the size, N =
// Eigen::Dynamic for any chain), as a C++20 concept: made from the chain it
// reads, and computing inverse dynamics, H, h = C qd + g, C qd, g and forward
// dynamics into the caller's vectors. The registry's entry() requires it,
// so a back-end file lacking one fails to compile naming the member.
// (clang-format 14 misreads a concept's constraints: the concepts are laid out by hand.)
// clang-format off
template <template <class, int> class Algo>
concept DynamicsAlgorithm =
    std::constructible_from<Algo<double, Eigen::Dynamic>, const Chain<double, Eigen::Dynamic>&> &&
    requires(Algo<double, Eigen::Dynamic>& a, const Eigen::VectorXd& q, Eigen::VectorXd& out, Eigen::MatrixXd& H) {
      { Algo<double, Eigen::Dynamic>::kName } -> std::convertible_to<const char*>;
      a.inverse_dynamics(q, q, q, out);
      a.mass_matrix(q, H);
      a.bias(q, q, out);
      a.coriolis(q, q, out);
      a.gravity(q, out);
      a.forward_dynamics(q, q, q, out);
    };
// clang-format on

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
