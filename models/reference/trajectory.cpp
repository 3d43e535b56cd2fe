#include "models/reference/trajectory.hpp"

#include "core/time_rule.hpp"
#include "models/reference/numerical_ik.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
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
  for (Piece& pc : pieces_) {
    Eigen::Vector3d a, b, d1, d2;
    eval(pc.s0, a, d1, d2);
    eval(pc.s0 + pc.len, b, d1, d2);
    pc.a = a.head<2>(), pc.b = b.head<2>();
    pc.dir = Eigen::Vector2d(std::cos(pc.heading0), std::sin(pc.heading0));
    if (pc.curvature != 0.0) {
      pc.centre = pc.p0 + Eigen::Vector2d(-std::sin(pc.heading0), std::cos(pc.heading0)) / pc.curvature;
    }
  }
}

void Path::eval(double s, Eigen::Vector3d& p, Eigen::Vector3d& dp, Eigen::Vector3d& ddp) const {
  s = std::clamp(s, 0.0, total_);
  eval_piece(piece(s), s, p, dp, ddp);
}

int Path::piece(double s) const {
  std::size_t k = 0;
  while (k + 1 < pieces_.size() && s > pieces_[k].s0 + pieces_[k].len) ++k;
  return static_cast<int>(k);
}

void Path::eval_piece(int k, double s, Eigen::Vector3d& p, Eigen::Vector3d& dp, Eigen::Vector3d& ddp) const {
  const Piece& pc = pieces_[static_cast<std::size_t>(k)];
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

const char* to_string(Interpolation i) {
  switch (i) {
    case Interpolation::kCartesian: return "cartesian";
    case Interpolation::kJointCubic: return "joint-cubic";
    case Interpolation::kJointQuintic: return "joint-quintic";
  }
  return "?";
}

std::vector<double> Path::breaks() const {
  std::vector<double> out;
  for (std::size_t k = 1; k < pieces_.size(); ++k) {
    if (pieces_[k].curvature != pieces_[k - 1].curvature) out.push_back(pieces_[k].s0);
  }
  return out;
}

double Path::distance(const Eigen::Vector3d& p, int* nearest) const {
  const Eigen::Vector2d xy = p.head<2>();
  double best = std::numeric_limits<double>::infinity();  // in the plane; the height once, at the end
  const int count = static_cast<int>(pieces_.size());
  const int first = nearest && *nearest >= 0 && *nearest < count ? *nearest : 0;
  for (int i = 0; i < count; ++i) {  // from `first`: its distance bounds the others' work
    const int k = (first + i) % count;
    const Piece& pc = pieces_[static_cast<std::size_t>(k)];
    double d = std::min((xy - pc.a).norm(), (xy - pc.b).norm());  // the ends
    if (pc.curvature == 0.0) {
      const double u = (xy - pc.p0).dot(pc.dir);
      if (u > 0 && u < pc.len) d = std::min(d, (xy - pc.p0 - u * pc.dir).norm());
    } else {
      // Arc points: c + (sin h, -cos h) / kappa with h = heading0 + kappa u.
      const Eigen::Vector2d r = xy - pc.centre;
      const double to_circle = std::abs(r.norm() - 1.0 / std::abs(pc.curvature));
      // The circle's nearest point counts only when it is on the arc; it
      // can lower the result only when nearer than the ends and than the
      // best so far (then the angle is taken: the same minimum, exactly).
      if (r.norm() > 0 && to_circle < d && to_circle < best) {
        const double sg = pc.curvature > 0 ? 1.0 : -1.0;
        const double h = std::atan2(sg * r.x(), -sg * r.y());
        double u = std::remainder(h - pc.heading0, 2 * M_PI) / pc.curvature;
        if (u < 0) u += 2 * M_PI / std::abs(pc.curvature);
        if (u < pc.len) d = to_circle;
      }
    }
    if (d < best) {
      best = d;
      if (nearest) *nearest = k;
    }
  }
  return std::hypot(best, p.z() - height_);
}

Reference::Reference(RobotModel robot, int n, Eigen::VectorXd q_held,
                     PumaConfig config, Eigen::Matrix3d R_fixed, Path path, Timing timing,
                     Interpolation interpolation, int via_segments, IkSettings ik)
    : robot_(std::move(robot)),
      n_(n),
      q_held_(q_held),
      config_(config),
      R_fixed_(R_fixed),
      path_(std::move(path)),
      timing_(std::move(timing)),
      interp_(interpolation),
      ik_(std::move(ik)) {
  if (q_held_.size() != robot_.dof()) throw std::invalid_argument("reference: q_held needs one entry per joint");
  if (ik_.method == IkMethod::kClosedForm) {
    if (const std::string why = puma_ik_unsupported(robot_); !why.empty()) {
      throw std::invalid_argument(why);
    }
    if (n_ != 3 && n_ != 6) throw std::invalid_argument("reference: expected 3 or 6 joints");
  } else if (n_ < 1 || n_ > robot_.dof()) {
    throw std::invalid_argument("reference: a Cartesian path needs 1 to " + std::to_string(robot_.dof()) +
                                " simulated joints, not " + std::to_string(n_));
  }
  if (ik_.guess && ik_.guess->size() < n_) throw std::invalid_argument("reference: the guess needs n entries");
  redundant_ = ik_.method == IkMethod::kNumerical && n_ > (n_ >= 6 ? 6 : 3);
  build_branch_table();
  if (interp_ != Interpolation::kCartesian) {
    if (via_segments < 1) throw std::invalid_argument("reference: expected at least one via-point segment");
    build_joint_spline(via_segments);
    breakpoints_.assign(knots_.begin() + 1, knots_.end());
  } else {
    breakpoints_ = timing_.breakpoints();
    for (double s : path_->breaks()) breakpoints_.push_back(timing_.time_at(s));
  }
  finish_breakpoints();
}

Reference::Reference(RobotModel robot, Eigen::VectorXd q_held, JointCurve curve, Timing timing)
    : robot_(std::move(robot)),
      n_(curve.joints()),
      q_held_(q_held),
      R_fixed_(Eigen::Matrix3d::Identity()),
      curve_(std::move(curve)),
      timing_(std::move(timing)),
      interp_(curve_->kind() == JointCurve::Kind::kCubic ? Interpolation::kJointCubic
                                                         : Interpolation::kJointQuintic) {
  if (n_ > robot_.dof()) throw std::invalid_argument("reference: the joint curve has more joints than the robot");
  if (q_held_.size() != robot_.dof()) throw std::invalid_argument("reference: q_held needs one entry per joint");
  if (!(std::abs(timing_.length() - curve_->length()) <= 1e-9 * curve_->length())) {
    throw std::invalid_argument("reference: the timing law does not run along the whole curve");
  }
  check_curve_limits();
  // The curve's knots, at the times the timing law reaches them (the given
  // times themselves when it is the identity).
  const bool identity = timing_.kind() == "unit-speed";
  breakpoints_ = timing_.breakpoints();
  for (double x : curve_->breaks()) breakpoints_.push_back(identity ? x : timing_.time_at(x));
  finish_breakpoints();
  build_trace();
}

const Path& Reference::path() const {
  if (!path_) throw std::logic_error("reference: a joint curve has no Cartesian path");
  return *path_;
}

std::string Reference::point_at(const Eigen::Vector3d& p, double s) const {
  return "the path point (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
         std::to_string(p.z()) + ") m at s = " + std::to_string(s) + " m (t = " +
         std::to_string(timing_.time_at(std::clamp(s, 0.0, timing_.length()))) + " s)";
}

// The branch table: the first point's angles (closed form: the configured
// wrist solution nearest the middle of each range; numerical: from the guess,
// default the middle of each range), then each point's solution and angles
// nearest the previous one's. 2000 points: cheap, once per scene (measured:
// commit 627bd3b). A point out of reach, a joint leaving its range or moving
// more than pi/4 between two points (a pass close to a singularity) is
// reported here, before any run.
void Reference::build_branch_table() {
  const int points = 2000;
  const double L = path_->length();
  Eigen::VectorXd prev = q_held_;
  for (int j = 0; j < n_; ++j) {  // the middle of the range; 0 for a joint without limits (a slide)
    const JointParams& J = robot_.joints[j];
    prev[j] = std::isfinite(J.q_min) && std::isfinite(J.q_max) ? 0.5 * (J.q_min + J.q_max) : 0.0;
  }
  if (ik_.method == IkMethod::kNumerical && ik_.guess) {
    for (int j = 0; j < n_; ++j) prev[j] = (*ik_.guess)[j];
  }
  rest_ = prev;  // the redundancy rule's rest pose: the guess
  IkWorkspace ik = ik_workspace();
  branch_.reserve(points);
  for (int k = 0; k < points; ++k) {
    const double s = L * k / (points - 1);
    Eigen::Vector3d p, dp, ddp;
    path_->eval(s, p, dp, ddp);
    Eigen::VectorXd q(robot_.dof());
    if (!joint_angles(p, prev, k > 0, q, ik)) {
      throw std::runtime_error("reference: " + point_at(p, s) + " is out of reach of the flange, " + robot_.flange);
    }
    for (int j = 0; j < n_; ++j) {
      const JointParams& J = robot_.joints[j];
      const char* unit = J.prismatic() ? " m" : " rad";
      if (k > 0 && std::abs(q[j] - prev[j]) > M_PI / 4) {
        throw std::runtime_error("reference: joint " + std::to_string(j + 1) + " moves by " +
                                 std::to_string(q[j] - prev[j]) + unit + " between s = " +
                                 std::to_string(L * (k - 1) / (points - 1)) + " and " + std::to_string(s) +
                                 " m of the path (too close to a singularity)");
      }
      if (q[j] < J.q_min - 1e-9 || q[j] > J.q_max + 1e-9) {
        throw std::runtime_error("reference: joint " + std::to_string(j + 1) + " at " + std::to_string(q[j]) + unit +
                                 " leaves its limits [" + std::to_string(J.q_min) + ", " +
                                 std::to_string(J.q_max) + "] at s = " + std::to_string(s) + " m of the path");
      }
    }
    branch_.push_back(q);
    prev = q;
  }
}

// A joint curve within the joints' limits: at its knots and 16 points per
// piece (a spline may overshoot between knots; a narrower excursion between
// the samples is not caught).
void Reference::check_curve_limits() const {
  const std::vector<double>& x = curve_->knots();
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    for (int i = 0; i <= 16; ++i) {
      const double xi = i == 16 ? x[k + 1] : x[k] + (x[k + 1] - x[k]) * i / 16;
      Eigen::VectorXd q(n_), dq(n_), ddq(n_);
      curve_->eval_piece(static_cast<int>(k), xi, q, dq, ddq);
      for (int j = 0; j < n_; ++j) {
        const JointParams& J = robot_.joints[j];
        if (q[j] < J.q_min - 1e-9 || q[j] > J.q_max + 1e-9) {
          throw std::runtime_error("reference: joint " + std::to_string(j + 1) + " at " + std::to_string(q[j]) +
                                   " rad leaves its limits [" + std::to_string(J.q_min) + ", " +
                                   std::to_string(J.q_max) + "] at the points' time " + std::to_string(xi) +
                                   " s of the joint curve");
        }
      }
    }
  }
}

