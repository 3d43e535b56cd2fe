// Rigid-body block: the links (any back-end from the registry), state slices
// q1..n (typical magnitude 1 rad) and qd1..n (1 rad/s). q' = qd and
// qdd = H^-1 (tau - h), or, with joints held by their friction (the hybrid
// model), the constrained solve below.
#pragma once

#include <vector>

#include "models/dynamics/tangent_backend.hpp"
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"

namespace pumasim {

class RigidBodyBlock {
 public:
  explicit RigidBodyBlock(std::vector<double> gear_ratio) : Z_(std::move(gear_ratio)) {}
  int joints() const { return static_cast<int>(Z_.size()); }
  double gear_ratio(int j) const { return Z_[static_cast<std::size_t>(j)]; }

  void declare(StateLayout& L) const {
    const std::vector<double> one(Z_.size(), 1.0);
    L.q = L.add(joint_names("q", joints()), one);
    L.qd = L.add(joint_names("qd", joints()), one);
  }

  template <class S>
  void load(const StateLayout& L, const S* x, PlantWorkspace<S>& w) const {
    for (int j = 0; j < joints(); ++j) {
      w.q[j] = x[L.q + j];
      w.qd[j] = x[L.qd + j];
    }
  }

  template <class S>
  void store(const StateLayout& L, const PlantWorkspace<S>& w, S* xdot) const {
    for (int j = 0; j < joints(); ++j) {
      xdot[L.q + j] = w.qd[j];
      xdot[L.qd + j] = w.qdd[j];
    }
  }

  // bias_known: w.h holds bias(q, qd) from this back-end (on the exact
  // Jacobian's scalar perhaps its values only, all TangentBackend reads).
  template <class S>
  void accelerations(PlantWorkspace<S>& w, bool bias_known) const {
    if (bias_known) {
      w.backend->forward_dynamics_with_bias(w.q, w.qd, w.h, w.tau, w.qdd);
    } else {
      w.backend->forward_dynamics(w.q, w.qd, w.tau, w.qdd);
    }
  }

  // Joints held by their friction (stuck(j)) have qdd_j = 0 and a friction
  // torque that is whatever holds them. Solve H qdd = tau - h (w.h computed)
  // with the stuck joints' rows and columns replaced by the identity (the
  // free block is unchanged since qdd_stuck = 0); then each stuck joint's row
  // of H gives the torque its friction must resist:
  // applied = K i - (h_j + H_j. qdd) / Z_j.
  template <class S, class Stuck>
  void constrained_accelerations(PlantWorkspace<S>& w, Stuck stuck) const {
    const int n = joints();
    if constexpr (kIsDualN<S>) {  // the exact Jacobian's pass: values and tangents from the back-end's
      auto& b = static_cast<TangentBackend<S::kTangents>&>(*w.backend);
      b.constrained_forward_dynamics(w.q, w.qd, w.tau, stuck, w.qdd, w.id.data(), w.h.data());
      for (int j = 0; j < n; ++j) {
        if (stuck(j)) w.applied[j] = w.tm[j] - w.id[j] / S(gear_ratio(j));
      }
      return;
    }
    w.backend->mass_matrix(w.q, w.H);
    w.Hc = w.H;
    for (int j = 0; j < n; ++j) {
      w.qdd[j] = w.tau[j] - w.h[j];
      if (!stuck(j)) continue;
      w.qdd[j] = S(0);
      for (int k = 0; k < n; ++k) w.Hc(j, k) = w.Hc(k, j) = S(k == j ? 1 : 0);
    }
    w.chol.factor(w.Hc);
    w.chol.solve_in_place(w.qdd);
    for (int j = 0; j < n; ++j) {
      if (!stuck(j)) continue;
      S sum = w.h[j];
      for (int k = 0; k < n; ++k) sum += w.H(j, k) * w.qdd[k];
      w.applied[j] = w.tm[j] - sum / S(gear_ratio(j));
    }
  }

 private:
  const std::vector<double> Z_;
};

}  // namespace pumasim
