// The textbook Lagrange-Euler formulation with 4x4 homogeneous matrices
// (Uicker 1965; Fu, Gonzalez & Lee, "Robotics: Control, Sensing, Vision and
// Intelligence", 1987, sec. 3.2 -- the paper's reference [10]). This is the
// "normal use of Lagrange" that the paper says its probing beats; it costs
// O(n^4) and is implemented as the book states it, without the recursive
// reformulations that later made Lagrange O(n).
//
//   U_ji  = d(0T_j)/dq_i        = 0T_i Q iT_j              (i <= j)
//   U_jkm = d(U_jk)/dq_m        = 0T_k Q kT_m Q mT_j       (k <= m <= j, symmetric in k, m)
//   D_ik  = sum_{j >= max(i,k)} Tr(U_jk J_j U_ji^T)        (+ Z^2 Im on the diagonal)
//   h_i   = sum_k sum_m sum_{j >= max(i,k,m)} Tr(U_jkm J_j U_ji^T) qd_k qd_m
//   c_i   = sum_{j >= i} -m_j g^T U_ji rbar_j
//   tau   = D qdd + h + c
//
// Q_i is the derivative operator of joint i (FGL eq. 3.2-7): about z for a
// revolute joint (Q(0,1) = -1, Q(1,0) = 1), along z for a prismatic one
// (Q(2,3) = 1; Q Q = 0, so a slide has no second derivative of its own); J_j
// the link's 4x4 pseudo-inertia in its joint frame, rbar_j its homogeneous
// centre of mass.
#pragma once

#include "models/dynamics/chain.hpp"

namespace pumasim {

template <class S> using Mat4 = Eigen::Matrix<S, 4, 4>;
template <class S> using Vec4 = Eigen::Matrix<S, 4, 1>;

template <class S, int N>
class LagrangeEuler {
 public:
  static constexpr const char* kName = "lagrange-euler";

  explicit LagrangeEuler(const Chain<S, N>& chain)
      : c_(chain),
        n_(chain.n),
        J_(static_cast<std::size_t>(n_)),
        T0_(static_cast<std::size_t>(n_)),
        Tij_(static_cast<std::size_t>(n_ * n_)),
        U_(static_cast<std::size_t>(n_ * n_)),
        W_(static_cast<std::size_t>(n_)),
        D_(make_mat<S, N>(n_)),
        hv_(make_vec<S, N>(n_)),
        cv_(make_vec<S, N>(n_)),
        chol_(n_) {
    Qr_.setZero();
    Qr_(0, 1) = S(-1);
    Qr_(1, 0) = S(1);
    Qp_.setZero();
    Qp_(2, 3) = S(1);
    g_ << c_.gravity.x(), c_.gravity.y(), c_.gravity.z(), S(0);
    for (int j = 0; j < n_; ++j) {
      // Pseudo-inertia: integral of rbar rbar^T dm = [[tr(Io)/2 1 - Io, h], [h^T, m]].
      Mat4<S>& J = J_[j];
      const Mat3<S>& Io = c_.Io[j];
      const S half_tr = S(0.5) * (Io(0, 0) + Io(1, 1) + Io(2, 2));
      J.template topLeftCorner<3, 3>() = -Io;
      for (int k = 0; k < 3; ++k) J(k, k) += half_tr;
      J.template topRightCorner<3, 1>() = c_.h[j];
      J.template bottomLeftCorner<1, 3>() = c_.h[j].transpose();
      J(3, 3) = c_.mass[j];
    }
  }

  int dof() const { return n_; }

  template <class Q, class Qd, class Qdd, class Tau>
  void inverse_dynamics(const Q& q, const Qd& qd, const Qdd& qdd, Tau&& tau) {
    kinematics(q);
    inertia();
    velocity_terms(qd);
    gravity_terms();
    for (int i = 0; i < n_; ++i) {
      S t = hv_[i] + cv_[i];
      for (int k = 0; k < n_; ++k) t += D_(i, k) * S(qdd[k]);
      tau[i] = t;
    }
  }

  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    kinematics(q);
    inertia();
    for (int i = 0; i < n_; ++i)
      for (int k = 0; k < n_; ++k) H(i, k) = D_(i, k);
  }

  template <class Q, class Qd, class V>
  void bias(const Q& q, const Qd& qd, V&& h) {
    kinematics(q);
    velocity_terms(qd);
    gravity_terms();
    for (int i = 0; i < n_; ++i) h[i] = hv_[i] + cv_[i];
  }

  template <class Q, class Qd, class V>
  void coriolis(const Q& q, const Qd& qd, V&& c) {
    kinematics(q);
    velocity_terms(qd);
    for (int i = 0; i < n_; ++i) c[i] = hv_[i];
  }