// The flange's polyline along a joint curve, for deviation().
void Reference::build_trace() {
  const std::vector<double>& x = curve_->knots();
  const double L = curve_->length();
  Eigen::VectorXd q = q_held_, c(n_), dc(n_), ddc(n_);
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    const int sub = std::max(1, static_cast<int>(std::ceil(4000 * (x[k + 1] - x[k]) / L)));
    for (int i = 0; i < sub; ++i) {
      curve_->eval_piece(static_cast<int>(k), x[k] + (x[k + 1] - x[k]) * i / sub, c, dc, ddc);
      for (int j = 0; j < n_; ++j) q[j] = c[j];
      trace_.push_back(position(q));
    }
  }
  for (int j = 0; j < n_; ++j) q[j] = curve_->points().back()[j];
  trace_.push_back(position(q));
}

double Reference::deviation(const Eigen::Vector3d& p, int* nearest) const {
  if (path_) return path_->distance(p, nearest);
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k + 1 < trace_.size(); ++k) {
    const Eigen::Vector3d a = trace_[k], d = trace_[k + 1] - a;
    const double len2 = d.squaredNorm();
    const double u = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (p - a - u * d).norm());
  }
  return best;
}

void Reference::finish_breakpoints() {
  std::sort(breakpoints_.begin(), breakpoints_.end());
  // One instant for breakpoints that coincide to rounding (a piece of the
  // timing law ending where a path piece does).
  seg_tol_ = time_tolerance(timing_.duration());  // core/time_rule.hpp
  breakpoints_.erase(std::unique(breakpoints_.begin(), breakpoints_.end(),
                                 [this](double a, double b) { return b - a <= seg_tol_; }),
                     breakpoints_.end());
  for (std::size_t k = 0; k <= breakpoints_.size(); ++k) {
    const double a = k == 0 ? 0.0 : breakpoints_[k - 1];
    const double mid = k < breakpoints_.size() ? 0.5 * (a + breakpoints_[k]) : a + 1.0;
    if (curve_ || interp_ == Interpolation::kCartesian) {
      double s, sd, sdd;
      timing_.eval(mid, s, sd, sdd);
      seg_timing_.push_back(timing_.piece(mid));
      seg_path_.push_back(curve_ ? curve_->piece(std::clamp(s, 0.0, curve_->length()))
                                 : path_->piece(std::clamp(s, 0.0, path_->length())));
    } else {
      const auto after = std::upper_bound(knots_.begin(), knots_.end(), std::min(mid, timing_.duration()));
      seg_timing_.push_back(static_cast<int>(std::clamp<std::ptrdiff_t>(after - knots_.begin() - 1, 0,
                                                                        std::ssize(coef_) - 1)));
      seg_path_.push_back(0);
    }
  }
}

