// Exact first derivatives of the rigid-body dynamics, analytically
// (Carpentier & Mansard 2018, "Analytical Derivatives of Rigid Body Dynamics
// Algorithms", RSS, sec. III-IV): forward dynamics qdd = FD(q, qd, tau) is
// defined by ID(q, qd, qdd) = tau, so at qdd = FD(q, qd, tau)
//   dFD/dq = -H^-1 dID/dq,   dFD/dqd = -H^-1 dID/dqd,   dFD/dtau = H^-1.
// The partials dID/dq and dID/dqd come from one RNEA (rnea.hpp) on a
// multi-tangent dual number per kPartialTangents of the 2n directions (one
// pass up to n = 6; DualN<6> for n <= 3, DualN<12> otherwise); the values (h, H, qdd) and the
// Cholesky factor of H from the given back-end in double. Every back-end
// computes the same ID up to rounding, so the partials serve every back-end
// without instantiating it on a new scalar. No allocation after construction.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/chain.hpp"
#include "models/dynamics/dual_n.hpp"
#include "models/dynamics/rnea.hpp"

namespace pumasim {

class DynamicsDerivatives {
 public:
  static constexpr int kPartialTangents = 12;

  // The values come from `values`, a back-end made for `model`.
  DynamicsDerivatives(const RobotModel& model, std::unique_ptr<DynamicsBackend> values);
  ~DynamicsDerivatives();
  DynamicsDerivatives(const DynamicsDerivatives&) = delete;
  DynamicsDerivatives& operator=(const DynamicsDerivatives&) = delete;

  int dof() const { return n_; }
  DynamicsBackend& values() { return *values_; }
  const DynamicsBackend& values() const { return *values_; }

  // dID/dq and dID/dqd (n x n each) at (q, qd, qdd); without gravity if
  // `gravity` is false (then H(q) qdd + C(q, qd) qd).
  void id_partials(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq, MatRef dqd);
  // H(q) with the back-end, and its Cholesky factor for solve().
  void factor_mass_matrix(ConstVecRef q);
  const Eigen::MatrixXd& mass_matrix() const { return H_; }
  // The bias h(q, qd) last computed by forward_dynamics.
  const Eigen::VectorXd& bias() const { return h_; }
  // x <- H^-1 x with the last factor.
  template <class V>
  void solve(V&& x) const {
    chol_.solve_in_place(x);
  }
  // qdd = H^-1 (tau - h) (the back-end's h and H) and dqdd/dq, dqdd/dqd,
  // dqdd/dtau (n x n each).
  void forward_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef tau, VecRef qdd, MatRef dq, MatRef dqd,
                        MatRef dtau);

 private:
  // One RNEA on DualN<K> and its inputs.
  template <int K>
  struct Engine {
    using T = DualN<K>;
    explicit Engine(const RobotModel& model)
        : chain(model), rot(chain.n), rnea(chain.n), q(chain.n), qd(chain.n), qdd(chain.n), tau(chain.n) {}
    void partials(const double* q0, const double* qd0, const double* qdd0, bool gravity, MatRef dq, MatRef dqd);
    Chain<T, Eigen::Dynamic> chain;
    JointTransforms<T, Eigen::Dynamic> rot;
    RneaPass<T, Eigen::Dynamic> rnea;
    Eigen::Matrix<T, Eigen::Dynamic, 1> q, qd, qdd, tau;
  };

  int n_;
  std::unique_ptr<DynamicsBackend> values_;
  std::unique_ptr<Engine<6>> small_;  // n <= 3
  std::unique_ptr<Engine<kPartialTangents>> large_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd h_;
  Cholesky<double, Eigen::Dynamic> chol_;
};

}  // namespace pumasim
