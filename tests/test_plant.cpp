// The plant: each block against a closed form, the friction rules case by
// case, the reduced model as the La -> 0 limit, the two Jacobians, the state
// layout, time events, inverse kinematics, and scene files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "core/errors.hpp"
#include "experiments/cli.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/plant/plant.hpp"
#include "models/robot/kinematics.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"

#include "tests/scene_paths.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

// The plant from its initial state to t_end with RK4 at dt, through the driver.
RunResult run_rk4(Plant& plant, double t_end, double dt, double output_interval, const Observer& observe) {
  IntegratorOptions o;
  o.dt = dt;
  auto rk4 = make_integrator("rk4", o);
  const RunResult r = run_plant(plant, *rk4, {.t_end = t_end, .output_interval = output_interval, .observe = observe});
  EXPECT_TRUE(r.ok) << r.failure;
  return r;
}

using test::scene_path;

// One joint about a vertical axis (gravity along it: no gravity torque), driven
// by a constant voltage: a PIV with zero gains and an offset u0.
PlantConfig one_joint(FrictionParams friction, double La, double u0) {
  RobotModel m;
  m.name = "one joint";
  JointParams J;
  J.mass = 1.0;
  J.com = Eigen::Vector3d(0.1, 0, 0);
  J.inertia = 0.01 * Eigen::Matrix3d::Identity();
  J.rotor_inertia = 1e-4;  // Z^2 Im = 0.25 kg m^2
  J.gear_ratio = 50.0;
  m.joints.push_back(J);
  PlantConfig c;
  c.robot = m;
  c.n = 1;
  c.drive = true;
  c.amplifier = {{2.0, 0.1, 100.0}};  // K_A, R0, V_max
  c.motor = {{La, 1.9, 0.1}};         // La, R, K
  c.friction = {friction};
  c.controller = ControllerMode::kContinuous;
  PivParams P;
  P.offset = u0;
  c.controller_params = LawParams<PivController>{{P}};
  c.q0 = Eigen::VectorXd::Zero(1);
  return c;
}

// Locked rotor (held by the hybrid model's static friction, far above the
// motor torque): i(t) = i_inf (1 - exp(-t / tau)), i_inf = K_A u0 / (R0 + R),
// tau = La / (R0 + R).
TEST(Motor, LockedRotorCurrentRisesWithTimeConstantLaOverR) {
  FrictionParams f;
  f.model = friction_model<HybridFriction>();
  f.static_torque = 1e6;
  Plant plant(one_joint(f, 1e-3, 1.5));
  const double i_inf = 2.0 * 1.5 / 2.0, tau = 1e-3 / 2.0;
  const int i_idx = plant.layout().index("i_motor1");
  ASSERT_GE(i_idx, 0);
  int checked = 0;
  run_rk4(plant, 5 * tau, 1e-6, tau / 4, [&](double t, const double* x) {
    EXPECT_NEAR(x[i_idx], i_inf * (1 - std::exp(-t / tau)), 1e-9) << "t = " << t;
    EXPECT_EQ(x[plant.layout().index("qd1")], 0.0);  // stuck: exactly at rest
    ++checked;
  });
  EXPECT_GE(checked, 20);
}

// Free-running motor with viscous friction B: at steady state K i = B w and
// i = (K_A u0 - K w) / R_t, so w = K K_A u0 / (K^2 + R_t B) (motor side).
TEST(Motor, FreeRunningSteadySpeed) {
  FrictionParams f;
  f.model = friction_model<ViscousFriction>();
  f.viscous = 1e-4;
  Plant plant(one_joint(f, 1e-3, 1.5));
  std::vector<double> x_end;
  run_rk4(plant, 0.6, 2e-5, 0.6, [&](double, const double* x) {
    x_end.assign(x, x + plant.size());
  });
  const double w = 0.1 * 3.0 / (0.01 + 2.0 * 1e-4);
  EXPECT_NEAR(x_end[plant.layout().index("qd1")], w / 50.0, 1e-8 * w);
  EXPECT_NEAR(x_end[plant.layout().index("i_motor1")], 1e-4 * w / 0.1, 1e-8);
}

