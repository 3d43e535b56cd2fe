// Private to the back-end sources: the adapter that wraps one algorithm
// template behind the DynamicsBackend interface, and its registry entry.
// Each back-end's entry is compiled in its own file (models/dynamics/backends/), so
// that the heavy template instantiations build in parallel.
#pragma once

#include <stdexcept>
#include <string>
#include <type_traits>

#include "models/dynamics/algorithms.hpp"
#include "models/dynamics/backend.hpp"

namespace pumasim::detail {

template <int N, class V>
auto vec_in(const V& v) {
  using S = typename V::Scalar;
  if constexpr (N == Eigen::Dynamic) {
    return Eigen::Map<const Eigen::Matrix<S, Eigen::Dynamic, 1>>(v.data(), v.size());
  } else {
    return Eigen::Map<const Eigen::Matrix<S, N, 1>>(v.data());
  }
}

template <int N, class V>
auto vec_out(V& v) {
  using S = typename V::Scalar;
  if constexpr (N == Eigen::Dynamic) {
    return Eigen::Map<Eigen::Matrix<S, Eigen::Dynamic, 1>>(v.data(), v.size());
  } else {
    return Eigen::Map<Eigen::Matrix<S, N, 1>>(v.data());
  }
}

template <int N, class M>
auto mat_out(M& m) {
  using S = typename M::Scalar;
  using Stride = Eigen::OuterStride<>;
  if constexpr (N == Eigen::Dynamic) {
    return Eigen::Map<Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>, 0, Stride>(
        m.data(), m.rows(), m.cols(), Stride(m.outerStride()));
  } else {
    return Eigen::Map<Eigen::Matrix<S, N, N>, 0, Stride>(m.data(), Stride(m.outerStride()));
  }
}

// Wraps one algorithm on scalar S: owns the chain (parameters) and the
// algorithm (workspace), checks sizes, and maps the arguments without copies.
template <template <class, int> class Algo, int N, class S = double>
class Adapter final : public BasicDynamicsBackend<S> {
  using Base = BasicDynamicsBackend<S>;
  using ConstVecRef = typename Base::ConstVecRef;
  using VecRef = typename Base::VecRef;
  using MatRef = typename Base::MatRef;

 public:
  explicit Adapter(const RobotModel& model)
      : chain_(model), algo_(chain_), H_(make_mat<S, N>(chain_.n)), chol_(chain_.n) {}
  Adapter(const Adapter&) = delete;
  Adapter& operator=(const Adapter&) = delete;

  const char* name() const override { return Algo<S, N>::kName; }
  int dof() const override { return chain_.n; }

  void inverse_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef qdd, VecRef tau) override {
    check(q, "q"), check(qd, "qd"), check(qdd, "qdd"), check(tau, "tau");
    algo_.inverse_dynamics(vec_in<N>(q), vec_in<N>(qd), vec_in<N>(qdd), vec_out<N>(tau));
  }
  void mass_matrix(ConstVecRef q, MatRef H) override {
    check(q, "q");
    if (H.rows() != chain_.n || H.cols() != chain_.n) size_error("H", H.rows() * H.cols());
    algo_.mass_matrix(vec_in<N>(q), mat_out<N>(H));
  }
  void bias(ConstVecRef q, ConstVecRef qd, VecRef h) override {
    check(q, "q"), check(qd, "qd"), check(h, "h");
    algo_.bias(vec_in<N>(q), vec_in<N>(qd), vec_out<N>(h));
  }
  void gravity(ConstVecRef q, VecRef g) override {
    check(q, "q"), check(g, "g");
    algo_.gravity(vec_in<N>(q), vec_out<N>(g));
  }
  void forward_dynamics(ConstVecRef q, ConstVecRef qd, ConstVecRef tau, VecRef qdd) override {
    check(q, "q"), check(qd, "qd"), check(tau, "tau"), check(qdd, "qdd");
    algo_.forward_dynamics(vec_in<N>(q), vec_in<N>(qd), vec_in<N>(tau), vec_out<N>(qdd));
  }
  void forward_dynamics_with_bias(ConstVecRef q, ConstVecRef qd, ConstVecRef h, ConstVecRef tau,
                                  VecRef qdd) override {
    check(q, "q"), check(qd, "qd"), check(h, "h"), check(tau, "tau"), check(qdd, "qdd");
    if constexpr (factors_mass_matrix<Algo>()) {  // its H, then the Cholesky solve of its forward dynamics
      algo_.mass_matrix(vec_in<N>(q), H_);
      chol_.factor(H_);
      auto out = vec_out<N>(qdd);
      for (int j = 0; j < chain_.n; ++j) out[j] = S(tau[j]) - S(h[j]);
      chol_.solve_in_place(out);
    } else {  // no H: its own forward dynamics (h given is its own bias)
      algo_.forward_dynamics(vec_in<N>(q), vec_in<N>(qd), vec_in<N>(tau), vec_out<N>(qdd));
    }
  }