double Reference::next_breakpoint(double t) const {
  const auto it = std::upper_bound(breakpoints_.begin(), breakpoints_.end(), t);
  return it == breakpoints_.end() ? std::numeric_limits<double>::infinity() : *it;
}

int Reference::segment_after(double t) const {
  return static_cast<int>(std::upper_bound(breakpoints_.begin(), breakpoints_.end(), t + seg_tol_) -
                          breakpoints_.begin());
}

void Reference::build_joint_spline(int M) {
  // Via-points at equal arc-length steps, at the times the timing law
  // reaches them; q, qd, qdd there from the Cartesian reference.
  knots_.resize(M + 1);
  std::vector<ReferenceSample> via(M + 1, sample());
  for (int k = 0; k <= M; ++k) {
    knots_[k] = k == 0 ? 0.0 : k == M ? timing_.duration() : timing_.time_at(path_->length() * k / M);
    eval_cartesian(knots_[k], via[k], -1);
  }
  for (int k = 0; k < M; ++k) {
    if (!(knots_[k + 1] > knots_[k])) throw std::invalid_argument("reference: via-points at the same time");
  }
  coef_.assign(M, Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(n_, 6));
  std::vector<double> y(M + 1);
  for (int j = 0; j < n_; ++j) {
    std::vector<PieceCoefficients> c(M);
    if (interp_ == Interpolation::kJointQuintic) {
      // Hermite quintic on each piece: q, qd, qdd at both ends.
      for (int k = 0; k < M; ++k) {
        c[k] = quintic_hermite(knots_[k + 1] - knots_[k], via[k].q[j], via[k].qd[j], via[k].qdd[j],
                               via[k + 1].q[j], via[k + 1].qd[j], via[k + 1].qdd[j]);
      }
    } else {
      // C2 cubic spline through the via-points, its end slopes clamped to the
      // reference's end speeds.
      for (int k = 0; k <= M; ++k) y[k] = via[k].q[j];
      c = clamped_cubic_spline(knots_, y, via[0].qd[j], via[M].qd[j]);
    }
    for (int k = 0; k < M; ++k)
      for (int e = 0; e < 6; ++e) coef_[k](j, e) = c[k][static_cast<std::size_t>(e)];
  }
}

