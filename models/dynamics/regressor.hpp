// The joint-torque regressor: tau = Y(q, qd, qdd) pi, linear in the
// parameters (Atkeson, An & Hollerbach 1986; Khalil & Dombre 2002, ch. 9).
//
// Columns, joint by joint (j = 1..n), in this order:
//   XXj XYj XZj YYj YZj ZZj  link j's inertia about joint frame j's origin [kg m^2]
//   MXj MYj MZj              its first moment of mass m c, joint frame j [kg m]
//   Mj                       its mass [kg]
//   Iaj                      the reflected rotor inertia Z^2 Im [kg m^2] (or [kg]), if `rotor`
//   Fvj Fcj Foj              joint-side friction, if `friction`: viscous
//                            Fv qd, Coulomb Fc sign(qd) (sign(0) = 0) and an
//                            offset Fo, as Gautier & Khalil identify them
// The frames are the algorithms' joint frames (chain.hpp: z on joint j's
// axis, origin on it), not Khalil's modified-DH frames; the base-parameter
// count does not depend on that choice, the regrouping's coefficients do.
// Y depends on the kinematics and gravity only, never on the inertial values.
//
// Two ways to the same matrix:
// - `compute`, the direct recursive form: one outward pass for each link's
//   velocity and acceleration (as the RNEA's), link j's wrench about its
//   origin as a 6 x 10 matrix times its parameters (Newton-Euler is linear
//   in m, m c and I_o), then each wrench carried inwards through joints
//   j, j-1, ..., 1, one 6 x 10 block per pair: O(n^2).
// - `compute_by_probing`, the paper's probing applied to parameters
//   (Sokolov & Toth 1999 probe the Newton-Euler equations with unit
//   accelerations to build H): the joint transforms once, then one RNEA pass
//   per column on a chain whose parameters are the unit vector e_k (as the
//   rnea-probing-shared back-end does for H). 11 n passes, O(n^2) too but
//   each repeats the velocity and acceleration recursion.
// Neither allocates after construction; both refuse (std::invalid_argument)
// vectors or a Y of the wrong size.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/dynamics/chain.hpp"
#include "models/dynamics/rnea.hpp"
#include "models/dynamics/robot_model.hpp"

namespace pumasim {

struct RegressorColumns {
  bool rotor = true;     // an Ia column per joint
  bool friction = true;  // Fv, Fc, Fo columns per joint
};

class JointTorqueRegressor {
 public:
  static constexpr int kLinkParameters = 10;

  explicit JointTorqueRegressor(const RobotModel& model, RegressorColumns columns = {});

  int dof() const { return chain_.n; }
  int parameters() const { return per_joint_ * chain_.n; }
  int per_joint() const { return per_joint_; }
  RegressorColumns columns() const { return columns_; }
  // "XX3", "MY2", "Ia1", "Fc6": column k's name (joints from 1).
  std::string parameter_name(int k) const;
  std::vector<std::string> parameter_names() const;
  // pi of `model` (which must have this regressor's kinematics): its links'
  // inertial values in joint frames, its rotors' Z^2 Im and its joints'
  // damping and coulomb (RobotModel's joint-side friction; offset 0).
  Eigen::VectorXd parameters_of(const RobotModel& model) const;
  // The inverse: `model` (this regressor's kinematics) with its links'
  // mass, centre of mass and inertia about it (in its DH frames, as a robot
  // file gives them), its rotors' Im = Ia / Z^2 and its joints' damping = Fv
  // and coulomb = Fc taken from pi; with_parameters(m, parameters_of(m))
  // is m to rounding. An offset Fo has no place in a robot model and is
  // dropped. std::invalid_argument for a pi of the wrong size, a mass < 0, a
  // mass 0 with a first moment (no centre of mass), or a nonzero Ia on a joint with Z = 0.
  // Whether the result is a rigid body is not checked here
  // (models/robot/link_inertia.hpp).
  RobotModel with_parameters(const RobotModel& model, const Eigen::VectorXd& pi) const;

  // Y (n x parameters()), including gravity.
  void compute(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y);
  void compute_by_probing(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
                          const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y);

 private:
  using Wrench = Eigen::Matrix<double, 6, kLinkParameters>;  // rows: force (3), moment about the origin (3)
  template <bool kMixed>
  void link_motion(const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd);
  void link_wrench(int j, Wrench& W) const;
  template <bool kMixed>
  void carry_inwards(Eigen::Ref<Eigen::MatrixXd> Y);
  void check_sizes(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
                   const Eigen::Ref<const Eigen::VectorXd>& qdd, const Eigen::Ref<Eigen::MatrixXd>& Y) const;
  void drive_columns(const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd,
                     bool rotor, Eigen::Ref<Eigen::MatrixXd> Y) const;

  RegressorColumns columns_;
  int per_joint_;
  Chain<double, Eigen::Dynamic> chain_;  // the kinematics; its inertial values unused
  Chain<double, Eigen::Dynamic> probe_;  // the same with every parameter 0 but the probed one
  JointTransforms<double, Eigen::Dynamic> rot_;
  RneaPass<double, Eigen::Dynamic> rnea_;
  std::vector<Eigen::Vector3d> w_, wd_, a_;  // link j's angular velocity, its rate, its origin's acceleration (frame j)
  Eigen::VectorXd column_;
};

}  // namespace pumasim
