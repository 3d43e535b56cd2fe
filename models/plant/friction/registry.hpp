// The friction models: one file per law (this folder) and one line in
// FrictionLaws below. A joint's FrictionParams name its law by its place in
// the list (FrictionModel, models/robot/drive.hpp; friction_model<Law>()); the
// first law is none, the parameters' default. A law is a type with
//   kName                its name in scene files
//   kNeedsAppliedTorque  it reads the torque it must resist at rest (the plant then computes h)
//   kStickSlipEvents     its stuck/slipping modes switch at root functions (the hybrid model)
//   kSetValued           its Coulomb part is the set-valued law (stuck up to Fs, else Fk against
//                        the motion) that time-stepping (moreau-jean) solves; B w_m stays smooth
//   kKeys                the [friction] keys it reads and its default band (law.hpp)
//   torque<S>(params, w_m, applied, mode)   the friction torque on the motor shaft [N m]
// Dispatch is a compile-time chain of comparisons over the list: no virtual
// call and no lookup by name in the right-hand side.
#pragma once

#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "models/plant/friction/dahl.hpp"
#include "models/plant/friction/hybrid.hpp"
#include "models/plant/friction/lugre.hpp"
#include "models/plant/friction/none.hpp"
#include "models/plant/friction/sigmoid.hpp"
#include "models/plant/friction/stick_band.hpp"
#include "models/plant/friction/stribeck.hpp"
#include "models/plant/friction/tanh.hpp"
#include "models/plant/friction/viscous.hpp"

namespace pumasim {

// What a friction law is (the list above, as a C++20 concept): a law the
// list is given that lacks a member, or has one of the wrong type, fails to
// compile here, naming the member, instead of deep inside a dispatch.
// (clang-format 14 misreads a concept's constraints: the concepts are laid out by hand.)
// clang-format off
template <class L>
concept FrictionLaw = std::default_initializable<L> &&
    requires(const FrictionParams& f, const double& w, const double& applied, SlipMode mode) {
  { L::kName } -> std::convertible_to<const char*>;
  { L::kNeedsAppliedTorque } -> std::convertible_to<bool>;
  { L::kStickSlipEvents } -> std::convertible_to<bool>;
  { L::kSetValued } -> std::convertible_to<bool>;
  { L::kKeys } -> std::convertible_to<FrictionKeys>;
  { L::template torque<double>(f, w, applied, mode) } -> std::same_as<double>;
};
// clang-format on

template <FrictionLaw... Laws>
struct FrictionLawList {
  // The law's FrictionModel: its place in the list.
  template <class Law>
  static constexpr FrictionModel model_of() {
    constexpr bool same[] = {std::is_same_v<Law, Laws>...};
    for (std::size_t i = 0; i < sizeof...(Laws); ++i) {
      if (same[i]) return FrictionModel{static_cast<std::uint8_t>(i)};
    }
    throw "not a friction law of the list";  // in a constant expression: a compile error
  }
  template <class F>
  static void visit(FrictionModel m, F&& f) {
    visit_in(m, f, std::index_sequence_for<Laws...>{});
  }
  template <class F>
  static void for_each(F&& f) {
    (f(Laws{}), ...);
  }

