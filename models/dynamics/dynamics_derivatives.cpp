#include "models/dynamics/dynamics_derivatives.hpp"

namespace pumasim {

DynamicsDerivatives::DynamicsDerivatives(const RobotModel& model, std::unique_ptr<DynamicsBackend> values)
    : n_(model.dof()),
      values_(std::move(values)),
      partials_(model),
      H_(n_, n_),
      h_(n_),
      chol_(n_),
      Pq_(n_, n_),
      Pqd_(n_, n_),
      Y_(n_, n_),
      c_(n_) {}

DynamicsDerivatives::~DynamicsDerivatives() = default;

void DynamicsDerivatives::id_partials(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq,
                                      MatRef dqd) {
  partials_.compute(q, qd, qdd, gravity, dq, dqd);
}

void DynamicsDerivatives::factor_mass_matrix(ConstVecRef q) {
  values_->mass_matrix(q, H_);
  chol_.factor(H_);
}

// dtau = H^-1 once, then dq = -H^-1 dID/dq and dqd = -H^-1 dID/dqd as two
// matrix products (Cholesky::inverse says why).
void DynamicsDerivatives::forward_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef tau, VecRef qdd, MatRef dq,
                                           MatRef dqd, MatRef dtau) {
  const int n = n_;
  values_->bias(q, qd, h_);
  factor_mass_matrix(q);
  for (int j = 0; j < n; ++j) qdd[j] = tau[j] - h_[j];
  chol_.solve_in_place(qdd);
  id_partials(q.data(), qd.data(), qdd.data(), true, Pq_, Pqd_);
  chol_.inverse(dtau, Y_, c_);
  dq.noalias() = -dtau * Pq_;
  dqd.noalias() = -dtau * Pqd_;
}

}  // namespace pumasim
