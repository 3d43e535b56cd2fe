// Moreau-Jean time-stepping (Moreau 1988, "Unilateral contact and dry
// friction in finite freedom dynamics"; Jean 1999, "The non-smooth contact
// dynamics method"; Acary & Brogliato 2008, "Numerical Methods for Nonsmooth
// Dynamical Systems", Sec. 10.1 -- cited from memory, not read here): a
// theta-method on the velocities, the friction an impulse over each step from
// its set-valued law, solved at every step; no events, no root finding.
//
// One step from (t, x), size h, for a system f = f_smooth + B(x) r
// (OdeSystem's set-valued interface):
//   A = I - h theta J,  J = d f_smooth / dx at (t, x)   (linearly implicit)
//   A dx_free = h f_smooth(t + theta h, x)
//   Y = A^-1 B,  v = b + W p  with  b_c = scale_c (x + dx_free)[vel_c],
//                                   W_cd = scale_c Y[vel_c, d]
//   p from the coupled stick/slip problem at velocity level (the system's
//     solve_set_valued) with impulse levels h Fs, h Fk: each row's
//     end-of-step speed v_c is 0 with |p_c| <= h Fs_c, or p_c = -sign(v_c) h Fk_c;
//     the static level for a row at rest at the step's start (|v| <= kAtRest)
//     only: a moving row sticks only where h Fk stops it (its speed reaches
//     zero within the step), as in the exact model, where a slipping joint
//     sticks at a speed reversal and not before
//   x <- x + dx_free + Y p.
// Without set-valued rows (the tanh, viscous or no friction) it is the
// linearly implicit theta-method on the whole state. theta = 1 is the
// default ("moreau-jean"): implicit Euler on the velocities, the usual choice
// for friction (dissipative, L-stable: a stiff mode's factor 1 / (1 - h
// lambda) -> 0, and the end-of-step velocity the law is imposed on is the one
// the position update uses); first order, also on smooth scenes.
// "moreau-jean-075" takes theta = 3/4: less numerical damping of the slow
// modes (its error constant is theta - 1/2 = 1/4 against 1/2), still A-stable
// with a stiff mode's factor -> -(1 - theta) / theta = -1/3; first order.
// theta = 1/2 would be second order on smooth problems but not damp stiff
// modes at all (factor -> -1): not offered.
//
// The system's root functions, when it has set-valued rows, are the
// event-driven treatment of the same friction (the hybrid model): ignored.
// Otherwise they are checked at each step's end like the other fixed-step
// methods. Dense output: linear between the step's ends (first order, as
// the method). Costs per step: one f_smooth, one Jacobian (its differences'
// right-hand sides counted too), one LU of A, 1 + k solves with it.
#include <cmath>

#include <Eigen/LU>

#include "integrators/fixed_step.hpp"

namespace pumasim::detail {
namespace {

// A row's speed at rest [the law's unit, rad/s on a motor shaft]: a stuck
// row's speed after the impulse is 0 up to rounding (the update is linear).
constexpr double kAtRest = 1e-9;

class MoreauJean final : public FixedStep {
 public:
  MoreauJean(const IntegratorOptions& o, double theta, const char* name)
      : FixedStep(o, 1), theta_(theta), name_(name) {}
  const char* name() const override { return name_; }
  IntegratorCapabilities capabilities() const override {
    IntegratorCapabilities c = FixedStep::capabilities();
    c.implicit = true;
    c.uses_jacobian = true;
    c.exact_jacobian = true;
    c.set_valued_friction = true;
    return c;
  }
  void reset(OdeSystem& sys, double t0, const double* x0) override {
    FixedStep::reset(sys, t0, x0);
    const int m = sys.size();
    k_ = sys.set_valued_rows();
    if (k_ > 0) g_.clear(), g_new_.clear();  // the event-driven friction's roots
    rows_.resize(static_cast<std::size_t>(k_));
    for (int c = 0; c < k_; ++c) rows_[static_cast<std::size_t>(c)] = sys.set_valued_row(c);
    A_.resize(m, m), J_.resize(m, m), B_.resize(m, k_), Y_.resize(m, k_);
    rhs_.resize(m), dx_.resize(m);
    W_.resize(static_cast<std::size_t>(k_) * k_), b_.resize(k_), s_.resize(k_), kin_.resize(k_), p_.resize(k_);
  }

