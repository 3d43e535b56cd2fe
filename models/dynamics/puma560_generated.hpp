// What every back-end built on kernels generated for the PUMA 560 shares
// (scripts/generate_lagrange.py, scripts/generate_recursive.py): whether a
// chain is the arm they were generated for, the chain's parameter vector in
// the generated order, and the choice of the 3- or 6-joint kernel.
//
// `Kernels` names the generated structs K3 and K6 (each with kTwistHalfPi,
// kNumParams, kParamNames and, when folded, kFoldedParams), the back-end's
// name kName, whether the numbers are folded in (kFolded), and the name of the
// variant with parameters at run time (kRuntimeName) that a refused model is
// pointed to.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "models/dynamics/chain.hpp"
#include "models/dynamics/counted.hpp"
#include "models/dynamics/dual.hpp"

namespace pumasim {

template <class Kernels>
class Puma560Generated {
  using K3 = typename Kernels::K3;
  using K6 = typename Kernels::K6;

 public:
  static constexpr int kMaxParams = K6::kNumParams;

  // Empty if the generated kernels describe `chain`, else why not.
  template <class C>
  static std::string why_unsupported(const C& chain) {
    std::string why = structure_mismatch(chain);
    if constexpr (Kernels::kFolded) {
      if (why.empty()) why = parameter_mismatch(chain);
    }
    return why;
  }

  // The chain's parameter vector in the generated order (see kParamNames).
  template <class C, class T>
  static void parameters(const C& chain, std::array<T, kMaxParams>& P) {
    int k = 0;
    for (int j = 0; j < chain.n; ++j) {
      const auto& I = chain.Io[j];
      for (const auto& x : {chain.mass[j], chain.h[j].x(), chain.h[j].y(), chain.h[j].z(), I(0, 0),
                            I(1, 1), I(2, 2), I(0, 1), I(1, 2), I(0, 2)}) {
        P[k++] = T(x);
      }
    }
    for (int j = 0; j < chain.n; ++j) P[k++] = T(chain.armature[j]);
    for (int j = 1; j < chain.n; ++j) {
      P[k++] = T(chain.p[j].x());
      P[k++] = T(chain.p[j].z());
    }
    for (int r = 0; r < 3; ++r) P[k++] = T(chain.gravity[r]);
  }

  // Calls f(K6{}) or f(K3{}): the generated kernel for this arm, chosen at
  // compile time for N = 3, 6 and by n for a dynamic N.
  template <int N, class F>
  static void with_kernel(int n, F&& f) {
    if constexpr (N == 6) {
      f(K6{});
    } else if constexpr (N == 3) {
      f(K3{});
    } else if (n == 6) {
      f(K6{});
    } else {
      f(K3{});
    }
  }

 private:
  template <class C>
  static std::string joint_mismatch(const C& chain, int j) {
    const int* twist = chain.n == 3 ? K3::kTwistHalfPi : K6::kTwistHalfPi;
    constexpr double tol = 1e-12;
    // Expected fixed rotation: identity for joint 1, Rx(twist_{j-1} pi/2) after.
    const int k = j == 0 ? 0 : twist[j - 1];
    const double c = std::round(std::cos(k * M_PI / 2)), s = std::round(std::sin(k * M_PI / 2));
    const double expected[3][3] = {{1, 0, 0}, {0, c, -s}, {0, s, c}};
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col)
        if (std::abs(value_of(chain.E[j](r, col)) - expected[r][col]) > tol) {
          return std::string(Kernels::kName) + " was generated for the PUMA 560's structure "
                 "(standard DH, twists pi/2, 0, -pi/2, pi/2, -pi/2, 0, no joint offsets); joint " +
                 std::to_string(j + 1) + " differs";
        }
    const bool off_axis = std::abs(value_of(chain.p[j].y())) > tol;
    const bool first_moved = j == 0 && (std::abs(value_of(chain.p[j].x())) > tol ||
                                        std::abs(value_of(chain.p[j].z())) > tol);
    if (off_axis || first_moved) {
      return std::string(Kernels::kName) + " was generated for the PUMA 560's structure; the "
             "origin of joint frame " + std::to_string(j + 1) + " is off its DH position";
    }
    return "";
  }

  template <class C>
  static std::string structure_mismatch(const C& chain) {
    const int n = chain.n;
    if (n != 3 && n != 6) {
      return std::string(Kernels::kName) +
             " was generated for the PUMA 560 with 3 or 6 joints, got " + std::to_string(n) +
             " joints";
    }
    for (int j = 0; j < n; ++j) {
      if (chain.type[j] == JointType::kPrismatic) {
        return std::string(Kernels::kName) + " was generated for the PUMA 560's structure "
               "(revolute joints only); joint " + std::to_string(j + 1) + " is prismatic";
      }
    }
    for (int j = 0; j < n; ++j) {
      if (std::string why = joint_mismatch(chain, j); !why.empty()) return why;
    }
    return "";
  }

  // For the folded kernels: the chain's parameters must be the folded ones.
  template <class C>
  static std::string parameter_mismatch(const C& chain) {
    std::array<typename C::Scalar, kMaxParams> Ps{};
    parameters(chain, Ps);
    const bool six = chain.n == 6;
    const int count = six ? K6::kNumParams : K3::kNumParams;
    for (int k = 0; k < count; ++k) {
      const double got = value_of(Ps[k]);
      const double want = six ? K6::kFoldedParams[k] : K3::kFoldedParams[k];
      if (std::abs(got - want) > 1e-9 * std::max(1.0, std::abs(want))) {
        return std::string(Kernels::kName) +
               " has the parameters of models/robots/puma560.toml folded in" +
               (six ? "" : " (wrist held at zero)") + "; this model's " +
               (six ? K6::kParamNames[k] : K3::kParamNames[k]) + " is " + std::to_string(got) +
               ", expected " + std::to_string(want) + " (use " + Kernels::kRuntimeName + ")";
      }
    }
    return "";
  }
};

}  // namespace pumasim
