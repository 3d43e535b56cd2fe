// The symplectic midpoint integrator (symplectic_midpoint.hpp): the
// canonical midpoint step, and the fixed-step integrator around it.
//
// The integrator keeps p between steps (from x only at a reset, p = M(q) qd)
// and reports qd = M(q)^-1 p. First guess of a step: the last step continued
// (z0 + (h / h_last)(z0 - z_last)); after a reset, q0 + h qd0 and p0.
// Dense output: q by the cubic Hermite interpolant of the step's end values
// and velocities, qd by the straight line (both order 2, as the method).
// Cost per step: the fixed-point iterations (each one mass matrix, one
// Cholesky, one mass matrix on dual numbers and one bias h(q, qd): counted as
// one right-hand side and one linear solve), and one mass matrix and Cholesky
// for the reported qd.
#include "integrators/symplectic_midpoint.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "integrators/fixed_step.hpp"

namespace pumasim {

namespace {

// An update at rounding level: below it, an update that no longer shrinks
// means the iteration has converged; above it, that it has stopped contracting.
constexpr double kRoundoffLevel = 1e-10;

}  // namespace

MidpointSolve midpoint_step(ConservativeMechanics& m, double h, const double* q0, const double* p0, double* q1,
                            double* p1, MidpointScratch& s, int max_iterations) {
  const int n = m.dof();
  MidpointSolve r;
  double previous = std::numeric_limits<double>::infinity();
  for (int it = 1; it <= max_iterations; ++it) {
    r.iterations = it;
    for (int j = 0; j < n; ++j) s.qm[j] = 0.5 * (q0[j] + q1[j]), s.pm[j] = 0.5 * (p0[j] + p1[j]);
    if (!midpoint_velocity(m, s.qm.data(), s.pm.data(), s.vm.data(), s)) {
      r.failure = "the mass matrix is not positive definite at the step's midpoint";
      return r;
    }
    m.lagrangian_gradient(s.qm.data(), s.vm.data(), s.g.data());
    double p_scale = 0;
    for (int j = 0; j < n; ++j) {
      s.q_next[j] = q0[j] + h * s.vm[j];
      s.p_next[j] = p0[j] + h * s.g[j];
      p_scale = std::max({p_scale, std::abs(p0[j]), std::abs(s.p_next[j])});
    }
    if (p_scale == 0) p_scale = 1;
    double d = 0;  // the update, relative: q to max(1, |q|), p to the momenta's size
    for (int j = 0; j < n; ++j) {
      d = std::max(d, std::abs(s.q_next[j] - q1[j]) / std::max(1.0, std::abs(s.q_next[j])));
      d = std::max(d, std::abs(s.p_next[j] - p1[j]) / p_scale);
      q1[j] = s.q_next[j], p1[j] = s.p_next[j];
    }
    r.update = d;
    if (!std::isfinite(d)) {
      r.failure = "the fixed-point iteration produced a non-finite iterate";
      return r;
    }
    if (d == 0 || (d >= previous && previous <= kRoundoffLevel)) {
      r.converged = true;
      return r;
    }
    if (d >= previous) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "the fixed-point iteration stopped contracting (update %.3g after %.3g, iteration %d)", d, previous,
                    it);
      r.failure = buf;
      return r;
    }
    previous = d;
  }
  r.failure = "the fixed-point iteration did not reach round-off in " + std::to_string(max_iterations) + " iterations";
  return r;
}

void midpoint_momentum(ConservativeMechanics& m, const double* q, const double* qd, double* p, MidpointScratch& s) {
  const int n = m.dof();
  m.mass_matrix(q, s.M);
  for (int i = 0; i < n; ++i) {
    double v = 0;
    for (int k = 0; k < n; ++k) v += s.M(i, k) * qd[k];
    p[i] = v;
  }
}

bool midpoint_velocity(ConservativeMechanics& m, const double* q, const double* p, double* qd, MidpointScratch& s) {
  const int n = m.dof();
  m.mass_matrix(q, s.M);
  s.llt.compute(s.M);
  if (s.llt.info() != Eigen::Success) return false;
  for (int j = 0; j < n; ++j) s.vm[j] = p[j];  // qd may be s.vm itself
  s.llt.solveInPlace(s.vm);
  for (int j = 0; j < n; ++j) qd[j] = s.vm[j];
  return true;
}

