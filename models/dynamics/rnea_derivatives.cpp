#include "models/dynamics/rnea_derivatives.hpp"

#include <cmath>

namespace pumasim {
namespace {

using Vec6 = RneaDerivatives::Vec6;
using Mat6 = RneaDerivatives::Mat6;

// m1 x m2 for motions.
EIGEN_ALWAYS_INLINE Vec6 cross_motion(const Vec6& m1, const Vec6& m2) {
  Vec6 r;
  r.head<3>() = m1.head<3>().cross(m2.head<3>());
  r.tail<3>() = m1.head<3>().cross(m2.tail<3>()) + m1.tail<3>().cross(m2.head<3>());
  return r;
}

// m x* f for a motion m and a force f.
EIGEN_ALWAYS_INLINE Vec6 cross_force(const Vec6& m, const Vec6& f) {
  Vec6 r;
  r.head<3>() = m.head<3>().cross(f.head<3>()) + m.tail<3>().cross(f.tail<3>());
  r.tail<3>() = m.head<3>().cross(f.tail<3>());
  return r;
}

}  // namespace

RneaDerivatives::RneaDerivatives(const RobotModel& model)
    : chain_(model),
      rot_(model.dof()),
      j_(static_cast<std::size_t>(model.dof())),
      tau_(static_cast<std::size_t>(model.dof())),
      left_(model.dof(), 9),
      St_(model.dof(), 6),
      right_q_(9, model.dof()),
      right_qd_(9, model.dof()),
      u_(6, model.dof()),
      w_(6, model.dof()),
      upper_(model.dof(), model.dof()) {}

// World-frame kinematics, the bodies' spatial inertias, their forces and B maps.
void RneaDerivatives::forward(const double* q, const double* qd, const double* qdd, bool gravity) {
  rot_.compute(chain_, q);
  if (chain_.any_prismatic) {
    forward_kinds<true>(qd, qdd, gravity);
  } else {
    forward_kinds<false>(qd, qdd, gravity);
  }
}

template <bool kMixed>
void RneaDerivatives::forward_kinds(const double* qd, const double* qdd, bool gravity) {
  Eigen::Matrix3d R0;
  Eigen::Vector3d o;
  Vec6 v_p = Vec6::Zero(), a_p = Vec6::Zero();
  if (gravity) a_p.tail<3>() = -chain_.gravity;
  for (int k = 0; k < chain_.n; ++k) {
    Joint& J = j_[k];
    world_frame<kMixed>(chain_, rot_, k, R0, o);
    const Eigen::Vector3d z = R0.col(2);
    if (slides<kMixed>(chain_, k)) {
      J.S << Eigen::Vector3d::Zero(), z;
    } else {
      J.S << z, o.cross(z);
    }
    J.d = cross_motion(v_p, J.S);
    J.e = cross_motion(a_p, J.S) + cross_motion(v_p, J.d);
    J.v = v_p + J.S * qd[k];
    J.a = a_p + J.S * qdd[k] + J.d * qd[k];  // v_k x S_k = v_p x S_k
    Inertia& I = J.I;
    I.m = chain_.mass[k];
    world_inertia(chain_, k, R0, o, I.h, I.IO);
    const Vec6 p = I * J.v;  // momentum (L; P)
    J.f = I * J.a + cross_force(J.v, p);
    J.P = p.tail<3>();
    const Eigen::Vector3d w = J.v.head<3>(), u = J.v.tail<3>();
    // [w x] I_O - I_O [w x] - u h^T - h u^T = Z + Z^T with Z = [w x] I_O - u h^T
    // (I_O is symmetric and [w x] skew): one product, its columns w x I_O(:, c).
    Eigen::Matrix3d Z;
    for (int c = 0; c < 3; ++c) Z.col(c) = w.cross(I.IO.col(c)) - I.h[c] * u;
    J.B = Z + Z.transpose();
    J.B -= skew<double>(p.head<3>());
    J.B.diagonal().array() += 2.0 * I.h.dot(u);
    v_p = J.v;
    a_p = J.a;
  }
}

// Composite sums from the tip and the vectors the assembly dots.
void RneaDerivatives::backward() {
  Inertia Ic;
  Eigen::Matrix3d Bc = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Pc = Eigen::Vector3d::Zero();
  Vec6 F = Vec6::Zero();
  // Bc y = (Bc y_a; -2 Pc x y_a) for y = (y_a; y_l).
  const auto Bc_times = [&](const Vec6& y) {
    Vec6 r;
    r.head<3>().noalias() = Bc * y.head<3>();
    r.tail<3>() = -2.0 * Pc.cross(y.head<3>());
    return r;
  };
  for (int k = chain_.n - 1; k >= 0; --k) {
    Joint& J = j_[k];
    F += J.f;
    Ic.m += J.I.m, Ic.h += J.I.h, Ic.IO += J.I.IO;
    Bc += J.B;
    Pc += J.P;
    tau_[k] = J.S.dot(F);
    // Row k of the left factors, column k of the right ones (see compute()).
    Eigen::Vector3d r2 = Bc.transpose() * J.S.head<3>();
    r2 += 2.0 * Pc.cross(J.S.tail<3>());
    left_.row(k).head<3>() = r2.transpose();
    left_.row(k).tail<6>() = (Ic * J.S).transpose();
    St_.row(k) = J.S.transpose();
    right_q_.col(k) << J.d.head<3>(), J.e;
    right_qd_.col(k) << J.S.head<3>(), 2.0 * J.d;
    u_.col(k) = cross_force(J.S, F) + Bc_times(J.d) + Ic * J.e;
    w_.col(k) = 2.0 * (Ic * J.d) + Bc_times(J.S);
  }
}

void RneaDerivatives::compute(const double* q, const double* qd, const double* qdd, bool gravity, MatRef dq,
                              MatRef dqd, double* tau) {
  const int n = chain_.n;
  forward(q, qd, qdd, gravity);
  backward();
  // The O(n^2) assembly: with r1_i = Ic_i S_i and r2_i = Bc_i^T S_i, i >= k reads
  //   dtau_i/dq_k = (r2_i; r1_i) . (d_k,ang; e_k),  dtau_i/dqd_k = (r2_i; r1_i) . (S_k,ang; 2 d_k),
  // and i < k reads S_i . u_k and S_i . w_k. On small chains one dot product
  // per entry; on large ones four small matrix products (inner size 9 or 6;
  // each computed whole, the triangle it is for kept), which Eigen's GEMM
  // runs faster than n^2 short dot products.
  if (n <= 12) {
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < k; ++i) {
        dq(i, k) = St_.row(i).dot(u_.col(k));
        dqd(i, k) = St_.row(i).dot(w_.col(k));
      }
      for (int i = k; i < n; ++i) {
        dq(i, k) = left_.row(i).dot(right_q_.col(k));
        dqd(i, k) = left_.row(i).dot(right_qd_.col(k));
      }
    }
  } else {
    dq.noalias() = left_ * right_q_;
    dqd.noalias() = left_ * right_qd_;
    upper_.noalias() = St_ * u_;
    dq.triangularView<Eigen::StrictlyUpper>() = upper_;
    upper_.noalias() = St_ * w_;
    dqd.triangularView<Eigen::StrictlyUpper>() = upper_;
  }
  if (tau) {
    for (int k = 0; k < n; ++k) tau[k] = tau_[k] + chain_.armature[k] * qdd[k];
  }
}

}  // namespace pumasim
