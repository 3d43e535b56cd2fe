// The plant's blocks on their own: the friction registry, the one PIV law and
// its integral bound, and the state slices the blocks declare.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"

#ifndef PUMASIM_SCENES_DIR
#error "PUMASIM_SCENES_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

// The laws' interfaces as C++20 concepts (friction/registry.hpp,
// controller/registry.hpp): every registered law satisfies its concept (the
// lists require it; checked again here), and a type that lacks one member,
// or has it with the wrong type, does not.
struct FrictionLawWithoutTorque {
  static constexpr const char* kName = "half";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{};
};
struct FrictionLawWithAnIntegerName : TanhFriction {
  static constexpr int kName = 3;
};
struct PivWithoutHold : PivController {
  using PivController::PivController;
  void hold() const {}
};

TEST(LawConcepts, EveryRegisteredLawSatisfiesItsConceptAndAPartialOneDoesNot) {
  FrictionLaws::for_each([](auto law) { static_assert(FrictionLaw<decltype(law)>); });
  ControllerLaws::for_each([](auto tag) { static_assert(ControllerLaw<typename decltype(tag)::Law>); });
  static_assert(!FrictionLaw<FrictionLawWithoutTorque>);
  static_assert(!FrictionLaw<FrictionLawWithAnIntegerName>);
  static_assert(!FrictionLaw<int>);
  static_assert(ControllerLaw<PivController>);
  static_assert(!ControllerLaw<PivWithoutHold>);
  static_assert(!ControllerLaw<TanhFriction>);
}

TEST(FrictionRegistry, EveryLawHasAUniqueNameThatReadsBack) {
  std::set<std::string> names;
  std::set<int> models;
  FrictionLaws::for_each([&](auto law) {
    using L = decltype(law);
    EXPECT_TRUE(names.insert(L::kName).second) << L::kName;
    EXPECT_TRUE(models.insert(friction_model<L>().index).second) << L::kName;
    FrictionModel m{};
    ASSERT_TRUE(friction_model_from_name(L::kName, &m)) << L::kName;
    EXPECT_EQ(m, friction_model<L>());
    EXPECT_STREQ(to_string(friction_model<L>()), L::kName);
    // An event-driven law needs the torque it must resist (to know when it breaks away).
    if (L::kStickSlipEvents) {
      EXPECT_TRUE(L::kNeedsAppliedTorque) << L::kName;
    }
  });
  FrictionModel m{};
  EXPECT_FALSE(friction_model_from_name("coulomb", &m));
}

// Every law but none opposes the motion (torque has the sign of the speed)
// away from "zero" speed, and none gives 0.
TEST(FrictionRegistry, EveryLawOpposesTheMotion) {
  FrictionParams base{friction_model<NoFriction>(), 0.01, 0.146, 0.124, 1e-6, 1e-2};
  base.sigmoid_level = 0.6, base.sigmoid_slope = 10.0, base.sigmoid_offset = -0.046;  // a negative phi3, as joint 3's
  FrictionLaws::for_each([&](auto law) {
    using L = decltype(law);
    FrictionParams f = base;
    f.model = friction_model<L>();
    for (double w : {-3.0, -0.5, 0.5, 3.0}) {
      const SlipMode mode = w > 0 ? SlipMode::kPositive : SlipMode::kNegative;
      const double tf = friction_torque(f, w, 0.0, mode);
      if (friction_model<L>() == friction_model<NoFriction>()) {
        EXPECT_EQ(tf, 0.0);
      } else {
        EXPECT_GT(tf * w, 0.0) << L::kName << " w = " << w;
      }
    }
  });
}

