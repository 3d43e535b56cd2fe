// The recursive algorithms customised for the PUMA 560: the like-for-like
// controls for the paper's probing claim (Sokolov & Toth 1999, sec. 5-6).
//
// scripts/generate_recursive.py unrolls this repository's RNEA (rnea.hpp) and
// CRBA (crba.hpp) for the PUMA's structure with SymPy, removing the operations
// on constant zeros and ones and sharing common subexpressions, exactly as
// scripts/generate_lagrange.py does for the closed-form Lagrange model. On top
// of those kernels:
//  - rnea-probing-symbolic(-puma560): the paper's probing, g = ID(q, 0, 0),
//    h = ID(q, qd, 0), H e_j = ID(q, qd, e_j) - h, then Cholesky: n + 2 calls of
//    the generated inverse dynamics, as `rnea-probing` makes n + 2 calls of the
//    generic RNEA (rnea_probing.hpp);
//  - crba-symbolic(-puma560): H by the generated CRBA and h by the generated
//    RNEA in one kernel, then Cholesky, as `crba` does generically.
// Both take the parameters at run time (any 3- or 6-joint chain with the PUMA's
// structure) or, with the suffix -puma560, have the numbers of
// models/robots/puma560.toml folded in and refuse other parameters, as the
// Lagrange pair does (lagrange_symbolic.hpp). Inverse dynamics is the
// generated RNEA; bias, Coriolis and gravity are the generated RNEA with the
// zero inputs substituted before generation (the same kernels for both).
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "models/dynamics/chain.hpp"
#include "models/dynamics/generated/recursive_puma560_3.hpp"
#include "models/dynamics/generated/recursive_puma560_6.hpp"
#include "models/dynamics/generated/recursive_puma560_folded_3.hpp"
#include "models/dynamics/generated/recursive_puma560_folded_6.hpp"
#include "models/dynamics/puma560_generated.hpp"

namespace pumasim {

template <bool kFoldedIn>
struct RecursiveKernels {
  using K3 = std::conditional_t<kFoldedIn, generated::RecursivePuma560Folded_3,
                                generated::RecursivePuma560_3>;
  using K6 = std::conditional_t<kFoldedIn, generated::RecursivePuma560Folded_6,
                                generated::RecursivePuma560_6>;
  static constexpr bool kFolded = kFoldedIn;
};

struct ProbingRuntimeKernels : RecursiveKernels<false> {
  static constexpr const char* kName = "rnea-probing-symbolic";
  static constexpr const char* kRuntimeName = "rnea-probing-symbolic";
};
struct ProbingFoldedKernels : RecursiveKernels<true> {
  static constexpr const char* kName = "rnea-probing-symbolic-puma560";
  static constexpr const char* kRuntimeName = "rnea-probing-symbolic";
};
struct CrbaRuntimeKernels : RecursiveKernels<false> {
  static constexpr const char* kName = "crba-symbolic";
  static constexpr const char* kRuntimeName = "crba-symbolic";
};
struct CrbaFoldedKernels : RecursiveKernels<true> {
  static constexpr const char* kName = "crba-symbolic-puma560";
  static constexpr const char* kRuntimeName = "crba-symbolic";
};

// The generated kernels behind the quantities both back-ends compute alike:
// inverse dynamics, bias, Coriolis and gravity; parameters and buffers.
template <class S, int N, class Kernels>
class RecursiveGenerated {
 protected:
  using Generated = Puma560Generated<Kernels>;

 public:
  static constexpr const char* kName = Kernels::kName;

  template <class C>
  static std::string why_unsupported(const C& chain) {
    return Generated::why_unsupported(chain);
  }

  explicit RecursiveGenerated(const Chain<S, N>& chain) : n_(chain.n) {
    if (const std::string why = why_unsupported(chain); !why.empty()) {
      throw std::invalid_argument(why);
    }
    Generated::parameters(chain, P_);
  }

  int dof() const { return n_; }

  template <class Q, class Qd, class Qdd, class Tau>
  void inverse_dynamics(const Q& q, const Qd& qd, const Qdd& qdd, Tau&& tau) {
    load(q, q_), load(qd, qd_), load(qdd, qdd_);
    id_into(out_);
    for (int i = 0; i < n_; ++i) tau[i] = out_[i];
  }

  template <class Q, class Qd, class V>
  void bias(const Q& q, const Qd& qd, V&& h) {
    load(q, q_), load(qd, qd_);
    with_kernel([&](auto k) { decltype(k)::bias(P_.data(), q_.data(), qd_.data(), out_.data()); });
    for (int i = 0; i < n_; ++i) h[i] = out_[i];
  }

  template <class Q, class Qd, class V>
  void coriolis(const Q& q, const Qd& qd, V&& c) {
    load(q, q_), load(qd, qd_);
    with_kernel([&](auto k) { decltype(k)::coriolis(P_.data(), q_.data(), qd_.data(), out_.data()); });
    for (int i = 0; i < n_; ++i) c[i] = out_[i];
  }

  template <class Q, class V>
  void gravity(const Q& q, V&& g) {
    load(q, q_);
    with_kernel([&](auto k) { decltype(k)::gravity(P_.data(), q_.data(), out_.data()); });
    for (int i = 0; i < n_; ++i) g[i] = out_[i];
  }

