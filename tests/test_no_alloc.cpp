// The dynamics calls allocate nothing on the heap. Two independent proofs:
//  1. Eigen's own guard: this file is compiled with EIGEN_RUNTIME_NO_MALLOC and
//     instantiates the algorithms itself; with set_is_malloc_allowed(false) any
//     Eigen heap allocation inside them aborts the test. The guard reports
//     through eigen_assert, so this file keeps asserts in every build
//     (tests/CMakeLists.txt: -UNDEBUG; checked below).
//  2. A counting malloc: this test binary interposes malloc/calloc/realloc (glibc
//     forwards to __libc_*), so every heap allocation of the process -- operator
//     new, std::vector, Eigen -- is counted, including those inside the compiled
//     library behind the DynamicsBackend interface.
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <filesystem>

#ifdef NDEBUG
#error "test_no_alloc.cpp needs asserts: Eigen's malloc guard reports through eigen_assert"
#endif

#include <atomic>
#include <cstdlib>

#include "integrators/radau5.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/dynamics_derivatives.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/robot_file.hpp"
#include "models/scene/scene.hpp"
#include "tests/any_n_scenes.hpp"
#include "tests/helpers.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
}

namespace {
std::atomic<long> g_allocations{0};
}

extern "C" void* malloc(std::size_t size) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
extern "C" void* calloc(std::size_t n, std::size_t size) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* p, std::size_t size) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, size);
}

namespace pumasim {
namespace {

TEST(NoAllocation, CountingMallocSeesAllocationsAtAll) {
  // The instrument works: a heap allocation is counted.
  const long before = g_allocations.load();
  auto* p = new std::vector<double>(100);
  delete p;
  EXPECT_GT(g_allocations.load(), before);
}

TEST(NoAllocation, EveryBackendThroughTheInterface) {
  for (const RobotModel& m : {load_robot("puma560"), random_chain(9, 4),
                              random_chain(6, 4, DhConvention::kStandard, "RP"),
                              random_chain(9, 4, DhConvention::kModified, "PRR")}) {
    const int n = m.dof();
    for (const auto& info : testing::supported(m)) {
      auto b = info.make(m);
      Rng rng(1);
      const Eigen::VectorXd q = rng.uniform_vector(n, -1, 1), qd = rng.uniform_vector(n, -1, 1);
      const Eigen::VectorXd tau = rng.uniform_vector(n, -1, 1);
      Eigen::VectorXd qdd(n), out(n);
      Eigen::MatrixXd H(n, n);
      const long before = g_allocations.load();
      for (int rep = 0; rep < 3; ++rep) {
        b->forward_dynamics(q, qd, tau, qdd);
        b->inverse_dynamics(q, qd, qdd, out);
        b->mass_matrix(q, H);
        b->bias(q, qd, out);
        b->gravity(q, out);
      }
      EXPECT_EQ(g_allocations.load() - before, 0) << info.name << " " << m.name;
    }
  }
}

// The exact derivatives of the forward dynamics, on small chains and on the
// large ones whose assembly and products with H^-1 go through Eigen's
// matrix products (n > 12: their work buffers on the stack), allocate
// nothing once constructed.
TEST(NoAllocation, ForwardDynamicsDerivatives) {
  for (const RobotModel& m :
       {load_robot("puma560"), random_chain(24, 5), random_chain(48, 5, DhConvention::kStandard, "RRRP")}) {
    const int n = m.dof();
    DynamicsDerivatives d(m, find_backend("crba").make(m));
    Rng rng(2);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1, 1), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -1, 1);
    Eigen::VectorXd qdd(n);
    Eigen::MatrixXd Dq(n, n), Dqd(n, n), Dt(n, n);
    const long before = g_allocations.load();
    Eigen::internal::set_is_malloc_allowed(false);
    for (int rep = 0; rep < 3; ++rep) {
      d.forward_dynamics(q, qd, tau, qdd, Dq, Dqd, Dt);
      d.id_partials(q.data(), qd.data(), qdd.data(), false, Dq, Dqd);
    }
    Eigen::internal::set_is_malloc_allowed(true);
    EXPECT_EQ(g_allocations.load() - before, 0) << m.name;
  }
}