 private:
  template <class F, std::size_t... I>
  static void visit_in(FrictionModel m, F& f, std::index_sequence<I...>) {
    (void)((m.index == I ? (f(Laws{}), true) : false) || ...);
  }
};

using FrictionLaws = FrictionLawList<NoFriction, ViscousFriction, PaperRuleFriction, HybridFriction, KarnoppFriction,
                                     TanhFriction, SigmoidFriction, StribeckFriction, LuGreFriction, DahlFriction>;

template <class Law>
constexpr FrictionModel friction_model() {
  constexpr FrictionModel m = FrictionLaws::model_of<Law>();
  return m;
}
static_assert(friction_model<NoFriction>().none(), "the first law, the default, is none");
// The plant's constrained accelerations (a stuck joint) read h, which it
// computes only for a law that reads the applied torque.
template <FrictionLaw... Laws>
constexpr bool events_read_applied_torque(FrictionLawList<Laws...>*) {
  return ((!Laws::kStickSlipEvents || Laws::kNeedsAppliedTorque) && ...);
}
static_assert(events_read_applied_torque(static_cast<FrictionLaws*>(nullptr)),
              "a law with stick/slip events must read the applied torque (Plant::friction_and_accelerations)");

// Friction torque on the motor shaft, opposing motion [N m, motor side].
// w: shaft speed; tau_applied: the torque the friction must resist when the
// shaft is at rest (see Plant); mode: the hybrid model's slip state.
template <class S>
S friction_torque(const FrictionParams& f, const S& w, const S& tau_applied, SlipMode mode) {
  S tf(0);
  FrictionLaws::visit(f.model, [&](auto law) { tf = decltype(law)::torque(f, w, tau_applied, mode); });
  return tf;
}

// A law with an internal state (LuGre's bristles) declares
//   kStates = 1, rate<S>(params, w_m, z) -> dz/dt, state_torque<S>(params,
//   w_m, z, dz/dt) -> its torque, state_bound(params) (the largest possible
//   |z|, also its typical magnitude) and kStateBoundWhy (the bound's source),
// and its torque<S>(...) is then the steady-state curve. Laws without one
// declare nothing (0 states).
template <class L>
constexpr int law_states() {
  if constexpr (requires { L::kStates; }) {
    return L::kStates;
  } else {
    return 0;
  }
}

inline int friction_states(FrictionModel m) {
  int r = 0;
  FrictionLaws::visit(m, [&](auto law) { r = law_states<decltype(law)>(); });
  return r;
}

// get(law) for the model's law when it has a state, else `otherwise`.
template <class R, class F>
R with_state_law(FrictionModel m, R otherwise, F&& get) {
  FrictionLaws::visit(m, [&](auto law) {
    if constexpr (law_states<decltype(law)>() > 0) otherwise = get(law);
  });
  return otherwise;
}

template <class S>
S friction_rate(const FrictionParams& f, const S& w, const S& z) {
  return with_state_law(f.model, S(0), [&](auto law) { return decltype(law)::rate(f, w, z); });
}

template <class S>
S friction_state_torque(const FrictionParams& f, const S& w, const S& z, const S& zdot) {
  return with_state_law(f.model, S(0), [&](auto law) { return decltype(law)::state_torque(f, w, z, zdot); });
}

// The largest possible |z| of the law's state (+inf without one), and where it comes from in words.
inline double friction_state_bound(const FrictionParams& f) {
  return with_state_law(f.model, HUGE_VAL, [&](auto law) { return decltype(law)::state_bound(f); });
}
inline std::string friction_state_bound_why(const FrictionParams& f) {
  return with_state_law(f.model, std::string(), [](auto law) { return std::string(decltype(law)::kStateBoundWhy); });
}

inline bool needs_applied_torque(FrictionModel m) {
  bool r = false;
  FrictionLaws::visit(m, [&](auto law) { r = decltype(law)::kNeedsAppliedTorque; });
  return r;
}

inline bool has_stick_slip_events(FrictionModel m) {
  bool r = false;
  FrictionLaws::visit(m, [&](auto law) { r = decltype(law)::kStickSlipEvents; });
  return r;
}

inline bool is_set_valued(FrictionModel m) {
  bool r = false;
  FrictionLaws::visit(m, [&](auto law) { r = decltype(law)::kSetValued; });
  return r;
}

inline FrictionKeys friction_keys(FrictionModel m) {
  FrictionKeys k;
  FrictionLaws::visit(m, [&](auto law) { k = decltype(law)::kKeys; });
  return k;
}

// The model's name in scene files ("?" for none registered).
const char* to_string(FrictionModel m);
// (name, model) of every law, in the registry's order: what a scene may name.
const std::vector<std::pair<std::string, FrictionModel>>& friction_model_choices();
// The model named `name`; false if no law has that name.
bool friction_model_from_name(const std::string& name, FrictionModel* m);

}  // namespace pumasim
