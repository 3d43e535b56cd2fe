// Shared part of the back-ends built on the RNEA: inverse dynamics, bias,
// Coriolis and gravity are one RNEA pass each; the back-ends differ in how they build H and
// solve for qdd. Not a virtual base: the derived algorithms are used through
// templates, and the registry wraps each one once (backend.hpp).
#pragma once

#include "models/dynamics/chain.hpp"
#include "models/dynamics/rnea.hpp"

namespace pumasim {

template <class S, int N>
class RneaBased {
 public:
  explicit RneaBased(const Chain<S, N>& chain)
      : c_(chain), rot_(chain.n), rnea_(chain.n), zero_(make_vec<S, N>(chain.n)) {}

  int dof() const { return c_.n; }

  // tau = H qdd + C qd + g (with rotor inertia Z^2 Im qdd when the chain has it)
  template <class Q, class Qd, class Qdd, class Tau>
  void inverse_dynamics(const Q& q, const Qd& qd, const Qdd& qdd, Tau&& tau) {
    rot_.compute(c_, q);
    rnea_.run(c_, rot_, qd, qdd, true, tau);
  }

  // h = C(q, qd) qd + g(q)
  template <class Q, class Qd, class V>
  void bias(const Q& q, const Qd& qd, V&& h) {
    rot_.compute(c_, q);
    rnea_.run(c_, rot_, qd, zero_, true, h);
  }

  // c = C(q, qd) qd: one RNEA pass without gravity or acceleration
  template <class Q, class Qd, class V>
  void coriolis(const Q& q, const Qd& qd, V&& c) {
    rot_.compute(c_, q);
    rnea_.run(c_, rot_, qd, zero_, false, c);
  }

  template <class Q, class V>
  void gravity(const Q& q, V&& g) {
    rot_.compute(c_, q);
    rnea_.run(c_, rot_, zero_, zero_, true, g);
  }

 protected:
  const Chain<S, N>& c_;
  JointTransforms<S, N> rot_;
  RneaPass<S, N> rnea_;
  VecN<S, N> zero_;
};

}  // namespace pumasim
