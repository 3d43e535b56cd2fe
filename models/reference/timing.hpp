// Timing laws: the arc length s(t) along a path of length L, from rest at
// s = 0 to rest at s = L in the duration T (the trajectory-planning methods
// the reference can use; trajectory.hpp puts one on a path).
//
// Every law but the quintic is a chain of pieces of constant jerk, so one
// evaluation covers them all: the paper's piecewise-linear speed table and
// the trapezoid (constant acceleration per piece, jerk 0), the jerk-limited
// S-curve, and the time-optimal law of time_optimal.hpp (constant
// acceleration between its grid points). The quintic is the closed form
// s = L (10 r^3 - 15 r^4 + 6 r^5), r = t / T.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace pumasim {

class Timing {
 public:
  // A piece from time t0: s = s0 + v0 u + a0 u^2 / 2 + j u^3 / 6, u = t - t0.
  struct Piece {
    double t0, s0, v0, a0, j;
  };

  // The paper's arbitrary profile: (t/T, v/v_max) points, t/T from 0 to 1
  // increasing, v/v_max in [0, 1] with maximum 1; speed linear between them;
  // T follows from L and v_max.
  static Timing table(const std::vector<Eigen::Vector2d>& shape, double L, double max_speed);
  // The same shape run in the duration T.
  static Timing table_with_duration(const std::vector<Eigen::Vector2d>& shape, double L, double T);
  // Trapezoidal speed: constant acceleration for blend T, cruise, constant
  // deceleration for blend T (0 < blend <= 1/2).
  static Timing trapezoid(double L, double T, double blend);
  // Jerk-limited S-curve: as the trapezoid, but in each acceleration phase the
  // acceleration ramps up and down linearly over jerk_fraction of the phase
  // (0 < jerk_fraction <= 1/2; 1/2: no constant-acceleration part).
  static Timing scurve(double L, double T, double blend, double jerk_fraction);
  // s = L (10 r^3 - 15 r^4 + 6 r^5): zero speed and acceleration at both ends.
  static Timing quintic(double L, double T);
  // Constant acceleration between grid points s_k with speeds sd_k (sd_0 and
  // sd_last may be 0, every inner one > 0): the time-optimal law's form.
  static Timing phase_plane(const std::vector<double>& s, const std::vector<double>& sd);
  // s = t over [0, L] (the path's own parameter; for derivatives along it).
  static Timing unit_speed(double L);

  double duration() const { return T_; }
  double length() const { return L_; }
  double peak_speed() const { return peak_speed_; }
  const std::string& kind() const { return kind_; }
  // s, ds/dt, d2s/dt2 at t; held at 0 before 0 and at L after T. Allocation-free.
  void eval(double t, double& s, double& sd, double& sdd) const;
  // The same from one smooth piece (its polynomial continued past its ends):
  // piece(t) gives the piece holding t; at a breakpoint, piece k's value is the
  // limit from inside piece k (pieces() = the hold at L after T).
  int piece(double t) const;
  int pieces() const { return static_cast<int>(pieces_.size()); }
  void eval_piece(int k, double t, double& s, double& sd, double& sdd) const;
  // The time at which s is reached (s in [0, L]; by bisection).
  double time_at(double s) const;
  // The instants in (0, T] where s(t) is not infinitely differentiable: the
  // ends of the constant-jerk pieces, and T (held at L after it).
  std::vector<double> breakpoints() const;

 private:
  struct Builder;
  Timing() = default;
  static Timing from(Builder& b, const char* kind);

  std::string kind_;
  std::vector<Piece> pieces_;  // empty for the quintic
  double T_ = 0, L_ = 0, peak_speed_ = 0;
};

}  // namespace pumasim