// The friction rules, case by case (paper sec. 4, Fs_a = 0.146, Fs_b = 0.124):
// at zero speed the friction balances the applied torque up to the static
// level; moving, it is the kinetic level against the motion.
TEST(Friction, RulesCaseByCase) {
  FrictionParams p{friction_model<PaperRuleFriction>(), 0.0, 0.146, 0.124, 1e-6, 1e-2};
  const SlipMode any = SlipMode::kStuck;
  EXPECT_DOUBLE_EQ(friction_torque(p, 0.0, 0.1, any), 0.1);
  EXPECT_DOUBLE_EQ(friction_torque(p, 0.0, -0.1, any), -0.1);
  EXPECT_DOUBLE_EQ(friction_torque(p, 0.0, 0.2, any), 0.146);
  EXPECT_DOUBLE_EQ(friction_torque(p, 0.0, -0.2, any), -0.146);
  EXPECT_DOUBLE_EQ(friction_torque(p, 5e-7, 0.1, any), 0.1);  // inside the "zero" band
  EXPECT_DOUBLE_EQ(friction_torque(p, 0.5, -0.3, any), 0.124);
  EXPECT_DOUBLE_EQ(friction_torque(p, -0.5, 0.3, any), -0.124);
  FrictionParams k = p;
  k.model = friction_model<KarnoppFriction>();
  k.zero_speed = 1e-3;
  k.viscous = 0.01;
  EXPECT_DOUBLE_EQ(friction_torque(k, 5e-4, 0.1, any), 0.1);
  EXPECT_DOUBLE_EQ(friction_torque(k, 2e-3, 0.1, any), 0.124 + 0.01 * 2e-3);
  FrictionParams th = p;
  th.model = friction_model<TanhFriction>();
  th.speed_scale = 0.05;
  EXPECT_DOUBLE_EQ(friction_torque(th, 0.05, 0.0, any), 0.124 * std::tanh(1.0));
  FrictionParams hy = p;
  hy.model = friction_model<HybridFriction>();
  EXPECT_DOUBLE_EQ(friction_torque(hy, 0.0, 0.13, SlipMode::kStuck), 0.13);
  EXPECT_DOUBLE_EQ(friction_torque(hy, 0.01, 0.0, SlipMode::kPositive), 0.124);
  EXPECT_DOUBLE_EQ(friction_torque(hy, -0.01, 0.0, SlipMode::kNegative), -0.124);
  FrictionParams v{friction_model<ViscousFriction>(), 0.02};
  EXPECT_DOUBLE_EQ(friction_torque(v, 3.0, 1.0, any), 0.06);
  EXPECT_DOUBLE_EQ(friction_torque(FrictionParams{}, 3.0, 1.0, any), 0.0);
}

// Hybrid stick/slip: at rest, a ramping motor torque breaks the joint loose
// exactly when K i reaches the static level (closed form from the current
// rise): the root function is positive while stuck, the driver switches the
// joint to slipping at that time (fixed step: at the end of the step that
// crosses it), and the joint then moves forward.
TEST(Friction, HybridBreakAwayAtTheClosedFormTime) {
  FrictionParams f{friction_model<HybridFriction>(), 0.0, 0.146, 0.124, 1e-6, 1e-2};
  Plant plant(one_joint(f, 1e-3, 1.5));  // K i_inf = 0.15 > 0.146: breaks away
  ASSERT_EQ(plant.num_roots(), 1);
  const double tau = 5e-4, i_break = 0.146 / 0.1;
  const double t_break = -tau * std::log(1 - i_break / 1.5);
  std::vector<double> g(1);
  const int qd = plant.layout().index("qd1");
  const RunResult r = run_rk4(plant, 2 * t_break, 1e-6, t_break / 10, [&](double t, const double* x) {
    if (t < 0.99 * t_break) {
      plant.roots(t, x, g.data());
      EXPECT_GT(g[0], 0.0) << t;
      EXPECT_EQ(plant.slip_mode(0), SlipMode::kStuck) << t;
      EXPECT_EQ(x[qd], 0.0) << t;
    }
    if (t > 1.01 * t_break) {
      EXPECT_EQ(plant.slip_mode(0), SlipMode::kPositive) << t;
      EXPECT_GT(x[qd], 0.0) << t;
    }
  });
  EXPECT_EQ(r.root_events, 1);
}

// Hybrid stick/slip on the six-joint paper scene, with every integrator that
// finds roots and with RK4 (sign checks per step): after every event the modes
// are consistent -- a stuck joint sits at exactly zero speed with its applied
// torque within the static level (root function >= 0); otherwise the root
// would start past its zero and never cross it again, and the joint would stay
// stuck for the rest of the run. (Found: joint 1 under cvode-bdf at rtol 1e-4,
// when a located break-away root released the joint only if |applied| > Fs
// there, and at the located point it was not, by rounding.) Every joint whose
// reference moves must slip at some time.
TEST(Friction, HybridModesStayConsistentWithEveryRootFinder) {
  Scene sc = load_scene(scene_path("paper_slow_6dof"));
  for (auto& f : sc.plant.friction) f.model = friction_model<HybridFriction>();
  for (const char* name : {"cvode-bdf", "cvode-adams", "arkode-dirk", "odeint-dopri5", "rk4"}) {
    Plant plant(sc.plant);
    IntegratorOptions o;
    o.rtol = 1e-4, o.atol = 1e-7;
    auto integ = make_integrator(name, o);
    const int n = plant.layout().n;
    std::vector<double> g(n), q_first(n), q_range(n, 0.0);
    std::vector<bool> slipped(n, false);
    bool first = true;
    const RunResult r = run_plant(
        plant, *integ, {.t_end = 4.0, .output_interval = 0.01, .observe = [&](double t, const double* x) {
                          plant.roots(t, x, g.data());
                          for (int j = 0; j < n; ++j) {
                            const double qr = plant.reference_at(t).q[j];
                            if (first) q_first[j] = qr;
                            q_range[j] = std::max(q_range[j], std::abs(qr - q_first[j]));
                            if (plant.slip_mode(j) != SlipMode::kStuck) {
                              slipped[j] = true;
                              continue;
                            }
                            EXPECT_EQ(x[plant.layout().qd + j], 0.0) << name << " joint " << j + 1 << " t = " << t;
                            EXPECT_GE(g[j], -1e-6 * sc.plant.friction[j].static_torque)
                                << name << " joint " << j + 1 << " t = " << t;
                          }
                          first = false;
                        }});
    ASSERT_TRUE(r.ok) << name << ": " << r.failure;
    EXPECT_GT(r.root_events, 0) << name;
    for (int j = 0; j < n; ++j) {
      if (q_range[j] > 0.01) {
        EXPECT_TRUE(slipped[j]) << name << " joint " << j + 1 << " never slipped";
      }
    }
  }
}