void Reference::eval_joint_space(double t, ReferenceSample& out, int segment, bool extend) const {
  const double T = timing_.duration();
  // A moving piece continued past its ends (extend), or t within [0, T].
  const bool continued = extend && segment >= 0 && segment < std::ssize(breakpoints_);
  const double tc = continued ? t : std::clamp(t, 0.0, T);
  // The piece [t_k, t_k+1) holding tc (or the segment's); the last one also holds T.
  const auto after = std::upper_bound(knots_.begin(), knots_.end(), tc) - knots_.begin();
  const std::size_t k =
      segment >= 0 ? static_cast<std::size_t>(seg_timing_[static_cast<std::size_t>(segment)])
                   : static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(after - 1, 0, std::ssize(coef_) - 1));
  const double u = tc - knots_[k];
  const auto& c = coef_[k];
  Eigen::VectorXd &q = out.q, &qd = out.qd, &qdd = out.qdd;
  q = q_held_, qd.setZero(), qdd.setZero();
  for (int j = 0; j < n_; ++j) {
    double p = c(j, 5), v = 5 * c(j, 5), a = 20 * c(j, 5);
    for (int e = 4; e >= 0; --e) p = p * u + c(j, e);
    for (int e = 4; e >= 1; --e) v = v * u + e * c(j, e);
    for (int e = 4; e >= 2; --e) a = a * u + e * (e - 1) * c(j, e);
    q[j] = p;
    // Moving inside (0, T); with a segment, up to its ends (the hold after T is the last).
    const bool moving = continued || (segment >= 0 ? segment < std::ssize(breakpoints_) && t > 0 : t > 0 && t < T);
    if (moving) qd[j] = v, qdd[j] = a;
  }
  out.p = position(q);
  out.v = flange_velocity(q, qd, out.work);
}

