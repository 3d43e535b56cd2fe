#include "simulation/mode_log.hpp"

#include <cstdio>

namespace pumasim {

ModeClassifier::ModeClassifier(Plant& plant, double stick_speed, double min_duration, bool speed_only)
    : plant_(plant),
      stick_speed_(stick_speed),
      min_duration_(min_duration),
      speed_only_(speed_only),
      now_(static_cast<std::size_t>(plant.layout().n)),
      applied_(static_cast<std::size_t>(plant.layout().n)),
      joints_(static_cast<std::size_t>(plant.layout().n)),
      sign_(static_cast<std::size_t>(plant.layout().n), 0) {}

void ModeClassifier::count(double t, const double* x) {
  if (last_t_ >= 0 && (shortest_ == 0 || t - last_t_ < shortest_)) shortest_ = t - last_t_;
  last_t_ = t;
  for (std::size_t j = 0; j < sign_.size(); ++j) {
    const double qd = x[plant_.layout().qd + static_cast<int>(j)];
    const int s = qd > 0 ? 1 : qd < 0 ? -1 : 0;
    if (s != 0 && sign_[j] != 0 && s != sign_[j]) ++sign_changes_;
    if (s != 0) sign_[j] = s;
  }
}

void ModeClassifier::step(double t, const double* x) {
  plant_.classify_modes(t, x, stick_speed_, now_.data(), applied_.data(), false, speed_only_);
  // A new candidate records the applied torque at its first step: evaluated then, even where no joint is slow.
  bool fresh = false;
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const int m = static_cast<int>(now_[j]);
    fresh |= m != joints_[j].confirmed && m != joints_[j].candidate;
  }
  if (fresh) plant_.classify_modes(t, x, stick_speed_, now_.data(), applied_.data(), true, speed_only_);
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    Joint& s = joints_[j];
    const int m = static_cast<int>(now_[j]);
    if (s.confirmed == 2) {  // the first classification (t = 0) is in force at once
      s.confirmed = m, s.candidate = 2;
      changes_.push_back({t, static_cast<int>(j), now_[j], applied_[j]});
      continue;
    }
    if (m == s.confirmed) {
      s.candidate = 2;
      continue;
    }
    if (m != s.candidate) s.candidate = m, s.since = t, s.applied = applied_[j];
    if (t - s.since >= min_duration_) {
      changes_.push_back({s.since, static_cast<int>(j), static_cast<SlipMode>(m), s.applied});
      s.confirmed = m, s.candidate = 2;
    }
  }
}

std::string events_csv(const Plant& plant, const std::vector<ModeChange>& changes) {
  std::string out = "t,joint,mode,applied_torque,static_torque\n";
  char line[160];
  for (const ModeChange& c : changes) {
    if (!plant.joint_has_modes(c.joint)) continue;
    const char* mode = c.mode == SlipMode::kStuck ? "stick" : c.mode == SlipMode::kPositive ? "slip+" : "slip-";
    std::snprintf(line, sizeof line, "%.17g,%d,%s,%.17g,%.17g\n", c.t, c.joint + 1, mode, c.applied,
                  plant.config().friction[static_cast<std::size_t>(c.joint)].static_torque);
    out += line;
  }
  return out;
}

}  // namespace pumasim