// The sigmoid law (Gaz et al., IEEE RA-L 4(4), 2019) is its exp form
// phi1/(1+exp(-phi2 (w+phi3))) - phi1/(1+exp(-phi2 phi3)) + B w, 0 at rest,
// its slope there phi1 phi2/4 sech^2(phi2 phi3/2) + B; and a joint-side set
// behind a gear Z (either sign) acts on the joint as the motor-side set
// (phi1/|Z|, phi2/|Z|, Z phi3): Z tau_m(Z qd) = tau_joint(qd).
TEST(FrictionRegistry, SigmoidIsGazEtAlsLawOnEitherSide) {
  FrictionParams f;
  f.model = friction_model<SigmoidFriction>();
  f.sigmoid_level = 0.55, f.sigmoid_slope = 40.0, f.sigmoid_offset = 0.03, f.viscous = 0.002;
  const auto exp_form = [](const FrictionParams& p, double w) {
    return p.sigmoid_level / (1 + std::exp(-p.sigmoid_slope * (w + p.sigmoid_offset))) -
           p.sigmoid_level / (1 + std::exp(-p.sigmoid_slope * p.sigmoid_offset)) + p.viscous * w;
  };
  EXPECT_EQ(friction_torque(f, 0.0, 0.0, SlipMode::kStuck), 0.0);
  for (double w : {-2.0, -0.1, -0.01, 0.004, 0.05, 1.5, 30.0}) {
    EXPECT_NEAR(friction_torque(f, w, 0.0, SlipMode::kStuck), exp_form(f, w), 1e-15) << w;
  }
  const double h = 1e-6, sech = 1 / std::cosh(0.5 * 40.0 * 0.03);
  EXPECT_NEAR((friction_torque(f, h, 0.0, SlipMode::kStuck) - friction_torque(f, -h, 0.0, SlipMode::kStuck)) / (2 * h),
              0.55 * 40.0 / 4 * sech * sech + 0.002, 1e-8);
  for (double Z : {100.0, -50.0}) {
    FrictionParams m = f;
    m.viscous = 0.0;
    FrictionParams joint = m;
    m.sigmoid_level = joint.sigmoid_level / std::abs(Z);
    m.sigmoid_slope = joint.sigmoid_slope / std::abs(Z);
    m.sigmoid_offset = Z * joint.sigmoid_offset;
    for (double qd : {-1.0, -0.02, 0.01, 0.7}) {
      EXPECT_NEAR(Z * friction_torque(m, Z * qd, 0.0, SlipMode::kStuck), exp_form(joint, qd), 1e-14) << Z << " " << qd;
    }
  }
}

// The smooth Stribeck law (Simscape's Rotational Friction form,
// models/plant/friction/stribeck.hpp):
//   tau_f = sqrt(2e) (Fs - Fk) exp(-(w/w_St)^2) (w/w_St) + Fk tanh(w/w_C) + B w.
// Its steady-state curve: the formula written out here, odd in w; with
// Fk = B = 0 it peaks at exactly Fs at w = w_St / sqrt(2) (the maximum of
// sqrt(2e) x exp(-x^2), at x = 1/sqrt(2), is 1), and in general its value
// there is (Fs - Fk) + Fk tanh(w_St / (sqrt(2) w_C)) + B w_St / sqrt(2);
// at large speed it tends to Fk + B w; its slope at rest is
// sqrt(2e) (Fs - Fk) / w_St + Fk / w_C + B.
TEST(FrictionRegistry, StribeckIsSimscapesCurve) {
  FrictionParams f;
  f.model = friction_model<StribeckFriction>();
  f.static_torque = 0.146, f.kinetic_torque = 0.124, f.viscous = 0.002;  // the paper's Fs, Fk; B chosen
  f.stribeck_speed = 0.1 * std::sqrt(2.0), f.speed_scale = 0.01;         // Simscape's w_brk = 0.1 rad/s
  const auto curve = [](const FrictionParams& p, double w) {
    const double x = w / p.stribeck_speed;
    return std::sqrt(2 * std::exp(1.0)) * (p.static_torque - p.kinetic_torque) * std::exp(-x * x) * x +
           p.kinetic_torque * std::tanh(w / p.speed_scale) + p.viscous * w;
  };
  EXPECT_EQ(friction_torque(f, 0.0, 0.0, SlipMode::kStuck), 0.0);
  for (double w : {-5.0, -0.3, -0.1, -0.004, 0.002, 0.05, 0.1, 0.7, 40.0}) {
    EXPECT_NEAR(friction_torque(f, w, 0.0, SlipMode::kStuck), curve(f, w), 1e-15) << w;
    EXPECT_EQ(friction_torque(f, -w, 0.0, SlipMode::kStuck), -friction_torque(f, w, 0.0, SlipMode::kStuck)) << w;
  }
  const double w_brk = f.stribeck_speed / std::sqrt(2.0);
  EXPECT_NEAR(friction_torque(f, w_brk, 0.0, SlipMode::kStuck),
              (0.146 - 0.124) + 0.124 * std::tanh(w_brk / 0.01) + 0.002 * w_brk, 1e-15);
  EXPECT_NEAR(friction_torque(f, 1e3, 0.0, SlipMode::kStuck), 0.124 + 0.002 * 1e3, 1e-12);
  const double h = 1e-7;
  EXPECT_NEAR((friction_torque(f, h, 0.0, SlipMode::kStuck) - friction_torque(f, -h, 0.0, SlipMode::kStuck)) / (2 * h),
              std::sqrt(2 * std::exp(1.0)) * 0.022 / f.stribeck_speed + 0.124 / 0.01 + 0.002, 1e-5);
  // Fk = B = 0: the peak is Fs, at w_brk, and nowhere above it.
  FrictionParams g = f;
  g.kinetic_torque = 0, g.viscous = 0;
  EXPECT_NEAR(friction_torque(g, w_brk, 0.0, SlipMode::kStuck), 0.146, 1e-15);
  double peak = 0;
  for (int k = 1; k <= 20000; ++k) peak = std::max(peak, friction_torque(g, 1e-5 * k, 0.0, SlipMode::kStuck));
  EXPECT_LE(peak, 0.146 * (1 + 1e-15));
  EXPECT_GT(peak, 0.146 * (1 - 1e-8));
}

