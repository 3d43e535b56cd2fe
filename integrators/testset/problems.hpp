// A standard ODE test set beside the robot: problems nobody here wrote, each
// with a published reference value at its end point (or a closed form), so
// that the integrators behind the registry can be checked against numbers
// that do not come from themselves.
//
// The problems and their references come from the Bari "Test Set for IVP
// Solvers" (F. Mazzia, C. Magherini and others, Department of Mathematics,
// University of Bari; www.dm.uniba.it/~testset/): each problem's description
// (report/<name>.pdf) and its Fortran file (src/problems/<name>.f, revision
// of 2006; its subroutine `solut` holds the reference solution at the end
// point, computed with RADAU/RADAU5 in extended precision). Pleiades and Van der Pol also appear in Hairer, Norsett & Wanner,
// Solving ODEs I (II.10) and Hairer & Wanner, Solving ODEs II (IV.10), where
// the test set took them from. Prothero-Robinson (Prothero & Robinson, Math.
// Comp. 28 (1974) 145-162) has a closed form, so its reference is exact.
//
// Every problem is an OdeSystem with its exact Jacobian and its exact df/dt
// (zero for the autonomous ones), its time span, its initial value, the
// reference value at the end, and a suggested absolute tolerance per unit
// of relative tolerance (tolerance_scale: run with atol = rtol, and every
// component's absolute tolerance is rtol * scale).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "integrators/integrator.hpp"

namespace pumasim::testset {

class Problem : public OdeSystem {
 public:
  const std::string& name() const { return name_; }
  // One line: what the problem is, its size and character (stiff or not).
  const std::string& description() const { return description_; }
  // Where the reference value comes from (document, table or routine).
  const std::string& reference_source() const { return source_; }
  bool stiff() const { return stiff_; }
  double t0() const { return t0_; }
  double t_end() const { return t_end_; }
  const Eigen::VectorXd& initial_value() const { return y0_; }
  // The published reference solution at t_end (or the closed form there).
  const Eigen::VectorXd& reference() const { return yref_; }
  // The closed-form solution at t, when the problem has one (Prothero-Robinson).
  virtual bool exact_solution(double /*t*/, double* /*y*/) const { return false; }
  // The suggested fixed steps, coarse to fine, for the fixed-step methods: a
  // ladder that starts where the explicit methods are (or are not yet)
  // stable and halves from there.
  const std::vector<double>& fixed_steps() const { return fixed_steps_; }

  int size() const override { return static_cast<int>(y0_.size()); }
  bool has_exact_jacobian() const override { return true; }
  double tolerance_scale(int i) const override { return scale_[static_cast<std::size_t>(i)]; }
  // The autonomous problems' df/dt is exactly zero: said so, not differenced.
  int time_derivative(double t, const double* x, double* dfdt) override;

 protected:
  std::string name_, description_, source_;
  bool stiff_ = false;
  double t0_ = 0, t_end_ = 0;
  Eigen::VectorXd y0_, yref_;
  std::vector<double> scale_;  // atol / rtol per component
  std::vector<double> fixed_steps_;
};

// The mixed error of the test set at the end point: max over components of
// |y - yref| / (|yref| + atol_i / rtol) (with atol_i / rtol = tolerance_scale(i)),
// and the number of correct significant digits, scd = -log10(mixed error).
struct EndError {
  double mixed = 0;     // max_i |y_i - ref_i| / (|ref_i| + scale_i)
  double absolute = 0;  // max_i |y_i - ref_i|
  double scd = 0;       // -log10(mixed)
  int worst = 0;        // the component of the largest mixed error
};
EndError end_error(const Problem& p, const double* y);

// Prothero-Robinson with the given stiffness (lambda < 0) and fixed-step ladder,
// for tests that need it at another lambda than the set's two.
std::unique_ptr<Problem> prothero_robinson(double lambda, std::vector<double> fixed_steps = {});

// Every problem of the set, in a fixed order.
std::vector<std::unique_ptr<Problem>> make_problems();
// The problem called `name`; std::invalid_argument listing the valid names otherwise.
std::unique_ptr<Problem> make_problem(std::string_view name);
std::string problem_names();

}  // namespace pumasim::testset
