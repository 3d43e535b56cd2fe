// References that do not need the PUMA: splines through joint-space points
// (polynomial reproduction, continuity, rates against differences), the CSV
// reader's refusals, the damped-least-squares inverse kinematics against
// closed forms (a planar two-link arm, the PUMA along the paper's path), a
// path leaving the workspace, and whole-plant runs on the planar arm.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <functional>
#include <string>
#include <vector>

#include "integrators/registry.hpp"
#include "models/reference/joint_curve.hpp"
#include "models/reference/numerical_ik.hpp"
#include "models/reference/trajectory.hpp"
#include "models/robot/kinematics.hpp"
#include "models/robot/robot_file.hpp"
#include "models/scene/joint_csv.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"

#include "tests/scene_paths.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

using test::scene_path;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// The points as the curve takes them (dynamic vectors).
std::vector<Eigen::VectorXd> dyn(const std::vector<Vec6>& v) { return {v.begin(), v.end()}; }

// The shipped planar arm (models/robots/planar2.toml), by its file path.
std::string planar2_path() { return std::string(PUMASIM_SCENES_DIR) + "/../../models/robots/planar2.toml"; }

// Value, first and second derivative of piece k of a spline at x.
void eval_coefficients(const PieceCoefficients& c, double u, double& p, double& v, double& a) {
  p = v = a = 0;
  for (int e = 5; e >= 0; --e) p = p * u + c[e];
  for (int e = 5; e >= 1; --e) v = v * u + e * c[e];
  for (int e = 5; e >= 2; --e) a = a * u + e * (e - 1) * c[e];
}

// Unequal knots (ratios up to about 5) on [0, 2].
std::vector<double> uneven_knots() { return {0.0, 0.1, 0.45, 0.6, 1.1, 1.2, 1.65, 2.0}; }

// The spline's pieces against p, p', p'' on a fine grid; `scale` is the
// largest |p| on the interval (rounding relative to it).
void expect_reproduces(const std::vector<double>& x, const std::vector<PieceCoefficients>& c,
                       const std::function<void(double, double&, double&, double&)>& poly) {
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    for (int i = 0; i <= 10; ++i) {
      const double xi = x[k] + (x[k + 1] - x[k]) * i / 10;
      double p, v, a, pw, vw, aw;
      eval_coefficients(c[k], xi - x[k], p, v, a);
      poly(xi, pw, vw, aw);
      EXPECT_NEAR(p, pw, 1e-12) << "x = " << xi;
      EXPECT_NEAR(v, vw, 1e-10) << "x = " << xi;
      EXPECT_NEAR(a, aw, 1e-9) << "x = " << xi;
    }
  }
}

// A polynomial's values at the knots, and its end slopes and second derivatives.
struct Samples {
  std::vector<double> p;
  double v0 = 0, a0 = 0, vM = 0, aM = 0;
};

template <class Poly>
Samples sample(const std::vector<double>& x, const Poly& poly) {
  Samples s;
  double p, v, a;
  for (double xi : x) {
    poly(xi, p, v, a);
    s.p.push_back(p);
  }
  poly(x.front(), p, s.v0, s.a0);
  poly(x.back(), p, s.vM, s.aM);
  return s;
}

// Uniqueness: a cubic is a C2 cubic spline on any knots, so the clamped
// spline through its values with its end slopes is the cubic itself (de Boor
// 2001, ch. IV). The values are of order 1; rounding in the tridiagonal solve
// leaves ~1e-15 on q, and each derivative divides by a knot spacing (>= 0.05).
TEST(Splines, ClampedCubicReproducesACubic) {
  const auto poly = [](double x, double& p, double& v, double& a) {
    p = 0.3 - 1.2 * x + 0.7 * x * x - 0.25 * x * x * x;
    v = -1.2 + 1.4 * x - 0.75 * x * x;
    a = 1.4 - 1.5 * x;
  };
  const std::vector<double> x = uneven_knots();
  const Samples y = sample(x, poly);
  expect_reproduces(x, clamped_cubic_spline(x, y.p, y.v0, y.vM), poly);
}

// Likewise a quintic is a C4 quintic spline: given its end slopes and second
// derivatives, the clamped quintic spline through its values is itself.
TEST(Splines, ClampedQuinticReproducesAQuintic) {
  const auto poly = [](double x, double& p, double& v, double& a) {
    const double c[6] = {0.2, -0.5, 0.8, 0.3, -0.6, 0.15};
    p = v = a = 0;
    for (int e = 5; e >= 0; --e) p = p * x + c[e];
    for (int e = 5; e >= 1; --e) v = v * x + e * c[e];
    for (int e = 5; e >= 2; --e) a = a * x + e * (e - 1) * c[e];
  };
  const std::vector<double> x = uneven_knots();
  const Samples y = sample(x, poly);
  expect_reproduces(x, clamped_quintic_spline(x, y.p, y.v0, y.a0, y.vM, y.aM), poly);
}

