// Articulated body algorithm (Featherstone 1983; Featherstone 2008, table 7.1)
// for forward dynamics in O(n), with the rotor inertia Z^2 Im as armature
// (added to D_j = S^T IA_j S). Spatial vectors are [angular; linear] in joint
// frame j, about its origin; the motion subspace is S = [z; 0] for a revolute
// joint and S = [0; z] for a prismatic one (Featherstone 2008, table 4.1).
//
// Articulated inertias are kept as three 3x3 blocks IA = [[A, B], [B^T, C]]
// (A and C symmetric), and the transform X^T IA X to the parent is done block
// by block. The ABA does not produce H: this back-end's mass_matrix is the
// CRBA's (crba.hpp); its inverse dynamics, bias and gravity are the RNEA's.
#pragma once

#include "models/dynamics/chain.hpp"
#include "models/dynamics/crba.hpp"
#include "models/dynamics/rnea_based.hpp"

namespace pumasim {

template <class S, int N>
class Aba : public RneaBased<S, N> {
  using Base = RneaBased<S, N>;
  using Base::c_;
  using Base::rot_;

 public:
  static constexpr const char* kName = "aba";
  // Forward dynamics in O(n) without H: no Cholesky to count (backend_impl.hpp).
  static constexpr bool kFactorsMassMatrix = false;

  explicit Aba(const Chain<S, N>& chain)
      : Base(chain),
        crba_(chain.n),
        A_(make_per_joint<Mat3<S>, N>(chain.n)),
        B_(make_per_joint<Mat3<S>, N>(chain.n)),
        C_(make_per_joint<Mat3<S>, N>(chain.n)),
        pn_(make_per_joint<Vec3<S>, N>(chain.n)),
        pf_(make_per_joint<Vec3<S>, N>(chain.n)),
        cw_(make_per_joint<Vec3<S>, N>(chain.n)),
        cv_(make_per_joint<Vec3<S>, N>(chain.n)),
        Ut_(make_per_joint<Vec3<S>, N>(chain.n)),
        Ub_(make_per_joint<Vec3<S>, N>(chain.n)),
        invD_(make_per_joint<S, N>(chain.n)),
        u_(make_per_joint<S, N>(chain.n)) {}

  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    rot_.compute(c_, q);
    crba_.run(c_, rot_, H);
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    rot_.compute(c_, q);
    if (c_.any_prismatic) {
      velocities<true>(qd);
      articulated_inertias<true>(tau);
      accelerations<true>(qdd);
    } else {
      velocities<false>(qd);
      articulated_inertias<false>(tau);
      accelerations<false>(qdd);
    }
  }

 private:
  template <bool kMixed, class Qd>
  void velocities(const Qd& qd) {
    const int n = c_.n;
    // Pass 1 (outwards): velocities, velocity-product accelerations c_j, and
    // the rigid-body inertias and bias forces as the start of IA_j and pA_j.
    Vec3<S> w_p = Vec3<S>::Zero(), v_p = Vec3<S>::Zero();
    for (int j = 0; j < n; ++j) {
      const Mat3<S>& R = rot_.R[j];
      const S qdj = S(qd[j]);
      Vec3<S> w = R.transpose() * w_p;
      Vec3<S> v = R.transpose() * (v_p + w_p.cross(rot_.template origin<kMixed>(c_, j)));
      if (slides<kMixed>(c_, j)) {
        // c = v x (S qd) = [0; w x z qd]
        v.z() += qdj;
        cw_[j].setZero();
        cv_[j] = Vec3<S>(w.y() * qdj, -w.x() * qdj, S(0));
      } else {
        w.z() += qdj;
        // c = [w x z qd; v x z qd]
        cw_[j] = Vec3<S>(w.y() * qdj, -w.x() * qdj, S(0));
        cv_[j] = Vec3<S>(v.y() * qdj, -v.x() * qdj, S(0));
      }
      const Vec3<S>& h = c_.h[j];
      A_[j] = c_.Io[j];
      B_[j] = skew(h);
      C_[j] = Mat3<S>::Identity() * c_.mass[j];
      // I v = [Io w + h x v; m v - h x w];  pA = [w x In + v x If; w x If]
      const Vec3<S> In = c_.Io[j] * w + h.cross(v);
      const Vec3<S> If = c_.mass[j] * v - h.cross(w);
      pn_[j] = w.cross(In) + v.cross(If);
      pf_[j] = w.cross(If);
      w_p = w;
      v_p = v;
    }
  }