 private:
  template <class V>
  void check(const V& v, const char* what) const {
    if (v.size() != chain_.n) size_error(what, v.size());
  }
  [[noreturn]] void size_error(const char* what, Eigen::Index got) const {
    throw std::invalid_argument(std::string(name()) + ": expected " + what + " with " +
                                std::to_string(chain_.n) + " entries, got " +
                                std::to_string(got));
  }

  const Chain<S, N> chain_;
  Algo<S, N> algo_;
  MatN<S, N> H_;         // forward_dynamics_with_bias's H and its factor
  Cholesky<S, N> chol_;
};

template <template <class, int> class Algo, class S = double>
std::unique_ptr<BasicDynamicsBackend<S>> make(const RobotModel& model) {
  if (const std::string why = why_unsupported<Algo>(model); !why.empty()) {
    throw std::invalid_argument(why);
  }
  count_backend_built();
  if constexpr (std::is_same_v<S, double>) {
    switch (model.dof()) {
      case 3: return std::make_unique<Adapter<Algo, 3, S>>(model);
      case 6: return std::make_unique<Adapter<Algo, 6, S>>(model);
      default: break;
    }
  }
  // Dual numbers serve Jacobians, not the hot loop: one dynamic-size instance.
  return std::make_unique<Adapter<Algo, Eigen::Dynamic, S>>(model);
}

// The solve that forward dynamics does once H and h are formed: Cholesky of
// H (here a symmetric positive definite stand-in of the same size; the
// operations do not depend on the values), then the two substitutions.
template <class M, class V>
void solve_ops(M& H, V& x) {
  const int n = static_cast<int>(H.rows());
  H.setConstant(Counted(0.1));
  for (int j = 0; j < n; ++j) H(j, j) = Counted(1.0 + n);
  Cholesky<Counted, Eigen::Dynamic> chol(n);
  chol.factor(H);
  chol.solve_in_place(x);
}

template <template <class, int> class Algo>
OpCounts count_ops(const RobotModel& model, Quantity what) {
  using V = Eigen::Matrix<Counted, Eigen::Dynamic, 1>;
  using M = Eigen::Matrix<Counted, Eigen::Dynamic, Eigen::Dynamic>;
  const int n = model.dof();
  const Chain<Counted, Eigen::Dynamic> chain(model);
  Algo<Counted, Eigen::Dynamic> algo(chain);
  // Deterministic, non-zero inputs; no algorithm branches on values.
  V q(n), qd(n), qdd(n), out(n);
  for (int j = 0; j < n; ++j) {
    q[j] = 0.1 * (j + 1);
    qd[j] = 0.2 - 0.05 * j;
    qdd[j] = 0.3 + 0.01 * j;
  }
  M H(n, n);
  op_counts() = OpCounts{};
  switch (what) {
    case Quantity::kInverseDynamics: algo.inverse_dynamics(q, qd, qdd, out); break;
    case Quantity::kMassMatrix: algo.mass_matrix(q, H); break;
    case Quantity::kBias: algo.bias(q, qd, out); break;
    case Quantity::kCoriolis: algo.coriolis(q, qd, out); break;
    case Quantity::kGravity: algo.gravity(q, out); break;
    case Quantity::kSolve:
      if constexpr (factors_mass_matrix<Algo>()) solve_ops(H, out);
      break;
    case Quantity::kForwardDynamics: algo.forward_dynamics(q, qd, qdd, out); break;
  }
  const OpCounts counted = op_counts();
  op_counts() = OpCounts{};
  return counted;
}

template <template <class, int> class Algo>
BackendInfo entry(const char* summary) {
  static_assert(DynamicsAlgorithm<Algo>, "a back-end's algorithm: models/dynamics/algorithms.hpp");
  return BackendInfo{.name = Algo<double, 6>::kName,
                     .summary = summary,
                     .why_unsupported = &why_unsupported<Algo>,
                     .make = &make<Algo>,
                     .make_dual = &make<Algo, Dual>,
                     .count_ops = &count_ops<Algo>};
}

}  // namespace pumasim::detail