// The reference of the six-joint scene: the wrist passes through its
// singularity (q5 changes sign) and the roll q6 beyond pi, yet every angle is
// continuous and its rate consistent with it (central differences), inside
// the joint limits, and the pose is the path point with the fixed orientation.
TEST(Reference, ContinuousThroughTheWristSingularityAndBeyondPi) {
  // paper_slow_6dof with the flange pointing straight down (the scene tilts it
  // to stay clear of the singularity).
  std::string text;
  {
    std::ifstream in(scene_path("paper_slow_6dof"));
    std::stringstream ss;
    ss << in.rdbuf();
    text = std::regex_replace(ss.str(), std::regex("orientation = \\[\\[.*"),
                              "orientation = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]");
  }
  const auto path = testing::scratch_root() / "pumasim_reference_down.toml";
  std::ofstream(path) << text;
  const Scene sc = load_scene(path.string());
  const Reference& ref = *sc.plant.reference;
  const RobotModel& m = sc.plant.robot;
  const double T = ref.timing().duration(), h = 1e-4;
  ReferenceSample a, b, c;
  double q5_min = 1e9, q5_max = -1e9, q6_max = -1e9;
  for (double t = h; t < T - h; t += 0.005) {
    ref.eval(t - h, a);
    ref.eval(t, b);
    ref.eval(t + h, c);
    const Eigen::Matrix<double, 6, 1> rate = (c.q - a.q) / (2 * h);
    EXPECT_LT((rate - b.qd).lpNorm<Eigen::Infinity>(), 1e-4) << "t = " << t;
    for (int j = 0; j < 6; ++j) {
      EXPECT_GE(b.q[j], m.joints[j].q_min) << j;
      EXPECT_LE(b.q[j], m.joints[j].q_max) << j;
    }
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    forward_kinematics<double>(m, b.q, R, p);
    EXPECT_LT((p - b.p).norm(), 1e-9) << "t = " << t;
    EXPECT_LT((R - sc.reference.orientation).norm(), 1e-9) << "t = " << t;
    q5_min = std::min(q5_min, b.q[4]), q5_max = std::max(q5_max, b.q[4]), q6_max = std::max(q6_max, b.q[5]);
  }
  EXPECT_LT(q5_min, 0.0);  // the test crosses the singularity ...
  EXPECT_GT(q5_max, 0.0);
  EXPECT_GT(q6_max, M_PI);  // ... and the roll goes past pi
}

// The energy ledger: for the ODE the balance (mechanical + magnetic)(t) -
// (...)(0) = e_in - e_copper - e_friction holds exactly (power balance of the
// motor equation and the rigid body, friction's power tau_f w_m), so with a
// tight tolerance its residual is a tiny fraction of the energies exchanged
// -- and it shrinks with the tolerance. Leaving out any one term (copper loss,
// friction loss, the magnetic energy) breaks it by far more.
TEST(Plant, EnergyLedgerClosesToTheTolerance) {
  auto residual = [](double rtol, double& scale) {
    const Scene sc = load_scene(scene_path("paper_slow_viscous"), {"scene.energy_ledger=true"});
    Plant plant(sc.plant);
    const int e = plant.layout().e;
    EXPECT_GE(e, 0);
    IntegratorOptions o;
    o.rtol = rtol, o.atol = rtol * 1e-3;
    auto integ = make_integrator("cvode-bdf", o);
    double E0 = 0, worst = 0;
    bool first = true;
    scale = 0;
    run_plant(plant, *integ, {.t_end = 3.0, .output_interval = 0.01, .observe = [&](double, const double* x) {
                                const double E = plant.mechanical_energy(x) + plant.magnetic_energy(x);
                                if (first) E0 = E, first = false;
                                worst = std::max(worst, std::abs(E - E0 - (x[e] - x[e + 1] - x[e + 2])));
                                scale = std::max({scale, x[e], x[e + 1], x[e + 2]});
                              }});
    return worst;
  };
  double scale_tight, scale_loose;
  const double tight = residual(1e-10, scale_tight), loose = residual(1e-5, scale_loose);
  EXPECT_GT(scale_tight, 1.0);  // joules exchanged: the test is not vacuous
  EXPECT_LT(tight, 1e-8 * scale_tight) << tight << " of " << scale_tight;
  EXPECT_LT(tight, loose);
}

