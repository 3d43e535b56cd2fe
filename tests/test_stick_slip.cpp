// The friction modes' own unit (models/plant/friction/stick_slip.hpp), on a
// const model with a context and an evaluator of the test's own: the root
// functions against their definitions, the coupled solve's decision for one
// joint against its closed form (stuck while |K i| <= Fs, else slipping in
// the torque's direction), the mode log, and the set-valued directions
// against H^-1 from the back-end.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "models/plant/friction/stick_slip.hpp"
#include "models/scene/scene.hpp"

namespace pumasim {
namespace {

constexpr double kZ = 50.0, kK = 0.1, kFs = 0.2, kFk = 0.1;

// One joint about a vertical axis (no gravity torque), a drive held at a
// constant voltage (PIV with zero gains), hybrid friction with Fs = 0.2 and
// Fk = 0.1 N m on the motor shaft.
PlantConfig one_joint() {
  RobotModel m;
  m.name = "one joint";
  JointParams J;
  J.mass = 1.0;
  J.com = Eigen::Vector3d(0.1, 0, 0);
  J.inertia = 0.01 * Eigen::Matrix3d::Identity();
  J.rotor_inertia = 1e-4;
  J.gear_ratio = kZ;
  m.joints.push_back(J);
  PlantConfig c;
  c.robot = m;
  c.n = 1;
  c.amplifier = {{2.0, 0.1, 100.0}};  // K_A, R0, V_max
  c.motor = {{1e-3, 1.9, kK}};        // La, R, K
  FrictionParams f;
  f.model = friction_model<HybridFriction>();
  f.static_torque = kFs;
  f.kinetic_torque = kFk;
  c.friction = {f};
  c.controller = ControllerMode::kContinuous;
  c.controller_params = LawParams<PivController>{{PivParams{}}};
  c.q0 = Eigen::VectorXd::Zero(1);
  return c;
}

struct OneJoint {
  PlantModel model{one_joint()};
  PlantContext context = model.make_context();
  std::unique_ptr<PlantWorkspace<double>> w = model.make_workspace<double>();
  StickSlip modes{model};
  std::vector<double> x = std::vector<double>(static_cast<std::size_t>(model.size()));
  int i = model.layout().i, qd = model.layout().qd;
  OneJoint() { model.start_state(context, *w, x.data()); }
};

TEST(StickSlip, RootFunctionsAreTheBreakAwayMarginAndTheSlipSpeed) {
  OneJoint s;
  ASSERT_EQ(s.modes.num_roots(), 1);
  ASSERT_EQ(s.context.modes[0], SlipMode::kStuck);
  s.x[s.i] = 1.5;  // K i = 0.15 N m < Fs: the constraint torque is K i (no gravity, one joint)
  double g = 0;
  s.modes.roots(s.context, *s.w, 0.0, s.x.data(), &g);
  EXPECT_NEAR(g, kFs - kK * 1.5, 1e-15);
  s.context.modes[0] = SlipMode::kNegative;  // slipping: the signed motor speed
  s.x[s.qd] = -0.01;
  s.modes.roots(s.context, *s.w, 0.0, s.x.data(), &g);
  EXPECT_DOUBLE_EQ(g, kZ * 0.01);
}

TEST(StickSlip, TheSolveHoldsAJointBelowFsAndReleasesItAboveInTheTorquesDirection) {
  for (const double i : {1.5, -1.5, 2.5, -2.5}) {  // K i = +-0.15 (held), +-0.25 N m (released)
    OneJoint s;
    s.x[s.i] = i;
    s.modes.settle(s.context, *s.w, 0.0, s.x.data());
    const SlipMode expected = std::abs(kK * i) <= kFs ? SlipMode::kStuck
                              : i > 0                 ? SlipMode::kPositive
                                                      : SlipMode::kNegative;
    EXPECT_EQ(s.context.modes[0], expected) << "K i = " << kK * i;
    EXPECT_TRUE(s.modes.last_solve().consistent);
    EXPECT_EQ(s.modes.stats().solves, 1);
  }
}

TEST(StickSlip, ASpeedReversalSticksTheJointAndTheLogRecordsIt) {
  OneJoint s;
  s.x[s.i] = 1.0;  // K i = 0.1 N m: held once at rest
  s.modes.settle(s.context, *s.w, 0.0, s.x.data());
  s.modes.start_log(s.context, *s.w, 0.0);
  ASSERT_EQ(s.modes.mode_changes().size(), 1u);  // the mode at t = 0
  s.context.modes[0] = SlipMode::kPositive;       // slipping forward, its speed reaching zero
  s.x[s.qd] = 1e-12;
  s.modes.record(s.context, *s.w, 0.1);  // logged: slipping (the release's torque)
  s.modes.on_root(s.context, *s.w, 0, 0.2, s.x.data());
  EXPECT_EQ(s.x[s.qd], 0.0) << "a joint stuck at its reversal is exactly at rest";
  EXPECT_EQ(s.context.modes[0], SlipMode::kStuck);
  const std::vector<ModeChange>& log = s.modes.mode_changes();
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[2].t, 0.2);
  EXPECT_EQ(log[2].mode, SlipMode::kStuck);
  EXPECT_NEAR(log[2].applied, kK * 1.0, 1e-15) << "the constraint torque holding it";
}

// B's column c, the change of qdd per unit friction torque on joint c's
// shaft, solves H b = Z_c e_c (H from a back-end of the registry).
TEST(StickSlip, SetValuedDirectionsAreColumnsOfHInverse) {
  const Scene sc = load_scene(std::string(PUMASIM_SCENES_DIR) + "/paper_slow_6dof_hybrid.toml");
  const PlantModel model(sc.plant);
  ASSERT_GT(model.set_valued_joints(), 0);
  PlantContext c = model.make_context();
  auto w = model.make_workspace<double>();
  std::vector<double> x(static_cast<std::size_t>(model.size()));
  model.start_state(c, *w, x.data());
  for (int j = 0; j < model.joints(); ++j) x[model.layout().q + j] += 0.1 * (j + 1);
  StickSlip modes(model);
  const int m = model.size(), k = model.set_valued_joints(), n = model.joints();
  std::vector<double> B(static_cast<std::size_t>(m) * k);
  modes.set_valued_directions(*w, x.data(), B.data());
  Eigen::VectorXd q(n);
  for (int j = 0; j < n; ++j) q[j] = x[model.layout().q + j];
  Eigen::MatrixXd H(n, n);
  make_backend("rnea-probing", model.simulated())->mass_matrix(q, H);
  for (int col = 0; col < k; ++col) {
    const int j = model.set_valued_joint(col);
    Eigen::VectorXd b(n), rhs = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) b[i] = B[static_cast<std::size_t>(col) * m + model.layout().qd + i];
    rhs[j] = model.gear_ratio(j);
    EXPECT_LT((H * b - rhs).norm(), 1e-10 * rhs.norm()) << "joint " << j + 1;
    for (int i = 0; i < m; ++i) {  // nothing but the speeds' rows
      if (i < model.layout().qd || i >= model.layout().qd + n) {
        EXPECT_EQ(B[static_cast<std::size_t>(col) * m + i], 0.0);
      }
    }
  }
}

}  // namespace
}  // namespace pumasim
