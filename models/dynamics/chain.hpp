// Chain<S, N>: the robot's parameters in the form the algorithms use.
//
// Every dynamics algorithm is templated on its scalar S (double, the
// operation-counting Counted, the forward-mode Dual) and on its joint count N
// (3 and 6 give fixed-size Eigen types and std::array storage for the PUMA;
// Eigen::Dynamic serves any n). A Chain is built once from a RobotModel and is
// then only read (Pinocchio's Model); each algorithm keeps its own workspace
// (Pinocchio's Data), allocated in its constructor and never after.
//
// Frames: joint frame j has its z axis on joint j. It is joint frame j-1 moved
// by a fixed rotation E_j and translation p_j, then rotated by Rz(q_j) about
// its z axis (revolute) or translated by q_j along it (prismatic):
//     revolute:  R_j = E_j Rz(q_j),  P_j = p_j
//     prismatic: R_j = E_j,          P_j = p_j + q_j E_j z
// (R_j: rotation joint frame j -> joint frame j-1; P_j: origin of joint frame
// j in joint frame j-1), so both DH conventions and both joint types reduce to
// one recursion (robot_model.cpp converts). The algorithms branch per joint on
// `type` where the two kinds differ: the motion subspace is S_j = [z; 0]
// (angular; linear) for a revolute joint and [0; z] for a prismatic one. Each
// kernel is compiled twice, chosen once per call by `any_prismatic`: for a
// chain of revolute joints only (the PUMA) the per-joint test is a constant
// false and the code is the revolute code alone (`slides<kMixed>` below).
#pragma once

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

#include "core/cholesky.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

template <class S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S> using Mat3 = Eigen::Matrix<S, 3, 3>;
template <class S, int N> using VecN = Eigen::Matrix<S, N, 1>;
template <class S, int N> using MatN = Eigen::Matrix<S, N, N>;

// Per-joint storage: in place for a fixed N, one allocation at construction otherwise.
// (A specialisation, not std::conditional_t: that would name std::array<T, -1>
// for a dynamic N, a narrowing that clang refuses.)
template <class T, int N>
struct PerJointStorage {
  using type = std::array<T, static_cast<std::size_t>(N)>;
};
template <class T>
struct PerJointStorage<T, Eigen::Dynamic> {
  using type = std::vector<T>;
};
template <class T, int N>
using PerJoint = typename PerJointStorage<T, N>::type;

// Zero of a scalar or of a fixed-size Eigen type.
template <class T>
T zero_value() {
  if constexpr (std::is_base_of_v<Eigen::EigenBase<T>, T>) {
    return T::Zero();
  } else {
    return T(0);
  }
}

template <class T, int N>
PerJoint<T, N> make_per_joint(int n, const T& init = zero_value<T>()) {
  if constexpr (N == Eigen::Dynamic) {
    return std::vector<T>(static_cast<std::size_t>(n), init);
  } else {
    PerJoint<T, N> a;
    a.fill(init);
    return a;
  }
}

template <class S, int N>
VecN<S, N> make_vec(int n) {
  VecN<S, N> v(n);
  v.setZero();
  return v;
}

template <class S, int N>
MatN<S, N> make_mat(int n) {
  MatN<S, N> m(n, n);
  m.setZero();
  return m;
}

// Skew-symmetric matrix of v: skew(v) * x = v x x.
template <class S>
Mat3<S> skew(const Vec3<S>& v) {
  Mat3<S> m;
  m << S(0), -v.z(), v.y(), v.z(), S(0), -v.x(), -v.y(), v.x(), S(0);
  return m;
}

template <class S, int N>
struct Chain {
  using Scalar = S;
  int n = 0;
  PerJoint<JointType, N> type;
  PerJoint<Mat3<S>, N> E;    // fixed rotation part of joint frame j in frame j-1
  PerJoint<Vec3<S>, N> p;    // origin of joint frame j in joint frame j-1 [m]
  PerJoint<S, N> mass;       // link mass [kg]
  PerJoint<Vec3<S>, N> com;  // centre of mass, joint frame j [m]
  PerJoint<Vec3<S>, N> h;    // first moment of mass, mass * com [kg m]
  PerJoint<Mat3<S>, N> Io;   // rotational inertia about the joint frame origin [kg m^2]
  PerJoint<S, N> armature;   // reflected rotor inertia Z^2 Im, link side [kg m^2] or [kg]
  bool any_prismatic = false;
  Vec3<S> gravity;           // gravitational acceleration in the base frame [m/s^2]
  Mat3<S> E_tool;            // flange (last DH frame) in joint frame n
  Vec3<S> p_tool;