Scene smooth_paper_scene() {
  Scene sc = load_scene(scene_path("paper_slow"));
  for (auto& f : sc.plant.friction) f = FrictionParams{friction_model<ViscousFriction>(), 1e-3};
  sc.plant.setpoint_interval = 1e-3;  // held set-points: cheap right-hand side
  return sc;
}

// The reduced model (La = 0) is the limit of the full one: the difference at a
// fixed time shrinks in proportion to La (singular perturbation, O(La)).
TEST(Plant, ReducedModelIsTheLimitOfVanishingInductance) {
  const Scene base = smooth_paper_scene();
  auto final_q = [&](double La) {
    PlantConfig c = base.plant;
    for (auto& m : c.motor) m.inductance = La;
    Plant plant(c);
    const double tau_e = La / 2.1;
    const double dt = La > 0 ? std::min(5e-5, tau_e / 10) : 5e-5;
    Eigen::Vector3d q;
    run_rk4(plant, 0.1, dt, 0.1, [&](double, const double* x) { q = Eigen::Vector3d(x[0], x[1], x[2]); });
    return q;
  };
  const Eigen::Vector3d q0 = final_q(0.0);
  const double d3 = (final_q(1e-3) - q0).norm(), d4 = (final_q(1e-4) - q0).norm(),
               d5 = (final_q(1e-5) - q0).norm();
  EXPECT_GT(d5, 0.0);
  EXPECT_GT(d3 / d4, 5.0) << d3 << " " << d4;
  EXPECT_GT(d4 / d5, 5.0) << d4 << " " << d5;
}

// Forward differences and dual numbers agree; some entries are known exactly.
TEST(Plant, FiniteDifferenceAndExactJacobiansAgree) {
  const Scene sc = smooth_paper_scene();
  Plant plant(sc.plant);
  std::vector<double> x(plant.size());
  plant.initial_state(x.data());
  const StateLayout& L = plant.layout();
  x[L.qd + 0] = 0.1, x[L.qd + 1] = -0.2, x[L.qd + 2] = 0.15;
  x[L.i + 1] += 0.3;
  Eigen::MatrixXd Jfd, Jex;
  PlantSystem sys(plant);
  sys.OdeSystem::jacobian(0.3, x.data(), Jfd);  // forward differences, relative step sqrt(eps)
  plant.jacobian_exact(0.3, x.data(), Jex);
  EXPECT_LT((Jfd - Jex).norm(), 1e-6 * Jex.norm());
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(Jex(L.q + j, L.qd + j), 1.0);                       // q' = qd
    EXPECT_DOUBLE_EQ(Jex(L.i + j, L.i + j), -(0.1 + 2.0) / 0.002);  // di'/di = -(R0 + R)/La
  }
}

