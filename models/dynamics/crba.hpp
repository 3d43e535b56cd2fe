// Composite rigid body algorithm (Walker & Orin 1982, method 3; Featherstone
// 2008, sec. 6.2) for H, one RNEA pass for the bias h, then Cholesky.
//
// Composite bodies are kept in the compact form (mass m, first moment hc about
// the frame origin, rotational inertia Ic about the origin) in joint frame j,
// and H's column j is the force that a unit acceleration of joint j needs,
// carried inwards joint by joint; H(i, j) is its moment about z_i (revolute
// joint i) or its force along z_i (prismatic joint i). The kinematics (joint
// transforms) are shared by the bias pass and the CRBA.
#pragma once

#include "models/dynamics/chain.hpp"
#include "models/dynamics/rnea_based.hpp"

namespace pumasim {

template <class S, int N>
class CompositeInertia {
 public:
  explicit CompositeInertia(int n)
      : m_(make_per_joint<S, N>(n)),
        hc_(make_per_joint<Vec3<S>, N>(n)),
        Ic_(make_per_joint<Mat3<S>, N>(n)) {}

  // H (with Z^2 Im on the diagonal) for the joint transforms already computed from q.
  template <class M>
  void run(const Chain<S, N>& c, const JointTransforms<S, N>& rot, M&& H) {
    if (c.any_prismatic) {
      run_kinds<true>(c, rot, H);
    } else {
      run_kinds<false>(c, rot, H);
    }
  }
  // CrbaShell's kernel interface: the body-frame recursion fills both triangles.
  template <class M>
  void full(const Chain<S, N>& c, const JointTransforms<S, N>& rot, M&& H) {
    run(c, rot, H);
  }
  template <class M>
  void lower(const Chain<S, N>& c, const JointTransforms<S, N>& rot, M&& H) {
    run(c, rot, H);
  }

 private:
  template <bool kMixed, class M>
  void run_kinds(const Chain<S, N>& c, const JointTransforms<S, N>& rot, M& H) {
    const int n = c.n;
    for (int j = 0; j < n; ++j) {
      m_[j] = c.mass[j];
      hc_[j] = c.h[j];
      Ic_[j] = c.Io[j];
    }
    for (int j = n - 1; j >= 0; --j) {
      // Force and moment (about origin j) for a unit acceleration of joint j:
      // about z_j, f = z x hc, n = Ic z; along z_j, f = m z, n = hc x z.
      Vec3<S> f, m;
      if (slides<kMixed>(c, j)) {
        f = Vec3<S>(S(0), S(0), m_[j]);
        m = Vec3<S>(hc_[j].y(), -hc_[j].x(), S(0));
        H(j, j) = f.z() + c.armature[j];
      } else {
        f = Vec3<S>(-hc_[j].y(), hc_[j].x(), S(0));
        m = Ic_[j].col(2);
        H(j, j) = m.z() + c.armature[j];
      }
      for (int i = j; i > 0; --i) {
        const Mat3<S>& R = rot.R[i];
        const Vec3<S> fp = R * f;
        m = R * m + rot.template origin<kMixed>(c, i).cross(fp);
        f = fp;
        const S Hij = slides<kMixed>(c, i - 1) ? f.z() : m.z();
        H(i - 1, j) = Hij;
        H(j, i - 1) = Hij;
      }
      if (j > 0) {
        // Add composite j to its parent, moving it into joint frame j-1:
        // body points r' = R r + p.
        const Mat3<S>& R = rot.R[j];
        const Vec3<S>& p = rot.template origin<kMixed>(c, j);
        const S mj = m_[j];
        const Vec3<S> hr = R * hc_[j];
        const Vec3<S> mp = mj * p;
        m_[j - 1] += mj;
        hc_[j - 1] += hr + mp;
        Mat3<S> I = R * Ic_[j] * R.transpose() - hr * p.transpose() - p * hr.transpose() -
                    mp * p.transpose();
        const S diag = S(2) * p.dot(hr) + mp.dot(p);
        I(0, 0) += diag;
        I(1, 1) += diag;
        I(2, 2) += diag;
        Ic_[j - 1] += I;
      }
    }
  }

  PerJoint<S, N> m_;
  PerJoint<Vec3<S>, N> hc_;
  PerJoint<Mat3<S>, N> Ic_;
};

// The shell of the CRBA back-ends: H from a composite-inertia kernel (`full`:
// every entry; `lower`: at least the lower triangle, all the Cholesky
// factorisation reads), h from one RNEA pass on the same joint transforms,
// qdd by Cholesky.
template <class S, int N, class Kernel>
class CrbaShell : public RneaBased<S, N> {
  using Base = RneaBased<S, N>;
  using Base::c_;
  using Base::rnea_;
  using Base::rot_;
  using Base::zero_;

 public:
  explicit CrbaShell(const Chain<S, N>& chain)
      : Base(chain), kernel_(chain.n), H_(make_mat<S, N>(chain.n)), chol_(chain.n) {}

  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    rot_.compute(c_, q);
    kernel_.full(c_, rot_, H);
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    rot_.compute(c_, q);
    rnea_.run(c_, rot_, qd, zero_, true, qdd);  // qdd <- h
    for (int j = 0; j < c_.n; ++j) qdd[j] = S(tau[j]) - qdd[j];
    kernel_.lower(c_, rot_, H_);
    chol_.factor(H_);
    chol_.solve_in_place(qdd);
  }

 private:
  Kernel kernel_;
  MatN<S, N> H_;
  Cholesky<S, N> chol_;
};

template <class S, int N>
class Crba : public CrbaShell<S, N, CompositeInertia<S, N>> {
 public:
  static constexpr const char* kName = "crba";
  using CrbaShell<S, N, CompositeInertia<S, N>>::CrbaShell;
};

}  // namespace pumasim
