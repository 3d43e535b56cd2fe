// The paper's method (Sokolov & Toth 1999, section 5): build g, h and H by
// "probing" the Newton-Euler inverse dynamics, then solve eq. (10).
//
//   A.  g = RNEA(q, 0, 0)                       (the paper's C(q))
//   B.  h = RNEA(q, qd, 0)                      (h(q, qd) qd + C(q))
//   C.  H e_j = RNEA(q, qd, e_j) - h,  j = 1..n
//   qdd = (H + Z^2 Im)^{-1} (tau - h)            (Cholesky)
//
// That is n + 2 complete inverse-dynamics calls per forward-dynamics call, each
// with its own kinematics, exactly as described; it is Walker & Orin's (1982)
// method 1. Step A does not change qdd; it is kept because the paper does it.
// `RneaProbingShared` is the economical variant: the joint rotations are
// computed once, and the columns of H are probed with qd = 0 and no gravity,
// so that no subtraction is needed (n + 1 passes, one trigonometric pass).
#pragma once

#include "models/dynamics/chain.hpp"
#include "models/dynamics/rnea_based.hpp"

namespace pumasim {

template <class S, int N>
class RneaProbing : public RneaBased<S, N> {
  using Base = RneaBased<S, N>;
  using Base::c_;
  using Base::zero_;

 public:
  static constexpr const char* kName = "rnea-probing";

  explicit RneaProbing(const Chain<S, N>& chain)
      : Base(chain),
        unit_(make_vec<S, N>(chain.n)),
        g_(make_vec<S, N>(chain.n)),
        h_(make_vec<S, N>(chain.n)),
        col_(make_vec<S, N>(chain.n)),
        H_(make_mat<S, N>(chain.n)),
        chol_(chain.n) {}

  // H from n + 1 inverse-dynamics calls: g, then RNEA(q, 0, e_j) - g.
  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    this->inverse_dynamics(q, zero_, zero_, g_);
    probe_columns(q, zero_, g_, H);
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    this->inverse_dynamics(q, zero_, zero_, g_);  // A
    this->inverse_dynamics(q, qd, zero_, h_);     // B
    probe_columns(q, qd, h_, H_);                 // C
    chol_.factor(H_);
    for (int j = 0; j < c_.n; ++j) qdd[j] = S(tau[j]) - h_[j];
    chol_.solve_in_place(qdd);
  }

 private:
  template <class Q, class Qd, class M>
  void probe_columns(const Q& q, const Qd& qd, const VecN<S, N>& offset, M&& H) {
    for (int j = 0; j < c_.n; ++j) {
      unit_[j] = S(1);
      this->inverse_dynamics(q, qd, unit_, col_);
      unit_[j] = S(0);
      for (int i = 0; i < c_.n; ++i) H(i, j) = col_[i] - offset[i];
    }
  }

  VecN<S, N> unit_, g_, h_, col_;
  MatN<S, N> H_;
  Cholesky<S, N> chol_;
};

template <class S, int N>
class RneaProbingShared : public RneaBased<S, N> {
  using Base = RneaBased<S, N>;
  using Base::c_;
  using Base::rnea_;
  using Base::rot_;
  using Base::zero_;

 public:
  static constexpr const char* kName = "rnea-probing-shared";

  explicit RneaProbingShared(const Chain<S, N>& chain)
      : Base(chain),
        unit_(make_vec<S, N>(chain.n)),
        col_(make_vec<S, N>(chain.n)),
        H_(make_mat<S, N>(chain.n)),
        chol_(chain.n) {}

  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    rot_.compute(c_, q);
    probe_columns(H);
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    rot_.compute(c_, q);
    rnea_.run(c_, rot_, qd, zero_, true, col_);  // h
    for (int j = 0; j < c_.n; ++j) qdd[j] = S(tau[j]) - col_[j];
    probe_columns(H_);
    chol_.factor(H_);
    chol_.solve_in_place(qdd);
  }

 private:
  // Column j of H (with Z^2 Im) = RNEA(q, 0, e_j) without gravity.
  template <class M>
  void probe_columns(M&& H) {
    for (int j = 0; j < c_.n; ++j) {
      unit_[j] = S(1);
      rnea_.run(c_, rot_, zero_, unit_, false, col_);
      unit_[j] = S(0);
      for (int i = 0; i < c_.n; ++i) H(i, j) = col_[i];
    }
  }

  VecN<S, N> unit_, col_;
  MatN<S, N> H_;
  Cholesky<S, N> chol_;
};

}  // namespace pumasim