// df/dt (what Rosenbrock methods multiply by h d_i) is the limit of difference
// quotients in t over the piece a step starting at t lies in: inside a piece
// the central quotient's error falls like h^2; at t = 0 and at every
// breakpoint, after the time event, the quotient (f(b + 2h) - f(b + h)) / h
// (blind to a jump of f at b itself) converges to it like h; just before the
// end of the motion, where the forward difference would reach past it, the
// backward quotient does. And at some breakpoint the backward quotient does
// not converge to it (falls less than fourfold while h falls 64-fold: the
// check sees the kink). Saturations are lifted so
// that (t, x) stays on one side of their kinks. Three kinds of reference:
// Cartesian with a tabulated speed profile, a joint-space cubic spline (its
// acceleration jumps at t = 0), and a quintic timing law.
void expect_time_derivative_is_the_steps_limit(const std::string& scene, std::vector<std::string> sets) {
  SCOPED_TRACE(scene + (sets.empty() ? "" : " " + sets.front()));
  sets.push_back("amplifier.voltage_limit=1e9");
  sets.push_back("controller.output_limit=1e9");
  const Scene sc = load_scene(scene_path(scene), sets);
  Plant plant(sc.plant);
  const int m = plant.size();
  std::vector<double> x(m), ft(m), fa(m), fb(m);
  plant.initial_state(x.data());
  const StateLayout& L = plant.layout();
  x[L.qd + 0] = 0.1, x[L.qd + 1] = -0.2, x[L.i + 1] += 0.3;
  auto max_diff = [&](double t0, double t1, double h) {  // |(f(t1) - f(t0)) / h - df/dt|, max over states
    plant.rhs(t0, x.data(), fa.data());
    plant.rhs(t1, x.data(), fb.data());
    double e = 0;
    for (int r = 0; r < m; ++r) e = std::max(e, std::abs((fb[r] - fa[r]) / h - ft[r]));
    return e;
  };
  auto expect_ratios = [](const std::vector<double>& e, double lo, double hi, const std::string& what) {
    for (std::size_t k = 0; k + 1 < e.size(); ++k) {
      EXPECT_GT(e[k] / e[k + 1], lo) << what << ", halving " << k;
      EXPECT_LT(e[k] / e[k + 1], hi) << what << ", halving " << k;
    }
  };
  const double T = sc.plant.reference->timing().duration();
  std::vector<double> starts{0.0};  // t = 0 and the breakpoints inside the motion
  for (double b : sc.plant.reference->breakpoints()) {
    if (b < T) starts.push_back(b);
  }
  ASSERT_GE(starts.size(), 1u);
  // Inside the first piece.
  const double first_end = starts.size() > 1 ? starts[1] : T;
  const double t = 0.5 * first_end;
  EXPECT_EQ(plant.time_derivative(t, x.data(), ft.data()), 3);
  double scale = 0;
  for (double v : ft) scale = std::max(scale, std::abs(v));
  ASSERT_GT(scale, 0);
  std::vector<double> central;
  for (double h = 1e-2 * first_end; h > 1e-3 * first_end; h /= 2) central.push_back(max_diff(t - h, t + h, 2 * h));
  expect_ratios(central, 3.5, 4.5, "central, inside the first piece (h^2)");
  // From t = 0 and from each breakpoint, the piece after it.
  bool kink_seen = false;
  for (const double b : starts) {
    if (b > 0) plant.on_time_event(b, x.data());
    plant.time_derivative(b, x.data(), ft.data());
    std::vector<double> forward, backward;
    for (double h = 1e-3; h > 1e-5; h /= 2) {
      forward.push_back(max_diff(b + h, b + 2 * h, h));
      backward.push_back(max_diff(b - h, b, h));
    }
    expect_ratios(forward, 1.7, 2.3, "forward from t = " + std::to_string(b) + " (h)");
    if (b > 0 && backward.back() > 0.25 * backward.front()) kink_seen = true;
  }
  if (starts.size() > 1) {
    EXPECT_TRUE(kink_seen) << "no breakpoint where the backward quotient fails to converge";
  }
  // Just before the end of the motion: the piece before it, continued.
  const double te = T - 2e-6;
  plant.time_derivative(te, x.data(), ft.data());
  std::vector<double> backward;
  for (double h = 1e-3; h > 1e-5; h /= 2) backward.push_back(max_diff(te - h, te, h));
  expect_ratios(backward, 1.7, 2.3, "backward from just before the end (h)");
}

TEST(Plant, TimeDerivativeIsTheLimitOfDifferenceQuotientsOnTheStepsSide) {
  expect_time_derivative_is_the_steps_limit("paper_slow_viscous", {});
  expect_time_derivative_is_the_steps_limit("paper_slow_viscous", {"reference.interpolation=\"joint-cubic\""});
  expect_time_derivative_is_the_steps_limit("smooth_line_quintic", {});
}

TEST(Plant, TimeDerivativeIsZeroWhereFDoesNotDependOnT) {
  const std::vector<std::vector<std::string>> cases{{"controller.mode=\"sampled\"", "controller.servo_period=1e-3"},
                                                     {"controller.setpoint_interval=1e-3"}};
  for (const auto& set : cases) {
    const Scene sc = load_scene(scene_path("paper_slow_viscous"), set);
    Plant plant(sc.plant);
    std::vector<double> x(plant.size()), ft(plant.size(), 1.0);
    plant.initial_state(x.data());
    EXPECT_EQ(plant.time_derivative(0.3, x.data(), ft.data()), 0) << set.front();
    for (double v : ft) EXPECT_EQ(v, 0.0) << set.front();
  }
}

TEST(Plant, StateLayoutHasOnlyTheIncludedBlocks) {
  auto names = [](const std::string& scene) {
    Plant p(load_scene(scene_path(scene)).plant);
    std::string s;
    for (const auto& n : p.layout().names) s += n + " ";
    return s;
  };
  EXPECT_EQ(names("paper_slow"), "q1 q2 q3 qd1 qd2 qd3 i_motor1 i_motor2 i_motor3 z_piv1 z_piv2 z_piv3 ");
  EXPECT_EQ(names("paper_slow_reduced"), "q1 q2 q3 qd1 qd2 qd3 z_piv1 z_piv2 z_piv3 ");
  EXPECT_EQ(names("passive_arm"), "q1 q2 q3 q4 q5 q6 qd1 qd2 qd3 qd4 qd5 qd6 ");
  Scene sampled = load_scene(scene_path("paper_slow"));
  sampled.plant.controller = ControllerMode::kSampled;
  sampled.plant.servo_period = 2.5e-4;
  Plant p(sampled.plant);
  EXPECT_EQ(p.layout().z, -1);  // a sampled PIV's integral is discrete, not a state
  EXPECT_DOUBLE_EQ(p.next_time_event(0.0), 2.5e-4);
  EXPECT_DOUBLE_EQ(p.next_time_event(2.5e-4), 5e-4);
}