// On data from no polynomial: the spline interpolates every knot, and at each
// inner knot its derivatives up to the second (cubic) or fourth (quintic)
// agree from both sides; the end conditions hold.
TEST(Splines, InterpolateTheKnotsWithTheirContinuity) {
  const std::vector<double> x = uneven_knots();
  const std::vector<double> y = {0.0, 0.4, -0.3, 0.9, 0.2, 0.25, -0.6, 0.1};
  const auto cubic = clamped_cubic_spline(x, y, 0.5, -0.2);
  const auto quintic = clamped_quintic_spline(x, y, 0.5, 1.0, -0.2, -3.0);
  // The d-th derivative of a piece at u.
  const auto deriv = [](const PieceCoefficients& c, double u, int d) {
    double s = 0;
    for (int e = 5; e >= d; --e) {
      double f = 1;
      for (int i = 0; i < d; ++i) f *= e - i;
      s = s * u + f * c[e];
    }
    return s;
  };
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    const double h = x[k + 1] - x[k];
    EXPECT_NEAR(deriv(cubic[k], 0, 0), y[k], 1e-15);
    EXPECT_NEAR(deriv(cubic[k], h, 0), y[k + 1], 1e-13);
    EXPECT_NEAR(deriv(quintic[k], 0, 0), y[k], 1e-15);
    EXPECT_NEAR(deriv(quintic[k], h, 0), y[k + 1], 1e-12);
    if (k == 0) continue;
    const double hl = x[k] - x[k - 1];
    for (int d = 1; d <= 2; ++d) {
      EXPECT_NEAR(deriv(cubic[k - 1], hl, d), deriv(cubic[k], 0, d), 1e-9 * std::pow(10.0, d)) << k << " " << d;
    }
    for (int d = 1; d <= 4; ++d) {
      EXPECT_NEAR(deriv(quintic[k - 1], hl, d), deriv(quintic[k], 0, d), 1e-9 * std::pow(10.0, d)) << k << " " << d;
    }
  }
  EXPECT_NEAR(deriv(cubic.front(), 0, 1), 0.5, 1e-15);
  EXPECT_NEAR(deriv(cubic.back(), x.back() - x[x.size() - 2], 1), -0.2, 1e-12);
  EXPECT_NEAR(deriv(quintic.front(), 0, 2), 1.0, 1e-15);
  EXPECT_NEAR(deriv(quintic.back(), x.back() - x[x.size() - 2], 2), -3.0, 1e-9);
}

// A reference starts and ends at rest: the curve's end slopes are 0 (and,
// quintic, its end second derivatives). Then the polynomials with those ends
// are reproduced: 3 r^2 - 2 r^3 (cubic) and 10 r^3 - 15 r^4 + 6 r^5 (quintic).
TEST(JointCurve, AtRestAtTheEndsReproducesTheRestToRestPolynomials) {
  const double T = 2.0;
  const std::vector<double> x = uneven_knots();
  for (const auto kind : {JointCurve::Kind::kCubic, JointCurve::Kind::kQuintic}) {
    const auto f = [&](double t, double& p, double& v, double& a) {
      const double r = t / T;
      if (kind == JointCurve::Kind::kCubic) {
        p = 3 * r * r - 2 * r * r * r, v = (6 * r - 6 * r * r) / T, a = (6 - 12 * r) / (T * T);
      } else {
        p = r * r * r * (10 - 15 * r + 6 * r * r), v = 30 * r * r * (1 - r) * (1 - r) / T;
        a = 60 * r * (1 - r) * (1 - 2 * r) / (T * T);
      }
    };
    std::vector<Vec6> pts;
    for (double xi : x) {
      double p, v, a;
      f(xi, p, v, a);
      Vec6 q = Vec6::Zero();
      q[0] = p, q[1] = -2 * p;
      pts.push_back(q);
    }
    const JointCurve curve(x, dyn(pts), 2, kind);
    for (double t = 0; t <= T; t += 0.01) {
      Vec6 q, dq, ddq;
      curve.eval(t, q, dq, ddq);
      double p, v, a;
      f(t, p, v, a);
      EXPECT_NEAR(q[0], p, 1e-13) << t;
      EXPECT_NEAR(dq[0], v, 1e-12) << t;
      EXPECT_NEAR(ddq[0], a, 1e-10) << t;
      EXPECT_NEAR(q[1], -2 * p, 2e-13) << t;
      EXPECT_EQ(q[2], 0.0);
    }
  }
}