  template <bool kMixed, class Tau>
  void articulated_inertias(const Tau& tau) {
    const int n = c_.n;
    // Pass 2 (inwards): articulated inertias and bias forces.
    for (int j = n - 1; j >= 0; --j) {
      // U = IA S = [Ut; Ub]: [A z; B^T z] about z, [B z; C z] along z.
      const bool slide = slides<kMixed>(c_, j);
      const Vec3<S> Ut = slide ? Vec3<S>(B_[j].col(2)) : Vec3<S>(A_[j].col(2));
      const Vec3<S> Ub = slide ? Vec3<S>(C_[j].col(2)) : Vec3<S>(B_[j].row(2).transpose());
      const S invD = S(1) / ((slide ? Ub.z() : Ut.z()) + c_.armature[j]);
      const S u = S(tau[j]) - (slide ? pf_[j].z() : pn_[j].z());
      Ut_[j] = Ut;
      Ub_[j] = Ub;
      invD_[j] = invD;
      u_[j] = u;
      if (j == 0) break;
      // Ia = IA - U U^T / D ; pa = pA + Ia c + U u / D
      const Vec3<S> Ut_D = Ut * invD, Ub_D = Ub * invD;
      Mat3<S> A = A_[j] - Ut_D * Ut.transpose();
      Mat3<S> B = B_[j] - Ut_D * Ub.transpose();
      Mat3<S> C = C_[j] - Ub_D * Ub.transpose();
      const Vec3<S> pa_n = pn_[j] + A * cw_[j] + B * cv_[j] + Ut_D * u;
      const Vec3<S> pa_f = pf_[j] + B.transpose() * cw_[j] + C * cv_[j] + Ub_D * u;
      // To the parent: X^T Ia X with X = [[R^T, 0], [-R^T P, R^T]], P = skew(p).
      const Mat3<S>& R = rot_.R[j];
      const Mat3<S> P = skew(rot_.template origin<kMixed>(c_, j));
      const Mat3<S> At = R * A * R.transpose();
      const Mat3<S> Bt = R * B * R.transpose();
      const Mat3<S> Ct = R * C * R.transpose();
      const Mat3<S> PCt = P * Ct;
      const Mat3<S> M = P * Bt.transpose();
      A_[j - 1] += At + M + M.transpose() - PCt * P;
      B_[j - 1] += Bt + PCt;
      C_[j - 1] += Ct;
      const Vec3<S> f_par = R * pa_f;
      pn_[j - 1] += R * pa_n + rot_.template origin<kMixed>(c_, j).cross(f_par);
      pf_[j - 1] += f_par;
    }
  }

  template <bool kMixed, class Qdd>
  void accelerations(Qdd& qdd) {
    const int n = c_.n;
    // Pass 3 (outwards): accelerations, starting from the base's -g.
    Vec3<S> aw_p = Vec3<S>::Zero();
    Vec3<S> av_p = -c_.gravity;
    for (int j = 0; j < n; ++j) {
      const Mat3<S>& R = rot_.R[j];
      Vec3<S> aw = R.transpose() * aw_p + cw_[j];
      Vec3<S> av = R.transpose() * (av_p + aw_p.cross(rot_.template origin<kMixed>(c_, j))) + cv_[j];
      const S qddj = (u_[j] - Ut_[j].dot(aw) - Ub_[j].dot(av)) * invD_[j];
      qdd[j] = qddj;
      (slides<kMixed>(c_, j) ? av : aw).z() += qddj;
      aw_p = aw;
      av_p = av;
    }
  }

  CompositeInertia<S, N> crba_;
  PerJoint<Mat3<S>, N> A_, B_, C_;  // articulated inertia blocks
  PerJoint<Vec3<S>, N> pn_, pf_;    // articulated bias force [moment; force]
  PerJoint<Vec3<S>, N> cw_, cv_;    // velocity-product acceleration c_j
  PerJoint<Vec3<S>, N> Ut_, Ub_;    // U_j = IA_j S_j
  PerJoint<S, N> invD_, u_;
};

}  // namespace pumasim
