// Shared helpers for the tests: random states, norms, and independent forward
// kinematics (through dh_transform, not through the Chain the algorithms use).
#pragma once

#include <Eigen/Core>

#include <utility>
#include <vector>

#include "models/dynamics/algorithms.hpp"
#include "models/dynamics/backend.hpp"
#include "models/dynamics/built_algorithms.hpp"
#include "models/robot/random_chain.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim::testing {

// ||a - b|| / max(||a||, floor): "relative to the norm", with an absolute
// floor (in the quantity's SI unit) for quantities that vanish by symmetry,
// such as the gravity torque about a vertical first joint: there the bound
// 1e-10 becomes 1e-13 absolute, about 1e-16 of the O(10..1000) terms that
// cancel in it.
inline double rel_err(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double floor = 1e-3) {
  return (a - b).norm() / std::max(a.norm(), floor);
}

// Every quantity a back-end computes, at one state: H, h, g, the inverse
// dynamics tau = ID(q, qd, qdd) and the forward dynamics qdd = FD(q, qd, tau).
struct Quantities {
  Eigen::MatrixXd H;
  Eigen::VectorXd h, g, tau, qdd;
};

inline Quantities evaluate(DynamicsBackend& b, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                           const Eigen::VectorXd& qdd, const Eigen::VectorXd& tau) {
  const int n = b.dof();
  Quantities r{Eigen::MatrixXd(n, n), Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::VectorXd(n),
               Eigen::VectorXd(n)};
  b.mass_matrix(q, r.H);
  b.bias(q, qd, r.h);
  b.gravity(q, r.g);
  b.inverse_dynamics(q, qd, qdd, r.tau);
  b.forward_dynamics(q, qd, tau, r.qdd);
  return r;
}

// The registered back-ends that can describe `m` (all but generated ones
// made for another arm).
inline std::vector<BackendInfo> supported(const RobotModel& m) {
  std::vector<BackendInfo> out;
  for (const auto& info : backends()) {
    if (info.why_unsupported(m).empty()) out.push_back(info);
  }
  return out;
}

// Calls f.template operator()<Algo>() for every algorithm template of this
// build's back-ends (BuiltAlgorithms, generated from
// models/dynamics/built_algorithms.hpp.in and the back-end list: a new
// back-end takes part with no edit here) that can describe the model m.
template <template <class, int> class... Algo, class F>
void for_each_algorithm_in(AlgorithmList<Algo...>, const RobotModel& m, F&& f) {
  auto call = [&]<template <class, int> class A>() {
    if (why_unsupported<A>(m).empty()) f.template operator()<A>();
  };
  (call.template operator()<Algo>(), ...);
}

template <class F>
void for_each_algorithm(const RobotModel& m, F&& f) {
  for_each_algorithm_in(BuiltAlgorithms{}, m, std::forward<F>(f));
}

}  // namespace pumasim::testing
