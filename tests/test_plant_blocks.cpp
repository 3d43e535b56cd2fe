// The plant's blocks on their own: the friction registry, the one PIV law and
// its integral bound, and the state slices the blocks declare.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

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