// A reference on the planar arm from points at their own times ("explicit")
// and retimed by a trapezoid along them.
std::vector<Reference> planar_curve_references() {
  const RobotModel robot = load_robot(planar2_path());
  std::vector<Vec6> pts(5, Vec6::Zero());
  pts[0].head<2>() << 0.3, 1.2;
  pts[1].head<2>() << 0.6, 0.9;
  pts[2].head<2>() << 0.9, 1.3;
  pts[3].head<2>() << 0.5, 1.6;
  pts[4].head<2>() << 0.2, 1.0;
  const std::vector<double> t = {0.0, 0.7, 1.5, 2.0, 3.0};
  std::vector<Reference> out;
  for (const auto kind : {JointCurve::Kind::kCubic, JointCurve::Kind::kQuintic}) {
    const JointCurve curve(t, dyn(pts), 2, kind);
    out.emplace_back(robot, Eigen::VectorXd::Zero(robot.dof()), curve, Timing::unit_speed(3.0));
    out.emplace_back(robot, Eigen::VectorXd::Zero(robot.dof()), curve, Timing::trapezoid(3.0, 2.0, 0.25));
  }
  return out;
}

// qd and qdd are the derivatives of q: central differences of q and qd, step
// h = 1e-5 s, at points clear of the breakpoints by more than h. Truncation
// h^2/6 |q'''| (|q'''| < 1e3 rad/s^3 here: about 2e-8) and rounding
// 1e-16/h (1e-11) are below the bound 1e-6.
TEST(JointReference, RatesAreTheDerivativesOfTheAngles) {
  for (const Reference& ref : planar_curve_references()) {
    const double h = 1e-5, T = ref.timing().duration();
    int checked = 0;
    for (double t = 0.013; t < T; t += 0.0371) {
      if (std::abs(ref.next_breakpoint(t - 2 * h) - t) < 2 * h) continue;
      ReferenceSample a, b, c;
      ref.eval(t - h, a), ref.eval(t, b), ref.eval(t + h, c);
      EXPECT_LT(((c.q - a.q) / (2 * h) - b.qd).lpNorm<Eigen::Infinity>(), 1e-6) << ref.timing().kind() << t;
      EXPECT_LT(((c.qd - a.qd) / (2 * h) - b.qdd).lpNorm<Eigen::Infinity>(), 1e-6) << ref.timing().kind() << t;
      // The Cartesian samples are the flange's: p = fk(q), v = J qd.
      EXPECT_LT(((c.p - a.p) / (2 * h) - b.v).norm(), 1e-6) << t;
      ++checked;
    }
    EXPECT_GT(checked, 40);
  }
}

// The given points at their times; at rest at both ends; held after the last
// point; the breakpoints are the inner knots and the end (explicit timing).
TEST(JointReference, ThroughThePointsAndHeldAfterTheLast) {
  const std::vector<Reference> refs = planar_curve_references();
  for (int i : {0, 2}) {  // the explicit-timing ones
    const Reference& ref = refs[static_cast<std::size_t>(i)];
    const JointCurve& c = *ref.curve();
    for (std::size_t k = 0; k < c.knots().size(); ++k) {
      ReferenceSample r;
      ref.eval(c.knots()[k], r);
      EXPECT_NEAR((r.q.head(c.joints()) - c.points()[k]).norm(), 0.0, 1e-13) << k;
    }
    EXPECT_EQ(ref.breakpoints(), (std::vector<double>{0.7, 1.5, 2.0, 3.0}));
    ReferenceSample r0, end;
    ref.eval(0.0, r0);
    ref.eval(7.0, end);
    EXPECT_LT(r0.qd.norm(), 1e-14);  // the clamped end slopes, to rounding
    EXPECT_LT((end.q.head(c.joints()) - c.points().back()).norm(), 1e-13);
    EXPECT_EQ(end.qd.norm(), 0.0);
    EXPECT_EQ(end.qdd.norm(), 0.0);
  }
}

// ---------------------------------------------------------------- CSV

std::string write_temp(const std::string& name, const std::string& text) {
  const auto path = testing::scratch_root() / name;
  std::ofstream(path) << text;
  return path.string();
}

