#include "models/reference/joint_curve.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/LU>

namespace pumasim {

std::vector<PieceCoefficients> clamped_cubic_spline(const std::vector<double>& x, const std::vector<double>& y,
                                                    double v0, double vM) {
  const int M = static_cast<int>(x.size()) - 1;
  if (M < 1 || y.size() != x.size()) throw std::invalid_argument("cubic spline: expected at least two knots");
  // The knots' second derivatives m solve a tridiagonal system (Thomas
  // algorithm; diagonally dominant).
  std::vector<double> lo(M + 1), di(M + 1), up(M + 1), r(M + 1), m(M + 1);
  auto hk = [&](int k) { return x[k + 1] - x[k]; };
  auto slope = [&](int k) { return (y[k + 1] - y[k]) / hk(k); };
  di[0] = 2 * hk(0), up[0] = hk(0), r[0] = 6 * (slope(0) - v0);
  for (int k = 1; k < M; ++k) {
    lo[k] = hk(k - 1), di[k] = 2 * (hk(k - 1) + hk(k)), up[k] = hk(k);
    r[k] = 6 * (slope(k) - slope(k - 1));
  }
  lo[M] = hk(M - 1), di[M] = 2 * hk(M - 1), r[M] = 6 * (vM - slope(M - 1));
  for (int k = 1; k <= M; ++k) {
    const double w = lo[k] / di[k - 1];
    di[k] -= w * up[k - 1];
    r[k] -= w * r[k - 1];
  }
  m[M] = r[M] / di[M];
  for (int k = M - 1; k >= 0; --k) m[k] = (r[k] - up[k] * m[k + 1]) / di[k];
  std::vector<PieceCoefficients> c(M, PieceCoefficients{});
  for (int k = 0; k < M; ++k) {
    const double h = hk(k);
    c[k][0] = y[k];
    c[k][1] = slope(k) - h * (2 * m[k] + m[k + 1]) / 6;
    c[k][2] = m[k] / 2;
    c[k][3] = (m[k + 1] - m[k]) / (6 * h);
  }
  return c;
}

PieceCoefficients quintic_hermite(double h, double q0, double v0, double a0, double q1, double v1, double a1) {
  PieceCoefficients c{};
  c[0] = q0, c[1] = v0, c[2] = a0 / 2;
  c[3] = (20 * (q1 - q0) - (8 * v1 + 12 * v0) * h - (3 * a0 - a1) * h * h) / (2 * h * h * h);
  c[4] = (30 * (q0 - q1) + (14 * v1 + 16 * v0) * h + (3 * a0 - 2 * a1) * h * h) / (2 * std::pow(h, 4));
  c[5] = (12 * (q1 - q0) - 6 * (v1 + v0) * h + (a1 - a0) * h * h) / (2 * std::pow(h, 5));
  return c;
}

namespace {

// Inner knot k of the quintic spline: with the Hermite pieces (q, v, a at
// both ends), the third and fourth derivatives at a piece's ends are
//   start: q''' = 60 D/h^3 - (36 v0 + 24 v1)/h^2 - (9 a0 - 3 a1)/h,
//          q'''' = -360 D/h^4 + (192 v0 + 168 v1)/h^3 + (36 a0 - 24 a1)/h^2,
//   end:   q''' = 60 D/h^3 - (24 v0 + 36 v1)/h^2 + (9 a1 - 3 a0)/h,
//          q'''' = 360 D/h^4 - (168 v0 + 192 v1)/h^3 + (36 a1 - 24 a0)/h^2,
// D = q1 - q0 (from quintic_hermite's coefficients: 6 c3, 24 c4, and their
// values at h). Equal at knot k from the left piece (h_l, D_l) and the right
// one (h_r, D_r): A x_(k-1) + B x_k + C x_(k+1) = r, x = (v, a).
struct KnotRows {
  Eigen::Matrix2d A, B, C;
  Eigen::Vector2d r;
};

KnotRows knot_rows(double hl, double hr, double Dl, double Dr) {
  KnotRows k;
  const double l2 = hl * hl, l3 = l2 * hl, r2 = hr * hr, r3 = r2 * hr;
  k.A << -24 / l2, -3 / hl, -168 / l3, -24 / l2;
  k.B << 36 / r2 - 36 / l2, 9 / hl + 9 / hr, -192 / l3 - 192 / r3, 36 / l2 - 36 / r2;
  k.C << 24 / r2, -3 / hr, -168 / r3, 24 / r2;
  k.r << 60 * Dr / (r3) - 60 * Dl / l3, -360 * Dr / (r3 * hr) - 360 * Dl / (l3 * hl);
  return k;
}

}  // namespace

std::vector<PieceCoefficients> clamped_quintic_spline(const std::vector<double>& x, const std::vector<double>& y,
                                                      double v0, double a0, double vM, double aM) {
  const int M = static_cast<int>(x.size()) - 1;
  if (M < 1 || y.size() != x.size()) throw std::invalid_argument("quintic spline: expected at least two knots");
  std::vector<Eigen::Vector2d> va(M + 1);
  va[0] = {v0, a0}, va[M] = {vM, aM};
  // Block Thomas algorithm over the inner knots 1..M-1 (2 x 2 blocks).
  std::vector<Eigen::Matrix2d> Bp(M), C(M);
  std::vector<Eigen::Vector2d> rp(M);
  for (int k = 1; k < M; ++k) {
    const KnotRows row = knot_rows(x[k] - x[k - 1], x[k + 1] - x[k], y[k] - y[k - 1], y[k + 1] - y[k]);
    Eigen::Vector2d r = row.r;
    if (k == 1) r -= row.A * va[0];
    if (k == M - 1) r -= row.C * va[M];
    Bp[k] = row.B, C[k] = row.C, rp[k] = r;
    if (k > 1) {
      const Eigen::Matrix2d W = row.A * Bp[k - 1].inverse();
      Bp[k] -= W * C[k - 1];
      rp[k] -= W * rp[k - 1];
    }
  }
  for (int k = M - 1; k >= 1; --k) {
    va[k] = Bp[k].partialPivLu().solve(k == M - 1 ? rp[k] : Eigen::Vector2d(rp[k] - C[k] * va[k + 1]));
  }
  std::vector<PieceCoefficients> c(M);
  for (int k = 0; k < M; ++k) {
    c[k] = quintic_hermite(x[k + 1] - x[k], y[k], va[k][0], va[k][1], y[k + 1], va[k + 1][0], va[k + 1][1]);
  }
  return c;
}

JointCurve::JointCurve(std::vector<double> knots, std::vector<Eigen::VectorXd> points, int n, Kind kind)
    : knots_(std::move(knots)), points_(std::move(points)), n_(n), kind_(kind) {
  const std::size_t K = knots_.size();
  if (K < 2 || points_.size() != K) throw std::invalid_argument("joint curve: expected at least two points");
  if (n_ < 1) throw std::invalid_argument("joint curve: expected at least one joint");
  for (const Eigen::VectorXd& q : points_) {
    if (q.size() < n_) throw std::invalid_argument("joint curve: a point with fewer entries than joints");
  }
  for (Eigen::VectorXd& q : points_) q.conservativeResize(n_);  // the curve's joints only
  if (knots_.front() != 0.0) throw std::invalid_argument("joint curve: expected the first point at 0");
  for (std::size_t k = 1; k < K; ++k) {
    if (!(knots_[k] > knots_[k - 1])) throw std::invalid_argument("joint curve: expected increasing knots");
  }
  coef_.assign(K - 1, Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(n_, 6));
  std::vector<double> y(K);
  for (int j = 0; j < n_; ++j) {
    for (std::size_t k = 0; k < K; ++k) y[k] = points_[k][j];
    const std::vector<PieceCoefficients> c = kind_ == Kind::kCubic ? clamped_cubic_spline(knots_, y, 0, 0)
                                                                   : clamped_quintic_spline(knots_, y, 0, 0, 0, 0);
    for (std::size_t k = 0; k + 1 < K; ++k)
      for (int e = 0; e < 6; ++e) coef_[k](j, e) = c[k][static_cast<std::size_t>(e)];
  }
  check_finite();
}

// Every number eval_piece forms on a piece of length h, for u in [0, h], is
// at most 20 sum_{e >= k} |c_e| h^(e - k) for some k (Horner's partial sums,
// the derivatives' factors e and e (e - 1) at most 20): all finite, the curve
// is finite everywhere. The rows' check (models/scene/joint_csv.cpp) bounds
// each step's terms, but the spline's knot equations couple neighbouring
// steps, and a value jump of 1e280 rad in 1e-6 s beside a step of 1 s passed
// it and overflowed the quintic (fuzz_joint_csv, in CI's smoke run).
void JointCurve::check_finite() const {
  for (std::size_t k = 0; k < coef_.size(); ++k) {
    const double h = knots_[k + 1] - knots_[k];
    for (int j = 0; j < n_; ++j) {
      // Horner on the absolute values: after the step that adds |c_lo| the
      // sum is sum_{e >= lo} |c_e| h^(e - lo), no power of h formed alone
      // (h^5 overflows for steps the reader accepts, and 0 * inf is NaN).
      double sum = 0;
      for (int lo = 5; lo >= 0; --lo) {
        sum = sum * h + std::abs(coef_[k](j, lo));
        if (!std::isfinite(20 * sum)) {
          char buf[200];
          std::snprintf(buf, sizeof buf,
                        "joint curve: joint %d's spline between the points at t = %.6g s and %.6g s is not finite "
                        "(values too large for their time steps)",
                        j + 1, knots_[k], knots_[k + 1]);
          throw std::invalid_argument(buf);
        }
      }
    }
  }
}

int JointCurve::piece(double x) const {
  const auto after = std::upper_bound(knots_.begin(), knots_.end(), x) - knots_.begin();
  return static_cast<int>(std::clamp<std::ptrdiff_t>(after - 1, 0, std::ssize(coef_) - 1));
}

void JointCurve::eval_piece(int k, double x, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> dq,
                            Eigen::Ref<Eigen::VectorXd> ddq) const {
  const auto& c = coef_[static_cast<std::size_t>(k)];
  const double u = x - knots_[static_cast<std::size_t>(k)];
  q.setZero(), dq.setZero(), ddq.setZero();
  for (int j = 0; j < n_; ++j) {  // Horner
    double p = c(j, 5), v = 5 * c(j, 5), a = 20 * c(j, 5);
    for (int e = 4; e >= 0; --e) p = p * u + c(j, e);
    for (int e = 4; e >= 1; --e) v = v * u + e * c(j, e);
    for (int e = 4; e >= 2; --e) a = a * u + e * (e - 1) * c(j, e);
    q[j] = p, dq[j] = v, ddq[j] = a;
  }
}

void JointCurve::eval(double x, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> dq,
                      Eigen::Ref<Eigen::VectorXd> ddq) const {
  const double xc = std::clamp(x, 0.0, length());
  eval_piece(piece(xc), xc, q, dq, ddq);
}

}  // namespace pumasim
