// The controller laws (models/plant/controller/): the registry, and the
// computed-torque law against what feedback linearisation promises. With the
// plant's own model, La = 0, no friction and no saturation, the closed loop
// is exactly qdd = qdd_ref + Kd (qd_ref - qd) + Kp (q_ref - q) at every state
// (Spong, Hutchinson and Vidyasagar, Robot Modeling and Control, 2006,
// sec. 8.3), so each joint's error obeys e'' + Kd e' + Kp e = 0, whose
// critically damped solution is e(t) = (e0 + (e0' + w e0) t) exp(-w t).
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "models/dynamics/backend.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"

#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

using test::scene_path;

TEST(ControllerRegistry, EveryLawHasAUniqueNameAndUniqueKeys) {
  std::set<std::string> names;
  ControllerLaws::for_each([&](auto tag) {
    using Law = typename decltype(tag)::Law;
    const std::string name(Law::kName);
    EXPECT_TRUE(names.insert(name).second) << name;
    ControllerParams p;
    ASSERT_TRUE(default_controller_params(name, 3, &p)) << name;
    EXPECT_EQ(controller_law_name(p), Law::kName);
    EXPECT_EQ(controller_joints(p), 3u);
    std::set<std::string_view> keys;
    for (const auto& k : Law::keys()) EXPECT_TRUE(keys.insert(k.key).second) << name << ": " << k.key;
    for (const auto& k : Law::text_keys()) EXPECT_TRUE(keys.insert(k.key).second) << name << ": " << k.key;
    // The drive's limit on the command is every law's (the current's scale).
    EXPECT_GT(controller_output_limit(p, 0), 0.0) << name;
  });
  EXPECT_EQ(controller_law_names().size(), names.size());
  ControllerParams p;
  EXPECT_FALSE(default_controller_params("pid", 3, &p));
}

// The computed-torque scene with nothing the law does not cancel: La = 0, no
// friction, limits far away.
Scene ideal_computed_torque(const std::string& backend, const std::string& mode = "continuous") {
  std::vector<std::string> set = {"motor.inductance=0", "amplifier.voltage_limit=1e9",
                                  "controller.output_limit=1e9", "scene.backend=\"" + backend + "\"",
                                  "controller.mode=\"" + mode + "\""};
  if (mode == "sampled") set.push_back("controller.servo_period=0.001");
  Scene sc = load_scene(scene_path("computed_torque"), set);
  for (auto& f : sc.plant.friction) f = FrictionParams{};
  return sc;
}

// Off the reference (angles and speeds perturbed), at a time when the
// reference moves: qdd from f is the PD law's acceleration, for every back-end.
TEST(ComputedTorque, LinearisesTheArmExactlyWithEveryBackend) {
  for (const BackendInfo& b : backends()) {
    const Scene probe = ideal_computed_torque("crba");
    if (!b.why_unsupported(simulated_robot(probe.plant.robot, probe.plant.n, probe.plant.q_held)).empty()) continue;
    const Scene sc = ideal_computed_torque(std::string(b.name));
    Plant plant(sc.plant);
    const StateLayout& L = plant.layout();
    const auto& P = law_params<ComputedTorqueController>(sc.plant);
    std::vector<double> x(plant.size()), f(plant.size());
    plant.initial_state(x.data());
    const double t = 5.0;
    for (int j = 0; j < L.n; ++j) x[L.q + j] += 0.01 * (j + 1), x[L.qd + j] += -0.03 * (j + 1);
    plant.rhs(t, x.data(), f.data());
    const ReferenceSample r = plant.reference_at(t);
    for (int j = 0; j < L.n; ++j) {
      const double want = r.qdd[j] + P[j].kd * (r.qd[j] - x[L.qd + j]) + P[j].kp * (r.q[j] - x[L.q + j]);
      EXPECT_NEAR(f[L.qd + j], want, 1e-9 * (1 + std::abs(want))) << b.name << " joint " << j + 1;
    }
  }
}

