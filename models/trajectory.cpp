#include "models/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/LU>

namespace pumasim {

Path::Path(Eigen::Vector2d start, double heading, double height, std::vector<PathSegment> segs)
    : height_(height) {
  Eigen::Vector2d p = start;
  double h = heading;
  for (const PathSegment& s : segs) {
    const bool arc = s.radius > 0;
    const double len = arc ? s.radius * std::abs(s.angle) : s.length;
    if (!(len > 0)) throw std::invalid_argument("path segment of zero length");
    const double kappa = arc ? (s.angle > 0 ? 1.0 : -1.0) / s.radius : 0.0;
    pieces_.push_back({total_, len, p, h, kappa});
    // Advance the turtle to the end of the piece.
    if (arc) {
      const double h1 = h + kappa * len;
      p += Eigen::Vector2d(std::sin(h1) - std::sin(h), -std::cos(h1) + std::cos(h)) / kappa;
      h = h1;
    } else {
      p += len * Eigen::Vector2d(std::cos(h), std::sin(h));
    }
    total_ += len;
  }
  if (pieces_.empty()) throw std::invalid_argument("path without segments");
}

void Path::eval(double s, Eigen::Vector3d& p, Eigen::Vector3d& dp, Eigen::Vector3d& ddp) const {
  s = std::clamp(s, 0.0, total_);
  std::size_t k = 0;
  while (k + 1 < pieces_.size() && s > pieces_[k].s0 + pieces_[k].len) ++k;
  const Piece& pc = pieces_[k];
  const double u = s - pc.s0, h = pc.heading0 + pc.curvature * u;
  Eigen::Vector2d xy;
  if (pc.curvature == 0.0) {
    xy = pc.p0 + u * Eigen::Vector2d(std::cos(h), std::sin(h));
  } else {
    xy = pc.p0 + Eigen::Vector2d(std::sin(h) - std::sin(pc.heading0),
                                 -std::cos(h) + std::cos(pc.heading0)) / pc.curvature;
  }
  p = Eigen::Vector3d(xy.x(), xy.y(), height_);
  dp = Eigen::Vector3d(std::cos(h), std::sin(h), 0);
  ddp = pc.curvature * Eigen::Vector3d(-std::sin(h), std::cos(h), 0);
}

SpeedProfile::SpeedProfile(std::vector<Eigen::Vector2d> shape, double path_length,
                           double max_speed)
    : vmax_(max_speed) {
  if (shape.size() < 2 || shape.front().x() != 0.0 || shape.back().x() != 1.0) {
    throw std::invalid_argument("speed profile: expected points from t/T = 0 to t/T = 1");
  }
  double area = 0, peak = 0;
  for (std::size_t i = 1; i < shape.size(); ++i) {
    if (!(shape[i].x() > shape[i - 1].x())) {
      throw std::invalid_argument("speed profile: t/T must increase");
    }
    area += 0.5 * (shape[i].y() + shape[i - 1].y()) * (shape[i].x() - shape[i - 1].x());
  }
  for (const auto& pt : shape) peak = std::max(peak, pt.y());
  if (!(area > 0) || std::abs(peak - 1.0) > 1e-12) {
    throw std::invalid_argument("speed profile: expected speeds v/v_max in [0, 1] with maximum 1");
  }
  // s(T) = v_max T area = L.
  T_ = path_length / (max_speed * area);
  double s = 0;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    shape_.emplace_back(shape[i].x() * T_, shape[i].y() * max_speed);
    if (i > 0) s += 0.5 * (shape_[i].y() + shape_[i - 1].y()) * (shape_[i].x() - shape_[i - 1].x());
    s_at_.push_back(s);
  }
}

