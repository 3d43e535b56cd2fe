// The test set's problems: right-hand sides, exact Jacobians, exact df/dt,
// and the reference values with their sources (see problems.hpp).
#include "integrators/testset/problems.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace pumasim::testset {

int Problem::time_derivative(double, const double*, double* dfdt) {
  for (int i = 0; i < size(); ++i) dfdt[i] = 0.0;
  return 0;
}

EndError end_error(const Problem& p, const double* y) {
  EndError e;
  for (int i = 0; i < p.size(); ++i) {
    const double d = std::abs(y[i] - p.reference()[i]);
    const double m = d / (std::abs(p.reference()[i]) + p.tolerance_scale(i));
    if (!(m <= e.mixed)) e.mixed = m, e.worst = i;  // a NaN wins
    if (!(d <= e.absolute)) e.absolute = d;
  }
  e.scd = -std::log10(e.mixed);
  return e;
}

namespace {

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double d : v) x[i++] = d;
  return x;
}

// dt0, dt0/2, ..., dt0/2^(n-1).
std::vector<double> halving(double dt0, int n) {
  std::vector<double> v;
  for (int k = 0; k < n; ++k) v.push_back(dt0 / std::pow(2.0, k));
  return v;
}

// ---------------------------------------------------------------------------
// Prothero-Robinson (Prothero & Robinson, Math. Comp. 28 (1974) 145-162), with
// a non-stiff second component coupled to it:
//   y0' = lambda (y0 - sin t) + cos t,   y0(0) = 0
//   y1' = y0 - y1,                       y1(0) = 0
// Exact solution: y0 = sin t (for every lambda: the stiff mode is never
// excited), and y1 = (sin t - cos t + exp(-t)) / 2 (y1' + y1 = sin t). The
// right-hand side depends on t explicitly: df/dt = (-lambda cos t - sin t, 0).
// A method that treats the t-dependence wrongly (a Rosenbrock method with
// inconsistent df/dt coefficients) loses its order here, not on y' = -y.
class ProtheroRobinson final : public Problem {
 public:
  ProtheroRobinson(const char* name, double lambda, std::vector<double> dts) : lambda_(lambda) {
    name_ = name;
    description_ = "Prothero-Robinson y0' = lambda (y0 - sin t) + cos t, lambda = " + fmt(lambda) +
                   ", with y1' = y0 - y1; 2 equations, non-autonomous, t in [0, 10]";
    source_ = "closed form: y0 = sin t, y1 = (sin t - cos t + exp(-t)) / 2";
    stiff_ = lambda < -1e3;
    t_end_ = 10.0;
    y0_ = vec({0.0, 0.0});
    yref_.resize(2);
    exact_solution(t_end_, yref_.data());
    scale_ = {1.0, 1.0};  // both components are O(1)
    fixed_steps_ = std::move(dts);
  }
  void rhs(double t, const double* y, double* f) override {
    f[0] = lambda_ * (y[0] - std::sin(t)) + std::cos(t);
    f[1] = y[0] - y[1];
  }
  void jacobian(double, const double*, Eigen::MatrixXd& J) override {
    J.resize(2, 2);
    J << lambda_, 0.0, 1.0, -1.0;
  }
  // f = diag(lambda, -1) y + (cos t - lambda sin t, y0): the exponential
  // methods integrate the stiff decay exactly.
  void linear_diagonal(double* l) const override {
    l[0] = lambda_;
    l[1] = -1.0;
  }
  int time_derivative(double t, const double*, double* dfdt) override {
    dfdt[0] = -lambda_ * std::cos(t) - std::sin(t);
    dfdt[1] = 0.0;
    return 0;
  }
  bool exact_solution(double t, double* y) const override {
    y[0] = std::sin(t);
    y[1] = 0.5 * (std::sin(t) - std::cos(t) + std::exp(-t));
    return true;
  }

 private:
  static std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
  }
  double lambda_;
};