 protected:
  template <class V>
  void load(const V& v, std::array<S, 6>& out) const {
    for (int i = 0; i < n_; ++i) out[i] = S(v[i]);
  }

  // out = ID(q_, qd_, qdd_): one call of the generated RNEA.
  void id_into(std::array<S, 6>& out) {
    with_kernel([&](auto k) {
      decltype(k)::inverse_dynamics(P_.data(), q_.data(), qd_.data(), qdd_.data(), out.data());
    });
  }

  template <class F>
  void with_kernel(F&& f) const {
    Generated::template with_kernel<N>(n_, f);
  }

  // The kernels fill the upper triangle of a row-major n x n buffer.
  template <class M>
  void copy_symmetric(M&& H) const {
    for (int i = 0; i < n_; ++i)
      for (int k = i; k < n_; ++k) {
        const S& x = Hbuf_[static_cast<std::size_t>(i * n_ + k)];
        H(i, k) = x;
        H(k, i) = x;
      }
  }

  int n_;
  std::array<S, Generated::kMaxParams> P_{};
  std::array<S, 6> q_{}, qd_{}, qdd_{}, out_{};
  std::array<S, 36> Hbuf_{};
};

// The paper's probing on the generated RNEA (rnea_probing.hpp's RneaProbing,
// call for call).
template <class S, int N, class Kernels>
class RneaProbingGenerated : public RecursiveGenerated<S, N, Kernels> {
  using Base = RecursiveGenerated<S, N, Kernels>;
  using Base::id_into;
  using Base::load;
  using Base::n_;
  using Base::qd_;
  using Base::qdd_;
  using Base::q_;

 public:
  explicit RneaProbingGenerated(const Chain<S, N>& chain)
      : Base(chain), H_(make_mat<S, N>(chain.n)), chol_(chain.n) {}

  // H from n + 1 inverse-dynamics calls: g, then ID(q, 0, e_j) - g.
  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    load(q, q_);
    qd_.fill(S(0));
    qdd_.fill(S(0));
    id_into(g_);
    probe_columns(g_, H);
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    load(q, q_);
    qd_.fill(S(0));
    qdd_.fill(S(0));
    id_into(g_);  // A (kept because the paper does it; qdd does not use it)
    load(qd, qd_);
    id_into(h_);  // B
    probe_columns(h_, H_);  // C
    chol_.factor(H_);
    for (int j = 0; j < n_; ++j) qdd[j] = S(tau[j]) - h_[j];
    chol_.solve_in_place(qdd);
  }

 private:
  // Column j of H = ID(q_, qd_, e_j) - offset, with qdd_ = 0 on entry.
  template <class M>
  void probe_columns(const std::array<S, 6>& offset, M&& H) {
    for (int j = 0; j < n_; ++j) {
      qdd_[j] = S(1);
      id_into(col_);
      qdd_[j] = S(0);
      for (int i = 0; i < n_; ++i) H(i, j) = col_[i] - offset[i];
    }
  }

  std::array<S, 6> g_{}, h_{}, col_{};
  MatN<S, N> H_;
  Cholesky<S, N> chol_;
};

// H by the generated CRBA, h by the generated RNEA, one kernel; Cholesky.
template <class S, int N, class Kernels>
class CrbaGenerated : public RecursiveGenerated<S, N, Kernels> {
  using Base = RecursiveGenerated<S, N, Kernels>;
  using Base::copy_symmetric;
  using Base::Hbuf_;
  using Base::load;
  using Base::n_;
  using Base::out_;
  using Base::P_;
  using Base::qd_;
  using Base::q_;
  using Base::with_kernel;

 public:
  explicit CrbaGenerated(const Chain<S, N>& chain)
      : Base(chain), H_(make_mat<S, N>(chain.n)), chol_(chain.n) {}

  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    load(q, q_);
    with_kernel([&](auto k) { decltype(k)::mass_matrix_upper(P_.data(), q_.data(), Hbuf_.data()); });
    copy_symmetric(H);
  }

  template <class Q, class Qd, class Tau, class Qdd>
  void forward_dynamics(const Q& q, const Qd& qd, const Tau& tau, Qdd&& qdd) {
    load(q, q_), load(qd, qd_);
    with_kernel([&](auto k) {
      decltype(k)::dynamics(P_.data(), q_.data(), qd_.data(), Hbuf_.data(), out_.data());
    });
    copy_symmetric(H_);
    for (int i = 0; i < n_; ++i) qdd[i] = S(tau[i]) - out_[i];
    chol_.factor(H_);
    chol_.solve_in_place(qdd);
  }

 private:
  MatN<S, N> H_;
  Cholesky<S, N> chol_;
};

template <class S, int N>
using RneaProbingSymbolic = RneaProbingGenerated<S, N, ProbingRuntimeKernels>;
template <class S, int N>
using RneaProbingSymbolicPuma560 = RneaProbingGenerated<S, N, ProbingFoldedKernels>;
template <class S, int N>
using CrbaSymbolic = CrbaGenerated<S, N, CrbaRuntimeKernels>;
template <class S, int N>
using CrbaSymbolicPuma560 = CrbaGenerated<S, N, CrbaFoldedKernels>;

}  // namespace pumasim
