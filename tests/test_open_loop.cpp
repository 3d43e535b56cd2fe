// The open-loop input (controller law "open_loop", models/plant/controller/
// open_loop.hpp): a command read from a CSV file, against closed forms.
// - Torques equal to gravity's at a pose, no friction: the arm's acceleration
//   is zero there (H qdd = tau - g, an identity) and it stays at rest.
// - A constant voltage on the PUMA's first joint (vertical axis: no gravity
//   torque, and alone it has a constant inertia J = H11, so no Coriolis term)
//   with the drive and viscous friction B: the DC motor's steady state
//   K i = B w_m, i = (e_a - K w_m) / (R0 + R), so w_m = K e_a / (K^2 + (R0 + R) B)
//   with e_a = sat(K_A sat(u, output_limit), V_max).
// - A torque ramp a t on that joint with no friction: linear interpolation
//   gives J qd = a t^2 / 2, J q = a t^3 / 6; the zero-order hold of rows
//   t_k = k h gives, at the rows, J qd_k = a h^2 k (k - 1) / 2 and
//   J (q_k - q_0) = a h^3 (k - 1) k (2k - 1) / 12 (each piece a constant
//   torque); after the last row the torque holds. Each solution is a
//   polynomial of degree at most 3 in t on every piece, which RK4 and
//   Dormand-Prince (orders 4 and 5) integrate exactly whatever their steps,
//   so the closed forms hold to rounding only if no step straddles a row (a
//   jump of the hold): the driver stops at the rows, as at controller samples.
// - Bad files and combinations: file, line and key, exit status 2.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/cli.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/plant/plant.hpp"
#include "models/scene/scene.hpp"
#include "simulation/driver.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

namespace fs = std::filesystem;