// ---------------------------------------------------------------------------
// VDPOL: Van der Pol's equation in the test set's scaled form (t rescaled by
// mu, eps = 1/mu^2 = 1e-6, i.e. mu = 1000):
//   y1' = y2,  y2' = ((1 - y1^2) y2 - y1) / eps,   y(0) = (2, 0),  t in [0, 2].
// Reference at t = 2: Test Set for IVP Solvers, problem VDPOL (vdpol.f,
// subroutine solut, "computed using double precision RADAU on an Alphaserver
// DS20E ... rtol = atol = h0 = 1.1d-18"). Hairer & Wanner II, Sec. IV.10,
// has the same problem.
class VanDerPol final : public Problem {
 public:
  VanDerPol() {
    name_ = "vdpol";
    description_ = "Van der Pol, scaled form, eps = 1e-6 (mu = 1e3); 2 equations, stiff, t in [0, 2]";
    source_ = "Test Set for IVP Solvers, VDPOL: vdpol.f, subroutine solut";
    stiff_ = true;
    t_end_ = 2.0;
    y0_ = vec({2.0, 0.0});
    yref_ = vec({0.1706167732170483e+01, -0.8928097010247975e+00});
    scale_ = {1.0, 1.0};  // chosen: atol = rtol, both components are O(1)
    // max |lambda| = 3e6 (at y1 = 2): explicit Euler needs dt < 6.7e-7, RK4
    // 9.3e-7, AB2 3.3e-7, AB3 1.8e-7, AB4 1e-7.
    fixed_steps_ = halving(1e-6, 5);
  }
  void rhs(double, const double* y, double* f) override {
    f[0] = y[1];
    f[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / kEps;
  }
  void jacobian(double, const double* y, Eigen::MatrixXd& J) override {
    J.resize(2, 2);
    J(0, 0) = 0.0;
    J(0, 1) = 1.0;
    J(1, 0) = (-2.0 * y[0] * y[1] - 1.0) / kEps;
    J(1, 1) = (1.0 - y[0] * y[0]) / kEps;
  }

 private:
  static constexpr double kEps = 1e-6;
};

// ---------------------------------------------------------------------------
// HIRES: "High Irradiance RESponse" of photomorphogenesis (Schäfer 1975), 8
// equations, t in [0, 321.8122]. Reference at the end: Test Set for IVP
// Solvers, problem HIRES (hires.f, its reference-solution routine -- solut,
// hiressol in R deTestSet's copy of the file: "computed using true
// double precision RADAU5 on Cray C90, uround = 1.01d-19, rtol = atol = h0 =
// 1.1d-18"). Hairer & Wanner II, Sec. IV.10, has the same problem.
class Hires final : public Problem {
 public:
  Hires() {
    name_ = "hires";
    description_ = "HIRES, plant physiology (Schaefer 1975); 8 equations, stiff, t in [0, 321.8122]";
    source_ = "Test Set for IVP Solvers, HIRES: hires.f, reference-solution routine";
    stiff_ = true;
    t_end_ = 321.8122;
    y0_ = vec({1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0057});
    yref_ = vec({0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4, 0.1175651343283149e-2,
                 0.2386356198831331e-2, 0.6238968252742796e-2, 0.2849998395185769e-2, 0.2850001604814231e-2});
    // Chosen: the components end between 6e-5 and 6e-3; an absolute floor
    // of 1e-4 rtol keeps the small ones measured relatively.
    scale_.assign(8, 1e-4);
    // max |lambda| = 212 (near t = 10.6): explicit Euler needs dt < 9.4e-3,
    // RK4 1.3e-2, AB2 4.7e-3, AB3 2.6e-3, AB4 1.4e-3.
    fixed_steps_ = halving(1e-2, 5);
  }
  void rhs(double, const double* y, double* f) override {
    f[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007;
    f[1] = 1.71 * y[0] - 8.75 * y[1];
    f[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4];
    f[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3];
    f[4] = -1.745 * y[4] + 0.43 * (y[5] + y[6]);
    f[5] = -280.0 * y[5] * y[7] + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6];
    f[6] = 280.0 * y[5] * y[7] - 1.81 * y[6];
    f[7] = -f[6];
  }
  void jacobian(double, const double* y, Eigen::MatrixXd& J) override {
    J.setZero(8, 8);
    J(0, 0) = -1.71, J(0, 1) = 0.43, J(0, 2) = 8.32;
    J(1, 0) = 1.71, J(1, 1) = -8.75;
    J(2, 2) = -10.03, J(2, 3) = 0.43, J(2, 4) = 0.035;
    J(3, 1) = 8.32, J(3, 2) = 1.71, J(3, 3) = -1.12;
    J(4, 4) = -1.745, J(4, 5) = 0.43, J(4, 6) = 0.43;
    J(5, 3) = 0.69, J(5, 4) = 1.71, J(5, 5) = -280.0 * y[7] - 0.43, J(5, 6) = 0.69, J(5, 7) = -280.0 * y[5];
    J(6, 5) = 280.0 * y[7], J(6, 6) = -1.81, J(6, 7) = 280.0 * y[5];
    J(7, 5) = -280.0 * y[7], J(7, 6) = 1.81, J(7, 7) = -280.0 * y[5];
  }
};

// ---------------------------------------------------------------------------
// OREGO: the Oregonator, Field & Noyes' model of the Belousov-Zhabotinskii
// reaction, 3 equations, t in [0, 360], y(0) = (1, 2, 3). Reference at the
// end: Test Set for IVP Solvers, problem OREGO (orego.f, subroutine solut:
// "computed using double precision RADAU on an Alphaserver DS20E ... rtol =
// h0 = 1.1d-18, atol = 1.1d-40"). Hairer & Wanner II,
// Sec. IV.10.
class Orego final : public Problem {
 public:
  Orego() {
    name_ = "orego";
    description_ = "OREGO, the Oregonator (Field & Noyes 1974); 3 equations, stiff, t in [0, 360]";
    source_ = "Test Set for IVP Solvers, OREGO: orego.f, subroutine solut";
    stiff_ = true;
    t_end_ = 360.0;
    y0_ = vec({1.0, 2.0, 3.0});
    yref_ = vec({0.1000814870318523e+01, 0.1228178521549917e+04, 0.1320554942846706e+03});
    // Chosen: atol = rtol (y1 and y3 stay between 1 and 1.2e5 and 3.1e4; y2
    // between 3e-3 and 1.8e3).
    scale_.assign(3, 1.0);
    // max |lambda| = 1.4e5 (near t = 37): explicit Euler needs dt < 1.5e-5,
    // RK4 2e-5, AB2 7.3e-6, AB3 4e-6, AB4 2.2e-6 (up to 7.2e7 steps).
    fixed_steps_ = halving(2e-5, 3);
  }
  void rhs(double, const double* y, double* f) override {
    f[0] = kS * (y[1] + y[0] * (1.0 - kQ * y[0] - y[1]));
    f[1] = (y[2] - (1.0 + y[0]) * y[1]) / kS;
    f[2] = kW * (y[0] - y[2]);
  }
  void jacobian(double, const double* y, Eigen::MatrixXd& J) override {
    J.resize(3, 3);
    J(0, 0) = kS * (1.0 - 2.0 * kQ * y[0] - y[1]);
    J(0, 1) = kS * (1.0 - y[0]);
    J(0, 2) = 0.0;
    J(1, 0) = -y[1] / kS;
    J(1, 1) = -(1.0 + y[0]) / kS;
    J(1, 2) = 1.0 / kS;
    J(2, 0) = kW;
    J(2, 1) = 0.0;
    J(2, 2) = -kW;
  }

