// Analytical first derivatives of inverse dynamics, dID/dq and dID/dqd, in
// double, in O(n) spatial recursions and an O(n^2) assembly of dot products
// (the approach of Carpentier & Mansard 2018, "Analytical Derivatives of Rigid
// Body Dynamics Algorithms", RSS: world-frame quantities, whose change with
// q_k is the action of joint k's axis; the derivation below is this file's own,
// in its notation, and is checked against forward-mode dual numbers and central
// differences by tests/test_jacobian.cpp).
//
// Spatial vectors are 6-vectors (angular; linear) in the world frame at its
// origin (Featherstone 2008, ch. 2): a motion (w; u), a force (n; f), the
// cross products m1 x m2 = (w1 x w2; w1 x u2 + u1 x w2) and
// m x* f = (w x n + u x f; w x f), and (m1 x m2) . f = -m2 . (m1 x* f).
// Joint k's axis S_k = (z_k; o_k x z_k) (revolute) or (0; z_k) (prismatic).
//   v_k = v_p + S_k qd_k,   a_k = a_p + S_k qdd_k + v_k x S_k qd_k   (p = k-1, a_0 = -g)
//   f_k = I_k a_k + v_k x* I_k v_k,   F_k = sum_{l >= k} f_l,   tau_k = S_k . F_k
// A change of q_k moves every body l >= k rigidly about S_k: a world motion
// attached to them changes by S_k x (.), a force by S_k x* (.), an inertia by
// the commutator; v_p, a_p and gravity do not move. With d_k = v_p x S_k,
// e_k = a_p x S_k + v_p x d_k and the linear map of body l
//   B_l x = I_l (x x v_l) + x x* (I_l v_l) + v_l x* (I_l x),
// (sums over l >= k: Ic_k = sum I_l, Bc_k = sum B_l) this gives, for l >= k,
//   df_l/dq_k  = S_k x* f_l + B_l d_k + I_l e_k,
//   df_l/dqd_k = 2 I_l d_k + B_l S_k,
// and, since (S_k x S_i) . F_i + S_i . (S_k x* F_i) = 0,
//   i >= k:  dtau_i/dq_k = (Bc_i^T S_i) . d_k + (Ic_i S_i) . e_k,
//            dtau_i/dqd_k = 2 (Ic_i S_i) . d_k + (Bc_i^T S_i) . S_k,
//   i <  k:  dtau_i/dq_k = S_i . (S_k x* F_k + Bc_k d_k + Ic_k e_k),
//            dtau_i/dqd_k = S_i . (2 Ic_k d_k + Bc_k S_k).
// Written out in 3-vector blocks, with p = I v = (L; P) the body's momentum
// and (w; u) = v, (m, h, I_O) the inertia (mass, first moment and rotational
// inertia about the world origin): B's right half is zero,
//   B = [ -[L x] + [w x] I_O - I_O [w x] - u h^T - h u^T + 2 (h . u) 1    0 ]
//       [ -2 [P x]                                                        0 ],
// so the sums keep a 3x3 block and a vector, and Ic its (m, h, I_O).
// The rotor term Z^2 Im qdd depends on neither. No allocation after
// construction.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/chain.hpp"
#include "models/dynamics/crba_world.hpp"

namespace pumasim {

class RneaDerivatives {
 public:
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;

  explicit RneaDerivatives(const RobotModel& model);

  int dof() const { return chain_.n; }

  // dID/dq and dID/dqd (n x n each) at (q, qd, qdd); without gravity if
  // `gravity` is false. tau (if not null) receives ID(q, qd, qdd) itself.
  void compute(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq, MatRef dqd,
               double* tau = nullptr);

 private:
  void forward(const double* q, const double* qd, const double* qdd, bool gravity);
  void backward();

  // A spatial inertia (m, h, I_O) and the composite sums.
  struct Inertia {
    double m = 0;
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    Eigen::Matrix3d IO = Eigen::Matrix3d::Zero();
    EIGEN_ALWAYS_INLINE Vec6 operator*(const Vec6& x) const {
      Vec6 r;
      r.head<3>().noalias() = IO * x.head<3>();
      r.head<3>() += h.cross(x.tail<3>());
      r.tail<3>() = m * x.tail<3>() - h.cross(x.head<3>());
      return r;
    }
  };

  template <bool kMixed>
  void forward_kinds(const double* qd, const double* qdd, bool gravity);

  Chain<double, Eigen::Dynamic> chain_;
  JointTransforms<double, Eigen::Dynamic> rot_;
  struct Joint {
    Vec6 S, v, a, d, e, f;
    Inertia I;
    Eigen::Matrix3d B;              // B's top-left block
    Eigen::Vector3d P;              // the linear momentum (B's bottom-left block is -2 [P x])
  };
  std::vector<Joint> j_;
  std::vector<double> tau_;
  // The assembly's factors (compute()): rows (Bc_k^T S_k; Ic_k S_k) (the
  // first's linear part is zero) and S_k^T, columns (d_k,ang; e_k),
  // (S_k,ang; 2 d_k), and the columns u_k, w_k for i < k.
  Eigen::Matrix<double, Eigen::Dynamic, 9> left_;
  Eigen::Matrix<double, Eigen::Dynamic, 6> St_;
  Eigen::Matrix<double, 9, Eigen::Dynamic> right_q_, right_qd_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> u_, w_;
  Eigen::MatrixXd upper_;
};

}  // namespace pumasim