// Break-away under a slow torque ramp: a shaft of inertia J under
// tau_a = r t, J w' = tau_a - tau_f(w), starting on the curve, creeps along the
// rising branch of the curve (tau_f(w) = tau_a, quasi-statically) until
// tau_a passes the curve's peak P (Fs to within Fk (1 - tanh(w_brk / w_C)),
// 4e-9 Fk here, with B = 0), then runs away. So it breaks away (its speed
// past 10 w_brk) after P, late by the lag of a slowly swept fold, of order
// (r J)^(2/3) c^(-1/3) (c = -tau_f'' at the peak: the fold's Riccati equation
// J u' = r s + c u^2 / 2), plus the run-away's time, of order r: the excess
// shrinks with r at an order between 2/3 and 1, and extrapolating the two
// slowest ramps with the fold's order 2/3 gives P to within 1 % of the
// Stribeck rise Fs - Fk. (A law whose peak lacked the sqrt(2e) factor would
// break away near 0.1334 N m, 57 % of the rise below 0.146.)
TEST(FrictionRegistry, StribeckBreaksAwayAtItsPeak) {
  FrictionParams f;
  f.model = friction_model<StribeckFriction>();
  f.static_torque = 0.146, f.kinetic_torque = 0.124, f.viscous = 0.0;
  f.stribeck_speed = 0.1 * std::sqrt(2.0), f.speed_scale = 0.01;
  const double J = 1e-3, w_brk = 0.1;  // [kg m^2], [rad/s]
  std::vector<double> excess;
  for (double r : {0.02, 0.005, 0.00125}) {  // [N m/s], each a quarter of the last
    const auto f_of = [&](double t, double w) { return (r * t - friction_torque(f, w, 0.0, SlipMode::kStuck)) / J; };
    // From 90 % of the peak, on the rising branch's quasi-static point
    // (tau_f(w0) = r t0, by bisection on [0, w_brk] where tau_f rises): the
    // creep before it is slow and costs most of the steps.
    double t = 0.9 * 0.146 / r, lo = 0, hi = w_brk;
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      (friction_torque(f, mid, 0.0, SlipMode::kStuck) < r * t ? lo : hi) = mid;
    }
    double w = lo;
    const double dt = 1e-4;  // [s] RK4: h lambda = 1.3 at the creep's fastest (J / slope at rest), stable
    while (w < 10 * w_brk && t < 2 * 0.146 / r) {
      const double k1 = f_of(t, w), k2 = f_of(t + dt / 2, w + dt / 2 * k1), k3 = f_of(t + dt / 2, w + dt / 2 * k2),
                   k4 = f_of(t + dt, w + dt * k3);
      w += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      t += dt;
    }
    ASSERT_GE(w, 10 * w_brk) << r;  // it broke away
    excess.push_back(r * t - 0.146);
    EXPECT_GT(excess.back(), -1e-6) << r;  // not before the peak (up to its 4e-9 Fk and one step)
  }
  for (std::size_t k = 1; k < excess.size(); ++k) {
    const double order = std::log(excess[k - 1] / excess[k]) / std::log(4.0);
    EXPECT_GT(order, 0.5) << k;
    EXPECT_LT(order, 1.0) << k;
  }
  const double g = std::pow(4.0, 2.0 / 3.0);  // the fold's order: excess ~ r^(2/3)
  const double peak = 0.146 + (g * excess[2] - excess[1]) / (g - 1);
  EXPECT_NEAR(peak, 0.146, 0.01 * (0.146 - 0.124));
}