void SpeedProfile::eval(double t, double& s, double& sd, double& sdd) const {
  if (t <= 0) {
    s = 0, sd = shape_.front().y(), sdd = 0;
    return;
  }
  if (t >= T_) {
    s = s_at_.back(), sd = 0, sdd = 0;
    return;
  }
  std::size_t k = 0;
  while (k + 2 < shape_.size() && t > shape_[k + 1].x()) ++k;
  const double t0 = shape_[k].x(), v0 = shape_[k].y();
  const double a = (shape_[k + 1].y() - v0) / (shape_[k + 1].x() - t0);
  const double u = t - t0;
  s = s_at_[k] + v0 * u + 0.5 * a * u * u;
  sd = v0 + a * u;
  sdd = a;
}

Reference::Reference(RobotModel robot, int n, Eigen::Matrix<double, 6, 1> q_held,
                     PumaConfig config, Eigen::Matrix3d R_fixed, Path path, SpeedProfile profile)
    : robot_(std::move(robot)),
      n_(n),
      q_held_(q_held),
      config_(config),
      R_fixed_(R_fixed),
      path_(std::move(path)),
      profile_(std::move(profile)) {
  if (const std::string why = puma_ik_unsupported(robot_); !why.empty()) {
    throw std::invalid_argument(why);
  }
  if (n_ != 3 && n_ != 6) throw std::invalid_argument("reference: expected 3 or 6 joints");
  // The branch table: the first point's angles (the configured wrist
  // solution) nearest the middle of each range, then each point's solution
  // and angles nearest the previous one's. 2000 points: a few
  // ms once per scene. A point out of reach, a joint leaving its range or
  // moving more than pi/4 between two points (a pass close to a singularity)
  // is reported here, before any run.
  const int points = 2000;
  const double L = path_.length();
  Eigen::Matrix<double, 6, 1> prev;
  for (int j = 0; j < 6; ++j) prev[j] = 0.5 * (robot_.joints[j].q_min + robot_.joints[j].q_max);
  branch_.reserve(points);
  for (int k = 0; k < points; ++k) {
    const double s = L * k / (points - 1);
    Eigen::Vector3d p, dp, ddp;
    path_.eval(s, p, dp, ddp);
    Eigen::Matrix<double, 6, 1> q;
    if (!joint_angles(p, prev, k > 0, q)) {
      throw std::runtime_error("reference: the path point (" + std::to_string(p.x()) + ", " +
                               std::to_string(p.y()) + ", " + std::to_string(p.z()) + ") m at s = " +
                               std::to_string(s) + " m is out of reach");
    }
    for (int j = 0; j < n_; ++j) {
      const JointParams& J = robot_.joints[j];
      if (k > 0 && std::abs(q[j] - prev[j]) > M_PI / 4) {
        throw std::runtime_error("reference: joint " + std::to_string(j + 1) + " turns by " +
                                 std::to_string(q[j] - prev[j]) + " rad between s = " +
                                 std::to_string(L * (k - 1) / (points - 1)) + " and " + std::to_string(s) +
                                 " m of the path (too close to a singularity)");
      }
      if (q[j] < J.q_min - 1e-9 || q[j] > J.q_max + 1e-9) {
        throw std::runtime_error("reference: joint " + std::to_string(j + 1) + " at " + std::to_string(q[j]) +
                                 " rad leaves its limits [" + std::to_string(J.q_min) + ", " +
                                 std::to_string(J.q_max) + "] at s = " + std::to_string(s) + " m of the path");
      }
    }
    branch_.push_back(q);
    prev = q;
  }
}

bool Reference::joint_angles(const Eigen::Vector3d& p, const Eigen::Matrix<double, 6, 1>& near,
                             bool track_wrist, Eigen::Matrix<double, 6, 1>& q) const {
  q = q_held_;
  bool ok;
  if (n_ == 3) {
    Eigen::Vector3d q3;
    ok = puma_ik_position(robot_, p, config_, q3);
    q.head<3>() = q3;
  } else {
    ok = puma_ik(robot_, p, R_fixed_, config_, q);
  }
  for (int j = 0; j < n_; ++j) q[j] += 2 * M_PI * std::round((near[j] - q[j]) / (2 * M_PI));
  if (n_ == 6 && track_wrist) {
    // The other wrist solution (q4 + pi, -q5, q6 + pi) gives the same pose;
    // through a wrist singularity (q5 = 0) the continuous motion passes from
    // one to the other, so take whichever is nearer.
    Eigen::Vector3d alt(q[3] + M_PI, -q[4], q[5] + M_PI);
    for (int j = 0; j < 3; ++j) alt[j] += 2 * M_PI * std::round((near[3 + j] - alt[j]) / (2 * M_PI));
    if ((alt - near.tail<3>()).squaredNorm() < (q.tail<3>() - near.tail<3>()).squaredNorm()) q.tail<3>() = alt;
  }
  return ok;
}

