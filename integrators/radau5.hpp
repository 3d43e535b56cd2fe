// Radau IIA of order 5 (integrators/radau5.cpp): its coefficients, derived
// here from their defining conditions and checked in tests/test_radau5.cpp
// against the closed forms of Hairer & Wanner, Solving ODEs II, Sec. IV.5
// (Table 5.6) and IV.8; and a fixed-step driver of the same Newton
// iteration, for the order tests.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "integrators/integrator.hpp"

namespace pumasim {

struct Radau5Tableau {
  Eigen::Vector3d c;  // the Radau points (4 -+ sqrt 6) / 10 and 1
  Eigen::Matrix3d A;  // Table 5.6; b is its last row (stiffly accurate)
  Eigen::Matrix3d A_inv;
  // T^-1 A^-1 T = [gamma 0 0; 0 alpha -beta; 0 beta alpha]: the real
  // eigenvalue and the complex pair of A^-1, which split the 3n x 3n Newton
  // system into one real and one complex n x n system (Sec. IV.8, (8.15)).
  Eigen::Matrix3d T, T_inv;
  double gamma = 0, alpha = 0, beta = 0;
  // The embedded error estimate err = (gamma/h I - J)^-1 (f(t0, y0) +
  // sum_i dd_i z_i / h) (Sec. IV.8, (8.19)-(8.20)): dd = gamma (b^ - b)^T
  // A^-1, with b^ the order-3 weights on the nodes (0, c) whose weight at 0
  // is 1/gamma.
  Eigen::Vector3d dd;
};

const Radau5Tableau& radau5_tableau();

// Radau IIA(5) with a constant step h (the last one shortened to each stop),
// the simplified Newton iteration run to convergence at every step (a fresh
// Jacobian per step, increments below 1e-14 of the state's size), no error
// control: the method alone, for the tests of its order.
std::unique_ptr<Integrator> make_radau5_fixed_step(double h);

}  // namespace pumasim