// LuGre (Canudas de Wit et al., IEEE TAC 40(3), 1995; models/plant/friction/
// lugre.hpp) at a constant speed w: dz/dt = w - a z with a = sigma0 |w| / G(w),
// so z(t) = (w / a)(1 - exp(-a t)) from z = 0, and it settles at
// z_ss = sgn(w) G(w) / sigma0, where the friction is the Stribeck curve
// sgn(w) G(w) + B w (the paper's eq. (5)), G(w) = Fk + (Fs - Fk) exp(-(w/vs)^2):
// Fs just off rest, Fk + B w at speed. The registry's torque without the
// state is that curve.
TEST(FrictionRegistry, LuGreSteadyStateIsItsStribeckCurve) {
  FrictionParams f;
  f.model = friction_model<LuGreFriction>();
  f.static_torque = 0.146, f.kinetic_torque = 0.124, f.viscous = 0.002;          // the paper's Fs, Fk; B chosen
  f.stribeck_speed = 0.1, f.bristle_stiffness = 100.0, f.bristle_damping = 0.6;  // chosen
  ASSERT_EQ(friction_states(f.model), 1);
  for (double w : {-3.0, -0.1, -0.02, 0.001, 0.05, 0.1, 0.4, 20.0}) {
    const double G = 0.124 + 0.022 * std::exp(-(w / 0.1) * (w / 0.1));
    const double z_ss = (w > 0 ? 1 : -1) * G / 100.0;
    EXPECT_NEAR(friction_rate(f, w, z_ss), 0.0, 1e-15 * std::max(1.0, std::abs(w))) << w;
    const double curve = (w > 0 ? 1 : -1) * G + 0.002 * w;
    EXPECT_NEAR(friction_state_torque(f, w, z_ss, 0.0), curve, 1e-15) << w;
    EXPECT_NEAR(friction_torque(f, w, 0.0, SlipMode::kStuck), curve, 1e-15) << w;
    // The transient from z = 0, in closed form, against the law's rate at its points.
    const double a = 100.0 * std::abs(w) / G;
    for (double t : {0.0, 0.3 / a, 2.0 / a}) {
      const double z = w / a * (1 - std::exp(-a * t)), dz = w * std::exp(-a * t);
      EXPECT_NEAR(friction_rate(f, w, z), dz, 1e-14 * std::max(1.0, std::abs(w))) << w << " " << t;
      EXPECT_NEAR(friction_state_torque(f, w, z, dz), 100.0 * z + 0.6 * dz + 0.002 * w, 1e-15);
    }
  }
  EXPECT_NEAR(friction_torque(f, 1e-9, 0.0, SlipMode::kStuck), 0.146, 1e-9);
  EXPECT_NEAR(friction_torque(f, 50.0, 0.0, SlipMode::kStuck), 0.124 + 0.002 * 50.0, 1e-15);
  EXPECT_NEAR(friction_state_bound(f), 0.146 / 100.0, 1e-18);  // Property 1: |z| <= Fs / sigma0
}