Eigen::Vector3d Reference::position(const Eigen::Matrix<double, 6, 1>& q_full) const {
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  forward_kinematics<double>(robot_, q_full, R, p);
  return p;
}

void Reference::jacobian(const Eigen::Matrix<double, 6, 1>& q, Eigen::Matrix<double, 6, 6>& J) const {
  geometric_jacobian(robot_, q, n_, J);
}

void Reference::jacobian_rate(const Eigen::Matrix<double, 6, 1>& q, const Eigen::Matrix<double, 6, 1>& qd,
                              Eigen::Matrix<double, 6, 6>& Jdot) const {
  Eigen::Matrix<Dual, 6, 1> qq;
  for (int j = 0; j < 6; ++j) qq[j] = Dual(q[j], qd[j]);
  Eigen::Matrix<Dual, 6, 6> JJ;
  geometric_jacobian(robot_, qq, n_, JJ);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) Jdot(r, c) = JJ(r, c).deriv();
}

void Reference::eval(double t, ReferenceSample& out) const {
  double s, sd, sdd;
  profile_.eval(t, s, sd, sdd);
  Eigen::Vector3d p, dp, ddp;
  path_.eval(s, p, dp, ddp);
  out.p = p;
  out.v = dp * sd;
  const Eigen::Vector3d a = ddp * sd * sd + dp * sdd;
  // Joint positions: the IK's branch nearest the table's angles at this s.
  const double L = path_.length();
  const auto k = static_cast<std::size_t>(std::lround(std::clamp(s / L, 0.0, 1.0) * (branch_.size() - 1)));
  Eigen::Matrix<double, 6, 1> q;
  const bool ok = joint_angles(p, branch_[k], true, q);
  if (!ok) {
    throw std::runtime_error("reference: the path point (" + std::to_string(p.x()) + ", " +
                             std::to_string(p.y()) + ", " + std::to_string(p.z()) +
                             ") m at t = " + std::to_string(t) + " s is out of reach");
  }
  // Rates: J qd = [v; 0] and J qdd = [a; 0] - Jdot qd, over the simulated joints
  // (n = 3: position rows only). Jdot qd exactly: the Jacobian on dual numbers
  // q + eps qd (a central difference here put noise of about 1e-10 into qdd,
  // which a tight-tolerance reference run could not get past).
  Eigen::Matrix<double, 6, 6> J;
  jacobian(q, J);
  const int rows = n_ == 3 ? 3 : 6;
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  rhs.head<3>() = out.v;
  Eigen::Matrix<double, 6, 1> qd = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> qdd = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> Jdot;
  if (rows == 3) {
    const Eigen::Matrix3d A = J.topLeftCorner<3, 3>();
    const Eigen::PartialPivLU<Eigen::Matrix3d> lu(A);
    qd.head<3>() = lu.solve(out.v);
    jacobian_rate(q, qd, Jdot);
    const Eigen::Vector3d Jdot_qd = Jdot.topLeftCorner<3, 3>() * qd.head<3>();
    qdd.head<3>() = lu.solve(a - Jdot_qd);
  } else {
    const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> lu(J);
    qd = lu.solve(rhs);
    jacobian_rate(q, qd, Jdot);
    Eigen::Matrix<double, 6, 1> acc = Eigen::Matrix<double, 6, 1>::Zero();
    acc.head<3>() = a;
    qdd = lu.solve(acc - Jdot * qd);
  }
  out.q = q;
  out.qd = qd;
  out.qdd = qdd;
}

}  // namespace pumasim
