// Every back-end agrees with every other on H, h, g, tau and qdd, and each is
// self-consistent (forward dynamics inverts inverse dynamics).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "models/dynamics/backend.hpp"
#include "models/dynamics/built_algorithms.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "tests/helpers.hpp"

namespace pumasim {
namespace {

using testing::evaluate;
using testing::Quantities;
using testing::rel_err;

// Agreement bound, relative to the norm of the quantity (the issue's 1e-10).
constexpr double kAgree = 1e-10;

void expect_all_agree(const RobotModel& model, std::uint64_t seed, int states) {
  std::vector<std::unique_ptr<DynamicsBackend>> all;
  for (const auto& info : testing::supported(model)) all.push_back(info.make(model));
  Rng rng(seed);
  const int n = model.dof();
  for (int s = 0; s < states; ++s) {
    const Eigen::VectorXd q = rng.uniform_vector(n, -M_PI, M_PI);
    const Eigen::VectorXd qd = rng.uniform_vector(n, -2, 2);
    const Eigen::VectorXd qdd = rng.uniform_vector(n, -5, 5);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -20, 20);
    const Quantities ref = evaluate(*all[0], q, qd, qdd, tau);
    // Self-consistency of the reference: tau = H qdd + h.
    EXPECT_LT(rel_err(ref.tau, ref.H * qdd + ref.h), kAgree) << model.name;
    for (std::size_t b = 1; b < all.size(); ++b) {
      const Quantities r = evaluate(*all[b], q, qd, qdd, tau);
      const std::string who = model.name + ": " + all[b]->name() + " vs " + all[0]->name() +
                              ", state " + std::to_string(s);
      EXPECT_LT(rel_err(ref.H, r.H), kAgree) << who << " H";
      EXPECT_LT(rel_err(ref.h, r.h), kAgree) << who << " h";
      EXPECT_LT(rel_err(ref.g, r.g), kAgree) << who << " g";
      EXPECT_LT(rel_err(ref.tau, r.tau), kAgree) << who << " tau";
      EXPECT_LT(rel_err(ref.qdd, r.qdd), kAgree) << who << " qdd";
    }
    // Forward dynamics given this back-end's own h is its forward dynamics:
    // to the last bit for the CRBA shells (the same operations without the
    // RNEA pass), within the agreement bound for the others (their H from
    // mass_matrix, or aba's own forward dynamics).
    for (const auto& b : all) {
      Eigen::VectorXd h(n), qdd(n), qdd_h(n);
      b->bias(q, qd, h);
      b->forward_dynamics(q, qd, tau, qdd);
      b->forward_dynamics_with_bias(q, qd, h, tau, qdd_h);
      const std::string who = model.name + ": " + b->name() + " with its bias, state " + std::to_string(s);
      if (std::string(b->name()) == "crba" || std::string(b->name()) == "crba-world") {
        for (int j = 0; j < n; ++j) EXPECT_EQ(qdd[j], qdd_h[j]) << who << ", joint " << j;
      } else {
        EXPECT_LT(rel_err(qdd, qdd_h), kAgree) << who;
      }
    }
    // Forward dynamics inverts inverse dynamics: ID(q, qd, FD(q, qd, tau)) = tau.
    Eigen::VectorXd tau_back(n);
    all[0]->inverse_dynamics(q, qd, ref.qdd, tau_back);
    EXPECT_LT(rel_err(tau, tau_back), kAgree) << model.name;
  }
}

// The back-ends generated for the PUMA 560 (closed-form Lagrange, unrolled
// RNEA and CRBA; parameters at run time, and puma560.toml's numbers folded in).
const std::vector<std::string> kGenerated = {
    "crba-symbolic",         "crba-symbolic-puma560",         "lagrange-symbolic",
    "lagrange-symbolic-puma560", "rnea-probing-symbolic", "rnea-probing-symbolic-puma560"};
const std::vector<std::string> kFolded = {"crba-symbolic-puma560", "lagrange-symbolic-puma560",
                                          "rnea-probing-symbolic-puma560"};

// The algorithm interface as a C++20 concept (models/dynamics/algorithms.hpp):
// every built algorithm satisfies it (AlgorithmList requires it), and one
// that cannot compute the mass matrix does not.
template <class S, int N>
struct AlgorithmWithoutMassMatrix {
  static constexpr const char* kName = "partial";
  explicit AlgorithmWithoutMassMatrix(const Chain<S, N>&) {}
  template <class V, class W>
  void inverse_dynamics(const V&, const V&, const V&, W&) {}
  template <class V, class W>
  void bias(const V&, const V&, W&) {}
  template <class V, class W>
  void coriolis(const V&, const V&, W&) {}
  template <class V, class W>
  void gravity(const V&, W&) {}
  template <class V, class W>
  void forward_dynamics(const V&, const V&, const V&, W&) {}
};

TEST(AlgorithmConcept, TheBuiltAlgorithmsSatisfyItAndAPartialOneDoesNot) {
  static_assert(DynamicsAlgorithm<Crba>);
  static_assert(DynamicsAlgorithm<Aba>);
  static_assert(!DynamicsAlgorithm<AlgorithmWithoutMassMatrix>);
}

TEST(BackendAgreement, Puma560) {
  const RobotModel puma = load_robot("puma560");
  ASSERT_EQ(testing::supported(puma).size(), backends().size()) << "every back-end takes part";
  expect_all_agree(puma, 1, 20);
}

TEST(BackendAgreement, Puma560WithoutRotorInertia) {
  expect_all_agree(without_rotor_inertia(load_robot("puma560")), 2, 10);
}

TEST(BackendAgreement, Puma560WristHeld) {
  const RobotModel puma = load_robot("puma560");
  expect_all_agree(lock_joints(puma, 3, puma.pose("qn")->q), 3, 10);
}

// The paper's experiment: joints 1-3 move, the wrist held at zero, the arm
// the folded 3-joint kernels were generated for.
TEST(BackendAgreement, Puma560WristHeldAtZero) {
  const RobotModel arm = lock_joints(load_robot("puma560"), 3, Eigen::VectorXd::Zero(6));
  ASSERT_EQ(testing::supported(arm).size(), backends().size()) << "every back-end takes part";
  expect_all_agree(arm, 4, 10);
}

TEST(BackendAgreement, RandomChainsStandardDh) {
  for (int n = 1; n <= 12; ++n) expect_all_agree(random_chain(n, 100 + n), 7 * n, 4);
}

TEST(BackendAgreement, RandomChainsModifiedDh) {
  for (int n = 1; n <= 12; ++n) {
    expect_all_agree(random_chain(n, 200 + n, DhConvention::kModified), 11 * n, 4);
  }
}

// Chains mixing revolute and prismatic joints (joint j prismatic where the
// pattern, repeated, has a 'P'), n = 3, 6, 12, both conventions.
TEST(BackendAgreement, RandomChainsMixingPrismaticJoints) {
  for (const char* pattern : {"RP", "PPR", "RRRP", "P"}) {
    for (int n : {1, 3, 6, 12}) {
      const std::uint64_t seed = 500 + 17 * n + std::string(pattern).size();
      expect_all_agree(random_chain(n, seed, DhConvention::kStandard, pattern), 13 * n, 4);
      expect_all_agree(random_chain(n, seed + 1, DhConvention::kModified, pattern), 19 * n, 4);
    }
  }
}

// The large arms that crba-world is made for (issue 17: n = 24 and 48), and
// the small ones it must also serve (n = 3 and 6 with the fixed-size code):
// every back-end agrees with every other, revolute chains and chains with
// prismatic joints, both conventions. (n = 1..12 are also in the tests above.)
TEST(BackendAgreement, RandomChainsLargeAndSmall) {
  for (int n : {3, 6, 24, 48}) {
    expect_all_agree(random_chain(n, 900 + n), 29 * n, 2);
    expect_all_agree(random_chain(n, 950 + n, DhConvention::kModified, "RRRP"), 31 * n, 2);
  }
}

// Every back-end that factors H (all but aba: its count of Cholesky
// operations is not zero) reads the h it is given rather than forming its
// own: with h + d in place of h the result is the forward dynamics of
// tau - d, qdd = H^-1 (tau - (h + d)). The PUMA (6 joints, and 3 with the
// wrist held: every generated back-end takes part) and random chains with a
// prismatic joint (n = 3, 6, 24).
TEST(BackendAgreement, BackEndsThatFactorHReadTheGivenBias) {
  const RobotModel puma = load_robot("puma560");
  std::vector<RobotModel> models = {puma, lock_joints(puma, 3, Eigen::VectorXd::Zero(6))};
  for (int n : {3, 6, 24}) models.push_back(random_chain(n, 700 + n, DhConvention::kStandard, "RRRP"));
  int checked = 0;
  for (const RobotModel& model : models) {
    const int n = model.dof();
    Rng rng(41 * n + static_cast<int>(models.size()));
    const Eigen::VectorXd q = rng.uniform_vector(n, -M_PI, M_PI), qd = rng.uniform_vector(n, -2, 2);
    const Eigen::VectorXd tau = rng.uniform_vector(n, -20, 20), d = rng.uniform_vector(n, -5, 5);
    for (const auto& info : testing::supported(model)) {
      if (info.count_ops(model, Quantity::kSolve).mul == 0) continue;  // forms no H: aba
      const std::unique_ptr<DynamicsBackend> b = info.make(model);
      Eigen::VectorXd h(n), given(n), direct(n);
      b->bias(q, qd, h);
      b->forward_dynamics_with_bias(q, qd, h + d, tau, given);
      b->forward_dynamics(q, qd, tau - d, direct);
      EXPECT_LT(rel_err(direct, given), kAgree) << info.name << ", " << model.name << ", n = " << n;
      ++checked;
    }
  }
  // every back-end but aba on each of the PUMA's two models (all take part there), and more on the chains
  EXPECT_GT(checked, 2 * (static_cast<int>(backends().size()) - 1));
}

// A standard-DH chain rewritten in the modified convention (same joints, link
// data moved from distal to proximal frames) has the same dynamics. The same
// rewrite holds for a prismatic joint: its d_j = q_j + offset sits, like a
// revolute joint's d_j, in the modified frame j (Rz(theta_j) Tz(d_j)), so
// type, theta and offset carry over unchanged.
RobotModel to_modified(const RobotModel& s) {
  RobotModel m = s;
  m.convention = DhConvention::kModified;
  for (int j = 0; j < s.dof(); ++j) {
    const JointParams& S = s.joints[j];
    JointParams& M = m.joints[j];
    M.a = j > 0 ? s.joints[j - 1].a : 0.0;
    M.alpha = j > 0 ? s.joints[j - 1].alpha : 0.0;
    M.d = S.d;
    // Standard frame j = modified frame j * Tz(d_j) Tx(a_j) Rx(alpha_j) * (Rz(offset) removed).
    const double c = std::cos(S.alpha), sn = std::sin(S.alpha);
    Eigen::Matrix3d Rx;
    Rx << 1, 0, 0, 0, c, -sn, 0, sn, c;
    // Modified frame j includes Rz(q + offset) and Tz(d), so only Tx(a) Rx(alpha) remain.
    M.com = Rx * S.com + Eigen::Vector3d(S.a, 0, 0);
    M.inertia = Rx * S.inertia * Rx.transpose();
  }
  return m;
}

TEST(BackendAgreement, StandardAndModifiedDhDescribeTheSameRobot) {
  for (const auto& [n, pattern] : std::vector<std::pair<int, std::string>>{
           {1, "R"}, {2, "R"}, {5, "R"}, {9, "R"}, {1, "P"}, {3, "PR"}, {6, "RRP"}, {9, "RP"}}) {
    const RobotModel s = random_chain(n, 300 + n, DhConvention::kStandard, pattern);
    const RobotModel m = to_modified(s);
    auto bs = make_backend("crba", s), bm = make_backend("crba", m);
    Rng rng(n);
    const Eigen::VectorXd q = rng.uniform_vector(n, -3, 3), qd = rng.uniform_vector(n, -2, 2);
    const Eigen::VectorXd qdd = rng.uniform_vector(n, -5, 5), tau = rng.uniform_vector(n, -9, 9);
    const Quantities a = evaluate(*bs, q, qd, qdd, tau), b = evaluate(*bm, q, qd, qdd, tau);
    EXPECT_LT(rel_err(a.H, b.H), kAgree) << n << pattern;
    EXPECT_LT(rel_err(a.h, b.h), kAgree) << n << pattern;
    EXPECT_LT(rel_err(a.qdd, b.qdd), kAgree) << n << pattern;
  }
}

// Holding joints k+1..n is the same as the full arm with those joints at rest
// at the held angles: the reduced H is the full H's top-left block and the
// reduced tau the full tau's head (qd = qdd = 0 on the held joints).
// A held prismatic joint is merged at its displacement.
void expect_lock_equals_rest(const RobotModel& robot, std::uint64_t seed) {
  Rng rng(seed);
  for (int k : {1, 3, 5}) {
    const Eigen::VectorXd held = rng.uniform_vector(6, -2, 2);
    const RobotModel reduced = lock_joints(robot, k, held);
    auto full = make_backend("rnea-probing-shared", robot), red = make_backend("crba", reduced);
    Eigen::VectorXd q = held, qd = Eigen::VectorXd::Zero(6), qdd = Eigen::VectorXd::Zero(6);
    q.head(k) = rng.uniform_vector(k, -2, 2);
    qd.head(k) = rng.uniform_vector(k, -1, 1);
    qdd.head(k) = rng.uniform_vector(k, -3, 3);
    Eigen::MatrixXd Hf(6, 6), Hr(k, k);
    Eigen::VectorXd tf(6), tr(k);
    full->mass_matrix(q, Hf);
    red->mass_matrix(q.head(k), Hr);
    full->inverse_dynamics(q, qd, qdd, tf);
    red->inverse_dynamics(q.head(k), qd.head(k), qdd.head(k), tr);
    EXPECT_LT(rel_err(Hf.topLeftCorner(k, k), Hr), kAgree) << robot.name << " " << k;
    EXPECT_LT(rel_err(tf.head(k), tr), kAgree) << robot.name << " " << k;
  }
}

TEST(LockJoints, EqualsTheFullArmWithHeldJointsAtRest) {
  expect_lock_equals_rest(load_robot("puma560"), 5);
  expect_lock_equals_rest(random_chain(6, 61, DhConvention::kStandard, "RPP"), 6);
  expect_lock_equals_rest(random_chain(6, 62, DhConvention::kModified, "PRRP"), 7);
}

// The PUMA 560's structure with other parameters: the generated closed form
// takes a_j, d_j and every inertial parameter at run time, so it must agree
// with the numeric back-ends for any such parameter set, not only the file's.
RobotModel puma_with_random_parameters(std::uint64_t seed) {
  RobotModel m = load_robot("puma560");
  const RobotModel donor = random_chain(6, seed);  // random masses, inertias, drives
  Rng rng(seed);
  for (int j = 0; j < 6; ++j) {
    JointParams& J = m.joints[j];
    J.a = rng.uniform(-0.5, 0.5);
    J.d = rng.uniform(-0.5, 0.5);
    J.mass = donor.joints[j].mass;
    J.com = donor.joints[j].com;
    J.inertia = donor.joints[j].inertia;
    J.rotor_inertia = donor.joints[j].rotor_inertia;
    J.gear_ratio = donor.joints[j].gear_ratio;
  }
  m.gravity = Eigen::Vector3d(rng.uniform(-3, 3), rng.uniform(-3, 3), -9.81);
  m.name = "puma560 structure, random parameters " + std::to_string(seed);
  return m;
}

TEST(GeneratedBackEnds, AllTakePartForThePuma) {
  for (const RobotModel& m : {load_robot("puma560"), lock_joints(load_robot("puma560"), 3,
                                                                 Eigen::VectorXd::Zero(6))}) {
    for (const std::string& name : kGenerated) {
      EXPECT_EQ(find_backend(name).why_unsupported(m), "") << name << ", " << m.name;
    }
  }
}

// A folded variant names the first parameter that differs and points to the
// variant with parameters at run time, which accepts the model.
TEST(GeneratedBackEnds, FoldedVariantsRefuseOtherParametersNamingOne) {
  RobotModel m = load_robot("puma560");
  m.joints[2].mass += 0.5;
  // Wrist held elsewhere than zero: a different lumped link 3.
  const RobotModel held = lock_joints(load_robot("puma560"), 3,
                                      (Eigen::VectorXd(6) << 0, 0, 0, 0.3, 0.2, 0).finished());
  for (const std::string& folded : kFolded) {
    const std::string runtime = folded.substr(0, folded.size() - std::string("-puma560").size());
    const std::string why = find_backend(folded).why_unsupported(m);
    EXPECT_NE(why.find("m2"), std::string::npos) << why;
    EXPECT_NE(why.find("(use " + runtime + ")"), std::string::npos) << why;
    EXPECT_THROW(make_backend(folded, m), std::invalid_argument) << folded;
    EXPECT_TRUE(find_backend(runtime).why_unsupported(m).empty()) << runtime;
    EXPECT_FALSE(find_backend(folded).why_unsupported(held).empty()) << folded;
    EXPECT_TRUE(find_backend(runtime).why_unsupported(held).empty()) << runtime;
  }
}

// Every back-end with parameters at run time takes part (expect_all_agree
// compares every supported back-end).
TEST(GeneratedBackEnds, AgreeForAnyParametersOfThePumaStructure) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const RobotModel m = puma_with_random_parameters(seed);
    expect_all_agree(m, seed, 5);
    Rng rng(seed);
    expect_all_agree(lock_joints(m, 3, rng.uniform_vector(6, -2, 2)), seed + 10, 5);
  }
}

