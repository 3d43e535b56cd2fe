#include "models/dynamics/dynamics_derivatives.hpp"

#include <algorithm>

namespace pumasim {

DynamicsDerivatives::DynamicsDerivatives(const RobotModel& model, std::unique_ptr<DynamicsBackend> values)
    : n_(model.dof()),
      values_(std::move(values)),
      H_(n_, n_),
      h_(n_),
      chol_(n_) {
  if (2 * n_ <= 6) {
    small_ = std::make_unique<Engine<6>>(model);
  } else {
    large_ = std::make_unique<Engine<kPartialTangents>>(model);
  }
}

DynamicsDerivatives::~DynamicsDerivatives() = default;

void DynamicsDerivatives::id_partials(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq,
                                      MatRef dqd) {
  if (small_) {
    small_->partials(q, qd, qdd, gravity, dq, dqd);
  } else {
    large_->partials(q, qd, qdd, gravity, dq, dqd);
  }
}

template <int K>
void DynamicsDerivatives::Engine<K>::partials(const double* q0, const double* qd0, const double* qdd0, bool gravity,
                                              MatRef dq, MatRef dqd) {
  const int n = chain.n;
  // Directions 0..n-1 are q's, n..2n-1 qd's; K of them per pass.
  for (int first = 0; first < 2 * n; first += K) {
    for (int j = 0; j < n; ++j) {
      q[j] = T(q0[j], j - first);
      qd[j] = T(qd0[j], n + j - first);
      qdd[j] = T(qdd0[j]);
    }
    rot.compute(chain, q);
    rnea.run(chain, rot, qd, qdd, gravity, tau);
    const int last = std::min(2 * n, first + K);
    for (int k = first; k < last; ++k) {
      for (int i = 0; i < n; ++i) (k < n ? dq(i, k) : dqd(i, k - n)) = tau[i].deriv(k - first);
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