 protected:
  void advance_step(double h, bool) override {
    const int m = static_cast<int>(x_.size());
    sys_->jacobian_smooth(t_, x_.data(), J_);
    ++stats_.jacobian_evaluations;
    if (!sys_->has_exact_jacobian()) stats_.rhs_evaluations += m + 1;  // forward differences
    sys_->rhs_smooth(t_ + theta_ * h, x_.data(), rhs_.data());
    ++stats_.rhs_evaluations;
    A_.noalias() = -(h * theta_) * J_;
    A_.diagonal().array() += 1.0;
    lu_.compute(A_);
    ++stats_.linear_solves;
    rhs_ *= h;
    dx_.noalias() = lu_.solve(rhs_);
    if (k_ > 0) impulses(h);
    for (int i = 0; i < m; ++i) x_[i] += dx_[i];
  }
  void extension(double th, double* out) const override {  // linear: x0 + th (x1 - x0)
    for (std::size_t i = 0; i < x_.size(); ++i) out[i] = th * (x_[i] - x0_[i]) / h_;
  }

 private:
  // The friction impulses p of the step, added to dx_.
  void impulses(double h) {
    sys_->set_valued_directions(t_, x_.data(), B_.data());
    Y_.noalias() = lu_.solve(B_);
    stats_.linear_solves += k_;
    for (int c = 0; c < k_; ++c) {
      const SetValuedRow& rc = rows_[static_cast<std::size_t>(c)];
      b_[c] = rc.scale * (x_[static_cast<std::size_t>(rc.velocity)] + dx_[rc.velocity]);
      for (int d = 0; d < k_; ++d) W_[static_cast<std::size_t>(c * k_ + d)] = rc.scale * Y_(rc.velocity, d);
      // The static level holds only a row at rest at the step's start; a
      // moving row may stick only where Fk can stop it within the step (its
      // speed would reach zero): with Fs there, a joint creeping under a
      // torque between Fk and Fs would stick early, at any small speed.
      const double v0 = rc.scale * x_[static_cast<std::size_t>(rc.velocity)];
      s_[c] = h * (std::abs(v0) <= kAtRest ? rc.static_level : rc.kinetic_level);
      kin_[c] = h * rc.kinetic_level;
    }
    const SetValuedSolve r = sys_->solve_set_valued(k_, W_.data(), b_.data(), s_.data(), kin_.data(), p_.data());
    ++stats_.friction_solves;
    stats_.friction_iterations += r.iterations;
    if (!r.converged) ++stats_.friction_unconverged;
    stats_.friction_worst_residual = std::max(stats_.friction_worst_residual, r.residual);
    for (int c = 0; c < k_; ++c) dx_ += Y_.col(c) * p_[c];
  }

  double theta_;
  const char* name_;
  int k_ = 0;
  std::vector<SetValuedRow> rows_;
  Eigen::MatrixXd A_, J_, B_, Y_;
  Eigen::VectorXd rhs_, dx_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
  std::vector<double> W_, b_, s_, kin_, p_;
};

}  // namespace

std::unique_ptr<Integrator> make_moreau_jean(const IntegratorOptions& o) {
  return std::make_unique<MoreauJean>(o, 1.0, "moreau-jean");
}
std::unique_ptr<Integrator> make_moreau_jean_075(const IntegratorOptions& o) {
  return std::make_unique<MoreauJean>(o, 0.75, "moreau-jean-075");
}

}  // namespace pumasim::detail
