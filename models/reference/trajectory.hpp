// Reference trajectories: a Cartesian path of lines and arcs in a horizontal
// plane, a speed profile along it, and the joint references q_ref, qd_ref and
// qdd_ref that the inverse kinematics gives for it (the PUMA's closed form,
// or damped least squares for any arm: numerical_ik.hpp); or a curve in
// joint space (joint_curve.hpp: splines through given points) with a timing
// law along its own parameter.
//
// The path is drawn like a turtle: a start point and heading in the plane
// z = height (base frame), then segments that go straight or turn along an arc,
// so that the tangent is continuous everywhere. A timing law (timing.hpp)
// gives the arc length s(t). The tracked point is the flange origin,
// which for the PUMA 560 (d6 = 0) is the wrist centre.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/robot/kinematics.hpp"
#include "models/dynamics/robot_model.hpp"
#include <optional>

#include "models/reference/joint_curve.hpp"
#include "models/reference/numerical_ik.hpp"
#include "models/reference/timing.hpp"

namespace pumasim {

struct PathSegment {
  double length = 0;  // straight segment [m] (when radius == 0)
  double radius = 0;  // arc radius [m]
  double angle = 0;   // arc turning angle [rad], positive = left turn
  bool operator==(const PathSegment&) const = default;
};

class Path {
 public:
  Path(Eigen::Vector2d start, double heading, double height, std::vector<PathSegment> segments);
  double length() const { return total_; }
  // Position, first and second derivative with respect to the arc length s.
  void eval(double s, Eigen::Vector3d& p, Eigen::Vector3d& dp, Eigen::Vector3d& ddp) const;
  // The piece holding s, and the same evaluation on piece k (a line or arc
  // continued past its ends: at a break, the limit from inside piece k).
  int piece(double s) const;
  void eval_piece(int k, double s, Eigen::Vector3d& p, Eigen::Vector3d& dp, Eigen::Vector3d& ddp) const;
  // Distance from p to the nearest point of the path [m] (exact for lines and
  // arcs). nearest, when given: the piece to measure first (a hint, such as
  // the previous call's answer along a run; any value is safe), and on
  // return the nearest piece. The hint changes the work, never the result.
  double distance(const Eigen::Vector3d& p, int* nearest = nullptr) const;
  // The arc lengths in (0, L) where the curvature jumps (a line meets an arc,
  // or arcs of different radius or turning direction meet).
  std::vector<double> breaks() const;

