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
      q[j] = bounded ? rng.uniform(jp.q_min, jp.q_max) : rng.uniform(-0.5, 0.5);
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
  const double largest = std::max(1.0, beta.row(i).cwiseAbs().maxCoeff());
  for (Eigen::Index k = 0; k < beta.cols(); ++k) {
    const double c = beta(i, k);
    if (std::abs(c) <= 1e-9 * largest) continue;
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

BaseParameters base_parameters(JointTorqueRegressor& regressor, const RobotModel& model, int samples,
                               std::uint64_t seed, double tolerance) {
  if (samples * regressor.dof() < regressor.parameters()) {
    throw std::invalid_argument("base_parameters: " + std::to_string(samples) + " samples give fewer rows than the " +
                                std::to_string(regressor.parameters()) + " columns");
  }
  BaseParameters out;
  out.names = regressor.parameter_names();
  out.tolerance = tolerance, out.samples = samples;
  Eigen::MatrixXd W = stacked_regressor(regressor, model, samples, seed);
  const Eigen::VectorXd norms = W.colwise().norm().transpose();
  const double largest = norms.maxCoeff();
  Eigen::MatrixXd scaled = W;
  std::vector<bool> zero(static_cast<std::size_t>(W.cols()));
  for (Eigen::Index k = 0; k < W.cols(); ++k) {
    zero[static_cast<std::size_t>(k)] = norms[k] <= tolerance * largest;
    if (zero[static_cast<std::size_t>(k)]) {
      scaled.col(k).setZero();
    } else {
      scaled.col(k) /= norms[k];
    }
  }
  out.singular_values = Eigen::JacobiSVD<Eigen::MatrixXd>(scaled).singularValues();
  const double top = out.singular_values[0];
  const auto svd_rank = (out.singular_values.array() > tolerance * top).count();
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(scaled);
  const Eigen::MatrixXd R = qr.matrixQR().triangularView<Eigen::Upper>();
  for (Eigen::Index k = 0; k < W.cols(); ++k) {
    const bool kept = !zero[static_cast<std::size_t>(k)] && std::abs(R(k, k)) > tolerance;
    (kept ? out.base : out.grouped).push_back(static_cast<int>(k));
    if (zero[static_cast<std::size_t>(k)]) out.no_effect.push_back(static_cast<int>(k));
  }
  if (static_cast<Eigen::Index>(out.base.size()) != svd_rank) {
    throw std::runtime_error("base_parameters: the columns kept in order (" + std::to_string(out.base.size()) +
                             ") and the SVD's rank (" + std::to_string(svd_rank) + ") disagree at tolerance " +
                             coefficient_text(tolerance) + ": it sits in no gap of the singular values");
  }
  // beta from the unscaled columns, so that its coefficients are in the parameters' units.
  const Eigen::MatrixXd Wb = out.columns(W);
  Eigen::MatrixXd Wd(W.rows(), static_cast<Eigen::Index>(out.grouped.size()));
  for (std::size_t k = 0; k < out.grouped.size(); ++k) Wd.col(static_cast<Eigen::Index>(k)) = W.col(out.grouped[k]);
  out.beta = Wb.colPivHouseholderQr().solve(Wd);
  for (std::size_t k = 0; k < out.grouped.size(); ++k) {
    if (zero[static_cast<std::size_t>(out.grouped[k])]) out.beta.col(static_cast<Eigen::Index>(k)).setZero();
  }
  return out;
}

}  // namespace pumasim