bool Reference::joint_angles(const Eigen::Vector3d& p, const Eigen::VectorXd& near, bool track_wrist,
                             Eigen::VectorXd& q, IkWorkspace& ik) const {
  if (ik_.method == IkMethod::kNumerical) {
    q = near;
    q.tail(robot_.dof() - n_) = q_held_.tail(robot_.dof() - n_);
    const IkSolveResult r = dls_ik(robot_, n_, p, n_ >= 6 ? &R_fixed_ : nullptr, q, ik, rest());
    if (!r.reached) return false;
    if (!r.converged) {  // reached, but the redundancy rule's Newton solve did not settle
      throw std::runtime_error("reference: the redundancy rule (the pose nearest ik_guess) did not converge at the "
                               "path point (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
                               std::to_string(p.z()) + ") m: residual " + std::to_string(r.error) +
                               " (a singular pose, or ik_guess far from the path's poses)");
    }
    // Revolute joints: the same pose at every 2 pi; the representative nearest
    // `near`. Not under the redundancy rule, whose condition q - q_r = J^T mu
    // is not 2 pi-periodic (its solution from `near` is continuous already).
    if (redundant_) return true;
    for (int j = 0; j < n_; ++j) {
      if (!robot_.joints[j].prismatic()) q[j] += 2 * M_PI * std::round((near[j] - q[j]) / (2 * M_PI));
    }
    return true;
  }
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
    if ((alt - near.segment<3>(3)).squaredNorm() < (q.segment<3>(3) - near.segment<3>(3)).squaredNorm()) {
      q.segment<3>(3) = alt;
    }
  }
  return ok;
}

Eigen::Vector3d Reference::position(const Eigen::Ref<const Eigen::VectorXd>& q_full) const {
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  forward_kinematics<double>(robot_, q_full, R, p);
  return p;
}

Eigen::Vector3d Reference::flange_velocity(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                           ReferenceScratch& w) const {
  geometric_jacobian(robot_, q, n_, w.J);
  return w.J.topRows<3>() * qd;
}

IkWorkspace Reference::ik_workspace() const {
  return IkWorkspace(robot_.dof(), n_, task_rows());
}

