// Radau IIA of order 5, written after Hairer & Wanner, Solving Ordinary
// Differential Equations II (2nd ed., Springer 1996), Sec. IV.8 ("Implementation
// of Implicit Runge-Kutta Methods"), the method of their code RADAU5:
//   - the three-stage collocation method at the Radau points, in the stage
//     increments z_i = Y_i - y0, Z = h (A x I) F(Z);
//   - the simplified Newton iteration with one Jacobian J per step (reused
//     over steps while the iteration contracts fast), transformed by T (T^-1
//     A^-1 T block diagonal) into one real system (gamma/h I - J) and one
//     complex system ((alpha + i beta)/h I - J) of size n, (8.15)-(8.16); its
//     stopping rule from the contraction estimate theta, (8.10)-(8.14);
//   - starting values from the last step's collocation polynomial, (8.17);
//   - the embedded error estimate filtered through (gamma/h I - J)^-1,
//     (8.19)-(8.20), re-filtered once at the first step and after a
//     rejection (8.21);
//   - the step size from that estimate with Gustafsson's predictive
//     controller (Sec. IV.8, (8.25); Gustafsson 1994), and a factor that
//     shrinks with the Newton iterations taken;
//   - dense output: the collocation polynomial through (t0, y0) and the three
//     stages (order 3 uniformly; the step's end has order 5).
// Tolerances as RADAU5 takes them: its error estimate is of order 3, so the
// given rtol becomes 0.1 rtol^(2/3) (and each atol_i the same multiple of
// itself) before use, which brings the end error closer to proportional to
// the given rtol than the raw estimate would; so a given rtol means what it
// means to RADAU5's users.
// The Newton tolerance is max(10 eps / rtol', min(0.03, sqrt(rtol'))).
// Roots: after an accepted step over which a root function changes sign, the
// zero is located on the collocation polynomial by the Illinois variant of
// regula falsi, and the run stops just past it, like CVODE; the polynomial
// still covers the shortened step. A reset (an event) starts afresh, as the
// interface asks: a new starting step, Jacobian and factorisations.
// No allocation after reset() with a system's own Jacobian (every vector and
// factorisation is sized there; OdeSystem's default difference Jacobian
// allocates, and its n + 1 right-hand sides are counted).
#include "integrators/radau5.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "core/time_rule.hpp"

namespace pumasim {

namespace {

Radau5Tableau build_tableau() {
  const double s6 = std::sqrt(6.0);
  Radau5Tableau t;
  t.c << (4 - s6) / 10, (4 + s6) / 10, 1.0;
  t.A << (88 - 7 * s6) / 360, (296 - 169 * s6) / 1800, (-2 + 3 * s6) / 225,  //
      (296 + 169 * s6) / 1800, (88 + 7 * s6) / 360, (-2 - 3 * s6) / 225,     //
      (16 - s6) / 36, (16 + s6) / 36, 1.0 / 9;
  t.A_inv = t.A.inverse();
  // A^-1's real eigenvalue gamma (eigenvector v) and its pair alpha +- i beta
  // (eigenvector a + i b for + i beta): in the basis (v, a, -b) A^-1 is
  // [gamma 0 0; 0 alpha -beta; 0 beta alpha].
  const Eigen::EigenSolver<Eigen::Matrix3d> es(t.A_inv);
  int real_k = -1, pair_k = -1;
  for (int k = 0; k < 3; ++k) {
    const std::complex<double> l = es.eigenvalues()(k);
    if (std::abs(l.imag()) < 1e-12 * std::abs(l)) real_k = k;
    if (l.imag() > 1e-12 * std::abs(l)) pair_k = k;
  }
  if (real_k < 0 || pair_k < 0) throw std::logic_error("radau5: A^-1 has no real eigenvalue and complex pair");
  t.gamma = es.eigenvalues()(real_k).real();
  t.alpha = es.eigenvalues()(pair_k).real();
  t.beta = es.eigenvalues()(pair_k).imag();
  t.T.col(0) = es.eigenvectors().col(real_k).real();
  t.T.col(1) = es.eigenvectors().col(pair_k).real();
  t.T.col(2) = -es.eigenvectors().col(pair_k).imag();
  t.T_inv = t.T.inverse();
  // The embedded weights: sum_j bh_j c_j^(k-1) = 1/k, k = 1..3, over the
  // nodes (0, c1, c2, c3), with bh_0 = 1/gamma given.
  Eigen::Matrix3d V;
  Eigen::Vector3d rhs;
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 3; ++j) V(k, j) = std::pow(t.c(j), k);
    rhs(k) = 1.0 / (k + 1) - (k == 0 ? 1.0 / t.gamma : 0.0);
  }
  const Eigen::Vector3d bh = V.partialPivLu().solve(rhs);
  const Eigen::Vector3d b = t.A.row(2).transpose();
  t.dd = t.gamma * (t.A_inv.transpose() * (bh - b));
  return t;
}

