// Joint-space curves: splines through knots (x_k, q_k), x the curve's own
// parameter (for a reference read from a CSV or given by via-points, the
// given times), and the spline constructions they use.
//
// Cubic: the C2 cubic spline with clamped ends (given end slopes), from the
// tridiagonal system of the knots' second derivatives (de Boor, A Practical
// Guide to Splines, 2001, ch. IV; Biagiotti & Melchiorri, Trajectory Planning
// for Automatic Machines and Robots, 2008, sec. 4.4). It reproduces any cubic
// polynomial whose end slopes it is given.
// Quintic: the C4 quintic spline with clamped ends (given end slopes and
// second derivatives): quintic Hermite pieces whose inner knots' first and
// second derivatives make the third and fourth derivatives continuous (a
// block-tridiagonal system of 2 x 2 blocks). It reproduces any quintic
// polynomial whose end derivatives it is given.
// A reference starts and ends at rest: the curves of JointCurve take zero end
// slopes (and, quintic, zero end second derivatives).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

namespace pumasim {

// Per piece k the coefficients c[e] of (x - x_k)^e, e = 0..5 (cubic: c4 = c5 = 0).
using PieceCoefficients = std::array<double, 6>;

// The C2 cubic spline through (x_k, y_k), slopes v0 at x_0 and vM at x_M.
// Needs M >= 1 pieces, x strictly increasing.
std::vector<PieceCoefficients> clamped_cubic_spline(const std::vector<double>& x, const std::vector<double>& y,
                                                    double v0, double vM);
// The C4 quintic spline through (x_k, y_k), first and second derivatives
// (v0, a0) at x_0 and (vM, aM) at x_M.
std::vector<PieceCoefficients> clamped_quintic_spline(const std::vector<double>& x, const std::vector<double>& y,
                                                      double v0, double a0, double vM, double aM);
// The quintic on [0, h] with value, slope and second derivative (q0, v0, a0)
// at 0 and (q1, v1, a1) at h.
PieceCoefficients quintic_hermite(double h, double q0, double v0, double a0, double q1, double v1, double a1);

// A curve q(x) in the space of the first n joints, x in [0, L]:
// a cubic or quintic spline per joint through the knots, at rest at both ends
// (zero slopes; quintic: zero second derivatives too), held at its end values
// outside [0, L].
class JointCurve {
 public:
  enum class Kind { kCubic, kQuintic };
  // knots: x_0 = 0 < x_1 < ... < x_M (M >= 1); points: q_k, first n entries
  // used (points() keeps those).
  JointCurve(std::vector<double> knots, std::vector<Eigen::VectorXd> points, int n, Kind kind);
  int joints() const { return n_; }
  Kind kind() const { return kind_; }
  double length() const { return knots_.back(); }
  const std::vector<double>& knots() const { return knots_; }
  const std::vector<Eigen::VectorXd>& points() const { return points_; }
  // The piece holding x (the last one also holds L; clamped to the pieces).
  int piece(double x) const;
  // q, dq/dx, d2q/dx2 on piece k at x (its polynomial continued past its
  // ends); q, dq, ddq have n entries or more, those beyond n set to 0.
  // Allocation-free.
  void eval_piece(int k, double x, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> dq,
                  Eigen::Ref<Eigen::VectorXd> ddq) const;
  // std::invalid_argument naming the joint and the piece if a piece could
  // evaluate to a non-finite number.
  void check_finite() const;
  // The same at x clamped to [0, L], on the piece holding it.
  void eval(double x, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> dq,
            Eigen::Ref<Eigen::VectorXd> ddq) const;
  // The inner knots: where a derivative jumps (cubic: the third, quintic: the fifth).
  std::vector<double> breaks() const { return {knots_.begin() + 1, knots_.end() - 1}; }

 private:
  std::vector<double> knots_;
  std::vector<Eigen::VectorXd> points_;
  int n_;
  Kind kind_;
  // coef_[k](j, e): joint j's coefficient of (x - x_k)^e on piece k.
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 6>> coef_;
};

}  // namespace pumasim
