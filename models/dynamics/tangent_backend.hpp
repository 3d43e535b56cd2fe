// A back-end on the multi-tangent dual number DualN<N> for exact Jacobians of
// a model built on the dynamics (the plant): every quantity's value comes from
// a double back-end and its N tangents analytically from the partials of
// inverse dynamics (DynamicsDerivatives, Carpentier & Mansard 2018), chained
// with the inputs' tangents:
//   d ID = dID/dq dq + dID/dqd dqd + H dqdd
//   d FD = H^-1 (dtau - dID/dq dq - dID/dqd dqd)       at qdd = FD
// so that the back-end (closed form, generated, ABA, ...) is never
// instantiated on DualN. The hybrid friction's constrained solve has its own
// entry (constrained_forward_dynamics). No allocation after construction.
#pragma once

#include <algorithm>
#include <memory>
#include <type_traits>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/dual_n.hpp"
#include "models/dynamics/dynamics_derivatives.hpp"

namespace pumasim {

template <class S>
inline constexpr bool kIsDualN = false;
template <int N>
inline constexpr bool kIsDualN<DualN<N>> = true;

template <int N>
class TangentBackend final : public BasicDynamicsBackend<DualN<N>> {
  using S = DualN<N>;
  using Base = BasicDynamicsBackend<S>;
  using TConstVecRef = typename Base::ConstVecRef;
  using TVecRef = typename Base::VecRef;
  using TMatRef = typename Base::MatRef;

 public:
  TangentBackend(const RobotModel& model, std::unique_ptr<DynamicsBackend> values)
      : d_(model, std::move(values)), n_(model.dof()), q_(n_), qd_(n_), qdd_(n_), v_(n_), zero_(Eigen::VectorXd::Zero(n_)),
        Pq_(n_, n_), Pqd_(n_, n_), T_(N, n_), X_(N, n_), Hc_(n_, n_), chol_(n_) {}

  const char* name() const override { return d_.values().name(); }
  int dof() const override { return n_; }

  void inverse_dynamics(TConstVecRef q, TConstVecRef qd, TConstVecRef qdd, TVecRef tau) override {
    load(q, qd);
    for (int j = 0; j < n_; ++j) qdd_[j] = qdd[j].value();
    d_.values().inverse_dynamics(q_, qd_, qdd_, v_);
    chain(q, qd, qdd_.data(), true);
    d_.compute_mass_matrix(q_);
    add_product(d_.mass_matrix(), qdd);  // + H dqdd
    store(tau);
  }
  void bias(TConstVecRef q, TConstVecRef qd, TVecRef h) override {
    load(q, qd);
    d_.values().bias(q_, qd_, v_);
    chain(q, qd, zero_.data(), true);
    store(h);
  }
  void gravity(TConstVecRef q, TVecRef g) override {
    load(q, q);
    d_.values().gravity(q_, v_);
    d_.id_partials(q_.data(), zero_.data(), zero_.data(), true, Pq_, Pqd_);
    tangents(q, q, false);
    store(g);
  }
  // h's value alone, its tangents zero: for a caller that uses no tangent of
  // h (one RNEA pass on the multi-tangent scalar fewer).
  void bias_value(TConstVecRef q, TConstVecRef qd, TVecRef h) {
    load(q, qd);
    d_.values().bias(q_, qd_, v_);
    for (int j = 0; j < n_; ++j) h.data()[j] = S(v_[j]);
  }
  // Column j of H is ID(q, 0, e_j) without gravity: its q-partials, one
  // RNEA pass each (this entry serves completeness, not a hot path).
  void mass_matrix(TConstVecRef q, TMatRef H) override {
    load(q, q);
    d_.compute_mass_matrix(q_);
    for (int j = 0; j < n_; ++j) {
      v_ = zero_;
      v_[j] = 1.0;
      d_.id_partials(q_.data(), zero_.data(), v_.data(), false, Pq_, Pqd_);
      tangents(q, q, false);
      for (int i = 0; i < n_; ++i) {
        H(i, j) = S(d_.mass_matrix()(i, j));
        for (int k = 0; k < N; ++k) H(i, j).deriv(k) = T_(k, i);
      }
    }
  }
  void forward_dynamics(TConstVecRef q, TConstVecRef qd, TConstVecRef tau, TVecRef qdd) override {
    constrained_forward_dynamics(q, qd, tau, [](int) { return false; }, qdd, nullptr);
  }
  // Only h's values are read (the plant's pass may hold values alone,
  // bias_value's): its tangents come from the derivative recursions.
  void forward_dynamics_with_bias(TConstVecRef q, TConstVecRef qd, TConstVecRef h, TConstVecRef tau,
                                  TVecRef qdd) override {
    constrained_forward_dynamics(q, qd, tau, [](int) { return false; }, qdd, nullptr, h.data());
  }