// The step-size controller's constants (Hairer & Wanner's RADAU5 defaults):
// the safety factor, the bounds on h_new / h, the Newton iterations allowed,
// the contraction below which the Jacobian is kept, and the band of h_new / h
// in which h and the factorisations are kept.
constexpr double kSafe = 0.9;
constexpr double kGrowMax = 8.0, kShrinkMax = 5.0;
constexpr int kNewtonMax = 7;
constexpr double kThetaKeep = 1e-3;
constexpr double kKeepLow = 1.0, kKeepHigh = 1.2;
constexpr double kEps = std::numeric_limits<double>::epsilon();

class Radau5 final : public Integrator {
 public:
  Radau5(const IntegratorOptions& o, double fixed_h)
      : Integrator(o.max_steps), tab_(radau5_tableau()), fixed_h_(fixed_h) {
    if (fixed_h_ > 0) {
      rtol_ = 1e-14, atol_ = 1e-14, fnewt_ = 1.0;  // fixed step: Newton to rounding
      return;
    }
    if (!(o.rtol > 0) || !(o.atol > 0)) throw std::invalid_argument("radau5: expected rtol > 0 and atol > 0");
    const double expo = 2.0 / 3.0;
    rtol_ = 0.1 * std::pow(o.rtol, expo);
    atol_ = o.atol * rtol_ / o.rtol;
    fnewt_ = std::max(10 * kEps / rtol_, std::min(0.03, std::sqrt(rtol_)));
  }
  const char* name() const override { return fixed_h_ > 0 ? "radau5-fixed-step" : "radau5"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c;
    c.adaptive = fixed_h_ <= 0;
    c.order = 5;
    c.implicit = true;
    c.uses_jacobian = true;
    c.exact_jacobian = true;
    c.finds_roots = true;
    return c;
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override;
  double time() const override { return t_; }
  const double* state() const override { return y_.data(); }
  double step_start() const override { return t_start_; }
  void dense_state(double t, double* x) override;

 protected:
  Outcome step(double t_stop) override;

 private:
  enum class Newton { kConverged, kSlow, kDiverged };
  Newton solve_stages(double t0, double h);
  void newton_increment(double t0, double h);
  double newton_norm() const;
  double error_estimate(double t0, double h);
  double rms(const Eigen::VectorXd& v) const;
  void factorise(double h);
  void evaluate_jacobian();
  void set_polynomial(double t0, double h);
  void polynomial_at(double theta, Eigen::VectorXd& out) const;
  void starting_values(double t0, double h);
  double initial_step(double t_stop);
  int locate_root(double t0, double h);
  Outcome accept(double t0, double h, double err, double quot, double t1, bool last);
  Outcome step_fixed(double t_stop);
  std::string failure(const std::string& what) const;
  void rhs(double t, const double* x, double* f) {
    sys_->rhs(t, x, f);
    ++stats_.rhs_evaluations;
  }

  const Radau5Tableau& tab_;
  double fixed_h_;
  double rtol_ = 0, atol_ = 0, fnewt_ = 0;
  OdeSystem* sys_ = nullptr;
  int n_ = 0;
  double t_ = 0, t_start_ = 0, h_ = 0;
  Eigen::VectorXd y_, f0_, scal_, atol_i_;
  // The stages: increments Z, transformed W = T^-1 Z, their Newton
  // corrections, the right-hand sides F at the stages, and scratch.
  Eigen::VectorXd z_[3], w_[3], dw_[3], f_[3], r_[3], ytmp_, err_;
  Eigen::VectorXcd rc_, uc_;
  Eigen::MatrixXd J_, E1_;
  Eigen::MatrixXcd E2_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu1_;
  Eigen::PartialPivLU<Eigen::MatrixXcd> lu2_;
  // The last step's collocation polynomial y0 + d1 s + d2 s (s - c1) + d3 s
  // (s - c1)(s - c2), s = (t - poly_t0_) / poly_h_ (Newton's form).
  Eigen::VectorXd p0_, p1_, p2_, p3_;
  double poly_t0_ = 0, poly_h_ = 0;
  bool have_poly_ = false;
  bool jac_fresh_ = false;  // J_ is at the current (t_, y_)
  bool jac_keep_ = false;   // the last step allows reusing J_ (theta <= kThetaKeep)
  double h_lu_ = 0;         // the h of the current factorisations (0: none)
  bool first_ = true, reject_ = false;
  double theta_ = 0, faccon_ = 1, h_acc_ = 0, err_acc_ = 1e-2;
  bool have_f0_ = false;      // f0_ is f(t_, y_)
  int newton_taken_ = 0;      // iterations of the last converged solve
  double slow_factor_ = 0.5;  // h's factor after a too slow iteration
  std::vector<double> g_, g_new_, g_try_;
};

void Radau5::reset(OdeSystem& sys, double t0, const double* x0) {
  if (sys_) ++stats_.restarts;
  const bool same_size = sys_ && n_ == sys.size();
  sys_ = &sys;
  n_ = sys.size();
  t_ = t_start_ = t0;
  h_ = 0;
  if (!same_size) {
    for (auto* v : {&y_, &f0_, &scal_, &atol_i_, &ytmp_, &err_, &p0_, &p1_, &p2_, &p3_}) v->resize(n_);
    for (int k = 0; k < 3; ++k)
      z_[k].resize(n_), w_[k].resize(n_), dw_[k].resize(n_), f_[k].resize(n_), r_[k].resize(n_);
    rc_.resize(n_), uc_.resize(n_);
    J_.resize(n_, n_), E1_.resize(n_, n_), E2_.resize(n_, n_);
    lu1_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n_);
    lu2_ = Eigen::PartialPivLU<Eigen::MatrixXcd>(n_);
  }
  for (int i = 0; i < n_; ++i) atol_i_(i) = atol_ * (fixed_h_ > 0 ? 1.0 : sys.tolerance_scale(i));
  y_ = Eigen::Map<const Eigen::VectorXd>(x0, n_);
  have_f0_ = false;  // f(t0, y0): evaluated by the first step, then carried from each step's end
  have_poly_ = false, jac_fresh_ = false, jac_keep_ = false, h_lu_ = 0;
  first_ = true, reject_ = false;
  theta_ = 0, faccon_ = 1, h_acc_ = 0, err_acc_ = 1e-2;
  g_.resize(sys.num_roots()), g_new_.resize(g_.size()), g_try_.resize(g_.size());
  if (!g_.empty()) sys.roots(t_, x0, g_.data());
}