// A controller on the reference at t = 0 starts in equilibrium: the initial
// state makes qdd = 0 (the currents hold gravity).
TEST(Plant, StartsInEquilibriumOnTheReference) {
  for (const char* name : {"paper_slow", "paper_slow_6dof", "paper_slow_reduced"}) {
    Scene sc = load_scene(scene_path(name));
    for (auto& f : sc.plant.friction) f = FrictionParams{};
    for (auto& p : law_params<PivController>(sc.plant)) p.kvff = p.kaff = 0;  // no feed-forward at t = 0
    Plant plant(sc.plant);
    std::vector<double> x(plant.size()), f(plant.size());
    plant.initial_state(x.data());
    plant.rhs(0.0, x.data(), f.data());
    for (int j = 0; j < plant.layout().n; ++j) EXPECT_NEAR(f[plant.layout().qd + j], 0.0, 1e-9) << name;
  }
}

TEST(Kinematics, PumaInverseKinematicsReproducesTheForward) {
  const RobotModel puma = load_robot("puma560");
  Rng rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Matrix<double, 6, 1> q;
    for (int j = 0; j < 6; ++j) q[j] = rng.uniform(-M_PI, M_PI);
    q[4] = rng.uniform(0.2, 2.5) * (rng.uniform() < 0.5 ? -1 : 1);  // away from the wrist singularity
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    forward_kinematics<double>(puma, q, R, p);
    bool found = false;
    for (int c = 0; c < 8; ++c) {
      const PumaConfig cfg{(c & 1) != 0, (c & 2) != 0, (c & 4) != 0};
      Eigen::Matrix<double, 6, 1> qi;
      ASSERT_TRUE(puma_ik(puma, p, R, cfg, qi));
      Eigen::Matrix3d Ri;
      Eigen::Vector3d pi;
      forward_kinematics<double>(puma, qi, Ri, pi);
      EXPECT_LT((pi - p).norm(), 1e-12);
      EXPECT_LT((Ri - R).norm(), 1e-12);
      Eigen::Matrix<double, 6, 1> d = qi - q;
      for (int j = 0; j < 6; ++j) d[j] = std::remainder(d[j], 2 * M_PI);
      found |= d.norm() < 1e-9;
    }
    EXPECT_TRUE(found) << "trial " << trial;
  }
}

// The geometric Jacobian against central differences of the forward
// kinematics (position rows) and of the rotation (angular rows, skew(w) = dR R^T),
// in both DH conventions, with and without prismatic joints; its rate on dual
// numbers against central differences of the Jacobian.
TEST(Kinematics, GeometricJacobianMatchesDifferencesOfForwardKinematics) {
  // Mixed chains: a prismatic column is [z; 0] (Siciliano et al. 2009, eq. 3.30).
  for (const RobotModel& m : {load_robot("puma560"), random_chain(6, 77, DhConvention::kModified),
                              random_chain(6, 78, DhConvention::kStandard, "PR"),
                              random_chain(6, 79, DhConvention::kModified, "RPP")}) {
    Rng rng(5);
    Eigen::Matrix<double, 6, 1> q;
    for (int j = 0; j < 6; ++j) q[j] = rng.uniform(-2, 2);
    Eigen::Matrix<double, 6, 6> J;
    geometric_jacobian(m, q, 6, J);
    Eigen::Matrix3d R0, Rp, Rm;
    Eigen::Vector3d p0, pp, pm;
    forward_kinematics<double>(m, q, R0, p0);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Eigen::Matrix<double, 6, 1> a = q, b = q;
      a[k] += h, b[k] -= h;
      forward_kinematics<double>(m, a, Rp, pp);
      forward_kinematics<double>(m, b, Rm, pm);
      const Eigen::Vector3d v = (pp - pm) / (2 * h);
      const Eigen::Matrix3d W = (Rp - Rm) / (2 * h) * R0.transpose();
      EXPECT_LT((J.block<3, 1>(0, k) - v).norm(), 1e-8) << m.name << " column " << k;
      EXPECT_LT((J.block<3, 1>(3, k) - Eigen::Vector3d(W(2, 1), W(0, 2), W(1, 0))).norm(), 1e-8) << m.name;
    }
    // On dual numbers q + eps qd the derivative parts are dJ/dt = J'(q) qd.
    Eigen::Matrix<double, 6, 1> qd;
    for (int j = 0; j < 6; ++j) qd[j] = rng.uniform(-1, 1);
    Eigen::Matrix<Dual, 6, 1> qq;
    for (int j = 0; j < 6; ++j) qq[j] = Dual(q[j], qd[j]);
    Eigen::Matrix<Dual, 6, 6> JJ;
    geometric_jacobian(m, qq, 6, JJ);
    Eigen::Matrix<double, 6, 6> Jp, Jm;
    geometric_jacobian(m, Eigen::Matrix<double, 6, 1>(q + h * qd), 6, Jp);
    geometric_jacobian(m, Eigen::Matrix<double, 6, 1>(q - h * qd), 6, Jm);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) {
        EXPECT_NEAR(JJ(r, c).value(), J(r, c), 1e-15) << m.name;
        EXPECT_NEAR(JJ(r, c).deriv(), (Jp(r, c) - Jm(r, c)) / (2 * h), 1e-8) << m.name;
      }
    }
  }
}

