#include "models/backend.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "models/algorithms.hpp"

namespace pumasim {
namespace {

template <int N>
auto vec_in(const ConstVecRef& v) {
  if constexpr (N == Eigen::Dynamic) {
    return Eigen::Map<const Eigen::VectorXd>(v.data(), v.size());
  } else {
    return Eigen::Map<const Eigen::Matrix<double, N, 1>>(v.data());
  }
}

template <int N>
auto vec_out(VecRef& v) {
  if constexpr (N == Eigen::Dynamic) {
    return Eigen::Map<Eigen::VectorXd>(v.data(), v.size());
  } else {
    return Eigen::Map<Eigen::Matrix<double, N, 1>>(v.data());
  }
}

template <int N>
auto mat_out(MatRef& m) {
  using Stride = Eigen::OuterStride<>;
  if constexpr (N == Eigen::Dynamic) {
    return Eigen::Map<Eigen::MatrixXd, 0, Stride>(m.data(), m.rows(), m.cols(),
                                                  Stride(m.outerStride()));
  } else {
    return Eigen::Map<Eigen::Matrix<double, N, N>, 0, Stride>(m.data(), Stride(m.outerStride()));
  }
}

// Wraps one algorithm for doubles: owns the chain (parameters) and the
// algorithm (workspace), checks sizes, and maps the arguments without copies.
template <template <class, int> class Algo, int N>
class Adapter final : public DynamicsBackend {
 public:
  explicit Adapter(const RobotModel& model) : chain_(model), algo_(chain_) {}
  Adapter(const Adapter&) = delete;
  Adapter& operator=(const Adapter&) = delete;

  const char* name() const override { return Algo<double, N>::kName; }
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

  const Chain<double, N> chain_;
  Algo<double, N> algo_;
};

template <template <class, int> class Algo>
std::unique_ptr<DynamicsBackend> make(const RobotModel& model) {
  if (const std::string why = why_unsupported<Algo>(model); !why.empty()) {
    throw std::invalid_argument(why);
  }
  switch (model.dof()) {
    case 3: return std::make_unique<Adapter<Algo, 3>>(model);
    case 6: return std::make_unique<Adapter<Algo, 6>>(model);
    default: return std::make_unique<Adapter<Algo, Eigen::Dynamic>>(model);
  }
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
    case Quantity::kGravity: algo.gravity(q, out); break;
    case Quantity::kForwardDynamics: algo.forward_dynamics(q, qd, qdd, out); break;
  }
  const OpCounts counted = op_counts();
  op_counts() = OpCounts{};
  return counted;
}

template <template <class, int> class Algo>
constexpr BackendInfo entry(const char* summary) {
  return BackendInfo{Algo<double, 6>::kName, summary, &why_unsupported<Algo>, &make<Algo>,
                     &count_ops<Algo>};
}

// Sorted by name (checked below). A new back-end is one line here.
const std::array<BackendInfo, 7> kBackends{{
    entry<Aba>("Featherstone's articulated body algorithm, O(n), rotor inertia as armature; "
               "H from the CRBA"),
    entry<Crba>("composite rigid body algorithm for H + one RNEA pass for h + Cholesky"),
    entry<LagrangeEuler>("textbook Lagrange-Euler with 4x4 matrices (Uicker / Fu-Gonzalez-Lee), "
                         "O(n^4) + Cholesky"),
    entry<LagrangeSymbolic>("closed-form Lagrange model generated with SymPy for the PUMA 560's "
                            "structure (3 or 6 joints; parameters at run time) + Cholesky"),
    entry<LagrangeSymbolicPuma560>("the same closed form with puma560.toml's numbers folded in "
                                   "(3 joints: wrist held at zero); other parameters are refused"),
    entry<RneaProbing>("the paper's method: n + 2 inverse-dynamics (RNEA) calls build g, h and "
                       "H, then Cholesky"),
    entry<RneaProbingShared>("probing with the kinematics shared: one trigonometric pass, h + n "
                             "gravity-free RNEA passes for H, then Cholesky"),
}};

bool registry_sorted() {
  return std::is_sorted(kBackends.begin(), kBackends.end(), [](const auto& a, const auto& b) {
    return std::string_view(a.name) < std::string_view(b.name);
  });
}

}  // namespace

std::span<const BackendInfo> backends() {
  static const bool sorted = registry_sorted();
  if (!sorted) throw std::logic_error("backend registry is not sorted by name");
  return kBackends;
}

std::string backend_names() {
  std::string s;
  for (const auto& b : backends()) {
    if (!s.empty()) s += ", ";
    s += b.name;
  }
  return s;
}

const BackendInfo& find_backend(std::string_view name) {
  const auto all = backends();
  const auto it = std::lower_bound(all.begin(), all.end(), name, [](const auto& b, auto key) {
    return std::string_view(b.name) < key;
  });
  if (it == all.end() || std::string_view(it->name) != name) {
    throw std::invalid_argument("unknown dynamics back-end '" + std::string(name) +
                                "'; expected one of: " + backend_names());
  }
  return *it;
}

}  // namespace pumasim
