#include "models/reference/time_optimal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "models/dynamics/backend.hpp"
#include "models/reference/trajectory.hpp"

namespace pumasim {
namespace {

// The largest x in [0, hi] with ok(x), given ok(0) (bisection to relative 1e-13).
template <class Ok>
double largest(double hi, const Ok& ok) {
  if (ok(hi)) return hi;
  double lo = 0.0;
  for (int it = 0; it < 200 && hi - lo > 1e-13 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (ok(mid) ? lo : hi) = mid;
  }
  return lo;
}

// -limit <= A u + B <= limit, intersected into [lo, hi].
void linear_bound(double A, double B, double limit, AccelerationBounds& u) {
  if (!std::isfinite(limit)) return;
  if (std::abs(A) < 1e-300) {
    if (std::abs(B) > limit) u.lo = 1, u.hi = 0;
    return;
  }
  double a = (-limit - B) / A, b = (limit - B) / A;
  if (a > b) std::swap(a, b);
  u.lo = std::max(u.lo, a);
  u.hi = std::min(u.hi, b);
}

}  // namespace

PhasePlaneResult time_optimal_grid(const std::vector<double>& s, const AdmissibleFn& admissible, double x_cap) {
  const int N = static_cast<int>(s.size()) - 1;
  if (N < 1) throw std::invalid_argument("time-optimal: expected at least two grid points");
  PhasePlaneResult r;
  r.s = s;
  r.x_max.resize(N + 1);
  r.x_stop.resize(N + 1);
  r.sd.resize(N + 1);
  auto fail = [&](int i, const std::string& what) {
    throw std::runtime_error("time-optimal: at s = " + std::to_string(s[i]) + " m of the path " + what);
  };
  for (int i = 0; i <= N; ++i) {
    const AccelerationBounds b0 = admissible(i, 0.0);
    if (!(b0.lo <= b0.hi)) fail(i, "no acceleration is admissible even at rest (a limit below the static load)");
    r.x_max[i] = largest(x_cap, [&](double x) {
      const AccelerationBounds b = admissible(i, x);
      return b.lo <= b.hi;
    });
  }
  // The largest u in [A, B] that is also admissible at the end of interval i
  // (at x + 2 d u): a scan of 17 candidates, then bisection above the largest
  // good one; NaN if none is.
  auto largest_at_both_ends = [&](int i, double x, double A, double B) {
    if (!(A <= B)) return std::nan("");
    const double d = s[i + 1] - s[i];
    auto at_end = [&](double u) {
      const AccelerationBounds e = admissible(i + 1, std::max(0.0, x + 2 * d * u));
      return e.lo <= u && u <= e.hi;
    };
    int k = 16;
    while (k >= 0 && !at_end(A + (B - A) * k / 16)) --k;
    if (k < 0) return std::nan("");
    if (k == 16) return B;
    double lo = A + (B - A) * k / 16, hi = A + (B - A) * (k + 1) / 16;
    for (int it = 0; it < 60 && hi - lo > 1e-13 * (std::abs(hi) + std::abs(lo)); ++it) {
      const double mid = 0.5 * (lo + hi);
      (at_end(mid) ? lo : hi) = mid;
    }
    return lo;
  };
  // Backward: the squared speeds from which the end (at rest) stays reachable.
  r.x_stop[N] = 0.0;
  for (int i = N - 1; i >= 0; --i) {
    const double d = s[i + 1] - s[i];
    // Some acceleration admissible at both ends of the interval that lands in [0, x_stop(i + 1)].
    auto ok = [&](double x) {
      const AccelerationBounds b = admissible(i, x);
      return !std::isnan(largest_at_both_ends(i, x, std::max(b.lo, -x / (2 * d)),
                                              std::min(b.hi, (r.x_stop[i + 1] - x) / (2 * d))));
    };
    if (!ok(0.0)) fail(i, "the arm cannot go on from rest towards the end");
    r.x_stop[i] = largest(r.x_max[i], ok);
  }
  // Forward from rest: the largest acceleration admissible at both ends of
  // the interval (the speed grows across it, and with it the back-EMF) that
  // stays stoppable; if no such acceleration exists, the largest one
  // admissible at the start (the check of the finished timing then shows it).
  double x = 0.0;
  r.sd[0] = 0.0;
  for (int i = 0; i < N; ++i) {
    const double d = s[i + 1] - s[i];
    const AccelerationBounds b = admissible(i, x);
    const double u_max = std::min(b.hi, (r.x_stop[i + 1] - x) / (2 * d));
    const double u_low = std::max(b.lo, -x / (2 * d));  // the least acceleration that keeps x >= 0
    double u = largest_at_both_ends(i, x, u_low, u_max);
    if (std::isnan(u)) u = u_max;
    const double next = std::max(0.0, x + 2 * d * u);
    if (next < x + 2 * d * b.lo - 1e-12 * std::max(1.0, x)) fail(i, "the forward pass left the stoppable set");
    x = next;
    r.sd[i + 1] = std::sqrt(x);
  }
  if (!(r.sd[1] > 0)) fail(0, "the arm cannot start");
  return r;
}

TimeOptimalPlanner::TimeOptimalPlanner(RobotModel simulated, std::string backend,
                                       std::vector<AmplifierParams> amplifier, std::vector<MotorParams> motor,
                                       std::vector<FrictionParams> friction, DriveLimits limits)
    : model_(std::move(simulated)),
      backend_(std::move(backend)),
      amp_(std::move(amplifier)),
      motor_(std::move(motor)),
      friction_(std::move(friction)),
      limits_(std::move(limits)) {
  const auto n = static_cast<std::size_t>(model_.dof());
  if (amp_.size() != n || motor_.size() != n || friction_.size() != n || limits_.voltage.size() != n ||
      limits_.current.size() != n || limits_.joint_speed.size() != n) {
    throw std::invalid_argument("time-optimal: expected drive data and limits for every simulated joint");
  }
}

PathDynamics TimeOptimalPlanner::path_dynamics(const Reference& ref, const std::vector<double>& s) const {
  const int n = model_.dof();
  auto be = make_backend(backend_, model_);
  PathDynamics d;
  ReferenceSample r;
  Eigen::VectorXd q(n), dq(n), ddq(n), zero = Eigen::VectorXd::Zero(n), g(n), t1(n), t2(n);
  for (double si : s) {
    ref.eval(si, r);  // unit speed: t = s, qd = q'(s), qdd = q''(s)
    q = r.q.head(n), dq = r.qd.head(n), ddq = r.qdd.head(n);
    be->gravity(q, g);
    be->inverse_dynamics(q, zero, dq, t1);  // H q' + g
    be->inverse_dynamics(q, dq, ddq, t2);   // H q'' + C(q, q') q' + g
    d.dq.push_back(dq);
    d.a.push_back(t1 - g);
    d.b.push_back(t2 - g);
    d.c.push_back(g);
  }
  return d;
}

void TimeOptimalPlanner::drive_demand(const PathDynamics& d, int i, int j, double sd, double sdd, double& volts,
                                      double& amps) const {
  const double Z = model_.joints[j].gear_ratio, K = motor_[j].torque_constant;
  const double R = amp_[j].output_resistance + motor_[j].resistance;
  const FrictionParams& f = friction_[j];
  const double dq = d.dq[i][j], wm = Z * dq * sd;
  const double tau = d.a[i][j] * sdd + d.b[i][j] * sd * sd + d.c[i][j];
  const double sgn = dq > 0 ? 1.0 : dq < 0 ? -1.0 : 0.0;  // the direction the joint moves along the path
  const double tf = f.model.none() ? 0.0 : f.kinetic_torque * sgn + f.viscous * wm;
  amps = (tau / Z + tf) / K;
  volts = R * amps + K * wm;
}

AccelerationBounds TimeOptimalPlanner::admissible(const PathDynamics& d, int i, double x) const {
  AccelerationBounds u{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  const double sd = std::sqrt(x);
  for (int j = 0; j < model_.dof(); ++j) {
    if (std::abs(d.dq[i][j]) * sd > limits_.joint_speed[j]) return {1, 0};
    // Current and voltage are affine in sdd: value(sdd) = value(0) + slope sdd.
    double v0, i0, v1, i1;
    drive_demand(d, i, j, sd, 0.0, v0, i0);
    drive_demand(d, i, j, sd, 1.0, v1, i1);
    linear_bound(v1 - v0, v0, limits_.voltage[j], u);
    linear_bound(i1 - i0, i0, limits_.current[j], u);
    if (!(u.lo <= u.hi)) return u;
  }
  return u;
}

Timing TimeOptimalPlanner::plan(const Reference& ref, int grid_points) const {
  const double L = ref.length();
  std::vector<double> s(grid_points + 1);
  for (int k = 0; k <= grid_points; ++k) s[k] = L * k / grid_points;
  const PathDynamics d = path_dynamics(ref, s);
  const PhasePlaneResult r =
      time_optimal_grid(s, [&](int i, double x) { return admissible(d, i, x); }, 1e4 /* (100 m/s)^2 */);
  return Timing::phase_plane(r.s, r.sd);
}

}  // namespace pumasim