TEST(Scene, ResolvedSceneLoadsBackToTheSameScene) {
  for (const char* name : {"paper_slow", "paper_fast", "paper_slow_6dof", "paper_slow_reduced", "passive_arm"}) {
    const Scene a = load_scene(scene_path(name));
    const std::string text = resolved_toml(a);
    const auto path = testing::scratch_root() / (std::string("resolved_") + name + ".toml");
    std::ofstream(path) << text;
    const std::string again = resolved_toml(load_scene(path.string()));
    // Identical but for the header line naming the source file and the
    // footer naming the files read (the scene file is now the copy).
    const auto body = [](const std::string& r) {
      const std::size_t from = r.find('\n'), to = r.find("\n# input file: ");
      return r.substr(from, to - from);
    };
    EXPECT_EQ(body(text), body(again)) << name;
    EXPECT_NE(again.find("# input file: " + path.string()), std::string::npos) << again;
  }
}

// Bad scene files: exit status 2 from `pumasim check`, one line naming the
// file, the line and the key, nothing on standard output.
class BadScene : public ::testing::Test {
 protected:
  void expect_rejected(const std::string& from, const std::string& to, const std::string& fragment) {
    std::ifstream in(scene_path("paper_slow"));
    std::stringstream buf;
    buf << in.rdbuf();
    std::string text = buf.str();
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    // One file per test: CTest runs the tests in parallel processes.
    const auto path = testing::scratch_root() /
                      (std::string("pumasim_bad_scene_") +
                       ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".toml");
    std::ofstream(path) << text;
    std::ostringstream out, err;
    const int status = run_cli({"check", path.string()}, out, err);
    EXPECT_EQ(status, kExitBadInput) << err.str();
    EXPECT_TRUE(out.str().empty());
    EXPECT_NE(err.str().find(path.string() + ":"), std::string::npos) << err.str();
    EXPECT_NE(err.str().find(fragment), std::string::npos) << err.str();
  }
};

// Command-line overrides: a value replaced, and bad ones named by the
// override itself (the file's line would point at the wrong value).
TEST(SceneOverrides, ReplaceValuesAndNameTheOverrideInErrors) {
  const Scene sc = load_scene(scene_path("paper_slow"), {"motor.inductance=1e-5", "controller.kp=[1, 2, 3]"});
  EXPECT_EQ(sc.plant.motor[2].inductance, 1e-5);
  EXPECT_EQ(law_params<PivController>(sc.plant)[1].kp, 2.0);
  const std::vector<std::pair<std::string, std::string>> bad{
      {"motor.inductance=-1", "--set motor.inductance=-1: motor.inductance: expected a number >= 0, got -1"},
      {"motor.inductanc=1", "--set motor.inductanc=1: unknown key 'motor.inductanc'"},
      {"motor.inductance=abc", "--set motor.inductance=abc: expected section.key=value with a TOML value"},
      {"inductance", "--set inductance: expected section.key=value"},
  };
  for (const auto& [o, fragment] : bad) {
    std::ostringstream out, err;
    const int status = run_cli({"check", scene_path("paper_slow"), "--set", o}, out, err);
    EXPECT_EQ(status, kExitBadInput) << o;
    EXPECT_TRUE(out.str().empty()) << o;
    EXPECT_NE(err.str().find(fragment), std::string::npos) << err.str();
  }
}

TEST_F(BadScene, UnknownKey) {
  expect_rejected("resistance = 2.0", "resistance = 2.0\nresistence = 2.0",
                  "unknown key 'motor.resistence'; expected one of: inductance, resistance");
}
TEST_F(BadScene, KeyThatMeansNothingForTheModel) {
  expect_rejected("model = \"paper\"", "model = \"viscous\"", "_torque'; expected one of: model, viscous");
}
TEST_F(BadScene, WrongType) {
  expect_rejected("inductance = 0.002", "inductance = \"2 mH\"",
                  "motor.inductance: expected a number or an array of 3 numbers (one per joint)");
}
TEST_F(BadScene, NegativeInductance) {
  expect_rejected("inductance = 0.002", "inductance = -0.002",
                  "motor.inductance: expected a number >= 0, got -0.002");
}
TEST_F(BadScene, ZeroServoPeriod) {
  expect_rejected("mode = \"continuous\"", "mode = \"sampled\"\nservo_period = 0.0",
                  "controller.servo_period: expected a number > 0, got 0");
}
TEST_F(BadScene, JointIndexOutOfRange) {
  expect_rejected("joints = 3", "joints = 7", "scene.joints: expected a number in [1, 6], got 7");
}
TEST_F(BadScene, MissingKey) {
  expect_rejected("torque_constant = 0.228", "", "motor: missing required key 'torque_constant'");
}
TEST_F(BadScene, UnknownFrictionModel) {
  expect_rejected("model = \"paper\"", "model = \"coulomb\"",
                  "friction.model: expected one of \"none\", \"viscous\", \"paper\"");
}
TEST_F(BadScene, WrongLengthPerJointArray) {
  expect_rejected("viscous = [1.48e-3, 0.817e-3, 1.38e-3]", "viscous = [1.48e-3, 0.817e-3]",
                  "friction.viscous: expected an array of 3 numbers");
}
TEST_F(BadScene, PathOutOfReach) {
  expect_rejected("height = -0.15", "height = 1.5", "out of reach");
}
TEST_F(BadScene, UnknownTiming) {
  expect_rejected("max_speed = 0.1", "max_speed = 0.1\ntiming = \"bang-bang\"",
                  "reference.timing: expected one of \"table\", \"trapezoid\"");
}
TEST_F(BadScene, TableWithBothSpeedAndDuration) {
  expect_rejected("max_speed = 0.1", "max_speed = 0.1\ntraversal_time = 24.0",
                  "exactly one of max_speed and traversal_time");
}
TEST_F(BadScene, PlanningWithoutTimeOptimalTiming) {
  expect_rejected("[reference]", "[planning]\nvoltage_fraction = 0.5\n\n[reference]",
                  "[planning] only with reference.timing = \"time-optimal\"");
}
TEST_F(BadScene, ViaSegmentsNotWhole) {
  expect_rejected("max_speed = 0.1", "max_speed = 0.1\ninterpolation = \"joint-cubic\"\nvia_segments = 2.5",
                  "reference.via_segments: expected a whole number >= 1");
}
TEST_F(BadScene, UnknownBackend) {
  expect_rejected("backend = \"crba\"", "backend = \"newton\"", "scene.backend: expected one of: aba, crba");
}

