#include "models/robot/base_parameters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "models/robot/random_chain.hpp"

namespace pumasim {

namespace {

// The regressor at `samples` random states, stacked.
Eigen::MatrixXd stacked_regressor(JointTorqueRegressor& regressor, const RobotModel& model, int samples,
                                  std::uint64_t seed) {
  const int n = regressor.dof();
  Rng rng(seed);
  Eigen::MatrixXd W(static_cast<Eigen::Index>(samples) * n, regressor.parameters());
  Eigen::VectorXd q(n);
  for (int s = 0; s < samples; ++s) {
    for (int j = 0; j < n; ++j) {
      const JointParams& jp = model.joints[static_cast<std::size_t>(j)];
      const bool bounded = std::isfinite(jp.q_min) && std::isfinite(jp.q_max);
      const double wide = jp.prismatic() ? 0.5 : 3.141592653589793;  // without two finite limits: [m] or [rad]
      q[j] = bounded ? rng.uniform(jp.q_min, jp.q_max) : rng.uniform(-wide, wide);
    }
    const Eigen::VectorXd qd = rng.uniform_vector(n, -2.0, 2.0), qdd = rng.uniform_vector(n, -2.0, 2.0);
    regressor.compute(q, qd, qdd, W.middleRows(static_cast<Eigen::Index>(s) * n, n));
  }
  return W;
}

std::string coefficient_text(double c) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", std::abs(c));
  return buf;
}

}  // namespace

double BaseParameters::gap() const {
  const Eigen::Index r = rank();
  if (r == 0 || r >= singular_values.size() || singular_values[r] == 0.0) {
    return std::numeric_limits<double>::infinity();
  }
  return singular_values[r - 1] / singular_values[r];
}

Eigen::VectorXd BaseParameters::values(const Eigen::VectorXd& pi) const {
  Eigen::VectorXd b(rank()), d(static_cast<Eigen::Index>(grouped.size()));
  for (int i = 0; i < rank(); ++i) b[i] = pi[base[static_cast<std::size_t>(i)]];
  for (Eigen::Index k = 0; k < d.size(); ++k) d[k] = pi[grouped[static_cast<std::size_t>(k)]];
  return b + beta * d;
}

Eigen::MatrixXd BaseParameters::columns(const Eigen::MatrixXd& Y) const {
  Eigen::MatrixXd Yb(Y.rows(), rank());
  for (int i = 0; i < rank(); ++i) Yb.col(i) = Y.col(base[static_cast<std::size_t>(i)]);
  return Yb;
}

std::string BaseParameters::definition(int i) const {
  std::string text = names[static_cast<std::size_t>(base[static_cast<std::size_t>(i)])];
  if (beta.cols() == 0) return text;
  for (Eigen::Index k = 0; k < beta.cols(); ++k) {
    const double c = beta(i, k);
    if (c == 0.0) continue;
    text += c < 0 ? " - " : " + ";
    if (std::abs(std::abs(c) - 1.0) > 1e-9) text += coefficient_text(c) + " ";
    text += names[static_cast<std::size_t>(grouped[static_cast<std::size_t>(k)])];
  }
  return text;
}

std::string BaseParameters::label(int i) const {
  const std::string& own = names[static_cast<std::size_t>(base[static_cast<std::size_t>(i)])];
  return definition(i) == own ? own : own + "R";
}

std::string BaseParameters::regrouping() const {
  std::ostringstream out;
  for (int i = 0; i < rank(); ++i) {
    const std::string l = label(i), d = definition(i);
    out << l << (l == d ? "" : " = " + d) << "\n";
  }
  if (!no_effect.empty()) {
    out << "no effect on the torques:";
    for (int k : no_effect) out << " " << names[static_cast<std::size_t>(k)];
    out << "\n";
  }
  return out.str();
}

