#include "models/dynamics/dynamics_derivatives.hpp"

#include <algorithm>

namespace pumasim {

DynamicsDerivatives::DynamicsDerivatives(const RobotModel& model, std::unique_ptr<DynamicsBackend> values)
    : n_(model.dof()),
      values_(std::move(values)),
      chain_(model),
      rot_(n_),
      rnea_(n_),
      qs_(n_),
      qds_(n_),
      qdds_(n_),
      taus_(n_),
      H_(n_, n_),
      h_(n_),
      chol_(n_) {}

DynamicsDerivatives::~DynamicsDerivatives() = default;

void DynamicsDerivatives::id_partials(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq,
                                      MatRef dqd) {
  const int n = n_;
  constexpr int K = kPartialTangents;
  // Directions 0..n-1 are q's, n..2n-1 qd's; K of them per pass.
  for (int first = 0; first < 2 * n; first += K) {
    for (int j = 0; j < n; ++j) {
      qs_[j] = Partial(q[j], j - first);
      qds_[j] = Partial(qd[j], n + j - first);
      qdds_[j] = Partial(qdd[j]);
    }
    rot_.compute(chain_, qs_);
    rnea_.run(chain_, rot_, qds_, qdds_, gravity, taus_);
    const int last = std::min(2 * n, first + K);
    for (int k = first; k < last; ++k) {
      for (int i = 0; i < n; ++i) (k < n ? dq(i, k) : dqd(i, k - n)) = taus_[i].deriv(k - first);
    }
  }
}

void DynamicsDerivatives::factor_mass_matrix(ConstVecRef q) {
  values_->mass_matrix(q, H_);
  chol_.factor(H_);
}

void DynamicsDerivatives::forward_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef tau, VecRef qdd, MatRef dq,
                                           MatRef dqd, MatRef dtau) {
  const int n = n_;
  values_->bias(q, qd, h_);
  factor_mass_matrix(q);
  for (int j = 0; j < n; ++j) qdd[j] = tau[j] - h_[j];
  chol_.solve_in_place(qdd);
  id_partials(q.data(), qd.data(), qdd.data(), true, dq, dqd);
  dtau.setIdentity();
  for (int k = 0; k < n; ++k) {
    dq.col(k) = -dq.col(k);
    dqd.col(k) = -dqd.col(k);
    chol_.solve_in_place(dq.col(k));
    chol_.solve_in_place(dqd.col(k));
    chol_.solve_in_place(dtau.col(k));
  }
}

}  // namespace pumasim