 private:
  struct Piece {
    double s0, len;
    Eigen::Vector2d p0;
    double heading0;
    double curvature;  // 0 for a line, +-1/r for an arc
    // What distance() reads, computed once by the formulas it used per call:
    // the ends (eval at s0 and s0 + len), a line's direction, an arc's centre.
    Eigen::Vector2d a, b, dir, centre;
  };
  std::vector<Piece> pieces_;
  double height_, total_ = 0;
};

// How the joints follow the path: through the closed-form inverse kinematics
// at every instant (Cartesian timing), or by interpolating in joint space
// between via-points of the path (the joint angles of the Cartesian reference
// at the via-points' times): a C2 cubic spline (clamped to the reference's end
// speeds), or quintic Hermite pieces matching the reference's q, qd, qdd at
// each via-point. Between via-points the flange then leaves the path.
enum class Interpolation { kCartesian, kJointCubic, kJointQuintic };
// "cartesian", "joint-cubic", "joint-quintic" (the scene's names).
const char* to_string(Interpolation i);

// How the joint angles of a Cartesian path are found: the PUMA's closed form,
// or damped least squares on the geometric Jacobian (any arm), warm-started
// from the solution at the nearest point of a table built by continuation
// along the path from `guess` (default: the middle of each joint's range).
// A redundant arm (more simulated joints than the task's rows) follows the
// rule of numerical_ik.hpp with the guess as its rest pose: of the poses
// that place the flange, the one nearest the guess, continued along the path.
enum class IkMethod { kClosedForm, kNumerical };
struct IkSettings {
  IkMethod method = IkMethod::kClosedForm;
  std::optional<Eigen::VectorXd> guess;  // the simulated joints' angles (at least n entries)
};

// What Reference::eval writes: q, qd, qdd for all the robot's joints (the
// simulated joints first; held joints fixed, their rates zero), and the
// flange's position and velocity. `work` is the exact evaluation's scratch.
// Reference::sample() gives one of the right sizes; eval sizes a sample of
// other sizes first (allocating once), then allocates nothing.
struct ReferenceScratch {
  Eigen::VectorXd q, near, c, dc, ddc;  // dof
  Eigen::Matrix<double, 6, Eigen::Dynamic> J;
  IkWorkspace ik;
};
struct ReferenceSample {
  Eigen::VectorXd q, qd, qdd;  // dof entries
  Eigen::Vector3d p, v;        // Cartesian position [m], velocity [m/s]
  ReferenceScratch work;
};

// Joint references for the first n joints of `robot`; the others are held at
// q_held (dof entries). A Cartesian path: n <= 5, the flange origin (the
// PUMA's wrist centre) follows the path; n >= 6: the flange also keeps the
// orientation R_fixed (closed form: n = 3 or 6 on a PUMA-structured arm).
// n = 1, 2 reach the path in least squares; n = 4, 5 are redundant for the
// position and n >= 7 for the pose: numerical_ik.hpp's rule picks the pose.
// A joint curve: q(t) = curve(s(t)), s the timing law along the curve's
// parameter.
class Reference {
 public:
  // via_segments: with joint-space interpolation, the via-points split the
  // path into this many pieces of equal length (>= 1).
  Reference(RobotModel robot, int n, Eigen::VectorXd q_held, PumaConfig config,
            Eigen::Matrix3d R_fixed, Path path, Timing timing,
            Interpolation interpolation = Interpolation::kCartesian, int via_segments = 0,
            IkSettings ik = {});
  // A joint-space reference: the curve's joints are the first n (n = curve.joints()).
  Reference(RobotModel robot, Eigen::VectorXd q_held, JointCurve curve, Timing timing);
  bool has_path() const { return path_.has_value(); }
  const Path& path() const;  // std::logic_error for a joint curve
  const JointCurve* curve() const { return curve_ ? &*curve_ : nullptr; }
  // The length of what the timing law runs along: the path [m], or the
  // curve's parameter range.
  double length() const { return path_ ? path_->length() : curve_->length(); }
  // Distance from p to the geometric path [m]: exact for a path of lines and
  // arcs; for a joint curve, to the polyline through the flange positions at
  // the curve's knots and at least 4000 points in all, equally spaced in the
  // parameter within each piece. nearest: Path::distance's hint (unused for
  // a joint curve).
  double deviation(const Eigen::Vector3d& p, int* nearest = nullptr) const;
  const Timing& timing() const { return timing_; }
  Interpolation interpolation() const { return interp_; }
  IkMethod ik_method() const { return ik_.method; }
  int simulated_joints() const { return n_; }
  int robot_joints() const { return robot_.dof(); }
  // Whether a Cartesian path's task includes the orientation (n >= 6).
  bool tracks_orientation() const { return path_ && n_ >= 6; }
  // A sample of this reference's sizes, at the held pose and at rest.
  ReferenceSample sample() const;
  bool fits(const ReferenceSample& s) const {
    const IkWorkspace& w = s.work.ik;
    return s.q.size() == robot_.dof() && w.n == n_ && w.dof == robot_.dof() && w.m == task_rows();
  }
  // The rows of the inverse kinematics' task: 6 with the orientation, else 3.
  int task_rows() const { return tracks_orientation() ? 6 : 3; }
  // Allocation-free for a sample of this reference's sizes (sample()).
  // Throws std::runtime_error if the path leaves the workspace.
  // With a segment (the smooth piece between breakpoints segment - 1 and
  // segment, see breakpoints()) and t within rounding of it, that piece's
  // formula is evaluated, so that at a breakpoint the value is the limit from
  // inside the segment: a step that ends there sees the left limit, one that
  // starts there the right limit. Otherwise the segment is found from t.
  // With extend, the segment's formula is evaluated at any t (its smooth
  // continuation past the piece's ends, for differences in t that must not see
  // a kink; the caller keeps t near the piece).
  void eval(double t, ReferenceSample& out, int segment = -1, bool extend = false) const;
  // The flange's reference position at t, eval(t, out).p bit for bit: a
  // Cartesian path's point without the inverse kinematics (what a figure
  // of the path error needs), else the full evaluation into `out`.
  Eigen::Vector3d point(double t, ReferenceSample& out) const;
  // The segment a step starting at t lies in: the number of breakpoints <= t
  // (to rounding).
  int segment_after(double t) const;
  // The instants where the reference is not infinitely differentiable in t,
  // sorted: the timing law's breakpoints and the times at which it crosses the
  // path's curvature jumps (Cartesian) or the joint curve's knots, or the
  // spline's knots (joint-space interpolation of a path).
  // The plant makes them time events, so that no integrator steps across one.
  const std::vector<double>& breakpoints() const { return breakpoints_; }
  // The first breakpoint strictly after t (+inf if none).
  double next_breakpoint(double t) const;
  // The flange position for joint angles q (simulated joints first).
  Eigen::Vector3d position(const Eigen::Ref<const Eigen::VectorXd>& q_full) const;

