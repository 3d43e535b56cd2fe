// Computed-torque control (feedback linearisation; Spong, Hutchinson and
// Vidyasagar, Robot Modeling and Control, 2006, sec. 8.3): the desired joint
// acceleration
//   a = qdd_ref + Kd (qd_ref - qd) + Kp (q_ref - q)
// is turned into joint torques by the plant's own model (inverse dynamics of
// the scene's back-end, rotor inertia included), tau = H(q) a + h(q, qd), and
// the torques into the amplifier command through the motor's steady-state
// electrical equation (La neglected):
//   i = tau / (Z K),   u = sat(((R0 + R) i + K Z qd) / K_A, +-output_limit).
// With an exact model, La = 0, no friction and no saturation each joint's
// error obeys e'' + Kd e' + Kp e = 0 (tests/test_controllers.cpp); armature
// inductance, friction and the drive's limits are what it does not cancel.
// It has no memory: nothing to declare, hold or integrate.
#pragma once

#include <cstddef>
#include <vector>

#include "models/plant/controller/law.hpp"
#include "models/plant/state_layout.hpp"
#include "models/plant/workspace.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/drive.hpp"

namespace pumasim {

struct ComputedTorqueParams {
  double kp = 0.0;             // [1/s^2] on the joint angle error
  double kd = 0.0;             // [1/s] on the joint speed error
  double output_limit = 10.0;  // [V], DAC range
};

class ComputedTorqueController : public WithoutSettings {
 public:
  static constexpr std::string_view kName = "computed_torque";
  using Params = ComputedTorqueParams;
  static const std::vector<ControllerKey<ComputedTorqueParams>>& keys() {
    static const std::vector<ControllerKey<ComputedTorqueParams>> k = {
        {"kp", &ComputedTorqueParams::kp, Bounds::non_negative(), "[1/s^2] joint side: omega^2", true},
        {"kd", &ComputedTorqueParams::kd, Bounds::non_negative(), "[1/s] joint side: 2 zeta omega", true},
        {"output_limit", &ComputedTorqueParams::output_limit, Bounds::positive(), "[V] DAC range"},
    };
    return k;
  }
  static double output_limit(const ComputedTorqueParams& p) { return p.output_limit; }

  ComputedTorqueController(ControllerMode, const std::vector<ComputedTorqueParams>& params, const NoSettings&,
                           const ControllerContext& context)
      : p_(params), c_(context) {}

  void declare(StateLayout&) const {}

  template <class S>
  void output(const ControllerClock&, const ReferenceSample& r, const S*, const StateLayout&,
              PlantWorkspace<S>& w) const {
    const int n = static_cast<int>(p_.size());
    for (int j = 0; j < n; ++j) {
      const ComputedTorqueParams& P = p_[static_cast<std::size_t>(j)];
      w.command_qdd[j] = S(r.qdd[j]) + S(P.kd) * (S(r.qd[j]) - w.qd[j]) + S(P.kp) * (S(r.q[j]) - w.q[j]);
    }
    w.backend->inverse_dynamics(w.q, w.qd, w.command_qdd, w.command_tau);
    for (int j = 0; j < n; ++j) {
      const std::size_t k = static_cast<std::size_t>(j);
      const double Z = c_.gear_ratio[k], K = c_.motor[k].torque_constant;
      const AmplifierParams& A = c_.amplifier[k];
      const S i = w.command_tau[j] / S(Z * K);
      const S ea = S(A.output_resistance + c_.motor[k].resistance) * i + S(K * Z) * w.qd[j];
      w.u[j] = saturate(ea / S(A.gain), p_[k].output_limit);
    }
  }

  template <class S>
  void rates(const ReferenceSample&, const S*, const StateLayout&, const PlantWorkspace<S>&, S*) const {}

  int discrete_size() const { return 0; }
  void sample(const ControllerClock& c, const ReferenceSample& r, const double* x, const StateLayout& L,
              PlantWorkspace<double>& w, ControllerDiscreteState& d) const {
    const int n = static_cast<int>(p_.size());
    for (int j = 0; j < n; ++j) w.q[j] = x[L.q + j], w.qd[j] = x[L.qd + j];
    output(c, r, x, L, w);
    for (int j = 0; j < n; ++j) d.u_held[static_cast<std::size_t>(j)] = w.u[j];
  }

  // At rest on the reference the law itself supplies gravity's torque.
  void hold(int, double, double*, const StateLayout&, ControllerDiscreteState&) const {}

 private:
  const std::vector<ComputedTorqueParams> p_;
  const ControllerContext c_;
};

}  // namespace pumasim
