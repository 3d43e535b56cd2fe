// Voltage amplifier block (paper sec. 3): e_a = sat(K_A u, +-V_max), in
// series with its output resistance R0 (which the motor block adds to R).
// No state.
#pragma once

#include <vector>

#include "models/plant/workspace.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

class AmplifierBlock {
 public:
  explicit AmplifierBlock(const std::vector<AmplifierParams>& params) : p_(params) {}
  const AmplifierParams& params(int j) const { return p_[static_cast<std::size_t>(j)]; }

  template <class S>
  S output(int j, const S& u) const {
    const AmplifierParams& A = params(j);
    return saturate(S(A.gain) * u, A.voltage_limit);
  }

 private:
  const std::vector<AmplifierParams> p_;
};

}  // namespace pumasim