void Radau5::evaluate_jacobian() {
  sys_->jacobian(t_, y_.data(), J_);
  ++stats_.jacobian_evaluations;
  if (!sys_->has_exact_jacobian()) stats_.rhs_evaluations += n_ + 1;  // OdeSystem's forward differences
  jac_fresh_ = true;
  h_lu_ = 0;
}

void Radau5::factorise(double h) {
  E1_ = -J_;
  E1_.diagonal().array() += tab_.gamma / h;
  E2_ = (-J_).cast<std::complex<double>>();
  E2_.diagonal().array() += std::complex<double>(tab_.alpha / h, tab_.beta / h);
  lu1_.compute(E1_);
  lu2_.compute(E2_);
  ++stats_.linear_solves;
  h_lu_ = h;
}

double Radau5::rms(const Eigen::VectorXd& v) const {
  return std::sqrt((v.array() / scal_.array()).square().sum() / n_);
}

void Radau5::set_polynomial(double t0, double h) {
  const double c1 = tab_.c(0), c2 = tab_.c(1);
  // Divided differences on the nodes (0, c1, c2, 1) of the values (0, z1, z2, z3).
  p1_ = z_[0] / c1;                                       // [0, c1]
  ytmp_ = (z_[1] - z_[0]) / (c2 - c1);                    // [c1, c2]
  p2_ = (ytmp_ - p1_) / c2;                               // [0, c1, c2]
  p3_ = ((z_[2] - z_[1]) / (1 - c2) - ytmp_) / (1 - c1);  // [c1, c2, 1]
  p3_ -= p2_;                                             // [0, c1, c2, 1] (the nodes span 1)
  p0_ = y_;
  poly_t0_ = t0, poly_h_ = h;
  have_poly_ = true;
}

