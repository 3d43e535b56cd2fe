#include "models/dynamics/regressor.hpp"

#include <cmath>
#include <stdexcept>

#include "models/dynamics/link_frame.hpp"

namespace pumasim {

namespace {

constexpr const char* kLinkNames[JointTorqueRegressor::kLinkParameters] = {"XX", "XY", "XZ", "YY", "YZ",
                                                                           "ZZ", "MX", "MY", "MZ", "M"};
// Io's entry of inertia column k (0..5), and its mirror.
constexpr int kInertiaRow[6] = {0, 0, 0, 1, 1, 2};
constexpr int kInertiaCol[6] = {0, 1, 2, 1, 2, 2};

// Io v as L(v) [XX XY XZ YY YZ ZZ]^T.
Eigen::Matrix<double, 3, 6> inertia_action(const Eigen::Vector3d& v) {
  Eigen::Matrix<double, 3, 6> L;
  L << v.x(), v.y(), v.z(), 0, 0, 0,  //
      0, v.x(), 0, v.y(), v.z(), 0,   //
      0, 0, v.x(), 0, v.y(), v.z();
  return L;
}

Chain<double, Eigen::Dynamic> without_parameters(Chain<double, Eigen::Dynamic> c) {
  for (int j = 0; j < c.n; ++j) {
    c.mass[j] = 0.0, c.armature[j] = 0.0;
    c.com[j].setZero(), c.h[j].setZero(), c.Io[j].setZero();
  }
  return c;
}

// Sets (value 1) or clears (value 0) link j's parameter k on the probe chain.
void set_parameter(Chain<double, Eigen::Dynamic>& c, int j, int k, double value) {
  if (k < 6) {
    c.Io[j](kInertiaRow[k], kInertiaCol[k]) = value;
    c.Io[j](kInertiaCol[k], kInertiaRow[k]) = value;
  } else if (k < 9) {
    c.h[j][k - 6] = value;
  } else if (k == 9) {
    c.mass[j] = value;
  } else {
    c.armature[j] = value;
  }
}

}  // namespace

JointTorqueRegressor::JointTorqueRegressor(const RobotModel& model, RegressorColumns columns)
    : columns_(columns),
      per_joint_(kLinkParameters + (columns.rotor ? 1 : 0) + (columns.friction ? 3 : 0)),
      chain_(model),
      probe_(without_parameters(chain_)),
      rot_(model.dof()),
      rnea_(model.dof()),
      w_(static_cast<std::size_t>(model.dof())),
      wd_(static_cast<std::size_t>(model.dof())),
      a_(static_cast<std::size_t>(model.dof())),
      column_(Eigen::VectorXd::Zero(model.dof())) {}

std::string JointTorqueRegressor::parameter_name(int k) const {
  if (k < 0 || k >= parameters()) throw std::out_of_range("JointTorqueRegressor: no column " + std::to_string(k));
  const int j = k / per_joint_, c = k % per_joint_;
  const std::string joint = std::to_string(j + 1);
  if (c < kLinkParameters) return kLinkNames[c] + joint;
  int extra = c - kLinkParameters;
  if (columns_.rotor) {
    if (extra == 0) return "Ia" + joint;
    --extra;
  }
  static constexpr const char* kFriction[3] = {"Fv", "Fc", "Fo"};
  return kFriction[extra] + joint;
}

std::vector<std::string> JointTorqueRegressor::parameter_names() const {
  std::vector<std::string> names;
  for (int k = 0; k < parameters(); ++k) names.push_back(parameter_name(k));
  return names;
}

Eigen::VectorXd JointTorqueRegressor::parameters_of(const RobotModel& model) const {
  if (model.dof() != dof()) {
    throw std::invalid_argument("JointTorqueRegressor: the model has " + std::to_string(model.dof()) +
                                " joints, the regressor " + std::to_string(dof()));
  }
  const Chain<double, Eigen::Dynamic> c(model);
  Eigen::VectorXd pi(parameters());
  for (int j = 0; j < c.n; ++j) {
    double* p = pi.data() + static_cast<std::ptrdiff_t>(j) * per_joint_;
    for (int k = 0; k < 6; ++k) p[k] = c.Io[j](kInertiaRow[k], kInertiaCol[k]);
    for (int k = 0; k < 3; ++k) p[6 + k] = c.h[j][k];
    p[9] = c.mass[j];
    int at = kLinkParameters;
    if (columns_.rotor) p[at++] = c.armature[j];
    if (columns_.friction) {
      const JointParams& jp = model.joints[static_cast<std::size_t>(j)];
      p[at] = jp.damping, p[at + 1] = jp.coulomb, p[at + 2] = 0.0;
    }
  }
  return pi;
}

RobotModel JointTorqueRegressor::with_parameters(const RobotModel& model, const Eigen::VectorXd& pi) const {
  if (model.dof() != dof() || pi.size() != parameters()) {
    throw std::invalid_argument("JointTorqueRegressor::with_parameters: expected a model of " + std::to_string(dof()) +
                                " joints and " + std::to_string(parameters()) + " parameters, got " +
                                std::to_string(model.dof()) + " and " + std::to_string(pi.size()));
  }
  RobotModel out = model;
  const Chain<double, Eigen::Dynamic> given(model);
  for (int j = 0; j < dof(); ++j) {
    const double* p = pi.data() + static_cast<std::ptrdiff_t>(j) * per_joint_;
    JointParams& J = out.joints[static_cast<std::size_t>(j)];
    const std::string link = "link " + std::to_string(j + 1);
    const Eigen::Vector3d h(p[6], p[7], p[8]);
    if (!(p[9] > 0.0) && !(p[9] == 0.0 && h.isZero(0.0))) {
      throw std::invalid_argument("JointTorqueRegressor::with_parameters: " + link + ": mass M" +
                                  std::to_string(j + 1) + " = " + std::to_string(p[9]) +
                                  ", expected > 0 (or 0 with a zero first moment)");
    }
    Eigen::Matrix3d Io;
    for (int k = 0; k < 6; ++k) Io(kInertiaRow[k], kInertiaCol[k]) = Io(kInertiaCol[k], kInertiaRow[k]) = p[k];
    // A massless link (the PUMA's first, in Corke's set) keeps its centre of mass, which nothing reads.
    const Eigen::Vector3d c = p[9] > 0.0 ? Eigen::Vector3d(h / p[9]) : given.com[j];
    // Io = I_c + m (c.c 1 - c c^T) (parallel axes), in joint frame j.
    const Eigen::Matrix3d Ic = Io - p[9] * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    J.mass = p[9];
    const LinkInJointFrame L = link_in_joint_frame(model, j);  // joint_frames' move, undone
    J.com = L.R.transpose() * (c - L.t);
    J.inertia = L.R.transpose() * Ic * L.R;
    J.inertia = 0.5 * (J.inertia + J.inertia.transpose());
    int at = kLinkParameters;
    if (columns_.rotor) {
      const double Ia = p[at++];
      if (J.gear_ratio == 0.0 && Ia != 0.0) {
        throw std::invalid_argument("JointTorqueRegressor::with_parameters: joint " + std::to_string(j + 1) +
                                    ": Ia = " + std::to_string(Ia) + " with gear ratio 0 (no rotor to carry it)");
      }
      J.rotor_inertia = J.gear_ratio == 0.0 ? 0.0 : Ia / (J.gear_ratio * J.gear_ratio);
    }
    if (columns_.friction) J.damping = p[at], J.coulomb = p[at + 1];
  }
  return out;
}

// Each link's angular velocity and acceleration and its origin's
// acceleration, gravity entering as the base's -g: the RNEA's outward pass
// (rnea.hpp), term for term.
template <bool kMixed>
void JointTorqueRegressor::link_motion(const Eigen::Ref<const Eigen::VectorXd>& qd,
                                       const Eigen::Ref<const Eigen::VectorXd>& qdd) {
  Eigen::Vector3d w_p = Eigen::Vector3d::Zero(), wd_p = Eigen::Vector3d::Zero(), a_p = -chain_.gravity;
  for (int j = 0; j < chain_.n; ++j) {
    const Eigen::Matrix3d& R = rot_.R[j];
    const Eigen::Vector3d& pj = rot_.template origin<kMixed>(chain_, j);
    Eigen::Vector3d a = R.transpose() * (a_p + wd_p.cross(pj) + w_p.cross(w_p.cross(pj)));
    const Eigen::Vector3d w_in = R.transpose() * w_p;
    Eigen::Vector3d w = w_in, wd = R.transpose() * wd_p;
    if (slides<kMixed>(chain_, j)) {
      a += Eigen::Vector3d(2.0 * qd[j] * w.y(), -2.0 * qd[j] * w.x(), qdd[j]);
    } else {
      w.z() += qd[j];
      wd += Eigen::Vector3d(w_in.y() * qd[j], -w_in.x() * qd[j], qdd[j]);
    }
    w_[j] = w_p = w, wd_[j] = wd_p = wd, a_[j] = a_p = a;
  }
}

// Link j's force and moment about its origin (frame j) per unit of each of
// its 10 parameters:
//   f = M a + (wd x + w x w x) m c
//   m = Io wd + w x Io w + m c x a.
void JointTorqueRegressor::link_wrench(int j, Wrench& W) const {
  const Eigen::Vector3d &w = w_[j], &wd = wd_[j], &a = a_[j];
  W.setZero();
  const Eigen::Matrix3d sw = skew(w);
  W.block<3, 3>(0, 6) = skew(wd) + sw * sw;
  W.block<3, 1>(0, 9) = a;
  W.block<3, 6>(3, 0) = inertia_action(wd) + sw * inertia_action(w);
  W.block<3, 3>(3, 6) = -skew(a);
}

// Joint i's row of link j's block: the wrench carried to frame i, its
// moment (revolute) or force (prismatic) along z_i.
template <bool kMixed>
void JointTorqueRegressor::carry_inwards(Eigen::Ref<Eigen::MatrixXd> Y) {
  Wrench W, parent;
  for (int j = 0; j < chain_.n; ++j) {
    link_wrench(j, W);
    const Eigen::Index col = static_cast<Eigen::Index>(j) * per_joint_;
    for (int i = j;; --i) {
      Y.block<1, kLinkParameters>(i, col) = slides<kMixed>(chain_, i) ? W.row(2) : W.row(5);
      if (i == 0) break;
      const Eigen::Matrix3d& R = rot_.R[i];
      parent.topRows<3>().noalias() = R * W.topRows<3>();
      parent.bottomRows<3>().noalias() = R * W.bottomRows<3>();
      parent.bottomRows<3>().noalias() += skew(rot_.template origin<kMixed>(chain_, i)) * parent.topRows<3>();
      W = parent;
    }
  }
}

// Joint j's rotor column Ia (Z^2 Im qdd_j) when `rotor`, and its friction
// columns (Fv qd_j, Fc sign(qd_j), Fo) when the regressor has them.
void JointTorqueRegressor::drive_columns(const Eigen::Ref<const Eigen::VectorXd>& qd,
                                         const Eigen::Ref<const Eigen::VectorXd>& qdd, bool rotor,
                                         Eigen::Ref<Eigen::MatrixXd> Y) const {
  for (int j = 0; j < chain_.n; ++j) {
    Eigen::Index col = static_cast<Eigen::Index>(j) * per_joint_ + kLinkParameters;
    if (columns_.rotor && rotor) Y(j, col) = qdd[j];
    if (columns_.rotor) ++col;
    if (columns_.friction) {
      Y(j, col) = qd[j];
      Y(j, col + 1) = qd[j] > 0.0 ? 1.0 : (qd[j] < 0.0 ? -1.0 : 0.0);
      Y(j, col + 2) = 1.0;
    }
  }
}

void JointTorqueRegressor::check_sizes(const Eigen::Ref<const Eigen::VectorXd>& q,
                                       const Eigen::Ref<const Eigen::VectorXd>& qd,
                                       const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                       const Eigen::Ref<Eigen::MatrixXd>& Y) const {
  const Eigen::Index n = dof();
  if (q.size() != n || qd.size() != n || qdd.size() != n || Y.rows() != n || Y.cols() != parameters()) {
    throw std::invalid_argument("JointTorqueRegressor: expected q, qd, qdd of " + std::to_string(n) + " and Y of " +
                                std::to_string(n) + " x " + std::to_string(parameters()));
  }
}

void JointTorqueRegressor::compute(const Eigen::Ref<const Eigen::VectorXd>& q,
                                   const Eigen::Ref<const Eigen::VectorXd>& qd,
                                   const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y) {
  check_sizes(q, qd, qdd, Y);
  Y.setZero();
  rot_.compute(chain_, q);
  if (chain_.any_prismatic) {
    link_motion<true>(qd, qdd);
    carry_inwards<true>(Y);
  } else {
    link_motion<false>(qd, qdd);
    carry_inwards<false>(Y);
  }
  drive_columns(qd, qdd, true, Y);
}

void JointTorqueRegressor::compute_by_probing(const Eigen::Ref<const Eigen::VectorXd>& q,
                                              const Eigen::Ref<const Eigen::VectorXd>& qd,
                                              const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                              Eigen::Ref<Eigen::MatrixXd> Y) {
  check_sizes(q, qd, qdd, Y);
  Y.setZero();
  const int probed = kLinkParameters + (columns_.rotor ? 1 : 0);
  rot_.compute(probe_, q);  // the joint transforms once: they do not depend on the parameters
  for (int j = 0; j < probe_.n; ++j) {
    for (int k = 0; k < probed; ++k) {
      set_parameter(probe_, j, k, 1.0);
      rnea_.run(probe_, rot_, qd, qdd, true, column_);  // one RNEA pass per column
      set_parameter(probe_, j, k, 0.0);
      Y.col(static_cast<Eigen::Index>(j) * per_joint_ + k) = column_;
    }
  }
  drive_columns(qd, qdd, false, Y);  // the friction columns: not in the Newton-Euler equations
}

}  // namespace pumasim
