// Composite rigid body algorithm in the world frame (Featherstone 2008,
// sec. 6.2, with every spatial quantity expressed in base coordinates about
// the base origin, as Pinocchio's crba does it: Carpentier et al. 2019, "The
// Pinocchio C++ library", SII 2019), one RNEA pass for h, then Cholesky.
//
// Each link's inertia is moved once into the base frame (compact form: mass
// m, first moment h about the base origin, rotational inertia I about it), so
// that composite inertias are plain sums, Ic_j = I_j + Ic_{j+1}, with no
// transform per ancestor. With the motion subspace S_i = [z_i; o_i x z_i]
// (revolute, about the base origin; [0; z_i] prismatic) and the force
// F_j = Ic_j S_j, the mass matrix is H_ij = S_i^T F_j for i <= j: 6
// multiplies a pair, a row of dot products with contiguous storage, against
// the body-frame CRBA's (crba.hpp) force carried through every ancestor
// (two 3x3 rotations and a cross product a pair).
#pragma once

#include <Eigen/Core>

#include "models/dynamics/chain.hpp"
#include "models/dynamics/crba.hpp"
#include "models/dynamics/rnea_based.hpp"

namespace pumasim {

// Link j's inertia about the base origin in base axes (first moment h,
// rotational inertia I; its mass is c.mass[j]), from its joint frame's
// rotation Rw and origin o in the base. Body points r' = Rw r + o (the
// parallel-axis move of crba.hpp's composites): I = Rw Io Rw^T - (k o^T + o k^T)
// + 2 (o.k) 1 with k = Rw h_j + m o / 2; symmetric, so only its upper
// triangle is formed.
template <class S, int N>
void world_inertia(const Chain<S, N>& c, int j, const Mat3<S>& Rw, const Vec3<S>& o, Vec3<S>& h, Mat3<S>& I) {
  const Vec3<S> hr = Rw * c.h[j];
  const Vec3<S> mo = c.mass[j] * o;
  const Vec3<S> k = hr + S(0.5) * mo;
  const Mat3<S> A = Rw * c.Io[j];
  const S diag = S(2) * o.dot(k);
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a <= b; ++a) {
      I(a, b) = A.row(a).dot(Rw.row(b)) - (k[a] * o[b] + o[a] * k[b]);
      I(b, a) = I(a, b);
    }
  }
  I(0, 0) += diag;
  I(1, 1) += diag;
  I(2, 2) += diag;
  h = hr + mo;
}

// Frame j in the base (rotation Rw, origin o), from frame j-1's and the joint
// transforms already computed from q (for j = 0, Rw and o are ignored).
template <bool kMixed, class S, int N>
void world_frame(const Chain<S, N>& c, const JointTransforms<S, N>& rot, int j, Mat3<S>& Rw, Vec3<S>& o) {
  if (j == 0) {
    Rw = rot.R[0];
    o = rot.template origin<kMixed>(c, 0);
    return;
  }
  o += Rw * rot.template origin<kMixed>(c, j);
  Rw = (Rw * rot.R[j]).eval();
}

template <class S, int N>
class WorldCompositeInertia {
  using Rows6 = Eigen::Matrix<S, N, 6>;  // one spatial vector [angular; linear] per row

 public:
  explicit WorldCompositeInertia(int n)
      : m_(make_per_joint<S, N>(n)),
        h_(make_per_joint<Vec3<S>, N>(n)),
        I_(make_per_joint<Mat3<S>, N>(n)),
        St_(Rows6::Zero(n, 6)),
        Ft_(Rows6::Zero(n, 6)) {}

  // H's lower triangle (with Z^2 Im on the diagonal) for the joint transforms
  // already computed from q; the strictly upper triangle is left as it was.
  template <class M>
  void lower(const Chain<S, N>& c, const JointTransforms<S, N>& rot, M& H) {
    if (c.any_prismatic) {
      bodies<true>(c, rot);
      composites<true>(c);
    } else {
      bodies<false>(c, rot);
      composites<false>(c);
    }
    const int n = c.n;
    for (int i = 0; i < n; ++i) {
      // H_ji = F_j^T S_i for j >= i: column i below the diagonal, contiguous.
      const int m = n - i;
      H.col(i).segment(i, m).noalias() = Ft_.bottomRows(m).lazyProduct(St_.row(i).transpose());
      H(i, i) += c.armature[i];
    }
  }

  // The whole symmetric H.
  template <class M>
  void full(const Chain<S, N>& c, const JointTransforms<S, N>& rot, M& H) {
    lower(c, rot, H);
    for (int j = 1; j < c.n; ++j) {
      for (int i = 0; i < j; ++i) H(i, j) = H(j, i);
    }
  }

 private:
  // Outwards: each joint's frame in the base (rotation Rw, origin o), its
  // motion subspace, and its link's inertia about the base origin.
  template <bool kMixed>
  void bodies(const Chain<S, N>& c, const JointTransforms<S, N>& rot) {
    Mat3<S> Rw;
    Vec3<S> o;
    for (int j = 0; j < c.n; ++j) {
      world_frame<kMixed>(c, rot, j, Rw, o);
      const Vec3<S> z = Rw.col(2);
      if (slides<kMixed>(c, j)) {
        St_.row(j).template head<3>().setZero();
        St_.row(j).template tail<3>() = z.transpose();
      } else {
        St_.row(j).template head<3>() = z.transpose();
        St_.row(j).template tail<3>() = o.cross(z).transpose();
      }
      m_[j] = c.mass[j];
      world_inertia(c, j, Rw, o, h_[j], I_[j]);
    }
  }

  // Inwards: composite inertias (sums) and F_j = Ic_j S_j, where a spatial
  // inertia acts as Ic [w; v] = [I w + h x v; m v - h x w].
  template <bool kMixed>
  void composites(const Chain<S, N>& c) {
    for (int j = c.n - 1; j >= 0; --j) {
      if (j + 1 < c.n) {
        m_[j] += m_[j + 1];
        h_[j] += h_[j + 1];
        I_[j] += I_[j + 1];
      }
      const Vec3<S> v = St_.row(j).template tail<3>().transpose();
      if (slides<kMixed>(c, j)) {
        Ft_.row(j).template head<3>() = h_[j].cross(v).transpose();
        Ft_.row(j).template tail<3>() = (m_[j] * v).transpose();
      } else {
        const Vec3<S> w = St_.row(j).template head<3>().transpose();
        Ft_.row(j).template head<3>() = (I_[j] * w + h_[j].cross(v)).transpose();
        Ft_.row(j).template tail<3>() = (m_[j] * v - h_[j].cross(w)).transpose();
      }
    }
  }

  PerJoint<S, N> m_;         // (composite) mass
  PerJoint<Vec3<S>, N> h_;   // (composite) first moment about the base origin, base axes
  PerJoint<Mat3<S>, N> I_;   // (composite) rotational inertia about the base origin, base axes
  Rows6 St_;                 // row j: S_j^T
  Rows6 Ft_;                 // row j: F_j^T
};

template <class S, int N>
class CrbaWorld : public CrbaShell<S, N, WorldCompositeInertia<S, N>> {
 public:
  static constexpr const char* kName = "crba-world";
  using CrbaShell<S, N, WorldCompositeInertia<S, N>>::CrbaShell;
};

}  // namespace pumasim
