// The symplectic midpoint integrator (integrators/symplectic_midpoint.hpp)
// on the lossless, unforced arm: what makes it symplectic tested directly,
// not only its bounded energy (a projection onto the energy surface also
// bounds the energy):
//  - the one-step map's Jacobian P in canonical coordinates z = (q, p)
//    satisfies P' J P = J (Hairer, Lubich & Wanner, Geometric Numerical
//    Integration, 2nd ed., Theorem VI.3.5), to 1e-10 on a 2-joint arm, P
//    from fourth-order central differences of the map; two maps that are
//    not symplectic, measured the same way, miss it by orders of magnitude
//    (the instrument sees a violation);
//  - time reversibility: the step with -h undoes the step with h;
//  - order 2 of the states and of the dense output, against RK4 at a step
//    whose error is far below;
//  - the energy error: bounded (no growth from the first to the last
//    quarter of a long run) and O(h^2);
// and that dL/dq, the force the method integrates, is the gradient of the
// plant's own L = T - V, and that driven or lossy scenes are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "integrators/registry.hpp"
#include "integrators/symplectic_midpoint.hpp"
#include "integrators/testset/problems.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "simulation/run.hpp"
#include "tests/scene_paths.hpp"

namespace pumasim {
namespace {

using test::scene_path;

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

// The passive PUMA of energy_long_time with its first two joints (the others
// held), started off rest so that both joints move and couple.
Scene two_joint_scene() { return load_scene(scene_path("energy_long_time"), {"scene.joints=2"}); }

std::vector<double> moving_start(Plant& plant) {
  std::vector<double> x(static_cast<std::size_t>(plant.size()));
  plant.initial_state(x.data());
  const StateLayout& l = plant.layout();
  const double q[2] = {0.3, -0.5}, qd[2] = {0.8, -1.2};
  for (int j = 0; j < 2; ++j) x[l.q + j] = q[j], x[l.qd + j] = qd[j];
  return x;
}

// The system's mechanics, asserting it has them.
ConservativeMechanics& mechanics_of(PlantSystem& sys) {
  std::string why;
  ConservativeMechanics* m = sys.conservative_mechanics(why);
  EXPECT_NE(m, nullptr) << why;
  return *m;
}

using Map = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

// z = (q, p) -> the canonical midpoint step of size h.
Map canonical_midpoint(ConservativeMechanics& m, double h) {
  return [&m, h](const Eigen::VectorXd& z) {
    const int n = m.dof();
    MidpointScratch s(n);
    Eigen::VectorXd z1 = z;
    const MidpointSolve r = midpoint_step(m, h, z.data(), z.data() + n, z1.data(), z1.data() + n, s);
    EXPECT_TRUE(r.converged) << r.failure;
    return z1;
  };
}

// The canonical vector field F(z) = (M^-1 p, dL/dq(q, M^-1 p)).
Eigen::VectorXd canonical_field(ConservativeMechanics& m, const Eigen::VectorXd& z) {
  const int n = m.dof();
  MidpointScratch s(n);
  Eigen::VectorXd f(2 * n);
  EXPECT_TRUE(midpoint_velocity(m, z.data(), z.data() + n, f.data(), s));
  m.lagrangian_gradient(z.data(), f.data(), f.data() + n);
  return f;
}

// Not symplectic: explicit Euler in (q, p).
Map euler_map(ConservativeMechanics& m, double h) {
  return [&m, h](const Eigen::VectorXd& z) { return Eigen::VectorXd(z + h * canonical_field(m, z)); };
}

// Not symplectic either: the same midpoint rule on the plant's own state
// (q, qd), x1 = x0 + h f((x0 + x1) / 2), iterated to round-off, seen in
// (q, p). The rule is symplectic only in canonical coordinates.
Map velocity_midpoint(Plant& plant, ConservativeMechanics& m, const std::vector<double>& x_template, double h) {
  return [&plant, &m, x_template, h](const Eigen::VectorXd& z) {
    const int n = m.dof();
    MidpointScratch s(n);
    std::vector<double> x0 = x_template;
    for (int j = 0; j < n; ++j) x0[m.position(j)] = z[j];
    EXPECT_TRUE(midpoint_velocity(m, z.data(), z.data() + n, s.q_next.data(), s));
    for (int j = 0; j < n; ++j) x0[m.velocity(j)] = s.q_next[j];
    std::vector<double> x1 = x0, xm(x0.size()), f(x0.size());
    for (int it = 0; it < 200; ++it) {
      for (std::size_t i = 0; i < x0.size(); ++i) xm[i] = 0.5 * (x0[i] + x1[i]);
      plant.rhs(0.0, xm.data(), f.data());
      for (std::size_t i = 0; i < x0.size(); ++i) x1[i] = x0[i] + h * f[i];
    }
    Eigen::VectorXd q1(n), qd1(n), z1(2 * n);
    for (int j = 0; j < n; ++j) q1[j] = x1[m.position(j)], qd1[j] = x1[m.velocity(j)];
    midpoint_momentum(m, q1.data(), qd1.data(), z1.data() + n, s);
    z1.head(n) = q1;
    return z1;
  };
}

// P = dPhi/dz by the five-point central difference (error O(d^4)), each
// column's step d_k = 1e-3 max(1, |z_k|).
Eigen::MatrixXd map_jacobian(const Map& phi, const Eigen::VectorXd& z) {
  const int m = static_cast<int>(z.size());
  Eigen::MatrixXd P(m, m);
  for (int k = 0; k < m; ++k) {
    const double d = 1e-3 * std::max(1.0, std::abs(z[k]));
    Eigen::VectorXd e = Eigen::VectorXd::Zero(m);
    e[k] = d;
    P.col(k) = (-phi(z + 2 * e) + 8 * phi(z + e) - 8 * phi(z - e) + phi(z - 2 * e)) / (12 * d);
  }
  return P;
}

// max |P' J P - J| over the entries, J = [0 I; -I 0].
double symplecticity_defect(const Eigen::MatrixXd& P) {
  const int n = static_cast<int>(P.rows()) / 2;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  J.topRightCorner(n, n) = Eigen::MatrixXd::Identity(n, n);
  J.bottomLeftCorner(n, n) = -Eigen::MatrixXd::Identity(n, n);
  return (P.transpose() * J * P - J).cwiseAbs().maxCoeff();
}

Eigen::VectorXd canonical_start(Plant& plant, ConservativeMechanics& m) {
  const std::vector<double> x = moving_start(plant);
  const int n = m.dof();
  Eigen::VectorXd q(n), qd(n), z(2 * n);
  for (int j = 0; j < n; ++j) q[j] = x[m.position(j)], qd[j] = x[m.velocity(j)];
  MidpointScratch s(n);
  midpoint_momentum(m, q.data(), qd.data(), z.data() + n, s);
  z.head(n) = q;
  return z;
}

// dL/dq = Mdot qd - h(q, qd) (Plant::lagrangian_gradient) is the gradient in
// q, at fixed qd, of the plant's own L = T - V = 2 T - E (its energy:
// mechanical_energy), by central differences (step 1e-5: truncation about
// 1e-10 times L's third derivative, rounding about 1e-16 |L| / 1e-5).
TEST(SymplecticMidpoint, ItsForceIsTheGradientOfThePlantsLagrangian) {
  // The PUMA (2 and 6 joints), the Stanford arm (a prismatic joint) and the
  // Panda (7 joints); Plant::lagrangian_gradient needs no lossless scene.
  const std::vector<std::pair<std::string, std::string>> cases = {{"energy_long_time", "scene.joints=2"},
                                                                  {"energy_long_time", "scene.joints=6"},
                                                                  {"stanford_passive", ""},
                                                                  {"panda_passive", ""}};
  for (const auto& [scene, set] : cases) {
    SCOPED_TRACE(scene + " " + set);
    std::vector<std::string> overrides;
    if (!set.empty()) overrides.push_back(set);
    Plant plant(load_scene(scene_path(scene), overrides).plant);
    const StateLayout& l = plant.layout();
    const int n = l.n;
    std::vector<double> x(static_cast<std::size_t>(plant.size()));
    plant.initial_state(x.data());
    for (int j = 0; j < n; ++j) x[l.q + j] += 0.02 * (j + 1) - 0.05, x[l.qd + j] = 0.7 - 0.3 * j;
    std::vector<double> g(n);
    plant.lagrangian_gradient(x.data() + l.q, x.data() + l.qd, g.data());
    const auto lagrangian = [&](std::vector<double> xs) {
      double kinetic = 0;
      const double energy = plant.mechanical_energy(xs.data(), &kinetic);
      return 2 * kinetic - energy;
    };
    double scale = 0;
    for (int i = 0; i < n; ++i) scale = std::max(scale, std::abs(g[i]));
    for (int i = 0; i < n; ++i) {
      const double d = 1e-5;
      std::vector<double> xp = x, xm = x;
      xp[l.q + i] += d, xm[l.q + i] -= d;
      const double fd = (lagrangian(xp) - lagrangian(xm)) / (2 * d);
      EXPECT_NEAR(g[i], fd, 1e-7 * std::max(1.0, scale)) << "joint " << i + 1;
    }
  }
}

// P' J P = J to 1e-10 at h = 0.05 s (a large step: the iterations take more
// than ten rounds), where the two non-symplectic maps miss it by more than
// 1e-6: explicit Euler by O(h^2), the midpoint rule in (q, qd) by more than
// a thousand times the bound.
TEST(SymplecticMidpoint, TheOneStepMapIsSymplectic) {
  Plant plant(two_joint_scene().plant);
  PlantSystem sys(plant);
  ConservativeMechanics& m = mechanics_of(sys);
  const Eigen::VectorXd z = canonical_start(plant, m);
  const double h = 0.05;
  const double defect = symplecticity_defect(map_jacobian(canonical_midpoint(m, h), z));
  EXPECT_LT(defect, 1e-10);
  const double euler = symplecticity_defect(map_jacobian(euler_map(m, h), z));
  EXPECT_GT(euler, 1e-6);
  std::vector<double> x = moving_start(plant);
  const double in_velocities = symplecticity_defect(map_jacobian(velocity_midpoint(plant, m, x, h), z));
  EXPECT_GT(in_velocities, 1e-6);
  RecordProperty("defect", sci(defect));
  RecordProperty("euler_defect", sci(euler));
  RecordProperty("velocity_midpoint_defect", sci(in_velocities));
}

// Phi_{-h}(Phi_h(z)) = z to rounding (1e-13 relative), where explicit Euler
// forward and back misses by O(h^2).
TEST(SymplecticMidpoint, TheStepIsTimeReversible) {
  Plant plant(two_joint_scene().plant);
  PlantSystem sys(plant);
  ConservativeMechanics& m = mechanics_of(sys);
  const Eigen::VectorXd z = canonical_start(plant, m);
  for (double h : {0.01, 0.05}) {
    const Eigen::VectorXd back = canonical_midpoint(m, -h)(canonical_midpoint(m, h)(z));
    double worst = 0;
    for (int i = 0; i < z.size(); ++i)
      worst = std::max(worst, std::abs(back[i] - z[i]) / std::max(1.0, std::abs(z[i])));
    RecordProperty("reversal_" + sci(h), sci(worst));
    EXPECT_LT(worst, 1e-13) << "h " << h;
    const Eigen::VectorXd euler = euler_map(m, -h)(euler_map(m, h)(z));
    EXPECT_GT((euler - z).cwiseAbs().maxCoeff(), 1e-6) << "h " << h;
  }
}

// The state after T through the integrator interface.
std::vector<double> state_after(Plant& plant, const std::string& method, double dt, double T,
                                double* dense_at = nullptr, std::vector<double>* dense = nullptr) {
  PlantSystem sys(plant);
  IntegratorOptions o;
  o.dt = dt;
  auto integ = make_integrator(method, o);
  const std::vector<double> x0 = moving_start(plant);
  integ->reset(sys, 0.0, x0.data());
  if (dense_at) {
    while (integ->time() < *dense_at) EXPECT_EQ(integ->step_toward(T).status, Outcome::kReached);
    dense->resize(x0.size());
    integ->dense_state(*dense_at, dense->data());
  }
  EXPECT_EQ(integ->advance_to(T).status, Outcome::kReached);
  return {integ->state(), integ->state() + plant.size()};
}

double max_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double e = 0;
  for (std::size_t i = 0; i < a.size(); ++i) e = std::max(e, std::abs(a[i] - b[i]));
  return e;
}

// Order 2 (within 0.2) of the state at 1 s and of the dense output read at
// 0.5 s + dt/3 (never a step's end), on dt = 0.02, 0.01, 0.005; the
// reference: RK4 at dt = 1e-4 (its error, about (1e-4)^4 times the
// solution's fifth derivative, is below 1e-12 here: far under the smallest
// midpoint error, about 1e-6).
TEST(SymplecticMidpoint, ConvergesAtOrderTwoWithItsDenseOutput) {
  Plant plant(two_joint_scene().plant);
  const std::vector<double> ref = state_after(plant, "rk4", 1e-4, 1.0);
  std::vector<double> errors, dense_errors;
  for (double dt : {0.02, 0.01, 0.005}) {
    double t_read = 0.5 + dt / 3;
    std::vector<double> dense, dense_ref;
    errors.push_back(max_difference(state_after(plant, "symplectic-midpoint", dt, 1.0, &t_read, &dense), ref));
    const std::vector<double> at_read = state_after(plant, "rk4", 1e-4, t_read);
    dense_errors.push_back(max_difference(dense, at_read));
  }
  for (std::size_t k = 0; k < errors.size(); ++k) {
    RecordProperty("error_" + std::to_string(k), sci(errors[k]));
    RecordProperty("dense_error_" + std::to_string(k), sci(dense_errors[k]));
  }
  for (std::size_t k = 0; k + 1 < errors.size(); ++k) {
    EXPECT_NEAR(std::log2(errors[k] / errors[k + 1]), 2.0, 0.2) << errors[k] << " " << errors[k + 1];
    EXPECT_NEAR(std::log2(dense_errors[k] / dense_errors[k + 1]), 2.0, 0.3)
        << dense_errors[k] << " " << dense_errors[k + 1];
  }
}

// The energy error over 2000 s at a fixed step: its largest value over the
// last quarter of the run no more than 1.5 times that over the first
// quarter (bounded, oscillating: backward error analysis, ibid. Theorem
// IX.8.1), and O(h^2): halving dt divides it by 4 (between 3 and 5). RK4,
// measured the same way, drifts: its last quarter's exceeds 1.5 times its
// first's.
struct EnergyQuarters {
  double first = 0, last = 0;  // max |E - E0| over the first and the last quarter of [0, T]
};

EnergyQuarters energy_quarters(Plant& plant, const std::string& method, double dt, double T) {
  PlantSystem sys(plant);
  IntegratorOptions o;
  o.dt = dt;
  auto integ = make_integrator(method, o);
  std::vector<double> x0 = moving_start(plant);
  const double e0 = plant.mechanical_energy(x0.data());
  integ->reset(sys, 0.0, x0.data());
  EnergyQuarters q;
  std::vector<double> x(x0.size());
  while (integ->time() < T) {
    EXPECT_EQ(integ->step_toward(T).status, Outcome::kReached);
    std::copy(integ->state(), integ->state() + plant.size(), x.begin());
    const double err = std::abs(plant.mechanical_energy(x.data()) - e0);
    if (integ->time() <= T / 4) q.first = std::max(q.first, err);
    if (integ->time() >= 3 * T / 4) q.last = std::max(q.last, err);
  }
  return q;
}

TEST(SymplecticMidpoint, EnergyErrorStaysBoundedAndIsOrderTwo) {
  Plant plant(two_joint_scene().plant);
  const double T = 2000.0;
  std::vector<double> overall;
  for (double dt : {0.02, 0.01}) {
    const EnergyQuarters q = energy_quarters(plant, "symplectic-midpoint", dt, T);
    RecordProperty("first_quarter_" + sci(dt), sci(q.first));
    RecordProperty("last_quarter_" + sci(dt), sci(q.last));
    EXPECT_LE(q.last, 1.5 * q.first) << "dt " << dt << ": first quarter " << q.first << ", last " << q.last;
    overall.push_back(std::max(q.first, q.last));
  }
  // The instrument sees a drift: RK4 at the larger step, not symplectic.
  const EnergyQuarters rk4 = energy_quarters(plant, "rk4", 0.02, T);
  RecordProperty("rk4_first_quarter", sci(rk4.first));
  RecordProperty("rk4_last_quarter", sci(rk4.last));
  EXPECT_GT(rk4.last, 1.5 * rk4.first) << "first quarter " << rk4.first << ", last " << rk4.last;
  EXPECT_GT(overall[0] / overall[1], 3.0) << overall[0] << " " << overall[1];
  EXPECT_LT(overall[0] / overall[1], 5.0) << overall[0] << " " << overall[1];
}

// Refused where it does not apply: the front door names the scene's reason
// (a driven arm, a lossy joint), and the integrator itself a system without
// the structure (the test set's Prothero-Robinson problem).
TEST(SymplecticMidpoint, RefusesWhatIsNotLosslessAndUnforced) {
  RunOptions a;
  a.integrator = "symplectic-midpoint";
  a.dt = 1e-3;
  const auto refusal = [&](const Scene& sc) {
    try {
      plan_run(sc, a);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal(load_scene(scene_path("paper_slow_viscous"))).find("the arm is driven"), std::string::npos);
  EXPECT_NE(refusal(load_scene(scene_path("energy_long_time"), {"friction.model=\"viscous\""}))
                .find("joint 1 has friction (friction.model = \"viscous\")"),
            std::string::npos);
  EXPECT_EQ(refusal(load_scene(scene_path("energy_long_time"))), "accepted");
  auto problem = testset::prothero_robinson(-5.0);
  IntegratorOptions o;
  auto integ = make_integrator("symplectic-midpoint", o);
  EXPECT_THROW(integ->reset(*problem, 0.0, problem->initial_value().data()), std::invalid_argument);
}

// The registry entry says what the instance is (the conformance suite's
// check, which leaves conservative-only methods out).
TEST(SymplecticMidpoint, RegistryEntryDescribesTheMethod) {
  const IntegratorInfo& i = find_integrator("symplectic-midpoint");
  IntegratorOptions o;
  const IntegratorCapabilities c = i.make(o)->capabilities();
  const IntegratorCapabilities e = capabilities_of(i);
  EXPECT_TRUE(i.conservative_only);
  EXPECT_EQ(c.order, i.order);
  EXPECT_EQ(c.implicit, e.implicit);
  EXPECT_EQ(c.adaptive, e.adaptive);
  EXPECT_EQ(c.uses_jacobian, e.uses_jacobian);
  EXPECT_EQ(c.finds_roots, e.finds_roots);
  EXPECT_EQ(c.set_valued_friction, e.set_valued_friction);
}

}  // namespace
}  // namespace pumasim
