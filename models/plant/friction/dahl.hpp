// Dahl friction (P. R. Dahl, "A solid friction model", The Aerospace
// Corporation, TOR-0158(3107-18)-1, 1968; "Solid friction damping of
// mechanical vibrations", AIAA Journal 14(12), 1976), in the state form of
// Olsson, Astrom, Canudas de Wit, Gafvert and Lischinsky ("Friction models
// and friction compensation", European Journal of Control 4(3), 1998,
// sec. 3.3): the friction torque F = sigma0 z, its state z [rad, on the
// motor shaft] (the deflection of the junctions), with
//
//   dF/dx = sigma0 |1 - (F / Fc) sgn(w)|^alpha sgn(1 - (F / Fc) sgn(w)),
//
// that is dz/dt = w s(1 - sigma0 z sgn(w) / Fc), s(u) = |u|^alpha sgn(u);
// tau_f = sigma0 z + B w. Fc is the Coulomb level (kinetic_torque),
// sigma0 the stiffness at rest (bristle_stiffness), alpha the exponent
// (dahl_exponent, >= 1 here: below 1 the rate is not Lipschitz at F = Fc).
// At a constant speed F settles at Fc sgn(w): Coulomb friction plus B w,
// with no static level above it. Its hysteresis is rate-independent: F is a
// function of the path x = integral of w, not of the time; for alpha = 1 a
// branch from F0 is F = sgn(w) Fc - (sgn(w) Fc - F0) exp(-sigma0 |x - x0| / Fc),
// and a cycle of x between -A and A settles on the loop whose ends are
// +-Fc tanh(sigma0 A / Fc). |z| <= Fc / sigma0 holds for all time from z = 0
// (z moves toward sgn(w) Fc / sigma0 and never crosses it).
#pragma once

#include <cmath>

#include "models/plant/friction/law.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct DahlFriction {
  static constexpr const char* kName = "dahl";
  static constexpr bool kNeedsAppliedTorque = false;
  static constexpr bool kStickSlipEvents = false;
  static constexpr bool kSetValued = false;
  static constexpr FrictionKeys kKeys{
      .viscous = true, .levels = true, .stiffness = true, .kinetic_only = true, .dahl = true};
  static constexpr int kStates = 1;  // z = F / sigma0
  static constexpr const char* kStateBoundWhy = "Fc / sigma0 (Dahl: F moves toward Fc sgn(w) and never crosses it)";

  template <class S>
  static S rate(const FrictionParams& f, const S& w, const S& z) {  // dz/dt [rad/s]
    using std::abs;
    using std::exp;
    using std::log;
    const S u = S(1) - S(f.bristle_stiffness / f.kinetic_torque) * z * sign_of(w);
    if (f.dahl_exponent == 1.0) return w * u;
    if (u == S(0)) return S(0);  // alpha > 1: the value and its derivative are 0 there
    // |u|^alpha sgn(u) = u |u|^(alpha - 1), alpha > 1: by exp and log, defined for every scalar type.
    return w * u * exp(S(f.dahl_exponent - 1.0) * log(abs(u)));
  }
  template <class S>
  static S state_torque(const FrictionParams& f, const S& w, const S& z, const S&) {
    return S(f.bristle_stiffness) * z + S(f.viscous) * w;
  }
  // Without its state: the steady-state curve Fc sgn(w) + B w (0 at rest).
  template <class S>
  static S torque(const FrictionParams& f, const S& w, const S&, SlipMode) {
    return S(f.kinetic_torque) * sign_of(w) + S(f.viscous) * w;
  }
  static double state_bound(const FrictionParams& f) {
    return f.bristle_stiffness > 0 && f.kinetic_torque > 0 ? f.kinetic_torque / f.bristle_stiffness : HUGE_VAL;
  }
};

}  // namespace pumasim