 private:
  void eval_cartesian(double t, ReferenceSample& out, int segment) const;
  void eval_joint_space(double t, ReferenceSample& out, int segment, bool extend) const;
  void eval_curve(double t, ReferenceSample& out, int segment) const;
  void build_joint_spline(int segments);
  void build_branch_table();
  void check_curve_limits() const;
  void build_trace();
  // The breakpoints (sorted, merged to rounding) and each segment's pieces.
  void finish_breakpoints();
  // The flange velocity J(q) qd (the simulated joints' columns).
  Eigen::Vector3d flange_velocity(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, ReferenceScratch& w) const;
  // IK at the path point p into q, each angle the representative (mod 2 pi)
  // nearest `near`, and with track_wrist the wrist solution nearest it; false
  // if out of reach. Numerical: damped least squares from `near` (and the
  // redundancy rule). near and q: dof entries, not the same vector.
  bool joint_angles(const Eigen::Vector3d& p, const Eigen::VectorXd& near, bool track_wrist, Eigen::VectorXd& q,
                    IkWorkspace& ik) const;
  // The rest pose of the redundancy rule, or nullptr when the task is not redundant.
  const Eigen::VectorXd* rest() const { return redundant_ ? &rest_ : nullptr; }
  IkWorkspace ik_workspace() const;
  // "the path point (x, y, z) m at s = ... m (t = ... s)".
  std::string point_at(const Eigen::Vector3d& p, double s) const;

  RobotModel robot_;
  int n_;
  Eigen::VectorXd q_held_;
  PumaConfig config_;
  Eigen::Matrix3d R_fixed_;
  std::optional<Path> path_;
  std::optional<JointCurve> curve_;
  Timing timing_;
  Interpolation interp_;
  IkSettings ik_;
  std::vector<Eigen::Vector3d> trace_;  // a joint curve's flange polyline (deviation)
  // Joint-space interpolation: knot times, and per piece the coefficients
  // c(j, k) of (t - t_k)^k for each simulated joint j.
  std::vector<double> knots_;
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 6>> coef_;
  // Joint angles along the path, unwrapped by continuity, at equal steps of
  // arc length: the wrist solution, and the branch of a joint whose range
  // exceeds 2 pi (the PUMA's wrist roll), are chosen nearest these, so the
  // reference stays continuous where the IK's (-pi, pi] would jump and through
  // a wrist singularity.
  std::vector<Eigen::VectorXd> branch_;
  // The redundancy rule (numerical IK, more joints than the task's rows):
  // its rest pose, the guess (default: the middle of each range).
  bool redundant_ = false;
  Eigen::VectorXd rest_;
  std::vector<double> breakpoints_;
  // Per segment: the timing law's and the path's or curve's piece (Cartesian,
  // joint curve), or the spline piece (joint-space interpolation of a path),
  // found at the segment's middle.
  std::vector<int> seg_timing_, seg_path_;
  double seg_tol_ = 0;  // how close to a segment's ends t counts as inside it [s]
};

}  // namespace pumasim