// The plant's right-hand side f(t, x), for every shipped scene (continuous
// reference and inverse kinematics included), allocates nothing.
TEST(NoAllocation, PlantRightHandSide) {
  // Every shipped scene: each block, friction law and controller law.
  for (const auto& entry : std::filesystem::directory_iterator(PUMASIM_SCENES_DIR)) {
    if (entry.path().extension() != ".toml") continue;
    const std::string name = entry.path().stem().string();
    Plant plant(load_scene(entry.path().string()).plant);
    std::vector<double> x(plant.size()), f(plant.size());
    plant.initial_state(x.data());
    plant.rhs(0.0, x.data(), f.data());
    const long before = g_allocations.load();
    for (int k = 1; k <= 5; ++k) plant.rhs(0.01 * k, x.data(), f.data());
    EXPECT_EQ(g_allocations.load() - before, 0) << name;
    // Moreau-Jean's per-step plant calls: f_smooth, the impulse directions B
    // and the coupled stick/slip solve (on B's first rows as a stand-in W).
    std::vector<double> B(static_cast<std::size_t>(plant.size() * plant.set_valued_joints()) + 1);
    plant.rhs_smooth(0.0, x.data(), f.data());
    const long before_smooth = g_allocations.load();
    for (int k = 1; k <= 5; ++k) plant.rhs_smooth(0.01 * k, x.data(), f.data());
    plant.set_valued_directions(x.data(), B.data());
    EXPECT_EQ(g_allocations.load() - before_smooth, 0) << name << " (rhs_smooth, set_valued_directions)";
    const int kc = plant.set_valued_joints();
    std::vector<double> W(static_cast<std::size_t>(kc * kc) + 1, 0.0), b(kc + 1, 1.0), r(kc + 1);
    std::vector<int> mode(kc + 1);
    for (int c = 0; c < kc; ++c) W[c * kc + c] = 1.0;
    const long before_solve = g_allocations.load();
    plant.solve_stick({kc, W.data(), b.data(), b.data(), b.data(), nullptr}, r.data(), mode.data());
    EXPECT_EQ(g_allocations.load() - before_solve, 0) << name << " (stick solve)";
  }
}

// The plant's exact Jacobian (multi-tangent pass, analytical dynamics
// derivatives), which the implicit methods call at every Jacobian update,
// allocates nothing once J has its size.
TEST(NoAllocation, PlantExactJacobian) {
  for (const auto& entry : std::filesystem::directory_iterator(PUMASIM_SCENES_DIR)) {
    if (entry.path().extension() != ".toml") continue;
    const std::string name = entry.path().stem().string();
    Plant plant(load_scene(entry.path().string()).plant);
    std::vector<double> x(plant.size());
    plant.initial_state(x.data());
    Eigen::MatrixXd J;
    plant.jacobian_exact(0.0, x.data(), J);
    const long before = g_allocations.load();
    for (int k = 1; k <= 3; ++k) plant.jacobian_exact(0.01 * k, x.data(), J);
    EXPECT_EQ(g_allocations.load() - before, 0) << name;
  }
}

// The numerical inverse kinematics (damped least squares in the reference,
// evaluated inside f) allocates nothing either.
TEST(NoAllocation, PlantRightHandSideWithNumericalInverseKinematics) {
  for (const std::string name : {"paper_slow", "paper_slow_6dof"}) {
    std::vector<std::string> unset = {"reference.arm", "reference.elbow"};
    if (name == "paper_slow_6dof") unset.push_back("reference.wrist");
    const std::string path = std::string(PUMASIM_SCENES_DIR) + "/" + name + ".toml";
    // Started at the closed form's first point (the default guess, mid-range,
    // finds another wrist branch, which leaves joint 4's range on this path).
    ReferenceSample start;
    load_scene(path).plant.reference->eval(0.0, start);
    std::string guess = "reference.ik_guess=[";
    for (int j = 0; j < 6; ++j) guess += (j ? ", " : "") + std::to_string(start.q[j]);
    if (name == "paper_slow") guess = "reference.ik_guess=[" + std::to_string(start.q[0]) + ", " +
                                      std::to_string(start.q[1]) + ", " + std::to_string(start.q[2]);
    Plant plant(load_scene(path, {"reference.ik=\"numerical\"", guess + "]"}, unset).plant);
    std::vector<double> x(plant.size()), f(plant.size());
    plant.initial_state(x.data());
    plant.rhs(0.0, x.data(), f.data());
    const long before = g_allocations.load();
    for (int k = 1; k <= 5; ++k) plant.rhs(0.37 * k, x.data(), f.data());
    EXPECT_EQ(g_allocations.load() - before, 0) << name;
  }
}