void Radau5::polynomial_at(double s, Eigen::VectorXd& out) const {
  const double c1 = tab_.c(0), c2 = tab_.c(1);
  out = p0_ + s * (p1_ + (s - c1) * (p2_ + (s - c2) * p3_));
}

void Radau5::dense_state(double t, double* x) {
  if (t >= t_ || !have_poly_ || t_ == t_start_) {
    std::copy(y_.data(), y_.data() + n_, x);
    return;
  }
  polynomial_at((std::max(t, t_start_) - poly_t0_) / poly_h_, ytmp_);
  std::copy(ytmp_.data(), ytmp_.data() + n_, x);
}

// Z from the last step's polynomial extrapolated to t0 + c_i h (zero at the
// first step and after a reset); W = T^-1 Z.
void Radau5::starting_values(double t0, double h) {
  for (int k = 0; k < 3; ++k) {
    if (have_poly_ && fixed_h_ <= 0) {
      polynomial_at((t0 + tab_.c(k) * h - poly_t0_) / poly_h_, z_[k]);
      z_[k] -= y_;
    } else {
      z_[k].setZero();
    }
  }
  for (int k = 0; k < 3; ++k) w_[k] = tab_.T_inv(k, 0) * z_[0] + tab_.T_inv(k, 1) * z_[1] + tab_.T_inv(k, 2) * z_[2];
}

// One simplified Newton correction dW of the stage equations
// (Lambda / h x I - I x J) dW = (T^-1 x I) F(y0 + Z) - (Lambda / h x I) W.
void Radau5::newton_increment(double t0, double h) {
  for (int k = 0; k < 3; ++k) {
    ytmp_ = y_ + z_[k];
    rhs(t0 + tab_.c(k) * h, ytmp_.data(), f_[k].data());
  }
  for (int k = 0; k < 3; ++k) r_[k] = tab_.T_inv(k, 0) * f_[0] + tab_.T_inv(k, 1) * f_[1] + tab_.T_inv(k, 2) * f_[2];
  const double g = tab_.gamma / h, a = tab_.alpha / h, b = tab_.beta / h;
  r_[0] -= g * w_[0];
  r_[1] -= a * w_[1] - b * w_[2];
  r_[2] -= b * w_[1] + a * w_[2];
  dw_[0] = lu1_.solve(r_[0]);
  rc_.real() = r_[1];
  rc_.imag() = r_[2];
  uc_ = lu2_.solve(rc_);
  dw_[1] = uc_.real();
  dw_[2] = uc_.imag();
}

double Radau5::newton_norm() const {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += (dw_[k].array() / scal_.array()).square().sum();
  return std::sqrt(s / (3.0 * n_));
}

// The simplified Newton iteration (Sec. IV.8, (8.10)-(8.14)): theta_k, the
// contraction, from successive increments; stop when theta/(1 - theta)
// |dW| <= fnewt; give up (slow) when the predicted error after the
// iterations left exceeds fnewt, or when theta >= 0.99 (diverged).
Radau5::Newton Radau5::solve_stages(double t0, double h) {
  starting_values(t0, h);
  faccon_ = std::pow(std::max(faccon_, kEps), 0.8);
  theta_ = kThetaKeep;
  double dyn_old = 0, thq_old = 0;
  for (int newt = 1; newt <= kNewtonMax; ++newt) {
    newton_increment(t0, h);
    ++stats_.nonlinear_iterations;
    const double dyno = newton_norm();
    if (!std::isfinite(dyno)) return Newton::kDiverged;
    if (newt > 1 && newt < kNewtonMax) {
      const double thq = dyno / dyn_old;
      theta_ = newt == 2 ? thq : std::sqrt(thq * thq_old);
      thq_old = thq;
      if (theta_ >= 0.99) return Newton::kDiverged;
      faccon_ = theta_ / (1 - theta_);
      const double dyth = faccon_ * dyno * std::pow(theta_, kNewtonMax - 1 - newt) / fnewt_;
      if (dyth >= 1) {
        // The step that would converge in the iterations left (RADAU5's rule).
        const double qnewt = std::max(1e-4, std::min(20.0, dyth));
        slow_factor_ = 0.8 * std::pow(qnewt, -1.0 / (4 + kNewtonMax - 1 - newt));
        return Newton::kSlow;
      }
    }
    dyn_old = std::max(dyno, kEps);
    for (int k = 0; k < 3; ++k) w_[k] += dw_[k];
    for (int k = 0; k < 3; ++k) z_[k] = tab_.T(k, 0) * w_[0] + tab_.T(k, 1) * w_[1] + tab_.T(k, 2) * w_[2];
    if (faccon_ * dyno <= fnewt_) {
      newton_taken_ = newt;
      return Newton::kConverged;
    }
  }
  return Newton::kDiverged;
}