// LuGre's bristle mode (models/plant/friction/lugre.hpp): at rest with
// z = 0, dz/dt = w_m to first order, so a joint held by its bristles obeys
// H q'' = -Z^2 sigma0 (q - q0) - Z^2 (sigma1 + B) q' (joint side; z = Z (q -
// q0), the law on the motor shaft). The plant's Jacobian at that state has
// the eigenvalue 0 (z - Z q is constant) and the two roots of
// H s^2 + Z^2 (sigma1 + B) s + Z^2 sigma0 = 0: the stiffness analysis sees
// the bristles. A passive PUMA 560 with only joint 1 simulated (a vertical
// axis: no gravity torque), H from the back-end at q0.
TEST(PlantStiffness, LuGreShowsTheBristleModeOfAStuckJoint) {
  const Scene sc =
      load_scene(scene_path("passive_arm"),
                 {"scene.joints=1", "friction.model=\"lugre\"", "friction.static_torque=0.146",
                  "friction.kinetic_torque=0.124", "friction.stribeck_speed=0.1", "friction.bristle_stiffness=100.0",
                  "friction.bristle_damping=0.6", "friction.viscous=0.001"});
  Plant plant(sc.plant);
  ASSERT_EQ(plant.size(), 3);  // q1, qd1, z_fric1
  std::vector<double> x(3);
  plant.initial_state(x.data());
  EXPECT_EQ(x[2], 0.0);
  Eigen::MatrixXd J;
  plant.jacobian_exact(0.0, x.data(), J);
  const RobotModel sim = simulated_robot(sc.plant.robot, 1, sc.plant.q_held);
  Eigen::MatrixXd H(1, 1);
  find_backend("crba").make(sim)->mass_matrix(Eigen::VectorXd::Constant(1, x[0]), H);
  const double Z = sc.plant.robot.joints[0].gear_ratio, a = H(0, 0), b = Z * Z * (0.6 + 0.001), c = Z * Z * 100.0;
  const std::complex<double> disc = std::sqrt(std::complex<double>(b * b - 4 * a * c));
  std::vector<std::complex<double>> want = {0.0, (-b + disc) / (2 * a), (-b - disc) / (2 * a)};
  const Eigen::EigenSolver<Eigen::MatrixXd> es(J, false);
  std::vector<std::complex<double>> got(es.eigenvalues().data(), es.eigenvalues().data() + 3);
  const auto order = [](const std::complex<double>& u, const std::complex<double>& v) {
    return u.real() != v.real() ? u.real() < v.real() : u.imag() < v.imag();
  };
  std::sort(want.begin(), want.end(), order);
  std::sort(got.begin(), got.end(), order);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(got[k].real(), want[k].real(), 1e-9 * std::abs(want[1])) << k;
    EXPECT_NEAR(got[k].imag(), want[k].imag(), 1e-9 * std::abs(want[1])) << k;
  }
}

// The energy ledger has no account for the bristles' potential energy: a
// scene with both is refused, naming the law.
TEST(PlantStiffness, LuGreWithTheLedgerIsRefused) {
  try {
    load_scene(scene_path("energy_long_time"),
               {"friction.model=\"lugre\"", "friction.static_torque=0.146", "friction.kinetic_torque=0.124",
                "friction.stribeck_speed=0.1", "friction.bristle_stiffness=100.0", "friction.bristle_damping=0.6"});
    ADD_FAILURE() << "loaded";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("lugre's bristles"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pumasim