// The whole loop over time: from an initial error, each joint's error follows
// the critically damped closed form (w = sqrt(kp), kd = 2 w in the scene).
TEST(ComputedTorque, ErrorDecaysAsTheLinearisedLoop) {
  const Scene sc = ideal_computed_torque("crba");
  Plant plant(sc.plant);
  const StateLayout& L = plant.layout();
  const auto& P = law_params<ComputedTorqueController>(sc.plant);
  const int m = plant.size(), n = L.n;
  std::vector<double> x(m), k1(m), k2(m), k3(m), k4(m), y(m);
  plant.initial_state(x.data());
  const double t0 = 2.0;
  // Start on the reference at t0, then perturb.
  ReferenceSample r0 = plant.reference_at(t0);
  std::vector<double> e0(n), de0(n);
  for (int j = 0; j < n; ++j) {
    e0[j] = 0.02 / (j + 1), de0[j] = -0.1 * (j + 1);
    x[L.q + j] = r0.q[j] - e0[j];  // e = q_ref - q
    x[L.qd + j] = r0.qd[j] - de0[j];
  }
  const double h = 1e-4, T = 0.2;
  auto stage = [&](double t, const std::vector<double>& base, const std::vector<double>& k, double a,
                   std::vector<double>& out) {
    for (int i = 0; i < m; ++i) y[i] = base[i] + a * k[i];
    plant.rhs(t, y.data(), out.data());
  };
  double t = t0;
  for (int s = 0; s < static_cast<int>(std::lround(T / h)); ++s) {  // RK4: error O(h^4) ~ 1e-12 here
    plant.rhs(t, x.data(), k1.data());
    stage(t + h / 2, x, k1, h / 2, k2);
    stage(t + h / 2, x, k2, h / 2, k3);
    stage(t + h, x, k3, h, k4);
    for (int i = 0; i < m; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    t += h;
  }
  const ReferenceSample r = plant.reference_at(t);
  for (int j = 0; j < n; ++j) {
    const double w = std::sqrt(P[j].kp);
    ASSERT_DOUBLE_EQ(P[j].kd, 2 * w);  // the scene's gains are critically damped
    const double want = (e0[j] + (de0[j] + w * e0[j]) * T) * std::exp(-w * T);
    EXPECT_NEAR(r.q[j] - x[L.q + j], want, 1e-9) << "joint " << j + 1;
  }
}

// The sampled law holds, from each sample, the output the continuous law
// gives at that instant and state.
TEST(ComputedTorque, SampledHoldsTheContinuousOutputAtTheSample) {
  Plant cont(ideal_computed_torque("crba").plant);
  Plant samp(ideal_computed_torque("crba", "sampled").plant);
  const int m = cont.size(), n = cont.layout().n;
  ASSERT_EQ(samp.size(), m);
  std::vector<double> x(m), xs(m);
  cont.initial_state(x.data());
  samp.initial_state(xs.data());
  const double t = 3.0;  // on the 1 ms grid
  for (int j = 0; j < n; ++j) x[cont.layout().q + j] += 0.005, x[cont.layout().qd + j] -= 0.02;
  xs = x;
  samp.on_time_event(t, xs.data());
  std::vector<DriveSignals> a(n), b(n);
  cont.drive_signals(t, x.data(), a.data());
  samp.drive_signals(t, xs.data(), b.data());
  for (int j = 0; j < n; ++j) EXPECT_NEAR(b[j].u, a[j].u, 1e-12 * (1 + std::abs(a[j].u))) << "joint " << j + 1;
}

// The exact Jacobian (dual numbers through the law's inverse dynamics) equals
// central differences of f, with the scene's inductance (the current a state)
// and viscous friction (smooth).
TEST(ComputedTorque, ExactJacobianMatchesDifferences) {
  Scene sc = load_scene(scene_path("computed_torque"));
  for (auto& f : sc.plant.friction) f.model = friction_model<ViscousFriction>();
  Plant plant(sc.plant);
  const int m = plant.size();
  ASSERT_GE(plant.layout().i, 0);
  std::vector<double> x(m), fp(m), fm(m);
  plant.initial_state(x.data());
  const double t = 4.0;
  for (int j = 0; j < plant.layout().n; ++j) x[plant.layout().qd + j] += 0.05;
  Eigen::MatrixXd J;
  plant.jacobian_exact(t, x.data(), J);
  for (int k = 0; k < m; ++k) {
    const double d = 1e-6 * std::max(1.0, std::abs(x[k]));
    std::vector<double> xp = x, xm = x;
    xp[k] += d, xm[k] -= d;
    plant.rhs(t, xp.data(), fp.data());
    plant.rhs(t, xm.data(), fm.data());
    for (int r = 0; r < m; ++r) {
      const double fd = (fp[r] - fm[r]) / (2 * d);
      EXPECT_NEAR(J(r, k), fd, 1e-6 * (1 + std::abs(fd))) << plant.layout().names[r] << " by " << plant.layout().names[k];
    }
  }
}

}  // namespace
}  // namespace pumasim
