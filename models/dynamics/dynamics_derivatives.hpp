// Exact first derivatives of the rigid-body dynamics, analytically
// (Carpentier & Mansard 2018, "Analytical Derivatives of Rigid Body Dynamics
// Algorithms", RSS, sec. III-IV): forward dynamics qdd = FD(q, qd, tau) is
// defined by ID(q, qd, qdd) = tau, so at qdd = FD(q, qd, tau)
//   dFD/dq = -H^-1 dID/dq,   dFD/dqd = -H^-1 dID/dqd,   dFD/dtau = H^-1.
// The partials dID/dq and dID/dqd come from the analytical recursions of
// rnea_derivatives.hpp, in double; the values (h, H, qdd) and the Cholesky
// factor of H from the given back-end, and H^-1 formed from it once per call
// (dFD/dtau itself, then two matrix products). Every back-end
// computes the same ID up to rounding, so the partials serve every back-end
// without instantiating it on a new scalar. No allocation after construction.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/chain.hpp"
#include "models/dynamics/rnea_derivatives.hpp"

namespace pumasim {

class DynamicsDerivatives {
 public:
  // The values come from `values`, a back-end made for `model`.
  DynamicsDerivatives(const RobotModel& model, std::unique_ptr<DynamicsBackend> values);
  ~DynamicsDerivatives();
  DynamicsDerivatives(const DynamicsDerivatives&) = delete;
  DynamicsDerivatives& operator=(const DynamicsDerivatives&) = delete;

  int dof() const { return n_; }
  DynamicsBackend& values() { return *values_; }
  const DynamicsBackend& values() const { return *values_; }

  // dID/dq and dID/dqd (n x n each) at (q, qd, qdd); without gravity if
  // `gravity` is false (then H(q) qdd + C(q, qd) qd).
  void id_partials(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq, MatRef dqd);
  // H(q) with the back-end (mass_matrix()); factor_mass_matrix also factors
  // it for forward_dynamics.
  void compute_mass_matrix(ConstVecRef q) { values_->mass_matrix(q, H_); }
  void factor_mass_matrix(ConstVecRef q);
  const Eigen::MatrixXd& mass_matrix() const { return H_; }
  // The bias h(q, qd) last computed by forward_dynamics.
  const Eigen::VectorXd& bias() const { return h_; }
  // qdd = H^-1 (tau - h) (the back-end's h and H) and dqdd/dq, dqdd/dqd,
  // dqdd/dtau (n x n each).
  void forward_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef tau, VecRef qdd, MatRef dq, MatRef dqd,
                        MatRef dtau);

 private:
  int n_;
  std::unique_ptr<DynamicsBackend> values_;
  RneaDerivatives partials_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd h_;
  Cholesky<double, Eigen::Dynamic> chol_;
  Eigen::MatrixXd Pq_, Pqd_, Y_;  // forward_dynamics' workspace: dID/dq, dID/dqd, L^-T
  Eigen::VectorXd c_;
};

}  // namespace pumasim
