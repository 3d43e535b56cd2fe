// One interface for every dynamics back-end, and the registry that names them.
//
// A back-end computes, for the chain it was made for (rotor inertia Z^2 Im
// included in H and tau exactly when the model has it):
//   inverse dynamics  tau = H(q) qdd + h(q, qd)
//   mass matrix       H(q)           (with Z^2 Im on the diagonal)
//   bias              h(q, qd) = C(q, qd) qd + g(q)
//   gravity           g(q)
//   forward dynamics  qdd = H(q)^{-1} (tau - h(q, qd))  (also given h)
// One virtual call per quantity; inside, the algorithm runs on fixed-size
// types for n = 3 and n = 6 and never allocates. A back-end object owns its
// workspace: use one object per thread.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "models/dynamics/counted.hpp"
#include "models/dynamics/dual.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

// The interface on scalar S: double for simulation, Dual for exact Jacobians
// of the plant (forward-mode derivatives through the whole algorithm).
template <class S>
class BasicDynamicsBackend {
 public:
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  using ConstVecRef = Eigen::Ref<const Vec>;
  using VecRef = Eigen::Ref<Vec>;
  using MatRef = Eigen::Ref<Mat>;

  virtual ~BasicDynamicsBackend() = default;
  virtual const char* name() const = 0;
  virtual int dof() const = 0;
  virtual void inverse_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef qdd, VecRef tau) = 0;
  virtual void mass_matrix(ConstVecRef q, MatRef H) = 0;
  virtual void bias(ConstVecRef q, ConstVecRef qd, VecRef h) = 0;
  virtual void gravity(ConstVecRef q, VecRef g) = 0;
  virtual void forward_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef tau, VecRef qdd) = 0;
  // Forward dynamics where the caller has h = bias(q, qd) from this back-end
  // already (the plant's friction laws that read the applied torque need it
  // first). A back-end that factors H returns H^-1 (tau - h) for the h
  // given, without forming h again: its mass_matrix and a Cholesky solve
  // (backend_impl.hpp; for the CRBA ones the operations of their forward
  // dynamics without its RNEA pass). One that forms no H (aba) ignores h and runs its own
  // forward dynamics, so h must be this back-end's bias(q, qd): then every
  // back-end returns its forward dynamics, up to rounding.
  virtual void forward_dynamics_with_bias(ConstVecRef q, ConstVecRef qd, ConstVecRef h, ConstVecRef tau,
                                          VecRef qdd) {
    static_cast<void>(h);
    forward_dynamics(q, qd, tau, qdd);
  }
};

using DynamicsBackend = BasicDynamicsBackend<double>;
using DualDynamicsBackend = BasicDynamicsBackend<Dual>;
using ConstVecRef = DynamicsBackend::ConstVecRef;
using VecRef = DynamicsBackend::VecRef;
using MatRef = DynamicsBackend::MatRef;

// What count_ops counts. kCoriolis is h without gravity, C(q, qd) qd; kSolve
// is the Cholesky factorisation of H and the two substitutions that forward
// dynamics does after forming H and h (nothing for a back-end that does not
// form H: the ABA).
enum class Quantity {
  kInverseDynamics,
  kMassMatrix,
  kBias,
  kCoriolis,
  kGravity,
  kSolve,
  kForwardDynamics
};

struct BackendInfo {
  const char* name;
  const char* summary;  // one line: algorithm, how H and qdd are obtained, cost
  // Empty if this back-end can describe `model`; otherwise why not (a generated
  // closed form, for instance, exists only for the arm it was generated for).
  std::string (*why_unsupported)(const RobotModel& model);
  // std::invalid_argument with that reason if the model is not supported.
  std::unique_ptr<DynamicsBackend> (*make)(const RobotModel& model);
  // The same algorithm on dual numbers (for exact Jacobians).
  std::unique_ptr<DualDynamicsBackend> (*make_dual)(const RobotModel& model);
  // Arithmetic of one call computing `what` for `model` (Counted scalar).
  OpCounts (*count_ops)(const RobotModel& model, Quantity what);
};

// All back-ends, sorted by name.
std::span<const BackendInfo> backends();

// The entry called `name`; std::invalid_argument listing the valid names otherwise.
const BackendInfo& find_backend(std::string_view name);

// "a, b, c": the registered names, for messages.
std::string backend_names();

// How many back-end instances the registry's make and make_dual have built
// in this process (all threads). For tests: loading a scene builds none.
long backends_built();

namespace detail {
void count_backend_built();
}  // namespace detail

inline std::unique_ptr<DynamicsBackend> make_backend(std::string_view name,
                                                     const RobotModel& model) {
  return find_backend(name).make(model);
}

}  // namespace pumasim
