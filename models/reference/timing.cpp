#include "models/reference/timing.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pumasim {

// Appends pieces by integrating forward: each has a duration, an initial
// acceleration (which may jump) and a constant jerk.
struct Timing::Builder {
  std::vector<Timing::Piece> pieces;
  double t = 0, s = 0, v = 0, a = 0;
  void add(double duration, double a0, double jerk) {
    if (!(duration > 0)) return;
    pieces.push_back({t, s, v, a0, jerk});
    const double u = duration;
    s += v * u + a0 * u * u / 2 + jerk * u * u * u / 6;
    v += a0 * u + jerk * u * u / 2;
    a = a0 + jerk * u;
    t += u;
  }
};

namespace {

void check_duration(double L, double T) {
  if (!(L > 0) || !(T > 0) || !std::isfinite(T)) {
    throw std::invalid_argument("timing: expected a path length > 0 and a duration > 0");
  }
}

}  // namespace

Timing Timing::table(const std::vector<Eigen::Vector2d>& shape, double L, double max_speed) {
  if (shape.size() < 2 || shape.front().x() != 0.0 || shape.back().x() != 1.0) {
    throw std::invalid_argument("speed profile: expected points from t/T = 0 to t/T = 1");
  }
  double area = 0, peak = 0;
  for (std::size_t i = 1; i < shape.size(); ++i) {
    if (!(shape[i].x() > shape[i - 1].x())) throw std::invalid_argument("speed profile: t/T must increase");
    area += 0.5 * (shape[i].y() + shape[i - 1].y()) * (shape[i].x() - shape[i - 1].x());
  }
  for (const auto& pt : shape) peak = std::max(peak, pt.y());
  if (!(area > 0) || std::abs(peak - 1.0) > 1e-12) {
    throw std::invalid_argument("speed profile: expected speeds v/v_max in [0, 1] with maximum 1");
  }
  const double T = L / (max_speed * area);  // s(T) = v_max T area = L
  check_duration(L, T);
  Builder b;
  b.v = shape.front().y() * max_speed;
  for (std::size_t i = 1; i < shape.size(); ++i) {
    const double dt = (shape[i].x() - shape[i - 1].x()) * T;
    b.add(dt, (shape[i].y() - shape[i - 1].y()) * max_speed / dt, 0.0);
  }
  return from(b, "table");
}

Timing Timing::table_with_duration(const std::vector<Eigen::Vector2d>& shape, double L, double T) {
  double area = 0;  // of v/v_max over t/T; table() checks the shape
  for (std::size_t i = 1; i < shape.size(); ++i) {
    area += 0.5 * (shape[i].y() + shape[i - 1].y()) * (shape[i].x() - shape[i - 1].x());
  }
  check_duration(L, T);
  if (!(area > 0)) throw std::invalid_argument("speed profile: expected speeds v/v_max in [0, 1] with maximum 1");
  return table(shape, L, L / (area * T));
}

Timing Timing::trapezoid(double L, double T, double blend) {
  check_duration(L, T);
  if (!(blend > 0 && blend <= 0.5)) throw std::invalid_argument("trapezoid: expected 0 < blend <= 0.5");
  const double Ta = blend * T, vc = L / (T - Ta), A = vc / Ta;
  Builder b;
  b.add(Ta, A, 0.0);
  b.add(T - 2 * Ta, 0.0, 0.0);
  b.add(Ta, -A, 0.0);
  return from(b, "trapezoid");
}

Timing Timing::scurve(double L, double T, double blend, double jerk_fraction) {
  check_duration(L, T);
  if (!(blend > 0 && blend <= 0.5)) throw std::invalid_argument("scurve: expected 0 < blend <= 0.5");
  if (!(jerk_fraction > 0 && jerk_fraction <= 0.5)) {
    throw std::invalid_argument("scurve: expected 0 < jerk_fraction <= 0.5");
  }
  // The acceleration is a trapezoid in time, symmetric in each phase, so the
  // phase covers vc Ta / 2 and L = vc (T - Ta).
  const double Ta = blend * T, tj = jerk_fraction * Ta, vc = L / (T - Ta), A = vc / (Ta - tj), J = A / tj;
  Builder b;
  b.add(tj, 0.0, J);
  b.add(Ta - 2 * tj, A, 0.0);
  b.add(tj, A, -J);
  b.add(T - 2 * Ta, 0.0, 0.0);
  b.add(tj, 0.0, -J);
  b.add(Ta - 2 * tj, -A, 0.0);
  b.add(tj, -A, J);
  return from(b, "scurve");
}

