// The plant's scratch for one evaluation of f in scalar type S (double, or a
// dual number for the exact Jacobian): sized once, reused, no allocation per
// evaluation. Internal to the plant and its blocks.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/chain.hpp"

namespace pumasim {

template <class S>
struct PlantWorkspace {
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  std::unique_ptr<BasicDynamicsBackend<S>> backend;
  Vec q, qd;     // joint angles and speeds
  Vec u;         // controller output (DAC) [V]
  Vec ea;        // amplifier output [V]
  Vec tm;        // motor torque K i [N m, motor side]
  Vec applied;   // the torque friction must resist at rest [N m, motor side]
  Vec tau;       // joint torque from the drive, friction subtracted [N m]
  Vec h;         // bias forces (Coriolis, centrifugal, gravity)
  Vec qdd;
  Vec id;       // inverse dynamics at the constrained solution (the exact Jacobian's pass)
  Vec command_qdd, command_tau;  // a model-based controller's scratch
  Mat H, Hc;     // mass matrix; with stuck joints' rows and columns replaced by the identity
  Cholesky<S, Eigen::Dynamic> chol;
  S p_in, p_cu, p_f;  // energy ledger: power in, copper and friction losses [W]
  explicit PlantWorkspace(int n)
      : q(n), qd(n), u(n), ea(n), tm(n), applied(n), tau(n), h(n), qdd(n), id(n), command_qdd(n), command_tau(n), H(n, n), Hc(n, n), chol(n) {}
};

}  // namespace pumasim