  // Forward dynamics with the joints for which stuck(j) holds fixed
  // (qdd_j = 0): the free joints F solve H_FF qdd_F = tau_F - h_F, whose
  // derivative is H_FF dqdd_F = (dtau - dID/dq dq - dID/dqd dqd)_F at the
  // solution; id (if given) receives ID(q, qd, qdd), the torque each stuck
  // joint's constraint supplies in its row (value and tangents). h (if
  // given) holds h(q, qd) from this back-end (bias_value's, or bias's
  // values): its RNEA pass is not run again.
  template <class Stuck>
  void constrained_forward_dynamics(TConstVecRef q, TConstVecRef qd, TConstVecRef tau, Stuck stuck, TVecRef qdd,
                                    S* id, const S* h = nullptr) {
    load(q, qd);
    if (h) {
      for (int j = 0; j < n_; ++j) v_[j] = h[j].value();
    } else {
      d_.values().bias(q_, qd_, v_);
    }
    d_.compute_mass_matrix(q_);
    const Eigen::MatrixXd& H = d_.mass_matrix();
    Hc_ = H;
    for (int j = 0; j < n_; ++j) {
      qdd_[j] = tau[j].value() - v_[j];
      if (!stuck(j)) continue;
      qdd_[j] = 0.0;
      Hc_.row(j).setZero(), Hc_.col(j).setZero(), Hc_(j, j) = 1.0;
    }
    chol_.factor(Hc_);
    chol_.solve_in_place(qdd_);
    chain(q, qd, qdd_.data(), true);  // T = dID/dq dq + dID/dqd dqd
    const S* tp = tau.data();
    for (int j = 0; j < n_; ++j) {
      double* x = X_.col(j).data();
      const double *dt = tp[j].derivs(), *t = T_.col(j).data();
      const bool held = stuck(j);
      for (int k = 0; k < N; ++k) x[k] = held ? 0.0 : dt[k] - t[k];
    }
    chol_.solve_rows_in_place(X_);
    S* out = qdd.data();
    for (int j = 0; j < n_; ++j) {
      out[j] = S(qdd_[j]);
      std::copy_n(X_.col(j).data(), N, out[j].derivs());
    }
    if (!id) return;
    v_.noalias() += H * qdd_;  // h + H qdd
    add_product(H, qdd);
    for (int j = 0; j < n_; ++j) {
      id[j] = S(v_[j]);
      std::copy_n(T_.col(j).data(), N, id[j].derivs());
    }
  }

 private:
  void load(TConstVecRef q, TConstVecRef qd) {
    for (int j = 0; j < n_; ++j) q_[j] = q[j].value(), qd_[j] = qd[j].value();
  }
  // T_ = dID/dq dq + dID/dqd dqd at (q_, qd_, qdd), along the inputs' tangents.
  void chain(TConstVecRef q, TConstVecRef qd, const double* qdd, bool gravity) {
    d_.id_partials(q_.data(), qd_.data(), qdd, gravity, Pq_, Pqd_);
    tangents(q, qd, true);
  }
  // Column i of T_ holds output i's N tangents (contiguous, as in DualN).
  void tangents(TConstVecRef q, TConstVecRef qd, bool with_qd) {
    T_.setZero();
    add_product(Pq_, q);
    if (with_qd) add_product(Pqd_, qd);
  }
  // T_ += A x's tangents
  void add_product(const Eigen::MatrixXd& A, TConstVecRef x) {
    const S* xp = x.data();
    for (int l = 0; l < n_; ++l) {
      const double* dx = xp[l].derivs();
      for (int i = 0; i < n_; ++i) {
        const double a = A(i, l);
        if (a == 0.0) continue;
        double* t = T_.col(i).data();
        for (int k = 0; k < N; ++k) t[k] += a * dx[k];
      }
    }
  }
  void store(TVecRef out) {
    S* o = out.data();
    for (int j = 0; j < n_; ++j) {
      o[j] = S(v_[j]);
      std::copy_n(T_.col(j).data(), N, o[j].derivs());
    }
  }

  DynamicsDerivatives d_;
  int n_;
  Eigen::VectorXd q_, qd_, qdd_, v_, zero_;
  Eigen::MatrixXd Pq_, Pqd_;
  Eigen::Matrix<double, N, Eigen::Dynamic> T_, X_;  // column j: joint j's N tangents
  Eigen::MatrixXd Hc_;
  Cholesky<double, Eigen::Dynamic> chol_;
};

}  // namespace pumasim