// The embedded error estimate, filtered by (gamma/h I - J)^-1 (Sec. IV.8,
// (8.19)-(8.20)); at the first step and after a rejection, an estimate of 1
// or more is filtered once more through f at y0 + err (8.21), which removes
// the stiff components' spurious part.
double Radau5::error_estimate(double t0, double h) {
  r_[1] = (tab_.dd(0) * z_[0] + tab_.dd(1) * z_[1] + tab_.dd(2) * z_[2]) / h;
  r_[0] = f0_ + r_[1];
  err_ = lu1_.solve(r_[0]);
  double err = std::max(rms(err_), 1e-10);
  if (err >= 1 && (first_ || reject_)) {
    ytmp_ = y_ + err_;
    rhs(t0, ytmp_.data(), f_[0].data());
    r_[0] = f_[0] + r_[1];
    err_ = lu1_.solve(r_[0]);
    err = std::max(rms(err_), 1e-10);
  }
  return err;
}

// The starting step (Hairer, Norsett & Wanner I, Sec. II.4, for an error
// estimate of order 3): h0 from |y| / |f|, one explicit Euler step to
// estimate the second derivative, h1 = (0.01 / max(|f|, |f'|))^(1/4).
double Radau5::initial_step(double t_stop) {
  for (int i = 0; i < n_; ++i) scal_(i) = atol_i_(i) + rtol_ * std::abs(y_(i));
  const double d0 = rms(y_), d1 = rms(f0_);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min(h0, t_stop - t_);
  ytmp_ = y_ + h0 * f0_;
  rhs(t_ + h0, ytmp_.data(), f_[0].data());
  r_[0] = (f_[0] - f0_) / h0;
  const double d2 = rms(r_[0]);
  const double dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 0.25);
  return std::min(100 * h0, h1);
}

std::string Radau5::failure(const std::string& what) const {
  std::string s = std::string(name()) + ": " + what + " at t = " + std::to_string(t_) + " s";
  const std::string bad = non_finite_components(*sys_, t_, y_.data());
  if (!bad.empty()) return s + "; " + bad;
  return s + "; fastest-changing component " + fastest_component(*sys_, t_, y_.data());
}

Outcome Radau5::step(double t_stop) {
  if (!before(t_, t_stop, t_stop)) {
    t_start_ = t_ = t_stop;
    return {};
  }
  if (!have_f0_) rhs(t_, y_.data(), f0_.data()), have_f0_ = true;
  if (fixed_h_ > 0) return step_fixed(t_stop);
  if (h_ <= 0) h_ = initial_step(t_stop);
  for (;;) {
    const double remaining = t_stop - t_;
    const double h = std::min(h_, remaining);
    const bool last = h >= remaining;
    if (!(h > 1e-14 * std::max(1.0, std::abs(t_))) || !std::isfinite(h)) {
      return {Outcome::kFailed, -1, failure("step size underflow (h = " + std::to_string(h) + ")")};
    }
    for (int i = 0; i < n_; ++i) scal_(i) = atol_i_(i) + rtol_ * std::abs(y_(i));
    if (!jac_fresh_ && !jac_keep_) evaluate_jacobian();
    if (h != h_lu_) factorise(h);
    const Newton nw = solve_stages(t_, h);
    double err = 2.0, quot = 1.0;
    if (nw == Newton::kConverged) {
      err = error_estimate(t_, h);
      // A smaller step when the iteration needed many iterations.
      const double fac = std::min(kSafe, kSafe * (1 + 2 * kNewtonMax) / (newton_taken_ + 2 * kNewtonMax));
      quot = std::clamp(std::pow(err, 0.25) / fac, 1 / kGrowMax, kShrinkMax);
      if (err < 1) return accept(t_, h, err, quot, last ? t_stop : t_ + h, last);
    }
    // Rejected steps are error-test failures, as CVODE and RADAU5 count them;
    // a Newton failure shows in the iterations.
    if (nw == Newton::kConverged) {
      ++stats_.rejected_steps;
      h_ = first_ ? 0.1 * h : h / quot;
    } else {
      h_ = h * (nw == Newton::kSlow ? slow_factor_ : 0.5);
    }
    reject_ = true;
    jac_keep_ = false;  // a Jacobian kept from an earlier step is evaluated here anew
  }
}