// A fresh folder for this test's files (CTest runs tests in parallel processes).
fs::path scratch() {
  const fs::path d = testing::scratch_root() /
                     ("pumasim_open_loop_" + std::to_string(::getpid()) + "_" +
                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::create_directories(d);
  return d;
}

// Writes input.csv and scene.toml into the test's folder; the scene's path.
std::string write_scene(const std::string& toml, const std::string& csv) {
  const fs::path d = scratch();
  std::ofstream(d / "input.csv") << csv;
  std::ofstream(d / "scene.toml") << toml;
  return (d / "scene.toml").string();
}

std::string exact(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

// Rows "t, u1, ..., un", values exactly as given.
std::string csv_of(const std::vector<std::vector<double>>& rows) {
  std::string out = "t";
  for (std::size_t j = 1; j < rows[0].size(); ++j) out += ",u" + std::to_string(j);
  out += "\n";
  for (const auto& r : rows) {
    for (std::size_t c = 0; c < r.size(); ++c) out += (c ? "," : "") + exact(r[c]);
    out += "\n";
  }
  return out;
}

// The PUMA with its first joint alone moving (the others held), an open-loop
// input from input.csv; `extra` is added to [scene].
std::string joint1_scene(const std::string& input, const std::string& interpolation, const std::string& extra) {
  return "[scene]\nname = \"open_loop_test\"\nrobot = \"puma560\"\njoints = 1\n"
         "held = [-0.6, 0.9, 0.1, 0.4, 0.2]\n" + extra +
         "\n[controller]\nlaw = \"open_loop\"\nmode = \"continuous\"\ninput = \"" + input +
         "\"\ninterpolation = \"" + interpolation + "\"\nfile = \"input.csv\"\n\n[initial]\nq = [0.3]\n";
}

// J = H11 of the simulated arm (rotor inertia included), the plant's own model.
double joint1_inertia(const PlantConfig& pc) {
  auto b = find_backend(pc.backend).make(simulated_robot(pc.robot, pc.n, pc.q_held));
  Eigen::MatrixXd H(1, 1);
  b->mass_matrix(pc.q0, H);
  return H(0, 0);
}

// Runs the plant to t_end with the named integrator; the state at each output.
RunResult run(Plant& plant, const std::string& integrator, double t_end, double output_interval,
              const Observer& observe) {
  IntegratorOptions o;
  o.dt = 1e-2;
  o.rtol = 1e-6;
  o.atol = 1e-8;
  auto method = make_integrator(integrator, o);
  const RunResult r =
      run_plant(plant, *method, {.t_end = t_end, .output_interval = output_interval, .observe = observe});
  EXPECT_TRUE(r.ok) << r.failure;
  return r;
}

// Joint torques equal to gravity's at q0, no friction: qdd = H^-1 (g - g) = 0
// at the start, to rounding (|g| up to about 40 N m, eps |g| |H^-1| of order
// 1e-13 rad/s^2); and the arm stays there (an unstable balance, perhaps, but
// rounding grows by at most exp(lambda t) with lambda of order 10 1/s).
TEST(OpenLoop, TorqueEqualToGravityHoldsTheArmAtRest) {
  const std::string head =
      "[scene]\nname = \"gravity_held\"\nrobot = \"puma560\"\njoints = 3\nheld = [0.1, 0.4, 0.2]\n"
      "duration = 1.0\n\n[controller]\nlaw = \"open_loop\"\nmode = \"continuous\"\ninput = \"torque\"\n";
  const std::string tail = "file = \"input.csv\"\n\n[initial]\nq = [0.3, -0.6, 0.9]\n";
  // The model's gravity torque at q0 first, from a probe scene (its rows do not matter).
  const std::string probe = write_scene(head + "interpolation = \"zoh\"\n" + tail, "t,u1,u2,u3\n0,0,0,0\n1,0,0,0\n");
  const PlantConfig pc0 = load_scene(probe).plant;
  auto b = find_backend(pc0.backend).make(simulated_robot(pc0.robot, pc0.n, pc0.q_held));
  Eigen::VectorXd g(3);
  b->gravity(pc0.q0, g);
  ASSERT_GT(g.norm(), 1.0);  // gravity does act there
  for (const std::string interpolation : {"zoh", "linear"}) {
    const std::string scene = write_scene(head + "interpolation = \"" + interpolation + "\"\n" + tail,
                                          csv_of({{0.0, g[0], g[1], g[2]}, {1.0, g[0], g[1], g[2]}}));
    Plant plant(load_scene(scene).plant);
    std::vector<double> x(static_cast<std::size_t>(plant.size())), f(x.size());
    plant.initial_state(x.data());
    plant.rhs(0.0, x.data(), f.data());
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(f[plant.layout().qd + j], 0.0, 1e-11) << interpolation << " joint " << j;
    run(plant, "rk4", 1.0, 0.25, [&](double t, const double* xs) {
      for (int j = 0; j < 3; ++j) {
        EXPECT_NEAR(xs[j], pc0.q0[j], 1e-10) << interpolation << " t = " << t;
        EXPECT_NEAR(xs[3 + j], 0.0, 1e-10) << interpolation << " t = " << t;
      }
    });
  }
}

// A constant voltage on joint 1 with the drive: the DC motor's steady state,
// linear, clamped by the input's output_limit, and saturated by the
// amplifier's voltage_limit (the drive's limit still applies).
TEST(OpenLoop, ConstantVoltageRunsTheMotorAtItsClosedFormSteadyState) {
  const double KA = 4.0, R0 = 0.1, Vmax = 40.0, La = 2e-3, R = 2.0, K = 0.228, B = 1.48e-3;
  const std::string drive = "[amplifier]\ngain = 4.0\noutput_resistance = 0.1\nvoltage_limit = 40.0\n\n"
                            "[motor]\ninductance = 2e-3\nresistance = 2.0\ntorque_constant = 0.228\n\n"
                            "[friction]\nmodel = \"viscous\"\nviscous = 1.48e-3\n";
  struct Case {
    double u, output_limit, ea;  // input [V], its clamp [V], the amplifier's output then [V]
  };
  for (const Case& c : {Case{1.5, INFINITY, KA * 1.5}, Case{15.0, 5.0, KA * 5.0}, Case{15.0, INFINITY, Vmax}}) {
    std::string text = joint1_scene("voltage", "zoh", "") + "\n" + drive;
    if (std::isfinite(c.output_limit)) text.insert(text.find("file = "), "output_limit = " + exact(c.output_limit) + "\n");
    const Scene sc = load_scene(write_scene(text, csv_of({{0.0, c.u}, {100.0, c.u}})));
    const double Z = sc.plant.robot.joints[0].gear_ratio, J = joint1_inertia(sc.plant), Rt = R0 + R;
    // Slowest decay: the roots of La J s^2 + (Rt J + La Z^2 B) s + Z^2 (K^2 + Rt B), real here, the
    // slower one's time constant at most b / c (the sum of both); 40 of them leave exp(-40) of the step.
    const double a2 = La * J, a1 = Rt * J + La * Z * Z * B, a0 = Z * Z * (K * K + Rt * B);
    ASSERT_GT(a1 * a1 - 4 * a2 * a0, 0.0);
    const double t_end = 40 * a1 / a0;
    const double w = K * c.ea / (K * K + Rt * B);  // motor side [rad/s]
    Plant plant(sc.plant);
    std::vector<double> x_end;
    IntegratorOptions o;
    o.dt = 1e-4;  // under the electrical time constant La / Rt ~ 1 ms
    auto rk4 = make_integrator("rk4", o);
    const RunResult r =
        run_plant(plant, *rk4, {.t_end = t_end, .output_interval = t_end, .observe = [&](double, const double* x) {
                                  x_end.assign(x, x + plant.size());
                                }});
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_NEAR(x_end[plant.layout().index("qd1")], w / Z, 1e-10 * std::abs(w / Z)) << c.u;
    EXPECT_NEAR(x_end[plant.layout().index("i_motor1")], B * w / K, 1e-10 * B * w / K) << c.u;
  }
}

// The ramp's closed forms at time t (J q measured from q0).
struct Motion {
  double Jq, Jqd;
};
Motion linear_ramp(double a, double t) { return {a * t * t * t / 6, a * t * t / 2}; }
Motion zoh_ramp(double a, double h, int k) {
  return {a * h * h * h * (k - 1) * k * (2 * k - 1) / 12, a * h * h * k * (k - 1) / 2};
}
// After the last row t_N: the torque a t_N held for s seconds.
Motion held_after(Motion at_end, double torque, double s) {
  return {at_end.Jq + at_end.Jqd * s + torque * s * s / 2, at_end.Jqd + torque * s};
}

// Rows t_k = k h, k = 0 ... N, of a torque ramp a t_k on joint 1, no friction,
// the energy ledger on: e_in = 1/2 J qd^2 (no loss, no potential change about
// a vertical axis).
struct RampRun {
  double a = 2.0, h = 0.1;
  int N = 10;
  double hold = 0.55;  // [s] run past the last row
  std::string scene(const std::string& interpolation, const std::string& mode) const {
    std::vector<std::vector<double>> rows;
    for (int k = 0; k <= N; ++k) rows.push_back({k * h, a * k * h});
    std::string text = joint1_scene("torque", interpolation, "energy_ledger = true\n");
    if (mode == "sampled") text.replace(text.find("\"continuous\""), 12, "\"sampled\"\nservo_period = " + exact(h));
    return write_scene(text, csv_of(rows));
  }
};

void expect_ramp(const std::string& interpolation, const std::string& mode, const std::string& integrator) {
  const RampRun ramp;
  Scene sc = load_scene(ramp.scene(interpolation, mode));
  const double tN = ramp.N * ramp.h;
  EXPECT_EQ(sc.duration, tN);  // no duration given: the input's last time
  const double J = joint1_inertia(sc.plant), q0 = sc.plant.q0[0];
  Plant plant(sc.plant);
  const int e_in = plant.layout().index("e_in");
  const bool zoh = interpolation == "zoh" || mode == "sampled";
  const Motion end = zoh ? zoh_ramp(ramp.a, ramp.h, ramp.N) : linear_ramp(ramp.a, tN);
  const std::string what = interpolation + " " + mode + " " + integrator;
  int checked = 0;
  run(plant, integrator, tN + ramp.hold, ramp.h, [&](double t, const double* x) {
    const int k = static_cast<int>(std::lround(t / ramp.h));
    const Motion m = t <= tN * (1 + 1e-12) ? (zoh ? zoh_ramp(ramp.a, ramp.h, k) : linear_ramp(ramp.a, t))
                                          : held_after(end, ramp.a * tN, t - tN);
    const double scale = std::max(1.0, std::abs(m.Jq));  // J q reaches about 0.5, J qd about 1
    EXPECT_NEAR(J * (x[0] - q0), m.Jq, 1e-12 * scale) << what << " t = " << t;
    EXPECT_NEAR(J * x[1], m.Jqd, 1e-12 * scale) << what << " t = " << t;
    EXPECT_NEAR(x[e_in], m.Jqd * m.Jqd / (2 * J), 1e-12) << what << " t = " << t;
    ++checked;
  });
  EXPECT_GE(checked, ramp.N + 6) << what;
}

TEST(OpenLoop, RampOnAFreeRotorFollowsTheInterpolationsClosedForms) {
  for (const std::string integrator : {"rk4", "odeint-dopri5"}) {
    expect_ramp("linear", "continuous", integrator);
    expect_ramp("zoh", "continuous", integrator);
  }
  // The sampled timing at the rows' spacing holds the linear input's samples:
  // the zero-order hold of the rows.
  expect_ramp("linear", "sampled", "rk4");
}

// df/dt inside a piece: a / J on qd for the linear ramp (its slope), exactly 0
// for the hold. The difference's rounding is about eps |f| / d = 1e-11 of a / J.
TEST(OpenLoop, TimeDerivativeIsTheInputsSlopeInsideAPiece) {
  const RampRun ramp;
  for (const std::string interpolation : {"linear", "zoh"}) {
    Scene sc = load_scene(ramp.scene(interpolation, "continuous"));
    const double J = joint1_inertia(sc.plant);
    Plant plant(sc.plant);
    std::vector<double> x(static_cast<std::size_t>(plant.size())), dfdt(x.size());
    plant.initial_state(x.data());
    plant.on_time_event(0.3, x.data());  // the piece from 0.3 s on
    plant.time_derivative(0.3, x.data(), dfdt.data());
    const double slope = interpolation == "linear" ? ramp.a / J : 0.0;
    EXPECT_NEAR(dfdt[1], slope, 1e-9 * ramp.a / J) << interpolation;
    EXPECT_EQ(dfdt[0], 0.0) << interpolation;
  }
}

// ---------------------------------------------------------------- refusals

struct Refused {
  std::string scene_text, csv, fragment;
  std::string key = "controller.";  // the scene's key the message names
};

void expect_input_refused(const Refused& c) {
  const std::string scene = write_scene(c.scene_text, c.csv);
  std::ostringstream out, err;
  const int status = run_cli({"check", scene}, out, err);
  EXPECT_EQ(status, kExitBadInput) << err.str();
  EXPECT_TRUE(out.str().empty());
  EXPECT_NE(err.str().find(scene + ":"), std::string::npos) << err.str();
  EXPECT_NE(err.str().find(c.key), std::string::npos) << err.str();
  EXPECT_NE(err.str().find(c.fragment), std::string::npos) << err.str();
}

TEST(OpenLoop, BadFilesAreRefusedNamingTheKeyAndTheFilesLine) {
  const std::string scene = joint1_scene("torque", "zoh", "");
  const std::string csv = (scratch() / "input.csv").string();
  const std::vector<Refused> cases = {
      {scene, "t,u1\n0,1\n1,2\n0.5,3\n", csv + ":4: column 1 (t): expected a time after", "controller.file: "},
      {scene, "t,u1\n0,1\n1,2,3\n", csv + ":3: expected 2 columns (t, then u1 ... u1", "controller.file: "},
      {scene, "t,u1,u2\n0,1,2\n", csv + ":1: expected 2 columns", "controller.file: "},
      {scene, "t,u1\n0,1\n1,nan\n", csv + ":3: column 2 (u1): expected a finite number, got \"nan\"",
       "controller.file: "},
      {scene, "t,u1\n0,1\n1,inf\n", csv + ":3: column 2 (u1): expected a finite number", "controller.file: "},
      {scene, "t,u1\n0.5,1\n1,2\n", csv + ":2: column 1 (t): expected the first point at t = 0",
       "controller.file: "},
      {scene, "t,u1\n0,1\n", csv + ": expected at least two points (rows t, u1 ... un)", "controller.file: "},
  };
  for (const Refused& c : cases) expect_input_refused(c);
  // A file that is not there.
  std::string missing = scene;
  missing.replace(missing.find("input.csv"), 9, "absent.csv");
  expect_input_refused({missing, "t,u1\n0,1\n1,1\n",
                  (scratch() / "absent.csv").string() + ": cannot be read (no such file); expected a CSV file",
                  "controller.file: "});
  // A folder where the file should be: said as such, not as an empty or unreadable file.
  std::filesystem::create_directories(scratch() / "a_folder.csv");
  std::string folder = scene;
  folder.replace(folder.find("input.csv"), 9, "a_folder.csv");
  expect_input_refused({folder, "t,u1\n0,1\n1,1\n",
                  (scratch() / "a_folder.csv").string() + ": cannot be read (a folder, not a file)",
                  "controller.file: "});
}

TEST(OpenLoop, CombinationsThatMeanNothingAreRefused) {
  const std::string csv = "t,u1\n0,1\n1,1\n";
  const std::string drive = "[amplifier]\ngain = 4.0\n\n[motor]\ninductance = 0.0\nresistance = 2.0\n"
                            "torque_constant = 0.228\n";
  const std::vector<Refused> cases = {
      // A torque input acts on the joints: no drive with it; a voltage needs the drive.
      {joint1_scene("torque", "zoh", "") + drive, csv, "expected \"voltage\" with the drive", "controller.input: "},
      {joint1_scene("voltage", "zoh", ""), csv, "expected \"torque\" without a drive", "controller.input: "},
      {joint1_scene("current", "zoh", ""), csv, "expected one of \"voltage\", \"torque\"", "controller.input: "},
      {joint1_scene("torque", "cubic", ""), csv, "expected one of \"zoh\", \"linear\"", "controller.interpolation: "},
      {[] {
         std::string s = joint1_scene("torque", "zoh", "");
         s.erase(s.find("interpolation ="), 22);  // the line 'interpolation = "zoh"\n'
         return s;
       }(),
       csv, "missing required key 'interpolation'", "controller: "},
      {[] {
         std::string s = joint1_scene("torque", "zoh", "");
         s.insert(s.find("file = "), "output_limit = -1.0\n");
         return s;
       }(),
       csv, "expected a number > 0 or inf, got -1", "controller.output_limit: "},
  };
  for (const Refused& c : cases) expect_input_refused(c);
}

// Another law has no file: the key is unknown there, named with the law.
TEST(OpenLoop, TheFileKeyMeansNothingForAnotherLaw) {
  std::string s = joint1_scene("torque", "zoh", "");
  s.replace(s.find("law = \"open_loop\""), 17, "law = \"piv\"\nkp = 1.0");
  expect_input_refused({s, "t,u1\n0,1\n1,1\n", "does not apply to controller.law = \"piv\"", "unknown key 'controller.file'"});
}

}  // namespace
}  // namespace pumasim