TEST(GeneratedBackEnds, RefuseOtherArmsWithTheReason) {
  for (const RobotModel& m : {random_chain(6, 9), random_chain(4, 9)}) {
    for (const std::string& name : kGenerated) {
      EXPECT_FALSE(find_backend(name).why_unsupported(m).empty()) << name;
      try {
        make_backend(name, m);
        ADD_FAILURE() << name << " accepted " << m.name;
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(name + " was generated for the PUMA 560"),
                  std::string::npos)
            << e.what();
      }
    }
  }
}

TEST(Registry, SortedUniqueAndUnknownNameListsTheValidOnes) {
  const auto all = backends();
  // A subset build (PUMASIM_BACKENDS) may have as few as two; the full one
  // has every shipped back-end (a glob that found too few fails here).
  ASSERT_GE(all.size(), PUMASIM_BACKEND_SUBSET ? 2u : 12u);
  for (std::size_t i = 1; i < all.size(); ++i) {
    EXPECT_LT(std::string_view(all[i - 1].name), std::string_view(all[i].name));
  }
  for (const auto& b : all) EXPECT_EQ(&find_backend(b.name), &b);
  try {
    find_backend("lagrange");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    for (const auto& b : all) EXPECT_NE(msg.find(b.name), std::string::npos) << msg;
  }
}

// The algorithm templates the tests iterate (BuiltAlgorithms) are the
// registry's, in its order: a back-end added to the list is in both.
template <template <class, int> class... Algo>
std::vector<std::string> algorithm_names(AlgorithmList<Algo...>) {
  return {Algo<double, 6>::kName...};
}

TEST(Registry, TheTestsIterateEveryBackEnd) {
  std::vector<std::string> registered;
  for (const auto& b : backends()) registered.emplace_back(b.name);
  EXPECT_EQ(algorithm_names(BuiltAlgorithms{}), registered);
}

TEST(Registry, WrongArgumentSizeIsAnError) {
  auto b = make_backend("crba", load_robot("puma560"));
  Eigen::VectorXd q5(5), out(6);
  EXPECT_THROW(b->gravity(q5, out), std::invalid_argument);
}

}  // namespace
}  // namespace pumasim