// The message of the ConfigError f throws ("" if none).
std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(JointCsv, BadFilesAreRefusedNamingFileLineAndColumn) {
  const std::string head = "t,q1,q2,q3\n0,0.1,0.2,0.3\n";
  struct Case {
    std::string name, body, where, what;
  };
  const std::vector<Case> cases = {
      {"bad_value", head + "1.0,0.2,oops,0.3\n", ":3: column 3 (q2)", "expected a finite number, got \"oops\""},
      {"nan_value", head + "1.0,0.2,nan,0.3\n", ":3: column 3 (q2)", "finite number"},
      {"unsorted", head + "1.0,0.2,0.2,0.3\n\n0.5,0.2,0.2,0.3\n", ":5: column 1 (t)", "strictly increasing"},
      {"same_time", head + "0,0.2,0.2,0.3\n", ":3: column 1 (t)", "strictly increasing"},
      {"columns", head + "1.0,0.2,0.3\n", ":3: ", "expected 4 columns"},
      {"header", "t,q1,q2\n0,0.1,0.2\n", ":1: ", "expected 4 columns"},
      {"late_start", "t,q1,q2,q3\n0.5,0.1,0.2,0.3\n1,0,0,0\n", ":2: column 1 (t)", "first point at t = 0"},
      {"one_row", head, ": ", "at least two points"},
      // Points whose curve is not finite (issue 32: `check` passed them, `run` failed unnamed).
      {"huge_value", head + "1.0,1e308,0.2,0.3\n", ":3: ", "slope or curvature overflows"},
      {"tiny_step", head + "1e-300,0.2,0.2,0.3\n", ":3: ", "at least 1e-06 s after the previous row's"},
      {"denormal_step", head + "5e-324,0.2,0.2,0.3\n", ":3: ", "at least 1e-06 s after"},
      // Found by fuzz_joint_csv: splines not finite through rows the checks above passed.
      {"jump_of_1e307", head + "1.2e27,1e307,0.2,0.3\n", ":3: ", "slope or curvature overflows"},
      {"jump_in_a_microsecond", head + "1e-6,1e290,0.2,0.3\n1,0,0,0\n", ":3: ", "slope or curvature overflows"},
      {"step_of_1e110_s", head + "1e110,1,0.2,0.3\n2e110,0,0,0\n", ":3: ", "at most 1e+75 s after"},
  };
  for (const Case& c : cases) {
    const std::string path = write_temp("pumasim_csv_" + c.name + ".csv", c.body);
    const std::string msg = refusal([&] { read_joint_csv(path, 3); });
    EXPECT_NE(msg.find(path + c.where), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.what), std::string::npos) << c.name << ": " << msg;
  }
  const std::string ok = write_temp("pumasim_csv_ok.csv", head + " 1.5 , -0.2, 2e-1 ,0.3\n");
  const auto rows = read_joint_csv(ok, 3);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1], (std::vector<double>{1.5, -0.2, 0.2, 0.3}));
}

// joint_space_csv.toml, written beside `name`.csv reading it: the scene's path.
std::string joint_space_scene_reading(const std::string& name) {
  std::ifstream in(scene_path("joint_space_csv"));
  std::stringstream buf;
  buf << in.rdbuf();
  std::string text = buf.str();
  const std::string from = "joints = \"joint_space_csv.csv\"";
  text.replace(text.find(from), from.size(), "joints = \"" + name + ".csv\"");
  return write_temp(name + ".toml", text);
}