Outcome Radau5::accept(double t0, double h, double err, double quot, double t1, bool last) {
  ++stats_.steps;
  if (!first_) {  // Gustafsson's predictive controller
    const double facgus =
        std::clamp((h_acc_ / h) * std::pow(err * err / err_acc_, 0.25) / kSafe, 1 / kGrowMax, kShrinkMax);
    quot = std::max(quot, facgus);
  }
  double h_new = h / quot;
  h_acc_ = h, err_acc_ = std::max(1e-2, err);
  set_polynomial(t0, h);
  y_ += z_[2];
  t_start_ = t0, t_ = t1;
  if (const std::string bad = non_finite_components(*sys_, t_, y_.data()); !bad.empty()) {
    return {Outcome::kFailed, -1, std::string(name()) + ": " + bad};
  }
  rhs(t_, y_.data(), f0_.data());
  if (reject_) h_new = std::min(h_new, h);
  reject_ = false, first_ = false, jac_fresh_ = false;
  jac_keep_ = theta_ <= kThetaKeep;
  // Fast contraction and almost the same step: keep h and the factorisations.
  if (jac_keep_ && h_new >= kKeepLow * h && h_new <= kKeepHigh * h) h_new = h;
  // After a step shortened to a stop, the earlier proposal stands unless the
  // shortened step's error predicts a smaller one (its proposal without the
  // growth cap: the error estimate scales as h^4).
  if (last && h < h_) {
    const double fac = std::min(kSafe, kSafe * (1 + 2 * kNewtonMax) / (newton_taken_ + 2 * kNewtonMax));
    h_ = std::min(h_, h * fac * std::pow(err, -0.25));
  } else {
    h_ = h_new;
  }
  if (!g_.empty()) {
    sys_->roots(t_, y_.data(), g_new_.data());
    if (first_crossing(g_, g_new_) >= 0) return {Outcome::kRoot, locate_root(t0, h), ""};
    g_ = g_new_;
  }
  return {};
}

// A root function crossed zero over the accepted step [t0, t_]: the Illinois
// variant of regula falsi on the collocation polynomial brackets the earliest
// zero to 100 eps (|t0| + h); the run moves to the bracket's end past it.
int Radau5::locate_root(double t0, double h) {
  double a = 0.0, b = (t_ - t0) / h;
  const double tol = 100 * kEps * (std::abs(t0) + h) / h;
  const int k = locate_earliest_root(g_, g_new_, g_try_, a, b, tol, [&](double s, std::vector<double>& g) {
    polynomial_at(s, ytmp_);
    sys_->roots(t0 + s * h, ytmp_.data(), g.data());
  });
  t_ = t0 + b * h;
  polynomial_at(b, y_);
  rhs(t_, y_.data(), f0_.data());
  g_ = g_new_;
  jac_keep_ = false;
  return k;
}

// The method alone at a constant step: a fresh Jacobian and factorisation
// per step, Newton to rounding; a Newton failure is a reported failure.
Outcome Radau5::step_fixed(double t_stop) {
  const double remaining = t_stop - t_;
  const bool last = remaining <= fixed_h_ * (1 + 1e-9);
  const double h = last ? remaining : fixed_h_;
  for (int i = 0; i < n_; ++i) scal_(i) = atol_i_(i) + rtol_ * std::abs(y_(i));
  evaluate_jacobian();
  factorise(h);
  faccon_ = 1;
  if (solve_stages(t_, h) != Newton::kConverged) return {Outcome::kFailed, -1, failure("Newton iteration failed")};
  ++stats_.steps;
  set_polynomial(t_, h);
  y_ += z_[2];
  t_start_ = t_;
  t_ = last ? t_stop : t_ + h;
  rhs(t_, y_.data(), f0_.data());
  return {};
}

}  // namespace

const Radau5Tableau& radau5_tableau() {
  static const Radau5Tableau t = build_tableau();
  return t;
}

std::unique_ptr<Integrator> make_radau5_fixed_step(double h) {
  if (!(h > 0)) throw std::invalid_argument("radau5: expected a step h > 0");
  return std::make_unique<Radau5>(IntegratorOptions{}, h);
}

namespace detail {
std::unique_ptr<Integrator> make_radau5(const IntegratorOptions& o) { return std::make_unique<Radau5>(o, 0.0); }
}  // namespace detail

}  // namespace pumasim