namespace {

class SymplecticMidpoint final : public detail::FixedStep {
 public:
  explicit SymplecticMidpoint(const IntegratorOptions& o) : FixedStep(o, 2) {}
  const char* name() const override { return "symplectic-midpoint"; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c = FixedStep::capabilities();
    c.implicit = true;
    return c;
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    std::string why;
    ConservativeMechanics* mech = sys.conservative_mechanics(why);
    if (!mech) {
      throw std::invalid_argument(std::string(name()) + ": " + why +
                                  "; it integrates lossless, unforced mechanical systems only");
    }
    check_constant_rest(sys, *mech, t0, x0);
    FixedStep::reset(sys, t0, x0);
    mech_ = mech;
    const int n = mech->dof();
    if (!scratch_ || scratch_->M.rows() != n) scratch_ = std::make_unique<MidpointScratch>(n);
    q0_.resize(n), p0_.resize(n), q1_.resize(n), p1_.resize(n), qd_.resize(n), p_.resize(n);
    q_last_.resize(n), p_last_.resize(n);
    for (int j = 0; j < n; ++j) q0_[j] = x0[mech->position(j)], qd_[j] = x0[mech->velocity(j)];
    midpoint_momentum(*mech, q0_.data(), qd_.data(), p_.data(), *scratch_);
    h_last_ = 0;
  }

 protected:
  void advance_step(double h, bool) override {
    ConservativeMechanics& m = *mech_;
    const int n = m.dof();
    for (int j = 0; j < n; ++j) {
      q0_[j] = x_[m.position(j)], p0_[j] = p_[j];
      if (h_last_ != 0) {  // the last step continued
        const double c = h / h_last_;
        q1_[j] = q0_[j] + c * (q0_[j] - q_last_[j]);
        p1_[j] = p0_[j] + c * (p0_[j] - p_last_[j]);
      } else {
        q1_[j] = q0_[j] + h * x_[m.velocity(j)];
        p1_[j] = p0_[j];
      }
    }
    const MidpointSolve r = midpoint_step(m, h, q0_.data(), p0_.data(), q1_.data(), p1_.data(), *scratch_);
    stats_.rhs_evaluations += r.iterations;
    stats_.nonlinear_iterations += r.iterations;
    stats_.linear_solves += r.iterations + 1;
    if (!r.converged || !midpoint_velocity(m, q1_.data(), p1_.data(), qd_.data(), *scratch_)) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s: at t = %.9g s, step h = %.3g s: ", name(), t_, h);
      step_failure_ = std::string(buf) +
                      (r.converged ? "the mass matrix is not positive definite at the step's end" : r.failure) +
                      " (a smaller dt)";
      return;
    }
    for (int j = 0; j < n; ++j) {
      q_last_[j] = q0_[j], p_last_[j] = p0_[j];
      p_[j] = p1_[j];
      x_[m.position(j)] = q1_[j], x_[m.velocity(j)] = qd_[j];
    }
    h_last_ = h;
  }
  void restart_history() override { h_last_ = 0; }
  // x(t0 + th h) = x0 + h out: q cubic Hermite, qd linear, the rest constant.
  void extension(double th, double* out) const override {
    std::fill(out, out + x_.size(), 0.0);
    if (h_ == 0) return;
    const ConservativeMechanics& m = *mech_;
    const double th2 = th * th, th3 = th2 * th;
    const double h01 = -2 * th3 + 3 * th2, h10 = th3 - 2 * th2 + th, h11 = th3 - th2;
    for (int j = 0; j < m.dof(); ++j) {
      const int iq = m.position(j), iv = m.velocity(j);
      out[iq] = h01 * (x_[iq] - x0_[iq]) / h_ + h10 * x0_[iv] + h11 * x_[iv];
      out[iv] = th * (x_[iv] - x0_[iv]) / h_;
    }
  }

 private:
  // Every component besides q and qd must be constant (an energy ledger's, on
  // a lossless arm): f = 0 there at the start.
  static void check_constant_rest(OdeSystem& sys, ConservativeMechanics& m, double t0, const double* x0) {
    const int size = sys.size();
    std::vector<double> f(static_cast<std::size_t>(size));
    sys.rhs(t0, x0, f.data());
    std::vector<bool> mechanical(static_cast<std::size_t>(size), false);
    for (int j = 0; j < m.dof(); ++j) mechanical[m.position(j)] = mechanical[m.velocity(j)] = true;
    for (int i = 0; i < size; ++i) {
      if (!mechanical[i] && f[i] != 0) {
        throw std::invalid_argument("symplectic-midpoint: state " + sys.state_name(i) +
                                    " changes (f != 0 at the start), so the system is not a conservative mechanical "
                                    "one with constant other states");
      }
    }
  }

  ConservativeMechanics* mech_ = nullptr;
  std::unique_ptr<MidpointScratch> scratch_;
  Eigen::VectorXd q0_, p0_, q1_, p1_, qd_, p_, q_last_, p_last_;
  double h_last_ = 0;
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_symplectic_midpoint(const IntegratorOptions& o) {
  return std::make_unique<SymplecticMidpoint>(o);
}
}  // namespace detail

}  // namespace pumasim