// Rows whose steps each pass the reader's check but whose spline couples a
// huge jump in a short step with a long neighbouring step (found by
// fuzz_joint_csv in CI's smoke run): the quintic's knot equations overflow.
// The curve refuses them, and a scene loading them names its file.
TEST(JointCsv, ASplineThatOverflowsIsRefusedByTheCurveAndTheScene) {
  const std::string csv = "t,q1,q2,q3\n0,0,0,0\n1e-6,1e280,0,0\n1,0,0,0\n";
  const std::string path = write_temp("pumasim_csv_coupled_overflow.csv", csv);
  const auto rows = read_joint_csv(path, 3);  // each step alone passes
  std::vector<double> knots;
  std::vector<Vec6> points;
  for (const auto& r : rows) {
    knots.push_back(r[0]);
    Vec6 q = Vec6::Zero();
    for (int j = 0; j < 3; ++j) q[j] = r[static_cast<std::size_t>(j) + 1];
    points.push_back(q);
  }
  std::string msg;
  try {
    JointCurve(knots, dyn(points), 3, JointCurve::Kind::kQuintic);
  } catch (const std::invalid_argument& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("joint 1's spline"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not finite"), std::string::npos) << msg;
  const std::string scene = joint_space_scene_reading("pumasim_csv_coupled_overflow");
  const std::string smsg = refusal([&] { load_scene(scene); });  // the scene's joint-quintic
  EXPECT_NE(smsg.find(scene + ":"), std::string::npos) << smsg;
  EXPECT_NE(smsg.find("not finite"), std::string::npos) << smsg;
}

// A step as long as the reader allows (up to kMaxRowStep) with finite values
// is a finite curve, and the check must not refuse it (its bound once formed
// h^5 alone: infinite for h = 1e62 s, times a zero coefficient NaN).
TEST(JointCsv, ALongStepOfFiniteValuesIsAFiniteCurve) {
  const std::vector<double> knots = {0.0, 1e62, 2e62};
  std::vector<Vec6> points(3, Vec6::Zero());
  points[1][0] = 1.0;
  for (const auto kind : {JointCurve::Kind::kCubic, JointCurve::Kind::kQuintic}) {
    const JointCurve c(knots, dyn(points), 1, kind);
    Vec6 q, dq, ddq;
    c.eval(1e62, q, dq, ddq);
    EXPECT_DOUBLE_EQ(q[0], 1.0);  // the curve passes through its points
    EXPECT_TRUE(dq.allFinite() && ddq.allFinite());
  }
}

// Through a scene: the scene's file, line and key, then the CSV's file and line.
TEST(JointCsv, SceneNamesItsKeyAndTheFilesLine) {
  write_temp("pumasim_csv_scene.csv", "t,q1,q2,q3\n0,-0.2349,0.6706,-3.5105\n1,x,0.6,-3.5\n");
  const std::string scene = joint_space_scene_reading("pumasim_csv_scene");
  const std::string msg = refusal([&] { load_scene(scene); });
  EXPECT_NE(msg.find(scene + ":"), std::string::npos) << msg;
  EXPECT_NE(msg.find("reference.joints: "), std::string::npos) << msg;
  EXPECT_NE(msg.find("pumasim_csv_scene.csv:3: column 2 (q1)"), std::string::npos) << msg;
  // via_points in the scene: the same checks, naming the row.
  const std::string msg2 = refusal([&] {
    load_scene(scene_path("joint_space_csv"), {"reference.via_points=[[0, 0, 0, 0], [1, 0, 0]]"},
               {"reference.joints"});
  });
  EXPECT_NE(msg2.find("reference.via_points: row 2: expected 4 columns"), std::string::npos) << msg2;
}

// ---------------------------------------------------------------- inverse kinematics

// The planar two-link arm's closed form (Siciliano et al. 2009, sec. 2.12.1):
// c2 = (x^2 + y^2 - a1^2 - a2^2) / (2 a1 a2), q2 = atan2(s2, c2) with
// s2 = +-sqrt(1 - c2^2), q1 = atan2(y, x) - atan2(a2 s2, a1 + a2 c2).
Eigen::Vector2d planar_ik(double a1, double a2, double x, double y, bool elbow_positive) {
  const double c2 = (x * x + y * y - a1 * a1 - a2 * a2) / (2 * a1 * a2);
  const double s2 = (elbow_positive ? 1 : -1) * std::sqrt(1 - c2 * c2);
  return {std::atan2(y, x) - std::atan2(a2 * s2, a1 + a2 * c2), std::atan2(s2, c2)};
}

// DLS from a guess 0.3 rad off reaches the closed form's solution on the same
// branch. Converged means an error below 1e-12 m, then polished; away from
// the singularity (|s2| >= 0.3 here) |J^-1| <= 1/(a1 a2 |s2|) < 4 1/m, so
// the angles agree within 4e-12 rad: asserted 1e-10.
TEST(NumericalIk, PlanarArmMatchesItsClosedForm) {
  const RobotModel robot = load_robot(planar2_path());
  int solved = 0;
  for (double r = 0.3; r <= 1.9; r += 0.2) {
    for (double phi = -3.0; phi <= 3.0; phi += 0.5) {
      for (bool elbow : {true, false}) {
        const double x = r * std::cos(phi), y = r * std::sin(phi);
        const Eigen::Vector2d want = planar_ik(1.0, 1.0, x, y, elbow);
        if (std::abs(std::sin(want[1])) < 0.3) continue;
        Vec6 q = Vec6::Zero();
        q.head<2>() = want + Eigen::Vector2d(0.3, -0.3);
        const IkSolveResult res = dls_ik(robot, 2, Eigen::Vector3d(x, y, 0.0), nullptr, q);
        ASSERT_TRUE(res.converged) << x << " " << y << " error " << res.error;
        EXPECT_NEAR(std::remainder(q[0] - want[0], 2 * M_PI), 0.0, 1e-10) << x << " " << y;
        EXPECT_NEAR(std::remainder(q[1] - want[1], 2 * M_PI), 0.0, 1e-10) << x << " " << y;
        ++solved;
      }
    }
  }
  EXPECT_GT(solved, 100);
  // Out of reach (beyond a1 + a2, or off the arm's plane): no convergence.
  Vec6 q = Vec6::Zero();
  q[1] = 0.5;
  EXPECT_FALSE(dls_ik(robot, 2, Eigen::Vector3d(2.2, 0.0, 0.0), nullptr, q).converged);
  EXPECT_FALSE(dls_ik(robot, 2, Eigen::Vector3d(1.0, 0.5, 0.1), nullptr, q).converged);
}

// A prismatic joint (tests/robots/rp_polar.toml): joint 1 turns about the
// vertical axis at height d1 = 0.5 m, joint 2 slides along z1 =
// Rz(q1) Rx(pi/2) e_z = (sin q1, -cos q1, 0) with d2 = q2 + 0.1 m, so the
// flange is at (r sin q1, -r cos q1, 0.5), r = q2 + 0.1: the closed form
// r = hypot(x, y), q1 = atan2(x, -y). The numerical IK, position only, finds it.
TEST(NumericalIk, PolarArmWithAPrismaticJointMatchesItsClosedForm) {
  const RobotModel robot = load_robot(std::string(PUMASIM_SCENES_DIR) + "/../../tests/robots/rp_polar.toml");
  int solved = 0;
  for (int i = 0; i <= 5; ++i) {
    for (int k = -5; k <= 5; ++k) {
      const double r = 0.15 + 0.1 * i, phi = 0.5 * k;  // r within the slide's [0, 0.6] m plus the 0.1 m offset
      const double x = r * std::sin(phi), y = -r * std::cos(phi);
      Vec6 q = Vec6::Zero();
      q[0] = phi + 0.2;
      q[1] = r - 0.1 - 0.05;
      const IkSolveResult res = dls_ik(robot, 2, Eigen::Vector3d(x, y, 0.5), nullptr, q);
      ASSERT_TRUE(res.converged) << x << " " << y << " error " << res.error;
      EXPECT_NEAR(std::remainder(q[0] - std::atan2(x, -y), 2 * M_PI), 0.0, 1e-10) << x << " " << y;
      EXPECT_NEAR(q[1], std::hypot(x, y) - 0.1, 1e-10) << x << " " << y;
      ++solved;
    }
  }
  EXPECT_EQ(solved, 66);
}

// Along the paper's path, 3 joints (wrist centre) and 6 (with orientation):
// the numerical IK started near the closed form's first point stays on its
// branch, and the references agree: angles within 1e-9 rad (the convergence
// criterion, 1e-12 m and rad, times |J^-1| along the path, well below 1e3),
// rates within 1e-8 relative to their scale (the same angles in the same
// formulas).
TEST(NumericalIk, PumaAgreesWithTheClosedFormAlongThePaperPath) {
  for (const std::string name : {"paper_slow", "paper_slow_6dof"}) {
    std::vector<std::string> branch_keys = {"reference.arm", "reference.elbow"};
    if (name == "paper_slow_6dof") branch_keys.push_back("reference.wrist");
    const Scene closed = load_scene(scene_path(name));
    const Reference& a = *closed.plant.reference;
    ASSERT_EQ(a.ik_method(), IkMethod::kClosedForm);
    ReferenceSample start;
    a.eval(0.0, start);
    std::string guess = "reference.ik_guess=[";
    for (int j = 0; j < closed.plant.n; ++j) guess += (j ? ", " : "") + std::to_string(start.q[j] + 0.05);
    const Scene numeric = load_scene(scene_path(name), {"reference.ik=\"numerical\"", guess + "]"}, branch_keys);
    const Reference& b = *numeric.plant.reference;
    ASSERT_EQ(b.ik_method(), IkMethod::kNumerical);
    const double T = a.timing().duration();
    double worst_q = 0, worst_qd = 0, worst_qdd = 0, qd_scale = 0, qdd_scale = 0;
    for (double t = 0; t <= T; t += T / 997) {
      ReferenceSample ra, rb;
      a.eval(t, ra), b.eval(t, rb);
      worst_q = std::max(worst_q, (ra.q - rb.q).lpNorm<Eigen::Infinity>());
      worst_qd = std::max(worst_qd, (ra.qd - rb.qd).lpNorm<Eigen::Infinity>());
      worst_qdd = std::max(worst_qdd, (ra.qdd - rb.qdd).lpNorm<Eigen::Infinity>());
      qd_scale = std::max(qd_scale, ra.qd.lpNorm<Eigen::Infinity>());
      qdd_scale = std::max(qdd_scale, ra.qdd.lpNorm<Eigen::Infinity>());
    }
    EXPECT_LT(worst_q, 1e-9) << name;
    EXPECT_LT(worst_qd, 1e-8 * qd_scale) << name;
    EXPECT_LT(worst_qdd, 1e-8 * qdd_scale) << name;
  }
}

// A planar-arm scene (computed torque, La = 0, no friction) with `reference`
// as its [reference] table.
std::string planar_scene(const std::string& name, const std::string& reference) {
  return "[scene]\nname = \"" + name + "\"\nrobot = \"" + planar2_path() +
         "\"\njoints = 2\noutput_interval = 0.01\n"
         "[integrator]\nname = \"rk4\"\ndt = 0.001\n"
         "[amplifier]\ngain = 20.0\nvoltage_limit = 1e9\n"
         "[motor]\ninductance = 0.0\nresistance = 1.0\ntorque_constant = 1.0\n"
         "[controller]\nlaw = \"computed_torque\"\nmode = \"continuous\"\nkp = 900.0\nkd = 60.0\n"
         "output_limit = 1e9\n[reference]\n" + reference;
}

// A line that leaves the reachable disc (radius a1 + a2 = 2 m) is refused
// when the scene is read, naming the time and the point; so is a path off the
// arm's plane z = 0.
TEST(NumericalIk, PathLeavingTheWorkspaceIsReportedWithTimeAndPoint) {
  const std::string line = "start = [1.5, 0.0]\nheading = 0.0\nsegments = [ { line = 1.0 } ]\n"
                           "timing = \"quintic\"\ntraversal_time = 4.0\nik_guess = [-0.5, 1.5]\n";
  const std::string out = write_temp("pumasim_planar_out.toml", planar_scene("out", "height = 0.0\n" + line));
  const std::string msg = refusal([&] { load_scene(out); });
  EXPECT_NE(msg.find(out + ":"), std::string::npos) << msg;
  EXPECT_NE(msg.find("out of reach"), std::string::npos) << msg;
  // The first point beyond 2 m: s just over 0.5 m, at the quintic's time for it.
  const auto at = msg.find("the path point (");
  ASSERT_NE(at, std::string::npos) << msg;
  const double x = std::stod(msg.substr(at + 16));
  EXPECT_GT(x, 2.0) << msg;
  EXPECT_LT(x, 2.001) << msg;
  const auto t_at = msg.find("(t = ");
  ASSERT_NE(t_at, std::string::npos) << msg;
  const double t = std::stod(msg.substr(t_at + 5));
  const double s = x - 1.5, r = t / 4.0;  // s(t) = L (10 r^3 - 15 r^4 + 6 r^5), L = 1 m
  EXPECT_NEAR(r * r * r * (10 - 15 * r + 6 * r * r), s, 1e-6) << msg;
  const std::string off = write_temp("pumasim_planar_off.toml", planar_scene("off", "height = 0.1\n" + line));
  const std::string msg2 = refusal([&] { load_scene(off); });
  EXPECT_NE(msg2.find("the path point (1.500000, 0.000000, 0.100000) m at s = 0.000000 m (t = 0"),
            std::string::npos) << msg2;
  // The closed form is the PUMA's only: asked of this arm, refused by name.
  const std::string cf =
      write_temp("pumasim_planar_cf.toml", planar_scene("cf", "height = 0.0\nik = \"closed-form\"\n" + line));
  const std::string msg3 = refusal([&] { load_scene(cf); });
  EXPECT_NE(msg3.find("reference.ik: expected \"numerical\" for this robot"), std::string::npos) << msg3;
}

// ---------------------------------------------------------------- whole plant on the planar arm

// The plant from rest to t_end with RK4 at 1 ms through the driver.
void run_rk4(Plant& plant, double t_end, const Observer& observe) {
  IntegratorOptions o;
  o.dt = 1e-3;
  auto rk4 = make_integrator("rk4", o);
  const RunResult r = run_plant(plant, *rk4, {.t_end = t_end, .output_interval = 0.01, .observe = observe});
  ASSERT_TRUE(r.ok) << r.failure;
}

// Computed torque with La = 0, no friction and no saturation makes each
// joint's error obey e'' + kd e' + kp e = 0 (Spong, Hutchinson & Vidyasagar
// 2006, sec. 8.3; tests/test_controllers.cpp). The plant starts on the
// reference at rest (e = e' = 0), so for the ODE the error is zero all along;
// what remains is RK4's error at 1 ms on a smooth motion whose fastest mode
// is the PD loop's -30 rad/s (h lambda = -0.03), far below the 1e-6 rad
// asserted. After the last point the arm rests there.
TEST(PlanarArm, TracksAJointSpaceReferenceThroughThePlant) {
  const std::string via = "via_points = [[0.0, 0.3, 1.2], [0.7, 0.6, 0.9], [1.5, 0.9, 1.3], [2.0, 0.5, 1.6], "
                          "[3.0, 0.2, 1.0]]\n";
  for (const char* interp : {"joint-cubic", "joint-quintic"}) {
    const std::string path = write_temp(std::string("pumasim_planar_") + interp + ".toml",
                                        planar_scene("planar_joints", via + "interpolation = \"" + interp + "\"\n"));
    const Scene sc = load_scene(path);
    Plant plant(sc.plant);
    const int q = plant.layout().q, qd = plant.layout().qd;
    double worst = 0;
    std::vector<double> last(plant.size());
    run_rk4(plant, 3.5, [&](double t, const double* x) {
      ReferenceSample r;
      sc.plant.reference->eval(t, r);
      worst = std::max({worst, std::abs(x[q] - r.q[0]), std::abs(x[q + 1] - r.q[1])});
      last.assign(x, x + plant.size());
    });
    EXPECT_LT(worst, 1e-6) << interp;
    EXPECT_NEAR(last[q], 0.2, 1e-6) << interp;
    EXPECT_NEAR(last[q + 1], 1.0, 1e-6) << interp;
    EXPECT_NEAR(last[qd], 0.0, 1e-6) << interp;
    EXPECT_NEAR(last[qd + 1], 0.0, 1e-6) << interp;
  }
}

// A Cartesian path on the planar arm (numerical IK, the only one it has):
// the reference's angles are the closed form's on the branch the guess picks
// (within 1e-10 rad, as for the IK alone), and the arm, under the exact
// computed torque, follows the path within RK4's error (1e-6 m asserted).
TEST(PlanarArm, FollowsACartesianPathByTheNumericalInverseKinematics) {
  const Eigen::Vector2d q0 = planar_ik(1.0, 1.0, 1.2, 0.3, true);
  const std::string ref = "height = 0.0\nstart = [1.2, 0.3]\nheading = 1.5707963267948966\n"
                          "segments = [ { line = 0.3 }, { arc_radius = 0.2, turn_degrees = 180.0 }, { line = 0.3 } ]\n"
                          "timing = \"quintic\"\ntraversal_time = 4.0\nik_guess = [" +
                          std::to_string(q0[0] + 0.1) + ", " + std::to_string(q0[1] - 0.1) + "]\n";
  const Scene sc = load_scene(write_temp("pumasim_planar_path.toml", planar_scene("planar_path", ref)));
  ASSERT_EQ(sc.plant.reference->ik_method(), IkMethod::kNumerical);
  Plant plant(sc.plant);
  double worst_q = 0, worst_p = 0;
  run_rk4(plant, 4.0, [&](double t, const double* x) {
    ReferenceSample r;
    sc.plant.reference->eval(t, r);
    const Eigen::Vector2d want = planar_ik(1.0, 1.0, r.p.x(), r.p.y(), true);
    worst_q = std::max({worst_q, std::abs(r.q[0] - want[0]), std::abs(r.q[1] - want[1])});
    worst_p = std::max(worst_p, (plant.tool_position(x) - r.p).norm());
  });
  EXPECT_LT(worst_q, 1e-10);
  EXPECT_LT(worst_p, 1e-6);
}

// The passive planar arm (no drive, viscous friction) released from rest in
// its vertical plane: with the energy ledger, E(t) - E(0) = -e_friction
// (nothing put in, no copper), to RK4's error at 1 ms; and it moves (the
// friction loss is not vacuous).
TEST(PlanarArm, PassiveArmKeepsTheEnergyBalance) {
  const std::string text = "[scene]\nname = \"planar_passive\"\nrobot = \"" + planar2_path() +
                           "\"\njoints = 2\nduration = 2.0\nenergy_ledger = true\n"
                           "[friction]\nmodel = \"viscous\"\nviscous = [0.01, 0.02]\n"
                           "[initial]\nq = [0.5, 0.3]\n";
  const Scene sc = load_scene(write_temp("pumasim_planar_passive.toml", text));
  Plant plant(sc.plant);
  const int e = plant.layout().e;
  ASSERT_GE(e, 0);
  double E0 = 0, worst = 0, lost = 0;
  bool first = true;
  run_rk4(plant, 2.0, [&](double, const double* x) {
    const double E = plant.mechanical_energy(x);
    if (first) E0 = E, first = false;
    worst = std::max(worst, std::abs(E - E0 - (x[e] - x[e + 1] - x[e + 2])));
    lost = x[e + 2];
  });
  EXPECT_GT(lost, 1.0);  // joules: the arm swings against its friction
  EXPECT_LT(worst, 1e-6 * lost) << worst;
}

}  // namespace
}  // namespace pumasim