  explicit Chain(const RobotModel& model) : Chain(joint_frames(model), model.dof()) {}

 private:
  static Mat3<S> cast3(const Eigen::Matrix3d& m) { return m.template cast<S>(); }
  static Vec3<S> cast3(const Eigen::Vector3d& v) { return v.template cast<S>(); }

  Chain(const JointFrameData& f, int dof)
      : n(dof),
        type(make_per_joint<JointType, N>(dof, JointType::kRevolute)),
        E(make_per_joint<Mat3<S>, N>(dof)),
        p(make_per_joint<Vec3<S>, N>(dof)),
        mass(make_per_joint<S, N>(dof)),
        com(make_per_joint<Vec3<S>, N>(dof)),
        h(make_per_joint<Vec3<S>, N>(dof)),
        Io(make_per_joint<Mat3<S>, N>(dof)),
        armature(make_per_joint<S, N>(dof)),
        gravity(cast3(f.gravity)),
        E_tool(cast3(f.E_tool)),
        p_tool(cast3(f.p_tool)) {
    if (N != Eigen::Dynamic && dof != N) {
      throw std::invalid_argument("Chain: fixed size " + std::to_string(N) + ", model has " +
                                  std::to_string(dof) + " joints");
    }
    for (int j = 0; j < dof; ++j) {
      type[j] = f.type[j];
      any_prismatic = any_prismatic || f.type[j] == JointType::kPrismatic;
      E[j] = cast3(f.E[j]);
      p[j] = cast3(f.p[j]);
      mass[j] = S(f.mass[j]);
      com[j] = cast3(f.com[j]);
      const Eigen::Vector3d hd = f.mass[j] * f.com[j];
      h[j] = cast3(hd);
      // Parallel-axis theorem: I_o = I_c + m (|c|^2 1 - c c^T).
      const Eigen::Matrix3d Iod =
          f.I_com[j] + f.mass[j] * (f.com[j].squaredNorm() * Eigen::Matrix3d::Identity() -
                                    f.com[j] * f.com[j].transpose());
      Io[j] = cast3(Iod);
      armature[j] = S(f.armature[j]);
    }
  }
};

template <class S, int N>
bool is_prismatic(const Chain<S, N>& c, int j) {
  return c.type[j] == JointType::kPrismatic;
}

// Joint j slides, in a kernel compiled for mixed chains (kMixed) or for chains
// of revolute joints only (a constant false: no test per joint).
template <bool kMixed, class S, int N>
bool slides(const Chain<S, N>& c, int j) {
  if constexpr (kMixed) {
    return is_prismatic(c, j);
  } else {
    (void)c, (void)j;
    return false;
  }
}

// R_j and P_j (above) for every joint: the one trigonometric pass of an
// algorithm. P_j is stored for mixed chains only; `origin` reads it, or the
// chain's fixed p_j when every joint is revolute.
template <class S, int N>
struct JointTransforms {
  PerJoint<Mat3<S>, N> R;
  PerJoint<Vec3<S>, N> p;

  explicit JointTransforms(int n) : R(make_per_joint<Mat3<S>, N>(n)), p(make_per_joint<Vec3<S>, N>(n)) {}

  template <bool kMixed>
  const Vec3<S>& origin(const Chain<S, N>& chain, int j) const {
    if constexpr (kMixed) {
      return p[j];
    } else {
      return chain.p[j];
    }
  }

  template <class Q>
  void compute(const Chain<S, N>& chain, const Q& q) {
    if (chain.any_prismatic) {
      compute_kinds<true>(chain, q);
    } else {
      compute_kinds<false>(chain, q);
    }
  }

 private:
  template <bool kMixed, class Q>
  void compute_kinds(const Chain<S, N>& chain, const Q& q) {
    using std::cos;
    using std::sin;
    for (int j = 0; j < chain.n; ++j) {
      const Mat3<S>& E = chain.E[j];
      Mat3<S>& Rj = R[j];
      if (slides<kMixed>(chain, j)) {
        Rj = E;
        p[j] = chain.p[j] + S(q[j]) * E.col(2);
        continue;
      }
      const S c = cos(S(q[j])), s = sin(S(q[j]));
      Rj.col(0) = c * E.col(0) + s * E.col(1);
      Rj.col(1) = c * E.col(1) - s * E.col(0);
      Rj.col(2) = E.col(2);
      if constexpr (kMixed) p[j] = chain.p[j];
    }
  }
};

// The Cholesky factorisation of H: core/cholesky.hpp.

}  // namespace pumasim