  template <class Q, class V>
  void gravity(const Q& q, V&& g) {
    kinematics(q);
    gravity_terms();
    for (int i = 0; i < n_; ++i) g[i] = cv_[i];
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    kinematics(q);
    inertia();
    velocity_terms(qd);
    gravity_terms();
    for (int i = 0; i < n_; ++i) qdd[i] = S(tau[i]) - hv_[i] - cv_[i];
    chol_.factor(D_);
    chol_.solve_in_place(qdd);
  }

 private:
  Mat4<S>& T(int i, int j) { return Tij_[static_cast<std::size_t>(i * n_ + j)]; }  // iT_j
  Mat4<S>& U(int j, int i) { return U_[static_cast<std::size_t>(j * n_ + i)]; }    // U_ji
  const Mat4<S>& Qop(int i) const { return is_prismatic(c_, i) ? Qp_ : Qr_; }

  // (j-1)T_j = [E_j, p_j] Rz(q_j) (revolute) or [E_j, p_j] Tz(q_j) (prismatic).
  template <class Qv>
  Mat4<S> joint_transform(int j, const Qv& q) const {
    using std::cos;
    using std::sin;
    Mat4<S> F = Mat4<S>::Identity();
    F.template topLeftCorner<3, 3>() = c_.E[j];
    F.template topRightCorner<3, 1>() = c_.p[j];
    if (is_prismatic(c_, j)) {
      F.template topRightCorner<3, 1>() += S(q[j]) * c_.E[j].col(2);
      return F;
    }
    const S cq = cos(S(q[j])), sq = sin(S(q[j]));
    Mat4<S> Rz = Mat4<S>::Identity();
    Rz(0, 0) = cq;
    Rz(0, 1) = -sq;
    Rz(1, 0) = sq;
    Rz(1, 1) = cq;
    return F * Rz;
  }

  // 0T_j, iT_j and U_ji from the joint transforms (j-1)T_j.
  template <class Qv>
  void kinematics(const Qv& q) {
    for (int j = 0; j < n_; ++j) {
      const Mat4<S> A = joint_transform(j, q);
      T(j, j).setIdentity();
      for (int i = 0; i < j; ++i) T(i, j) = T(i, j - 1) * A;
      T0_[j] = (j == 0) ? A : Mat4<S>(T0_[j - 1] * A);
    }
    for (int j = 0; j < n_; ++j)
      for (int i = 0; i <= j; ++i) U(j, i) = T0_[i] * Qop(i) * T(i, j);
  }

  void inertia() {
    for (int i = 0; i < n_; ++i) {
      for (int k = 0; k <= i; ++k) {
        S d = S(0);
        for (int j = i; j < n_; ++j) d += trace_of_product(U(j, k) * J_[j], U(j, i));
        D_(i, k) = d;
        D_(k, i) = d;
      }
      D_(i, i) += c_.armature[i];
    }
  }

  template <class Qd>
  void velocity_terms(const Qd& qd) {
    for (int i = 0; i < n_; ++i) hv_[i] = S(0);
    for (int j = 0; j < n_; ++j) {
      // Tr(U_jkm J_j U_ji^T) = sum of entries of U_jkm .* (U_ji J_j), J_j symmetric.
      for (int i = 0; i <= j; ++i) W_[i] = U(j, i) * J_[j];
      for (int k = 0; k <= j; ++k) {
        for (int m = 0; m <= j; ++m) {
          const int lo = k < m ? k : m, hi = k < m ? m : k;
          const Mat4<S> Ujkm = T0_[lo] * Qop(lo) * T(lo, hi) * Qop(hi) * T(hi, j);
          const S qq = S(qd[k]) * S(qd[m]);
          for (int i = 0; i <= j; ++i) hv_[i] += trace_of_product(Ujkm, W_[i]) * qq;
        }
      }
    }
  }

  void gravity_terms() {
    for (int i = 0; i < n_; ++i) {
      S ci = S(0);
      for (int j = i; j < n_; ++j) {
        // m_j rbar_j is the pseudo-inertia's last column.
        ci -= g_.dot(U(j, i) * J_[j].col(3));
      }
      cv_[i] = ci;
    }
  }

  // Tr(A B^T) = sum over all entries of A .* B
  static S trace_of_product(const Mat4<S>& A, const Mat4<S>& B) {
    S t = S(0);
    for (int r = 0; r < 4; ++r)
      for (int col = 0; col < 4; ++col) t += A(r, col) * B(r, col);
    return t;
  }

  const Chain<S, N>& c_;
  int n_;
  Mat4<S> Qr_, Qp_;  // derivative operators, revolute and prismatic
  Vec4<S> g_;
  std::vector<Mat4<S>> J_, T0_, Tij_, U_, W_;
  MatN<S, N> D_;
  VecN<S, N> hv_, cv_;
  Cholesky<S, N> chol_;
};

}  // namespace pumasim