namespace {

// The columns kept in order: each whose distance from the span of those
// kept before it (modified Gram-Schmidt, twice, against the kept columns
// only) exceeds `threshold`. Zero columns are grouped with no effect.
void keep_in_order(const Eigen::MatrixXd& scaled, const std::vector<bool>& zero, double threshold,
                   BaseParameters& out) {
  Eigen::MatrixXd Q(scaled.rows(), scaled.cols());
  Eigen::Index r = 0;
  for (Eigen::Index k = 0; k < scaled.cols(); ++k) {
    if (zero[static_cast<std::size_t>(k)]) {
      out.grouped.push_back(static_cast<int>(k)), out.no_effect.push_back(static_cast<int>(k));
      continue;
    }
    Eigen::VectorXd v = scaled.col(k);
    for (int pass = 0; pass < 2; ++pass) v -= Q.leftCols(r) * (Q.leftCols(r).transpose() * v);
    const double distance = v.norm();
    if (distance > threshold) {
      Q.col(r++) = v / distance;
      out.base.push_back(static_cast<int>(k));
    } else {
      out.grouped.push_back(static_cast<int>(k));
    }
  }
}

// "sigma_38 = 0.41, sigma_39 = 2e-3 (...)": the singular values about the
// threshold, and a tolerance in the widest gap, for the message of a
// tolerance that sits in none.
std::string near_threshold(const Eigen::VectorXd& sv, double tolerance) {
  Eigen::Index widest = 0;
  double best = 0;
  for (Eigen::Index i = 0; i + 1 < sv.size(); ++i) {
    const double ratio = sv[i + 1] > 0 ? sv[i] / sv[i + 1] : std::numeric_limits<double>::infinity();
    if (ratio > best) best = ratio, widest = i;
  }
  char buf[200];
  const double suggest = sv[widest + 1] > 0 ? std::sqrt(sv[widest] * sv[widest + 1]) / sv[0] : 1e-8;
  std::snprintf(buf, sizeof buf,
                "the widest gap is between sigma_%ld = %.3g and sigma_%ld = %.3g (of %.3g): try --tolerance %.1g "
                "(now %.3g)",
                static_cast<long>(widest + 1), sv[widest], static_cast<long>(widest + 2), sv[widest + 1], sv[0],
                suggest, tolerance);
  return buf;
}

// beta from the scaled columns (dimensionless, each column of unit norm),
// its rounding-level entries set to zero, then unscaled into the
// parameters' units; the regrouping checked to reproduce the grouped columns
// to within the rank's threshold.
void regroup(const Eigen::MatrixXd& W, const Eigen::MatrixXd& scaled, const Eigen::VectorXd& norms, double threshold,
             BaseParameters& out) {
  const Eigen::MatrixXd Sb = out.columns(scaled);
  Eigen::MatrixXd Sd(W.rows(), static_cast<Eigen::Index>(out.grouped.size()));
  for (std::size_t k = 0; k < out.grouped.size(); ++k)
    Sd.col(static_cast<Eigen::Index>(k)) = scaled.col(out.grouped[k]);
  Eigen::MatrixXd b = Sb.householderQr().solve(Sd);
  const double rounding = 1e3 * std::numeric_limits<double>::epsilon() * std::sqrt(static_cast<double>(W.cols()));
  const double residual = (Sb * b - Sd).norm();
  // Each grouped column lies within `threshold` of the kept columns' span (keep_in_order).
  if (residual > 10 * threshold * std::sqrt(static_cast<double>(Sd.cols())) + rounding) {
    throw std::runtime_error("base_parameters: the regrouping leaves a residual of " + coefficient_text(residual) +
                             " of the grouped columns");
  }
  b = b.unaryExpr([rounding](double c) { return std::abs(c) <= rounding ? 0.0 : c; });
  out.beta.resize(b.rows(), b.cols());
  for (Eigen::Index i = 0; i < b.rows(); ++i) {
    for (Eigen::Index k = 0; k < b.cols(); ++k) {
      const int d = out.grouped[static_cast<std::size_t>(k)];
      out.beta(i, k) = norms[d] > 0 ? b(i, k) * norms[d] / norms[out.base[static_cast<std::size_t>(i)]] : 0.0;
    }
  }
}

}  // namespace

BaseParameters base_parameters(JointTorqueRegressor& regressor, const RobotModel& model, int samples,
                               std::uint64_t seed, double tolerance) {
  if (!(tolerance > 0 && tolerance < 1)) {
    throw std::invalid_argument("base_parameters: expected a rank tolerance in (0, 1), got " +
                                coefficient_text(tolerance));
  }
  if (static_cast<long>(samples) * regressor.dof() < regressor.parameters()) {
    throw std::invalid_argument("base_parameters: " + std::to_string(samples) + " samples give fewer rows than the " +
                                std::to_string(regressor.parameters()) + " columns: expected at least " +
                                std::to_string((regressor.parameters() + regressor.dof() - 1) / regressor.dof()));
  }
  BaseParameters out;
  out.names = regressor.parameter_names();
  out.tolerance = tolerance, out.samples = samples;
  const Eigen::MatrixXd W = stacked_regressor(regressor, model, samples, seed);
  const Eigen::VectorXd norms = W.colwise().norm().transpose();
  // A column at rounding level of the largest has no effect (a threshold of
  // its own, independent of the units: the rank's tolerance applies to the
  // scaled columns).
  const double zero_level =
      100 * std::numeric_limits<double>::epsilon() * std::sqrt(static_cast<double>(W.rows())) * norms.maxCoeff();
  Eigen::MatrixXd scaled = W;
  std::vector<bool> zero(static_cast<std::size_t>(W.cols()));
  for (Eigen::Index k = 0; k < W.cols(); ++k) {
    zero[static_cast<std::size_t>(k)] = norms[k] <= zero_level;
    if (zero[static_cast<std::size_t>(k)]) {
      scaled.col(k).setZero();
    } else {
      scaled.col(k) /= norms[k];
    }
  }
  out.singular_values = Eigen::JacobiSVD<Eigen::MatrixXd>(scaled).singularValues();
  const double threshold = tolerance * out.singular_values[0];
  const auto svd_rank = (out.singular_values.array() > threshold).count();
  keep_in_order(scaled, zero, threshold, out);
  if (static_cast<Eigen::Index>(out.base.size()) != svd_rank) {
    throw std::invalid_argument("base_parameters: the columns kept in order (" + std::to_string(out.base.size()) +
                                ") and the SVD's rank (" + std::to_string(svd_rank) +
                                ") disagree: the tolerance sits in no clear gap of the singular values; " +
                                near_threshold(out.singular_values, tolerance));
  }
  regroup(W, scaled, norms, threshold, out);
  if (out.gap() < 1e6) {
    out.warning = "the gap at this tolerance is only " + coefficient_text(out.gap()) +
                  ": the rank is not clear (axes nearly parallel or nearly perpendicular, or too few samples?)";
  }
  return out;
}

}  // namespace pumasim