// Break-away under a slow torque ramp, J w' = r t - tau_f(w, z) with the
// bristles' state: below Fs the bristles hold (z follows r t / sigma0, the
// shaft creeps at about r / sigma0); the steady-state curve falls from Fs
// at rest, so the shaft breaks away (speed past 10 vs) once the ramp passes
// Fs, later by less the slower the ramp: each ramp a quarter of the last,
// the excess shrinks, and the slowest breaks away within 1 % of the Stribeck
// rise Fs - Fk above Fs. No run's bristles leave |z| <= Fs / sigma0.
TEST(FrictionRegistry, LuGreBreaksAwayAtFs) {
  FrictionParams f;
  f.model = friction_model<LuGreFriction>();
  f.static_torque = 0.146, f.kinetic_torque = 0.124, f.viscous = 0.0;
  f.stribeck_speed = 0.1, f.bristle_stiffness = 100.0, f.bristle_damping = 0.6;
  const double J = 1e-3;  // [kg m^2]; the bristle mode sqrt(sigma0 / J) = 316 rad/s, damped (ratio 0.95)
  double previous = HUGE_VAL, z_max = 0;
  for (double r : {0.02, 0.005, 0.00125}) {  // [N m/s]
    const auto rates = [&](double t, const std::array<double, 2>& y) {
      const double zd = friction_rate(f, y[0], y[1]);
      return std::array<double, 2>{(r * t - friction_state_torque(f, y[0], y[1], zd)) / J, zd};
    };
    // From 90 % of Fs on the presliding regime's quasi-static point: sigma0 z = r t, so
    // dz/dt = r / sigma0 = w (1 - sigma0 z / G(0)) gives w = (r / sigma0) / (1 - 0.9).
    double t = 0.9 * 0.146 / r;
    std::array<double, 2> y{r / 100.0 / (1 - 0.9), r * t / 100.0};
    const double dt = 1e-4;  // [s] RK4, 0.03 rad of the bristle mode per step
    const auto axpy = [](const std::array<double, 2>& a, double h, const std::array<double, 2>& b) {
      return std::array<double, 2>{a[0] + h * b[0], a[1] + h * b[1]};
    };
    while (y[0] < 10 * 0.1 && t < 2 * 0.146 / r) {
      const auto k1 = rates(t, y), k2 = rates(t + dt / 2, axpy(y, dt / 2, k1)),
                 k3 = rates(t + dt / 2, axpy(y, dt / 2, k2)), k4 = rates(t + dt, axpy(y, dt, k3));
      for (int i = 0; i < 2; ++i) y[i] += dt / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
      t += dt;
      z_max = std::max(z_max, std::abs(y[1]));
    }
    ASSERT_GE(y[0], 1.0) << r;
    const double excess = r * t - 0.146;
    EXPECT_GT(excess, 0.0) << r;
    EXPECT_LT(excess, previous) << r;
    previous = excess;
  }
  EXPECT_LT(previous, 0.01 * (0.146 - 0.124));
  EXPECT_LE(z_max, 0.146 / 100.0 * (1 + 1e-12));
}

// LuGre's presliding hysteresis: at speeds far below vs, G(w) ~ Fs and the
// bristles obey Dahl's law with Fc = Fs (dz/dx = 1 - sigma0 z sgn(w) / Fs),
// whose loop under x = A sin(Omega t) ends at +-Fs tanh(sigma0 A / Fs)
// (dahl.hpp). LuGre's loop tends to it as the speed A Omega goes to 0: G
// falls short of Fs by (Fs - Fk)(w / vs)^2 to first order, so the loop's end
// (where w = 0 and tau_f = sigma0 z) lies below Dahl's, by a gap that
// shrinks at order 2 in Omega: a quarter of the speed, less than an eighth
// of the gap.
TEST(FrictionRegistry, LuGrePreslidingLoopTendsToDahls) {
  FrictionParams f;
  f.model = friction_model<LuGreFriction>();
  f.static_torque = 0.146, f.kinetic_torque = 0.124, f.viscous = 0.0;
  f.stribeck_speed = 0.1, f.bristle_stiffness = 100.0, f.bristle_damping = 0.6;
  const double A = 0.002, dahl_end = 0.146 * std::tanh(100.0 * A / 0.146);
  std::vector<double> gap;
  for (double Omega : {0.5, 0.125}) {  // [rad/s]: peak speeds 1e-3 and 2.5e-4 rad/s, far below vs
    const double T = 2 * M_PI / Omega;
    const int steps = 4000;  // per period; w's sign changes (T/4 + k T/2) on step boundaries
    const double dt = T / steps;
    const auto zdot = [&](double t, double z) { return friction_rate(f, A * Omega * std::cos(Omega * t), z); };
    double z = 0, top = 0;
    for (int k = 0; k < 4 * steps; ++k) {
      const double t = k * dt;
      const double k1 = zdot(t, z), k2 = zdot(t + dt / 2, z + dt / 2 * k1), k3 = zdot(t + dt / 2, z + dt / 2 * k2),
                   k4 = zdot(t + dt, z + dt * k3);
      z += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      if (k == 3 * steps + steps / 4 - 1) top = 100.0 * z;  // x = A, w = 0: tau_f = sigma0 z
    }
    gap.push_back(dahl_end - top);
    EXPECT_GT(gap.back(), 0.0) << Omega;
    const double speed = A * Omega / 0.1;                             // the peak speed against vs
    EXPECT_LT(gap.back(), (0.146 - 0.124) * speed * speed) << Omega;  // G's shortfall at the peak speed
  }
  EXPECT_GT(gap[0] / gap[1], 8.0);
}

