// Recursive Newton-Euler algorithm (Luh, Walker & Paul 1980), in joint frames.
//
// Inverse dynamics tau = H(q) qdd + C(q, qd) qd + g(q) + diag(Z^2 Im) qdd in
// O(n). Velocities and accelerations are propagated outwards in each link's
// own frame; forces and moments (about each frame's origin, using the link's
// first moment h = m c and inertia about the origin Io) come back inwards.
// Gravity enters as a base acceleration of -g (the usual trick). The rotor
// inertia enters as Z^2 Im qdd_j only: no gyroscopic rotor terms, as in the
// Robotics Toolbox and in the paper's eq. (10).
//
// Across a prismatic joint (Luh, Walker & Paul 1980, eqs. for a sliding joint;
// Siciliano et al. 2009, sec. 7.5) w and wd do not change, the origin's
// acceleration gains the Coriolis term 2 w x (qd z) and qdd z, and the joint
// force is f.z instead of the moment n.z.
#pragma once

#include "models/dynamics/chain.hpp"

namespace pumasim {

template <class S, int N>
class RneaPass {
 public:
  explicit RneaPass(int n)
      : f_(make_per_joint<Vec3<S>, N>(n)),
        m_(make_per_joint<Vec3<S>, N>(n)) {}

  // tau = ID(q, qd, qdd) for the joint transforms already computed from q.
  // With `with_gravity` false the base does not accelerate (H qdd + C qd only).
  template <class Qd, class Qdd, class Tau>
  void run(const Chain<S, N>& c, const JointTransforms<S, N>& rot, const Qd& qd, const Qdd& qdd,
           bool with_gravity, Tau&& tau) {
    if (c.any_prismatic) {
      run_kinds<true>(c, rot, qd, qdd, with_gravity, tau);
    } else {
      run_kinds<false>(c, rot, qd, qdd, with_gravity, tau);
    }
  }

 private:
  template <bool kMixed, class Qd, class Qdd, class Tau>
  void run_kinds(const Chain<S, N>& c, const JointTransforms<S, N>& rot, const Qd& qd, const Qdd& qdd,
                 bool with_gravity, Tau& tau) {
    const int n = c.n;
    Vec3<S> w_p = Vec3<S>::Zero(), wd_p = Vec3<S>::Zero();
    Vec3<S> a_p = with_gravity ? Vec3<S>(-c.gravity) : Vec3<S>(Vec3<S>::Zero());
    for (int j = 0; j < n; ++j) {
      const Mat3<S>& R = rot.R[j];
      const Vec3<S>& pj = rot.template origin<kMixed>(c, j);
      const S qdj = S(qd[j]), qddj = S(qdd[j]);
      // Origin acceleration of frame j, from the parent's motion.
      Vec3<S> a = R.transpose() * (a_p + wd_p.cross(pj) + w_p.cross(w_p.cross(pj)));
      const Vec3<S> w_in = R.transpose() * w_p;
      Vec3<S> w = w_in;
      Vec3<S> wd = R.transpose() * wd_p;
      if (slides<kMixed>(c, j)) {
        // 2 w x (qd z) = 2 qd (w.y, -w.x, 0), plus qdd z.
        const S two_qd = S(2) * qdj;
        a.x() += two_qd * w.y();
        a.y() -= two_qd * w.x();
        a.z() += qddj;
      } else {
        w.z() += qdj;
        // w_in x (qd z) = (w_in.y qd, -w_in.x qd, 0)
        wd.x() += w_in.y() * qdj;
        wd.y() -= w_in.x() * qdj;
        wd.z() += qddj;
      }
      // Newton-Euler for link j, moments about the frame origin.
      const Vec3<S>& h = c.h[j];
      f_[j] = c.mass[j] * a + wd.cross(h) + w.cross(w.cross(h));
      m_[j] = c.Io[j] * wd + w.cross(c.Io[j] * w) + h.cross(a);
      w_p = w;
      wd_p = wd;
      a_p = a;
    }
    for (int j = n - 1; j >= 0; --j) {
      tau[j] = (slides<kMixed>(c, j) ? f_[j].z() : m_[j].z()) + c.armature[j] * S(qdd[j]);
      if (j > 0) {
        const Mat3<S>& R = rot.R[j];
        const Vec3<S> f_in_parent = R * f_[j];
        f_[j - 1] += f_in_parent;
        m_[j - 1] += R * m_[j] + rot.template origin<kMixed>(c, j).cross(f_in_parent);
      }
    }
  }

  PerJoint<Vec3<S>, N> f_, m_;  // force and moment (about the origin) through joint j
};

}  // namespace pumasim