ReferenceSample Reference::sample() const {
  ReferenceSample s;
  const int dof = robot_.dof();
  s.q = q_held_, s.qd = Eigen::VectorXd::Zero(dof), s.qdd = Eigen::VectorXd::Zero(dof);
  s.p.setZero(), s.v.setZero();
  ReferenceScratch& w = s.work;
  w.q = q_held_, w.near = q_held_;
  w.c = w.dc = w.ddc = Eigen::VectorXd::Zero(dof);
  w.J = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, dof);
  w.ik = ik_workspace();
  return s;
}

void Reference::eval(double t, ReferenceSample& out, int segment, bool extend) const {
  if (!fits(out)) out = sample();  // allocates once
  const int m = static_cast<int>(breakpoints_.size());
  const bool inside = segment >= 0 && segment <= m &&
                      (extend ||
                       ((segment == 0 || t >= breakpoints_[static_cast<std::size_t>(segment - 1)] - seg_tol_) &&
                        (segment == m || t <= breakpoints_[static_cast<std::size_t>(segment)] + seg_tol_)));
  if (!inside) segment = -1;
  if (curve_) {
    eval_curve(t, out, segment);
  } else if (interp_ == Interpolation::kCartesian) {
    eval_cartesian(t, out, segment);
  } else {
    eval_joint_space(t, out, segment, extend);
  }
}

Eigen::Vector3d Reference::point(double t, ReferenceSample& out) const {
  if (curve_ || interp_ != Interpolation::kCartesian) {
    eval(t, out);
    return out.p;
  }
  double s, sd, sdd;
  Eigen::Vector3d p, dp, ddp;
  timing_.eval(t, s, sd, sdd);  // eval_cartesian's steps with no segment given, up to out.p
  path_->eval(s, p, dp, ddp);
  return p;
}

void Reference::eval_cartesian(double t, ReferenceSample& out, int segment) const {
  double s, sd, sdd;
  Eigen::Vector3d p, dp, ddp;
  if (segment < 0) {
    timing_.eval(t, s, sd, sdd);
    path_->eval(s, p, dp, ddp);
  } else {
    timing_.eval_piece(seg_timing_[static_cast<std::size_t>(segment)], t, s, sd, sdd);
    path_->eval_piece(seg_path_[static_cast<std::size_t>(segment)], s, p, dp, ddp);
  }
  out.p = p;
  out.v = dp * sd;
  const Eigen::Vector3d a = ddp * sd * sd + dp * sdd;
  // Joint positions: the IK's branch nearest the table's angles at this s.
  const double L = path_->length();
  const auto k = static_cast<std::size_t>(std::lround(std::clamp(s / L, 0.0, 1.0) * (branch_.size() - 1)));
  const bool ok = joint_angles(p, branch_[k], true, out.q, out.work.ik);
  if (!ok) {
    throw std::runtime_error("reference: the path point (" + std::to_string(p.x()) + ", " +
                             std::to_string(p.y()) + ", " + std::to_string(p.z()) +
                             ") m at t = " + std::to_string(t) + " s is out of reach of the flange, " + robot_.flange);
  }
  task_rates(robot_, n_, tracks_orientation(), out.q, rest(), out.v, a, out.qd, out.qdd, out.work.ik);
}

void Reference::eval_curve(double t, ReferenceSample& out, int segment) const {
  double s, sd, sdd;
  Eigen::VectorXd &c = out.work.c, &dc = out.work.dc, &ddc = out.work.ddc;
  if (segment < 0) {
    timing_.eval(t, s, sd, sdd);
    curve_->eval(s, c, dc, ddc);
  } else {
    timing_.eval_piece(seg_timing_[static_cast<std::size_t>(segment)], t, s, sd, sdd);
    curve_->eval_piece(seg_path_[static_cast<std::size_t>(segment)], s, c, dc, ddc);
  }
  // q(t) = c(s(t)): qd = c' sd, qdd = c'' sd^2 + c' sdd (entries beyond n are 0).
  out.q = q_held_;
  for (int j = 0; j < n_; ++j) out.q[j] = c[j];
  out.qd = dc * sd;
  out.qdd = ddc * (sd * sd) + dc * sdd;
  out.p = position(out.q);
  out.v = flange_velocity(out.q, out.qd, out.work);
}

}  // namespace pumasim
