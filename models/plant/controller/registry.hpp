// The controller laws: one file per law (this folder; what a law provides:
// law.hpp) and one line in ControllerLaws below. Everything else follows from
// the list: the parameters a plant configuration holds (ControllerParams, a
// variant over the laws), the block the plant runs (ControllerBlock), the
// scene's [controller] law names and keys (models/scene/scene.cpp walks each
// law's keys() and text_keys()), and the names the command line and the tests
// list.
#pragma once

#include <concepts>
#include <cstddef>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "models/plant/controller/computed_torque.hpp"
#include "models/plant/controller/law.hpp"
#include "models/plant/controller/open_loop.hpp"
#include "models/plant/controller/piv.hpp"

namespace pumasim {

// What a controller law is (law.hpp's list, as a C++20 concept): a law the
// list is given that lacks a member, or has one of the wrong shape, fails
// to compile here, naming it, instead of deep inside the plant's dispatch.
// (clang-format 14 misreads a concept's constraints: the concepts are laid out by hand.)
// clang-format off
template <class L>
concept ControllerLaw =
    std::constructible_from<L, ControllerMode, const std::vector<typename L::Params>&, const typename L::Settings&,
                            const ControllerContext&> &&
    requires(const L& law, const typename L::Params& p, const typename L::Settings& settings, StateLayout& declared,
             const StateLayout& layout, const ControllerClock& clock, const ReferenceSample& r, const double* x,
             double* x_out, PlantWorkspace<double>& w, double* xdot, ControllerDiscreteState& d, double t, int j) {
      { L::kName } -> std::convertible_to<std::string_view>;
      { L::kHasInput } -> std::convertible_to<bool>;
      { L::keys() } -> std::convertible_to<const std::vector<ControllerKey<typename L::Params>>&>;
      { L::text_keys() } -> std::convertible_to<const std::vector<ControllerTextKey<typename L::Settings>>&>;
      { L::command(settings) } -> std::same_as<ControllerCommand>;
      { L::output_limit(p) } -> std::convertible_to<double>;
      { L::input_end(settings) } -> std::convertible_to<double>;
      law.declare(declared);
      law.template output<double>(clock, r, x, layout, w);
      law.template rates<double>(r, x, layout, w, xdot);
      { law.discrete_size() } -> std::convertible_to<int>;
      law.sample(clock, r, x, layout, w, d);
      law.hold(j, t, x_out, layout, d);
      { law.next_time_event(t) } -> std::convertible_to<double>;
      { law.piece_after(t) } -> std::convertible_to<int>;
    };
// clang-format on

// A law's parameters, one per simulated joint, and its settings for all
// joints (a type per law, so that two laws may share a Params struct).
template <class L>
struct LawParams {
  using Law = L;
  std::vector<typename L::Params> joints;
  typename L::Settings settings{};
};

template <class L>
struct LawTag {
  using Law = L;
};

template <ControllerLaw... Laws>
struct ControllerLawList {
  using Params = std::variant<LawParams<Laws>...>;
  using Block = std::variant<Laws...>;
  // f(LawTag<Law>{}) for every law, in the list's order.
  template <class F>
  static void for_each(F&& f) {
    (f(LawTag<Laws>{}), ...);
  }
  // f(LawTag<Law>{}) for the law named `name`; false if none is.
  template <class F>
  static bool visit(std::string_view name, F&& f) {
    return ((name == Laws::kName ? (f(LawTag<Laws>{}), true) : false) || ...);
  }
};

using ControllerLaws = ControllerLawList<PivController, ComputedTorqueController, OpenLoopController>;
using ControllerParams = ControllerLaws::Params;  // the first law's, empty, by default
using ControllerBlock = ControllerLaws::Block;

// The laws' names, in the list's order (the first is the default).
inline std::vector<std::string> controller_law_names() {
  std::vector<std::string> names;
  ControllerLaws::for_each([&](auto tag) { names.emplace_back(decltype(tag)::Law::kName); });
  return names;
}

// The named law's parameters for n joints, each at its struct's defaults;
// false if no law has that name.
inline bool default_controller_params(std::string_view name, int n, ControllerParams* out) {
  return ControllerLaws::visit(name, [&](auto tag) {
    using Law = typename decltype(tag)::Law;
    *out = LawParams<Law>{std::vector<typename Law::Params>(static_cast<std::size_t>(n))};
  });
}

inline std::string_view controller_law_name(const ControllerParams& p) {
  return std::visit([](const auto& lp) { return std::decay_t<decltype(lp)>::Law::kName; }, p);
}

inline std::size_t controller_joints(const ControllerParams& p) {
  return std::visit([](const auto& lp) { return lp.joints.size(); }, p);
}

// Joint j's output range: |u| <= this [V].
inline double controller_output_limit(const ControllerParams& p, int j) {
  return std::visit(
      [j](const auto& lp) {
        return std::decay_t<decltype(lp)>::Law::output_limit(lp.joints[static_cast<std::size_t>(j)]);
      },
      p);
}

// What the law's output is: a voltage to the drive, or joint torques (no drive).
inline ControllerCommand controller_command(const ControllerParams& p) {
  return std::visit([](const auto& lp) { return std::decay_t<decltype(lp)>::Law::command(lp.settings); }, p);
}

// The last time the law's own input is given for [s] (+inf: it has none; after
// it, the input holds its last values).
inline double controller_input_end(const ControllerParams& p) {
  return std::visit([](const auto& lp) { return std::decay_t<decltype(lp)>::Law::input_end(lp.settings); }, p);
}

// The block of the law the parameters belong to.
inline ControllerBlock make_controller(ControllerMode mode, const ControllerParams& p, const ControllerContext& c) {
  return std::visit(
      [&](const auto& lp) {
        using Law = typename std::decay_t<decltype(lp)>::Law;
        return ControllerBlock(std::in_place_type<Law>, mode, lp.joints, lp.settings, c);
      },
      p);
}

}  // namespace pumasim