// Dahl (1968, 1976; models/plant/friction/dahl.hpp) at a constant speed
// settles at Coulomb friction Fc sgn(w) + B w; its hysteresis is a function
// of the path x alone. For alpha = 1, dF/dx = sigma0 (1 - F sgn(w) / Fc):
// a cycle of x between -A and A (here x = A sin(Omega t)) settles on the
// loop whose ends are +-Fc tanh(sigma0 A / Fc), and the ascending branch
// from -F* at x = -A is F = Fc - (Fc + F*) exp(-sigma0 (x + A) / Fc), at any
// Omega. For alpha = 2, dF/dx = sigma0 (1 - F / Fc)^2 (F < Fc) integrates to
// 1 / (1 - F / Fc) = 1 / (1 - F0 / Fc) + sigma0 (x - x0) / Fc.
TEST(FrictionRegistry, DahlHysteresisIsItsClosedForm) {
  FrictionParams f;
  f.model = friction_model<DahlFriction>();
  f.kinetic_torque = 0.124, f.viscous = 0.0, f.bristle_stiffness = 100.0;  // the paper's Fk; sigma0 chosen
  ASSERT_EQ(friction_states(f.model), 1);
  for (double w : {-2.0, -0.01, 0.3}) {
    const double z_ss = (w > 0 ? 1 : -1) * 0.124 / 100.0;
    EXPECT_NEAR(friction_rate(f, w, z_ss), 0.0, 1e-15) << w;
    EXPECT_NEAR(friction_torque(f, w, 0.0, SlipMode::kStuck), (w > 0 ? 0.124 : -0.124), 1e-15) << w;
  }
  const double A = 0.002;  // [rad] about the deflection Fc / sigma0 = 1.24 mrad: a fat loop
  const double F_end = 0.124 * std::tanh(100.0 * A / 0.124);
  for (double Omega : {2.0, 50.0}) {  // [rad/s]: the loop must not depend on it
    const double T = 2 * M_PI / Omega;
    // RK4 in t on dz/dt = w(t) s(1 - sigma0 z sgn(w) / Fc), whose kinks in t
    // (where w changes sign, at T/4 + k T/2) fall on step boundaries.
    const int steps = 20000;  // per period
    const double dt = T / steps;
    const auto zdot = [&](double t, double z) { return friction_rate(f, A * Omega * std::cos(Omega * t), z); };
    double z = 0;
    double F_top = 0, F_mid = 0;
    for (int k = 0; k < 4 * steps;
         ++k) {  // four periods: z(0) = 0 is forgotten as exp(-2 sigma0 A / Fc) per half cycle
      const double t = k * dt;
      const double k1 = zdot(t, z), k2 = zdot(t + dt / 2, z + dt / 2 * k1), k3 = zdot(t + dt / 2, z + dt / 2 * k2),
                   k4 = zdot(t + dt, z + dt * k3);
      z += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      if (k == 3 * steps + steps / 4 - 1) F_top = 100.0 * z;  // x = A (t = 3T + T/4)
      if (k == 4 * steps - 1) F_mid = 100.0 * z;              // x = 0 on the way up (t = 4T), from x = -A at 3T + 3T/4
    }
    EXPECT_NEAR(F_top, F_end, 1e-9) << Omega;
    EXPECT_NEAR(F_mid, 0.124 - (0.124 + F_end) * std::exp(-100.0 * A / 0.124), 1e-9) << Omega;
  }
  // alpha = 2: along w > 0 from F0 = 0, F(x) in closed form.
  f.dahl_exponent = 2.0;
  const double w = 0.5, dt = 1e-6;
  double z = 0;
  const auto zd = [&](double zz) { return friction_rate(f, w, zz); };
  for (int k = 0; k < 4000; ++k) {  // x = w t = 2 mrad
    const double k1 = zd(z), k2 = zd(z + dt / 2 * k1), k3 = zd(z + dt / 2 * k2), k4 = zd(z + dt * k3);
    z += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  const double x = w * 4000 * dt;
  EXPECT_NEAR(100.0 * z, 0.124 * (1 - 1 / (1 + 100.0 * x / 0.124)), 1e-9);
}

// u = sat(Kp e + Ki z - Kv Z qd + Kvff Z qd_ref + Kaff Z qdd_ref + offset), by hand.
TEST(PivLaw, IsTheCardsFormulaAndSaturates) {
  PivParams P;
  P.kp = 2, P.ki = 3, P.kv = 0.5, P.kvff = 0.25, P.kaff = 0.125, P.offset = 0.1, P.output_limit = 10;
  const double Z = -4, q_ref = 0.3, q = 0.2, qd = 0.5, qd_ref = 0.4, qdd_ref = 1.0, z = 0.05;
  const double e = piv_error(Z, q_ref, q);
  EXPECT_DOUBLE_EQ(e, -4 * 0.1);
  const double want = 2 * e + 3 * z - 0.5 * Z * qd + 0.25 * Z * qd_ref + 0.125 * Z * qdd_ref + 0.1;
  EXPECT_NEAR(piv_law(P, Z, e, z, qd, qd_ref, qdd_ref), want, 1e-15);
  P.output_limit = 0.5;
  EXPECT_EQ(piv_law(P, Z, 100.0, z, qd, qd_ref, qdd_ref), 0.5);
  EXPECT_EQ(piv_law(P, Z, -100.0, z, qd, qd_ref, qdd_ref), -0.5);
}

// |Ki z| <= integral_limit, sampled (clamp) and continuous (rate 0 at the bound
// while the error pushes past it), for both signs of Ki.
TEST(PivLaw, BothTimingsKeepTheIntegralWithinItsBound) {
  for (double ki : {4.0, -4.0}) {
    PivParams P;
    P.ki = ki, P.integral_limit = 2.0;
    const double b = piv_integral_bound(P);
    EXPECT_DOUBLE_EQ(b, 0.5);
    EXPECT_DOUBLE_EQ(piv_clamp_integral(P, 0.7), 0.5);
    EXPECT_DOUBLE_EQ(piv_clamp_integral(P, -0.7), -0.5);
    EXPECT_DOUBLE_EQ(piv_clamp_integral(P, 0.2), 0.2);
    const double z_top = ki > 0 ? b : -b;  // Ki z = +integral_limit
    const double push = ki > 0 ? 1.0 : -1.0;  // an error that raises Ki z
    EXPECT_EQ(piv_integral_rate(P, z_top, push), 0.0);
    EXPECT_EQ(piv_integral_rate(P, z_top, -push), -push);  // it may come back
    EXPECT_EQ(piv_integral_rate(P, 0.0, push), push);
  }
  PivParams none;  // Ki = 0: unbounded, never clamped
  EXPECT_EQ(piv_clamp_integral(none, 1e9), 1e9);
}

// Each block declares its slice: names and typical magnitudes from its own
// parameters (a current: min(K_A u_max, V_max) / (R0 + R); an integral:
// integral_limit / |Ki|; angles, speeds and energies 1).
TEST(PlantBlocks, DeclareTheirSlicesWithTheirMagnitudes) {
  Scene sc = load_scene(std::string(PUMASIM_SCENES_DIR) + "/paper_slow.toml", {"scene.energy_ledger=true"});
  Plant plant(sc.plant);
  const StateLayout& L = plant.layout();
  const int n = L.n;
  ASSERT_EQ(L.size, 4 * n + 3);
  ASSERT_GE(L.i, 0);
  ASSERT_GE(L.z, 0);
  for (int j = 0; j < n; ++j) {
    const AmplifierParams& A = sc.plant.amplifier[j];
    const PivParams& P = law_params<PivController>(sc.plant)[j];
    const double stall = std::min(A.gain * P.output_limit, A.voltage_limit) /
                         (A.output_resistance + sc.plant.motor[j].resistance);
    EXPECT_EQ(L.names[L.i + j], "i_motor" + std::to_string(j + 1));
    EXPECT_DOUBLE_EQ(plant.tolerance_scale(L.i + j), stall);
    EXPECT_EQ(L.names[L.z + j], "z_piv" + std::to_string(j + 1));
    EXPECT_DOUBLE_EQ(plant.tolerance_scale(L.z + j), P.integral_limit / std::abs(P.ki));
    EXPECT_EQ(plant.tolerance_scale(L.q + j), 1.0);
    EXPECT_EQ(plant.tolerance_scale(L.qd + j), 1.0);
  }
  EXPECT_EQ(L.names[L.e], "e_in");
  EXPECT_EQ(L.names[L.e + 2], "e_friction");
  EXPECT_EQ(static_cast<int>(L.scale.size()), L.size);
}

}  // namespace
}  // namespace pumasim
