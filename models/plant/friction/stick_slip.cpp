#include "models/plant/friction/stick_slip.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "models/plant/profile.hpp"

namespace pumasim {

StickSlip::StickSlip(const PlantModel& model) : m_(model) {
  const int n = m_.joints();
  const auto un = static_cast<std::size_t>(n);
  f_.resize(static_cast<std::size_t>(m_.size()));
  solver_.reserve(n);
  candidates_.resize(un), candidate_mode_.resize(un), coupling_.resize(un * un);
  free_accel_.resize(un), static_level_.resize(un), kinetic_level_.resize(un), friction_.resize(un);
  may_stick_ = std::make_unique<bool[]>(un);
  column_.resize(n);
  released_.assign(un, 0.0);
}

int StickSlip::num_roots() const { return m_.has_mode_events() ? m_.joints() : 0; }

void StickSlip::evaluate(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x) {
  const bool current = w.last_valid && t == w.last_t && std::equal(x, x + m_.size(), w.last_x.begin());
  if (!current) m_.rhs(c, w, t, x, f_.data());
}

void StickSlip::roots(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x, double* g) {
  PUMASIM_PROFILE_CONTEXT(kRoots);
  const FrictionBlock& fr = m_.friction();
  const int n = m_.joints(), qd = m_.layout().qd;
  bool stuck = false;
  for (int j = 0; j < n; ++j) stuck = stuck || (fr.has_events(j) && c.modes[j] == SlipMode::kStuck);
  if (stuck) evaluate(c, w, t, x);  // fills the applied torques
  for (int j = 0; j < n; ++j) {
    if (!fr.has_events(j)) {
      g[j] = 1.0;
      continue;
    }
    const double wm = m_.gear_ratio(j) * x[qd + j];
    g[j] = c.modes[j] == SlipMode::kStuck ? fr.params(j).static_torque - std::abs(w.applied[j])
                                          : wm * static_cast<int>(c.modes[j]);
  }
}

void StickSlip::on_root(PlantContext& c, PlantWorkspace<double>& w, int j, double t, double* x) {
  PUMASIM_PROFILE_CONTEXT(kEvents);
  w.last_valid = false;
  if (c.modes[j] != SlipMode::kStuck) {  // the speed reached zero: stick (the solve may release it)
    x[m_.layout().qd + j] = 0.0;
    m_.settle_currents(c, w, t, x);  // algebraic currents lose the joint's back-EMF at once
    c.modes[j] = SlipMode::kStuck;
    solve_modes(c, w, t, x, -1);
  } else {  // break-away: |applied| reached Fs; it slips, in the direction the solve finds
    m_.settle_currents(c, w, t, x);  // algebraic currents on the balance at the root (no-op for an ODE)
    solve_modes(c, w, t, x, j);
  }
  record(c, w, t);
}

// The net changes since the last record, each with the applied torque that
// decided it: for a stick, the constraint torque holding the joint after the
// change (the solve's last evaluation was at the final modes); for a
// release, the constraint torque that reached or passed Fs just before it.
void StickSlip::record(const PlantContext& c, const PlantWorkspace<double>& w, double t) {
  const FrictionBlock& fr = m_.friction();
  if (!fr.has_events() || logged_.empty()) return;  // (before start_log: not yet)
  for (int j = 0; j < m_.joints(); ++j) {
    const auto k = static_cast<std::size_t>(j);
    if (!fr.has_events(j) || c.modes[k] == logged_[k]) continue;
    const double applied = c.modes[k] == SlipMode::kStuck ? w.applied[j] : released_[k];
    log_.push_back({t, j, c.modes[k], applied});
    logged_[k] = c.modes[k];
  }
}

void StickSlip::start_log(const PlantContext& c, const PlantWorkspace<double>& w, double t) {
  log_.clear();
  logged_.assign(static_cast<std::size_t>(m_.joints()), SlipMode{2});  // no mode: every joint logged
  record(c, w, t);
}

void StickSlip::classify(const PlantContext& c, PlantWorkspace<double>& w, double t, const double* x,
                         double stick_speed, SlipMode* mode, double* applied, bool always_applied,
                         bool speed_only) {
  const FrictionBlock& fr = m_.friction();
  const int n = m_.joints(), qd = m_.layout().qd;
  bool evaluate = always_applied && fr.needs_applied_torque() && !speed_only;
  for (int j = 0; j < n; ++j) {
    const bool slow = std::abs(m_.gear_ratio(j) * x[qd + j]) <= stick_speed;
    evaluate |= slow && needs_applied_torque(fr.params(j).model) && !speed_only;
  }
  if (evaluate) m_.rhs(c, w, t, x, f_.data());  // fills the applied torques
  for (int j = 0; j < n; ++j) {
    const double wm = m_.gear_ratio(j) * x[qd + j];
    const FrictionParams& f = fr.params(j);
    const bool branch = needs_applied_torque(f.model) && !speed_only;
    applied[j] = !branch ? std::numeric_limits<double>::quiet_NaN() : evaluate ? w.applied[j] : 0.0;
    const bool held = !branch || std::abs(applied[j]) <= f.static_torque;
    const double direction = wm != 0 ? wm : applied[j];
    mode[j] = std::abs(wm) <= stick_speed && held ? SlipMode::kStuck
              : direction >= 0                    ? SlipMode::kPositive
                                                  : SlipMode::kNegative;
  }
}

// W = Z (H^-1)_CC Z over the k joints candidates_ (H in w from the last
// evaluation), and b = W applied_C.
void StickSlip::stick_operator(PlantWorkspace<double>& w, int k) {
  w.chol.factor(w.H);
  for (int a = 0; a < k; ++a) {
    const int ja = candidates_[a];
    column_.setZero();
    column_[ja] = m_.gear_ratio(ja);
    w.chol.solve_in_place(column_);
    for (int c = 0; c < k; ++c) coupling_[c * k + a] = m_.gear_ratio(candidates_[c]) * column_[candidates_[c]];
  }
  for (int a = 0; a < k; ++a) {
    free_accel_[a] = 0.0;
    for (int c = 0; c < k; ++c) free_accel_[a] += coupling_[a * k + c] * w.applied[candidates_[c]];
  }
}

// The coupled mode solve over the joints at rest (the stuck ones; `breaking`
// among them may only slip), at acceleration level. A mode switch (or a
// controller sample) changes every held joint's torque at once through H, so
// their modes are one problem; the greedy release it replaces (the largest
// excess first, one at a time) can end in modes that are not consistent
// (tests/test_moreau_jean.cpp).
void StickSlip::solve_modes(PlantContext& c, PlantWorkspace<double>& w, double t, double* x, int breaking) {
  const FrictionBlock& fr = m_.friction();
  if (!fr.has_events()) return;
  PUMASIM_PROFILE_CONTEXT(kEvents);
  const int n = m_.joints(), qd = m_.layout().qd;
  // A slipping joint whose speed is zero or past it (a fixed-step method
  // stops at the first root of a step only: another joint's reversal in the
  // same step is then already behind, and its root function would never
  // cross zero again) is at a reversal too: stuck, then part of the solve.
  for (int j = 0; j < n; ++j) {
    const auto mode = c.modes[static_cast<std::size_t>(j)];
    if (!fr.has_events(j) || mode == SlipMode::kStuck) continue;
    if (m_.gear_ratio(j) * x[qd + j] * static_cast<int>(mode) > 0) continue;
    x[qd + j] = 0.0;
    c.modes[static_cast<std::size_t>(j)] = SlipMode::kStuck;
  }
  m_.rhs(c, w, t, x, f_.data());  // the held joints' applied torques, and H
  int k = 0;
  for (int j = 0; j < n; ++j) {
    if (fr.stuck(j, c.modes)) candidates_[k++] = j;
  }
  if (k == 0) return;
  stick_operator(w, k);
  for (int a = 0; a < k; ++a) {
    const FrictionParams& f = fr.params(candidates_[a]);
    static_level_[a] = std::max(f.static_torque, f.kinetic_torque);
    kinetic_level_[a] = f.kinetic_torque;
    may_stick_[a] = candidates_[a] != breaking;
  }
  const StickProblem p{k, coupling_.data(), free_accel_.data(), static_level_.data(), kinetic_level_.data(),
                       may_stick_.get()};
  result_ = solver_.solve(p, friction_.data(), candidate_mode_.data());
  ++stats_.solves;
  stats_.iterations += result_.iterations;
  if (!(result_.converged && result_.consistent)) ++stats_.unconverged;
  stats_.worst_residual = std::max(stats_.worst_residual, result_.residual);
  for (int a = 0; a < k; ++a) {
    const int mode = candidate_mode_[a];
    const auto j = static_cast<std::size_t>(candidates_[a]);
    if (mode != 0) released_[j] = w.applied[candidates_[a]];  // the constraint torque it was released at
    c.modes[j] = mode == 0 ? SlipMode::kStuck : (mode > 0 ? SlipMode::kPositive : SlipMode::kNegative);
  }
  m_.rhs(c, w, t, x, f_.data());  // the applied torques at the final modes (record reads them)
}

void StickSlip::set_valued_directions(PlantWorkspace<double>& w, const double* x, double* B) {
  const int m = m_.size(), k = m_.set_valued_joints(), n = m_.joints();
  const StateLayout& L = m_.layout();
  std::fill(B, B + static_cast<std::ptrdiff_t>(m) * k, 0.0);
  if (k == 0) return;
  for (int j = 0; j < n; ++j) w.q[j] = x[L.q + j], w.qd[j] = x[L.qd + j];
  w.backend->mass_matrix(w.q, w.H);
  w.chol.factor(w.H);
  for (int c = 0; c < k; ++c) {
    const int j = m_.set_valued_joint(c);
    column_.setZero();
    column_[j] = m_.gear_ratio(j);
    w.chol.solve_in_place(column_);
    for (int i = 0; i < n; ++i) B[static_cast<std::ptrdiff_t>(c) * m + L.qd + i] = column_[i];
  }
}

}  // namespace pumasim
