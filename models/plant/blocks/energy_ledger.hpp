// Energy ledger block: three quadrature states e_in, e_copper, e_friction [J]
// (typical magnitude 1 J): the electrical input e_a i (without a drive, a
// torque input's mechanical power tau qd), the copper loss
// (R0 + R) i^2 and the friction loss tau_f w_m, summed over the joints and
// integrated with the rest. The drive and friction blocks add their powers to
// the workspace (p_in, p_cu, p_f) while they compute; the ledger writes them.
#pragma once

#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"

namespace pumasim {

class EnergyLedgerBlock {
 public:
  explicit EnergyLedgerBlock(bool on) : on_(on) {}
  bool on() const { return on_; }

  void declare(StateLayout& L) const {
    if (on_) L.e = L.add({"e_in", "e_copper", "e_friction"}, {1.0, 1.0, 1.0});
  }

  template <class S>
  void reset(PlantWorkspace<S>& w) const {
    w.p_in = w.p_cu = w.p_f = S(0);
  }

  template <class S>
  void store(const StateLayout& L, const PlantWorkspace<S>& w, S* xdot) const {
    if (!on_) return;
    xdot[L.e] = w.p_in;
    xdot[L.e + 1] = w.p_cu;
    xdot[L.e + 2] = w.p_f;
  }

 private:
  const bool on_;
};

}  // namespace pumasim