 private:
  static constexpr double kS = 77.27, kQ = 8.375e-6, kW = 0.161;
};

// ---------------------------------------------------------------------------
// ROBER: Robertson's chemical kinetics (Robertson 1966), 3 equations, t in
// [0, 1e11], y(0) = (1, 0, 0). Reference at the end: Test Set for IVP
// Solvers, problem ROBER (rober.f, subroutine solut: "computed using double
// precision RADAU on an Alphaserver DS20E ... rtol = atol = h0 = 1.1d-18";
// Hairer & Wanner II, Sec. IV.10.
class Robertson final : public Problem {
 public:
  Robertson() {
    name_ = "rober";
    description_ = "ROBER, Robertson's chemical kinetics (1966); 3 equations, stiff, t in [0, 1e11]";
    source_ = "Test Set for IVP Solvers, ROBER: rober.f, subroutine solut";
    stiff_ = true;
    t_end_ = 1e11;
    y0_ = vec({1.0, 0.0, 0.0});
    yref_ = vec({0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050e+00});
    // Chosen: y2 peaks near 3.6e-5 and ends near 8e-14, y1 ends near 2e-8;
    // an absolute floor of 1e-10 rtol keeps both measured, and keeps the
    // concentrations from drifting negative (which makes the problem blow up).
    scale_.assign(3, 1e-10);
    // No explicit fixed step reaches 1e11 (|lambda| about 1e4, so dt < 2.8e-4
    // even for RK4: over 3e14 steps): the ladder's runs end in a reported
    // failure, by instability or by the step budget.
    fixed_steps_ = halving(4e-4, 2);
  }
  void rhs(double, const double* y, double* f) override {
    f[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
    f[2] = 3e7 * y[1] * y[1];
    f[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1];
  }
  void jacobian(double, const double* y, Eigen::MatrixXd& J) override {
    J.resize(3, 3);
    J(0, 0) = -0.04, J(0, 1) = 1e4 * y[2], J(0, 2) = 1e4 * y[1];
    J(1, 0) = 0.04, J(1, 1) = -1e4 * y[2] - 6e7 * y[1], J(1, 2) = -1e4 * y[1];
    J(2, 0) = 0.0, J(2, 1) = 6e7 * y[1], J(2, 2) = 0.0;
  }
};

// ---------------------------------------------------------------------------
// PLEI: the Pleiades, seven stars in the plane with masses m_j = j and unit
// gravitational constant; 28 equations (x1..x7, y1..y7, x1'..x7', y1'..y7'),
// non-stiff, t in [0, 3]. Hairer, Norsett & Wanner I, Sec. II.10. Reference
// at t = 3: Test Set for IVP Solvers, problem PLEI (report plei.pdf,
// "Reference solution", all 28 components to 16 digits; the same values are
// quoted from it by Drake's Pleiades test system and by IVPTestSuite.jl).
class Pleiades final : public Problem {
 public:
  Pleiades() {
    name_ = "plei";
    description_ = "PLEI, the Pleiades (7 bodies in the plane); 28 equations, non-stiff, t in [0, 3]";
    source_ = "Test Set for IVP Solvers, PLEI: plei.pdf, reference solution";
    stiff_ = false;
    t_end_ = 3.0;
    y0_ = vec({3, 3, -1, -3, 2, -2, 2,                    // x
               3, -3, 2, 0, 0, -4, 4,                     // y
               0, 0, 0, 0, 0, 1.75, -1.5,                 // x'
               0, 0, 0, -1.25, 1, 0, 0});                 // y'
    yref_ = vec({0.3706139143970502e+00, 0.3237284092057233e+01, -0.3222559032418324e+01, 0.6597091455775310e+00,
                 0.3425581707156584e+00, 0.1562172101400631e+01, -0.7003092922212495e+00,
                 -0.3943437585517392e+01, -0.3271380973972550e+01, 0.5225081843456543e+01, -0.2590612434977470e+01,
                 0.1198213693392275e+01, -0.2429682344935824e+00, 0.1091449240428980e+01,
                 0.3417003806314313e+01, 0.1354584501625501e+01, -0.2590065597810775e+01, 0.2025053734714242e+01,
                 -0.1155815100160448e+01, -0.8072988170223021e+00, 0.5952396354208710e+00,
                 -0.3741244961234010e+01, 0.3773459685750630e+00, 0.9386858869551073e+00, 0.3667922227200571e+00,
                 -0.3474046353808490e+00, 0.2344915448180937e+01, -0.1947020434263292e+01});
    scale_.assign(28, 1.0);  // positions and speeds are O(1)
    // max |lambda| = 623 (the close encounter near t = 1.7); accuracy, not
    // stability, sets the step there.
    fixed_steps_ = halving(2e-3, 6);
  }
  void rhs(double, const double* z, double* f) override {
    for (int i = 0; i < 14; ++i) f[i] = z[14 + i];
    for (int i = 0; i < 7; ++i) f[14 + i] = f[21 + i] = 0.0;
    for (int i = 0; i < 7; ++i) {
      for (int j = 0; j < 7; ++j) {
        if (i == j) continue;
        const double dx = z[j] - z[i], dy = z[7 + j] - z[7 + i];
        const double r2 = dx * dx + dy * dy, r3 = r2 * std::sqrt(r2);
        f[14 + i] += (j + 1) * dx / r3;
        f[21 + i] += (j + 1) * dy / r3;
      }
    }
  }
  void jacobian(double, const double* z, Eigen::MatrixXd& J) override {
    J.setZero(28, 28);
    for (int i = 0; i < 14; ++i) J(i, 14 + i) = 1.0;
    // a_i = sum_j m_j d_ij / r_ij^3 with d_ij = p_j - p_i:
    // d(d r^-3)/dd = r^-3 I - 3 d d^T r^-5, and d_ij moves with +p_j, -p_i.
    for (int i = 0; i < 7; ++i) {
      for (int j = 0; j < 7; ++j) {
        if (i == j) continue;
        const double dx = z[j] - z[i], dy = z[7 + j] - z[7 + i];
        const double r2 = dx * dx + dy * dy, r = std::sqrt(r2);
        const double r3 = r2 * r, r5 = r3 * r2, m = j + 1;
        const double axx = m * (1.0 / r3 - 3.0 * dx * dx / r5), axy = m * (-3.0 * dx * dy / r5);
        const double ayy = m * (1.0 / r3 - 3.0 * dy * dy / r5);
        // rows: x''_i (14 + i), y''_i (21 + i); columns: x_j (j), y_j (7 + j)
        J(14 + i, j) += axx, J(14 + i, 7 + j) += axy;
        J(21 + i, j) += axy, J(21 + i, 7 + j) += ayy;
        J(14 + i, i) -= axx, J(14 + i, 7 + i) -= axy;
        J(21 + i, i) -= axy, J(21 + i, 7 + i) -= ayy;
      }
    }
  }
  std::string state_name(int i) const override {
    static const char* kBlock[] = {"x", "y", "xd", "yd"};
    return std::string(kBlock[i / 7]) + std::to_string(i % 7 + 1);
  }
};

}  // namespace

std::unique_ptr<Problem> prothero_robinson(double lambda, std::vector<double> fixed_steps) {
  return std::make_unique<ProtheroRobinson>("prothero-robinson", lambda, std::move(fixed_steps));
}

std::vector<std::unique_ptr<Problem>> make_problems() {
  std::vector<std::unique_ptr<Problem>> v;
  // Fixed-step ladders: lambda = -50 limits explicit Euler to dt < 0.04,
  // lambda = -1e4 to dt < 2e-4 (RK4 2.8e-4, AB4 3e-5).
  v.push_back(std::make_unique<ProtheroRobinson>("prothero-robinson", -50.0, halving(0.04, 6)));
  v.push_back(std::make_unique<ProtheroRobinson>("prothero-robinson-stiff", -1e4, halving(4e-4, 6)));
  v.push_back(std::make_unique<VanDerPol>());
  v.push_back(std::make_unique<Hires>());
  v.push_back(std::make_unique<Orego>());
  v.push_back(std::make_unique<Robertson>());
  v.push_back(std::make_unique<Pleiades>());
  return v;
}

std::string problem_names() {
  std::string s;
  for (const auto& p : make_problems()) {
    if (!s.empty()) s += ", ";
    s += p->name();
  }
  return s;
}

std::unique_ptr<Problem> make_problem(std::string_view name) {
  for (auto& p : make_problems()) {
    if (p->name() == name) return std::move(p);
  }
  throw std::invalid_argument("unknown test problem '" + std::string(name) + "'; expected one of: " +
                              problem_names());
}

}  // namespace pumasim::testset
