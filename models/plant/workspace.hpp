// The plant's evaluator on scalar type S (double, or a dual number for the
// Jacobians): the scratch of one evaluation of f, its own back-end instance,
// and what it remembers between evaluations (the reference sample last
// computed, the last f's point). Sized once, reused, no allocation per
// evaluation. One per thread: the model (plant_model.hpp) is shared and
// const, its evaluators are not. Internal to the plant and its blocks.
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/chain.hpp"
#include "models/reference/trajectory.hpp"

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

  // The reference sample last computed, and for which (t, segment, extend):
  // f at one time reads it several times (controller output and rates).
  ReferenceSample reference{};
  double reference_t = std::numeric_limits<double>::quiet_NaN();
  int reference_segment = -1;
  bool reference_extended = false;
  // Inside a difference in t (PlantModel's time derivative): the smooth
  // pieces of the reference and of a law's input continued past their ends.
  bool extend_piece = false;

  // The point of the last f (double only) whose workspace (applied torques,
  // H) is still f there under the context it was evaluated with: the root
  // functions reuse it. Whoever changes the context clears last_valid.
  std::vector<double> last_x;
  double last_t = 0;
  bool last_valid = false;

  PlantWorkspace(int n, int states)
      : q(n), qd(n), u(n), ea(n), tm(n), applied(n), tau(n), h(n), qdd(n), id(n), command_qdd(n), command_tau(n),
        H(n, n), Hc(n, n), chol(n), last_x(static_cast<std::size_t>(states)) {}
};

}  // namespace pumasim