// Long arms: a 7- and a 12-joint random chain on a Cartesian pose path, the
// redundancy rule's inverse kinematics and rates (dynamic sizes, dual and
// Jet2 passes, the rule's Newton solve) inside f, with the reference table
// and without it (the exact reference at every call).
TEST(NoAllocation, PlantRightHandSideOfARedundantArm) {
  for (const int n : {7, 12}) {
    for (const bool table : {true, false}) {
      Scene sc = load_scene(testing::random_tracking_scene_file(n, 1e-5));
      sc.plant.tabulate_reference = table;
      Plant plant(sc.plant);
      std::vector<double> x(plant.size()), f(plant.size());
      plant.initial_state(x.data());
      plant.rhs(0.0, x.data(), f.data());
      const long before = g_allocations.load();
      for (int k = 1; k <= 5; ++k) plant.rhs(0.37 * k, x.data(), f.data());
      EXPECT_EQ(g_allocations.load() - before, 0) << n << (table ? " (table)" : " (exact reference)");
      Eigen::MatrixXd J;
      plant.jacobian_exact(0.0, x.data(), J);
      const long before_j = g_allocations.load();
      for (int k = 1; k <= 3; ++k) plant.jacobian_exact(0.01 * k, x.data(), J);
      EXPECT_EQ(g_allocations.load() - before_j, 0) << n << " (exact Jacobian)";
    }
  }
}

struct EigenGuard {
  const RobotModel& m;
  template <template <class, int> class Algo>
  void operator()() {
    const int n = m.dof();
    const Chain<double, Eigen::Dynamic> chain(m);
    Algo<double, Eigen::Dynamic> algo(chain);
    Rng rng(2);
    const Eigen::VectorXd q = rng.uniform_vector(n, -1, 1), qd = rng.uniform_vector(n, -1, 1);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -1, 1);
    Eigen::VectorXd qdd(n);
    Eigen::MatrixXd H(n, n);
    Eigen::internal::set_is_malloc_allowed(false);
    algo.forward_dynamics(q, qd, tau, qdd);
    algo.mass_matrix(q, H);
    Eigen::internal::set_is_malloc_allowed(true);
    EXPECT_TRUE(qdd.allFinite()) << Algo<double, Eigen::Dynamic>::kName;
  }
};

// The guard is live in this build: an Eigen allocation while it is closed aborts.
// radau5 (integrators/radau5.cpp) sizes every vector and factorisation in
// reset(): its steps (Newton iterations, rejections, the error estimate,
// dense output) allocate nothing on a system with its own Jacobian. Van der
// Pol at mu = 100 (stiff, nonlinear: the iteration and the step control both work).
class StiffVanDerPol final : public OdeSystem {
 public:
  int size() const override { return 2; }
  void rhs(double, const double* y, double* f) override {
    f[0] = y[1];
    f[1] = kMu * (1 - y[0] * y[0]) * y[1] - y[0];
  }
  bool has_exact_jacobian() const override { return true; }
  void jacobian(double, const double* y, Eigen::MatrixXd& J) override {
    J.resize(2, 2);
    J << 0.0, 1.0, -2.0 * kMu * y[0] * y[1] - 1.0, kMu * (1 - y[0] * y[0]);
  }

 private:
  static constexpr double kMu = 100.0;
};

TEST(NoAllocation, Radau5StepsAfterReset) {
  StiffVanDerPol sys;
  IntegratorOptions o;
  o.rtol = o.atol = 1e-6;
  auto integ = make_integrator("radau5", o);
  const double y0[2] = {2.0, 0.0};
  integ->reset(sys, 0.0, y0);
  double y[2];
  const long before = g_allocations.load();
  // 400 s: two and a half periods (about (3 - 2 ln 2) mu = 162 s each), with their fast jumps.
  while (integ->time() < 400.0) {
    ASSERT_EQ(integ->step_toward(400.0).status, Outcome::kReached);
    integ->dense_state(0.5 * (integ->step_start() + integ->time()), y);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(integ->stats().rejected_steps, 0);  // the step control worked, rejections included
}

TEST(NoAllocationDeathTest, EigenRuntimeGuardFiresOnAnAllocation) {
  EXPECT_DEATH(
      {
        Eigen::internal::set_is_malloc_allowed(false);
        Eigen::VectorXd v(16);
        v.setZero();
      },
      "");
}

TEST(NoAllocation, EigenRuntimeGuardOnTheAlgorithms) {
  for (const RobotModel& m : {random_chain(7, 5), random_chain(7, 5, DhConvention::kStandard, "RP")}) {
    testing::for_each_algorithm(m, EigenGuard{m});
  }
}

}  // namespace
}  // namespace pumasim