Timing Timing::quintic(double L, double T) {
  check_duration(L, T);
  Timing tm;
  tm.kind_ = "quintic";
  tm.T_ = T;
  tm.L_ = L;
  tm.peak_speed_ = 15.0 * L / (8.0 * T);  // at r = 1/2: 30 r^2 (1 - r)^2 L / T
  return tm;
}

Timing Timing::phase_plane(const std::vector<double>& s, const std::vector<double>& sd) {
  if (s.size() < 2 || s.size() != sd.size()) throw std::invalid_argument("phase_plane: expected matching grids");
  Builder b;
  b.v = sd.front();
  for (std::size_t k = 0; k + 1 < s.size(); ++k) {
    const double ds = s[k + 1] - s[k], v0 = sd[k], v1 = sd[k + 1];
    if (!(ds > 0) || !(v0 + v1 > 0) || v0 < 0 || v1 < 0) {
      throw std::invalid_argument("phase_plane: expected increasing s and speeds >= 0, not both 0 on an interval");
    }
    b.v = v0;  // the exact speed at the grid point (no drift from the sums)
    b.s = s[k];
    b.add(2 * ds / (v0 + v1), (v1 * v1 - v0 * v0) / (2 * ds), 0.0);
  }
  return from(b, "time-optimal");
}

Timing Timing::unit_speed(double L) {
  check_duration(L, L);
  Builder b;
  b.v = 1.0;
  b.add(L, 0.0, 0.0);
  return from(b, "unit-speed");
}

Timing Timing::from(Builder& b, const char* kind) {
  Timing tm;
  tm.kind_ = kind;
  tm.T_ = b.t;
  tm.L_ = b.s;
  // The speed is monotone within each piece (no piece's acceleration changes
  // sign inside it), so its maximum is at a piece boundary.
  tm.peak_speed_ = b.v;
  for (const Piece& p : b.pieces) tm.peak_speed_ = std::max(tm.peak_speed_, p.v0);
  tm.pieces_ = std::move(b.pieces);
  return tm;
}

void Timing::eval(double t, double& s, double& sd, double& sdd) const {
  if (pieces_.empty()) {  // quintic: at rest before 0, the polynomial, the hold from T
    if (t <= 0) {
      s = 0, sd = 0, sdd = 0;
      return;
    }
    return eval_piece(t >= T_ ? 1 : 0, t, s, sd, sdd);
  }
  if (t <= 0) {
    s = 0, sd = pieces_.front().v0, sdd = 0;
    return;
  }
  eval_piece(piece(t), t, s, sd, sdd);
}

int Timing::piece(double t) const {
  if (pieces_.empty()) return t > T_ ? 1 : 0;  // quintic: the motion, then the hold
  if (t > T_) return pieces();
  // The last piece starting at or before t.
  const auto it = std::upper_bound(pieces_.begin(), pieces_.end(), t,
                                   [](double x, const Piece& p) { return x < p.t0; });
  return static_cast<int>((it == pieces_.begin() ? it : it - 1) - pieces_.begin());
}

void Timing::eval_piece(int k, double t, double& s, double& sd, double& sdd) const {
  if (pieces_.empty()) {  // quintic: piece 0 the polynomial (at any t), piece 1 the hold after T (C2 there)
    if (k >= 1) {
      s = L_, sd = 0, sdd = 0;
      return;
    }
    const double r = t / T_, r2 = r * r;
    s = L_ * r2 * r * (10 - 15 * r + 6 * r2);
    sd = L_ / T_ * 30 * r2 * (1 - r) * (1 - r);
    sdd = L_ / (T_ * T_) * 60 * r * (1 - r) * (1 - 2 * r);
    return;
  }
  if (k >= pieces()) {
    s = L_, sd = 0, sdd = 0;
    return;
  }
  const Piece& p = pieces_[static_cast<std::size_t>(k)];
  const double u = t - p.t0;
  s = p.s0 + p.v0 * u + p.a0 * u * u / 2 + p.j * u * u * u / 6;
  sd = p.v0 + p.a0 * u + p.j * u * u / 2;
  sdd = p.a0 + p.j * u;
}

std::vector<double> Timing::breakpoints() const {
  std::vector<double> out;
  for (const Piece& pc : pieces_) {
    if (pc.t0 > 0 && pc.t0 < T_) out.push_back(pc.t0);
  }
  out.push_back(T_);
  return out;
}

double Timing::time_at(double s_target) const {
  double lo = 0, hi = T_;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(1.0, T_); ++it) {
    const double mid = 0.5 * (lo + hi);
    double s, sd, sdd;
    eval(mid, s, sd, sdd);
    (s < s_target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace pumasim
