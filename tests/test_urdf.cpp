// URDF robot files (models/robot/urdf_file.hpp): the shipped PUMA 560 URDF
// (written by scripts/robot_to_urdf.py from models/robots/puma560.toml) is
// the robot file's model to 1e-10 (H, h, g, the flange's pose and Jacobian,
// potential energy, locked joints, `pumasim dynamics`, a scene's Cartesian
// reference); so is the polar R-P arm (tests/robots/rp_polar.urdf, the same
// script) and random chains written as URDF with arbitrary axes, a base and a
// tool transform; small hand-written URDFs against closed forms (a fixed
// joint merged, a prismatic joint, an axis off z under a rotated origin, the
// axis sign, a link without <inertial>, a continuous joint); and every
// refusal (a tree, a closed loop, floating and planar joints, ...) naming the
// file, the line and what was found, with exit status 2 from the command line;
// and the pre-scan before urdfdom reads a file (its limits one past and at
// them, the markup it refuses or reads past, a loop of links).
#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "experiments/cli.hpp"
#include "models/dynamics/backend.hpp"
#include "models/reference/numerical_ik.hpp"
#include "models/robot/kinematics.hpp"
#include "models/robot/random_chain.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/urdf_file.hpp"
#include "models/scene/scene.hpp"
#include "simulation/run_documents.hpp"
#include "tests/helpers.hpp"
#include "tests/scratch.hpp"

#ifndef PUMASIM_TEST_ROBOTS_DIR
#error "PUMASIM_TEST_ROBOTS_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

namespace fs = std::filesystem;
using testing::rel_err;

// The issue's bound for the URDF model against the robot file's.
constexpr double kSameModel = 1e-10;
// Closed forms against the model: a few hundred roundings of O(1) numbers.
constexpr double kClosedForm = 1e-12;

const std::string kPumaUrdf = std::string(PUMASIM_SCENES_DIR) + "/../../models/robots/puma560.urdf";

fs::path scratch() {
  static const fs::path d = [] {
    const fs::path p = testing::scratch_root() / ("pumasim_urdf_" + std::to_string(::getpid()));
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

// Writes name.urdf (and its side file when `side` is given) under scratch().
std::string write_urdf(const std::string& name, const std::string& xml, const std::string& side = "") {
  const fs::path p = scratch() / (name + ".urdf");
  std::ofstream(p) << xml;
  fs::remove(urdf_side_file(p.string()));
  if (!side.empty()) std::ofstream(urdf_side_file(p.string())) << side;
  return p.string();
}

std::string robot(const std::string& body) { return "<?xml version=\"1.0\"?>\n<robot name=\"t\">\n" + body + "</robot>\n"; }

std::string link(const std::string& name, const std::string& inertial = "") {
  return inertial.empty() ? "<link name=\"" + name + "\"/>\n"
                          : "<link name=\"" + name + "\">\n" + inertial + "</link>\n";
}

std::string inertial(double m, const std::string& xyz, const std::string& rpy, const std::string& ixx_iyy_izz) {
  std::istringstream s(ixx_iyy_izz);
  std::string a, b, c;
  s >> a >> b >> c;
  return "<inertial><origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/><mass value=\"" + std::to_string(m) +
         "\"/><inertia ixx=\"" + a + "\" iyy=\"" + b + "\" izz=\"" + c +
         "\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\n";
}

std::string joint(const std::string& name, const std::string& type, const std::string& parent, const std::string& child,
                  const std::string& xyz = "0 0 0", const std::string& rpy = "0 0 0", const std::string& axis = "0 0 1",
                  const std::string& extra = "<limit lower=\"-3\" upper=\"3\" effort=\"0\" velocity=\"0\"/>") {
  return "<joint name=\"" + name + "\" type=\"" + type + "\">\n  <parent link=\"" + parent + "\"/><child link=\"" +
         child + "\"/>\n  <origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/>\n" +
         (type == "fixed" ? "" : "  <axis xyz=\"" + axis + "\"/>\n  " + extra + "\n") + "</joint>\n";
}

// URDF's rpy: R = Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z).
Eigen::Matrix3d rpy(double r, double p, double y) {
  return (Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(p, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Matrix<double, 6, 1> six(const Eigen::VectorXd& v) { return v.head<6>(); }

// Every quantity of two models of one robot at random states: H, h, g from
// every back-end that describes both, the flange's pose, potential energy,
// and for 6 joints the geometric Jacobian.
void expect_same_robot(const RobotModel& a, const RobotModel& b, int states, std::uint64_t seed) {
  ASSERT_EQ(a.dof(), b.dof());
  const int n = a.dof();
  Rng rng(seed);
  for (int s = 0; s < states; ++s) {
    const Eigen::VectorXd q = rng.uniform_vector(n, -M_PI, M_PI), qd = rng.uniform_vector(n, -2, 2);
    for (const auto& info : testing::supported(a)) {
      if (!info.why_unsupported(b).empty()) continue;
      auto ba = info.make(a), bb = info.make(b);
      const auto A = testing::evaluate(*ba, q, qd, qd, qd), B = testing::evaluate(*bb, q, qd, qd, qd);
      EXPECT_LT(rel_err(A.H, B.H), kSameModel) << info.name << " H, state " << s;
      EXPECT_LT(rel_err(A.h, B.h), kSameModel) << info.name << " h, state " << s;
      EXPECT_LT(rel_err(A.g, B.g), kSameModel) << info.name << " g, state " << s;
      EXPECT_LT(rel_err(A.qdd, B.qdd), kSameModel) << info.name << " forward dynamics, state " << s;
    }
    Eigen::Matrix3d Ra, Rb;
    Eigen::Vector3d pa, pb;
    forward_kinematics<double>(a, q, Ra, pa);
    forward_kinematics<double>(b, q, Rb, pb);
    EXPECT_LT((Ra - Rb).norm(), kSameModel) << "flange orientation, state " << s;
    EXPECT_LT((pa - pb).norm(), kSameModel) << "flange position, state " << s;
    EXPECT_NEAR(potential_energy(a, q), potential_energy(b, q), kSameModel * (1 + std::abs(potential_energy(a, q))));
    if (n == 6) {
      Eigen::Matrix<double, 6, 6> Ja, Jb;
      geometric_jacobian(a, six(q), 6, Ja);
      geometric_jacobian(b, six(q), 6, Jb);
      EXPECT_LT(rel_err(Ja, Jb), kSameModel) << "Jacobian, state " << s;
    }
  }
}

// ---------------------------------------------------------------- the PUMA 560

TEST(UrdfPuma, IsTheRobotFilesModel) {
  const RobotModel toml = load_robot("puma560"), urdf = load_robot(kPumaUrdf);
  EXPECT_EQ(urdf.name, "puma560");
  EXPECT_EQ(urdf.convention, DhConvention::kModified);
  expect_same_robot(toml, urdf, 20, 560);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(urdf.joints[j].q_min, toml.joints[j].q_min) << j;
    EXPECT_EQ(urdf.joints[j].q_max, toml.joints[j].q_max) << j;
    EXPECT_EQ(urdf.joints[j].gear_ratio, toml.joints[j].gear_ratio) << j;
    EXPECT_EQ(urdf.joints[j].rotor_inertia, toml.joints[j].rotor_inertia) << j;
  }
  EXPECT_EQ(urdf.gravity, toml.gravity);
  ASSERT_EQ(urdf.poses.size(), toml.poses.size());
  for (const NamedPose& p : toml.poses) EXPECT_EQ(urdf.pose(p.name)->q, p.q) << p.name;
}

// Locked joints: the same reduced robot, whose flange is the full robot's
// with the held joints at their angles.
TEST(UrdfPuma, LockedJointsAreTheRobotFilesToo) {
  const RobotModel toml = load_robot("puma560"), urdf = load_robot(kPumaUrdf);
  const Eigen::VectorXd held = toml.pose("qn")->q;
  const RobotModel reduced = lock_joints(toml, 3, held);
  expect_same_robot(reduced, lock_joints(urdf, 3, held), 10, 3);
  Eigen::VectorXd q = held;
  q.head<3>() = Eigen::Vector3d(0.3, -0.4, 1.2);
  Eigen::Matrix3d R, Rr;
  Eigen::Vector3d p, pr;
  forward_kinematics<double>(toml, q, R, p);
  forward_kinematics<double>(reduced, q.head<3>(), Rr, pr);
  EXPECT_LT((R - Rr).norm(), kClosedForm);
  EXPECT_LT((p - pr).norm(), kClosedForm);
}

// The closed-form inverse kinematics needs the robot file's standard DH rows:
// on the URDF model it says why not (a scene then uses the numerical one).
TEST(UrdfPuma, TheClosedFormInverseKinematicsRefusesIt) {
  EXPECT_NE(puma_ik_unsupported(load_robot(kPumaUrdf)), "");
}

nlohmann::json dynamics_json(const std::string& robot_arg) {
  std::ostringstream out, err;
  const int status = run_cli({"dynamics", "--robot", robot_arg, "--backend", "crba", "--q=qn",
                              "--qd=0.3,-0.2,0.5,1,-1,2", "--tau=1,2,3,0.1,0.2,0.3"},
                             out, err);
  EXPECT_EQ(status, kExitOk) << err.str();
  return nlohmann::json::parse(out.str());
}

TEST(UrdfPuma, PumasimDynamicsPrintsTheSame) {
  const nlohmann::json a = dynamics_json("puma560"), b = dynamics_json(kPumaUrdf);
  for (const char* key : {"bias", "gravity", "qdd"}) {
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(a[key][i].get<double>(), b[key][i].get<double>(), kSameModel) << key;
  }
  for (int i = 0; i < 6; ++i) {
    for (int k = 0; k < 6; ++k) {
      EXPECT_NEAR(a["mass_matrix"][i][k].get<double>(), b["mass_matrix"][i][k].get<double>(), kSameModel);
    }
  }
}

// A scene with the URDF robot: its Cartesian reference (numerical inverse
// kinematics now, converged to an error of 1e-12 m: DlsOptions) puts the
// robot file's flange on the path, in one base frame.
TEST(UrdfPuma, ASceneFollowsThePathWithIt) {
  const std::string scene = std::string(PUMASIM_SCENES_DIR) + "/paper_slow.toml";
  const Scene sc = load_scene(scene, {"scene.robot=\"" + fs::absolute(kPumaUrdf).lexically_normal().string() + "\""},
                              {"reference.arm", "reference.elbow"});  // the closed form's branch
  ASSERT_TRUE(sc.plant.reference);
  EXPECT_EQ(sc.plant.robot.source, fs::absolute(kPumaUrdf).lexically_normal().string());
  const RobotModel toml = load_robot("puma560");
  for (double t : {0.0, 3.0, 11.5, 24.0}) {
    ReferenceSample r;
    sc.plant.reference->eval(t, r);
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    forward_kinematics<double>(toml, r.q, R, p);
    EXPECT_LT((p - r.p).norm(), 1e-11) << "t = " << t;
  }
}

// A run's meta.json names the side file with its hash (it holds the drive),
// as the bytes read hash by FNV-1a (its published test vectors in
// tests/test_cli.cpp); a robot file's run has none.
TEST(UrdfPuma, MetaJsonHashesTheSideFile) {
  const std::string scene = std::string(PUMASIM_SCENES_DIR) + "/passive_arm.toml";
  const std::string urdf = fs::absolute(kPumaUrdf).lexically_normal().string();
  const RunContext c = run_context({"pumasim"}, load_scene(scene, {"scene.robot=\"" + urdf + "\""}));
  EXPECT_EQ(c.robot_file, urdf);
  std::ifstream f(urdf + ".toml", std::ios::binary);
  std::ostringstream bytes;
  bytes << f.rdbuf();
  const auto side = std::find_if(c.inputs.begin(), c.inputs.end(),
                                 [&](const InputFile& i) { return i.path == urdf + ".toml"; });
  ASSERT_NE(side, c.inputs.end());
  EXPECT_EQ(side->fnv1a64, fnv1a64(bytes.str()));
  EXPECT_EQ(side->bytes, bytes.str().size());
  EXPECT_NE(meta_json(c).find("\"" + urdf + ".toml\""), std::string::npos);
  const RunContext t = run_context({"pumasim"}, load_scene(scene));
  EXPECT_EQ(meta_json(t).find(".urdf.toml"), std::string::npos);
}

// ---------------------------------------------------------------- written from other models

// The polar R-P arm written by scripts/robot_to_urdf.py: a prismatic joint.
TEST(UrdfConversion, PolarArmFromTheScript) {
  const std::string dir = PUMASIM_TEST_ROBOTS_DIR;
  expect_same_robot(load_robot(dir + "/rp_polar.toml"), load_robot(dir + "/rp_polar.urdf"), 20, 2);
}

// `m` as URDF text, independently of the loader: each joint frame of
// joint_frames (robot_model.hpp) turned by a rotation A_j into the URDF link
// frame, so the URDF axis is A_j^T z (no coordinate axis) and every origin
// has a general rpy; inertial data and the next origin in the turned frame.
std::string urdf_of(const RobotModel& m, const std::vector<Eigen::Matrix3d>& A) {
  const JointFrameData f = joint_frames(m);
  const auto origin = [](const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
    const Eigen::Vector3d ypr = R.eulerAngles(2, 1, 0);
    char b[256];
    std::snprintf(b, sizeof b, "<origin xyz=\"%.17g %.17g %.17g\" rpy=\"%.17g %.17g %.17g\"/>", p.x(), p.y(), p.z(),
                  ypr[2], ypr[1], ypr[0]);
    return std::string(b);
  };
  std::string s = "<?xml version=\"1.0\"?>\n<robot name=\"" + m.name + "\">\n<link name=\"l0\"/>\n";
  Eigen::Matrix3d prev = Eigen::Matrix3d::Identity();
  for (int j = 0; j < m.dof(); ++j) {
    const Eigen::Vector3d axis = A[j].transpose() * Eigen::Vector3d::UnitZ();
    std::string l = "l";
    l += std::to_string(j + 1);
    char buf[512];
    std::snprintf(buf, sizeof buf, "<axis xyz=\"%.17g %.17g %.17g\"/>", axis.x(), axis.y(), axis.z());
    s += "<joint name=\"j" + std::to_string(j + 1) + "\" type=\"" + (f.type[j] == JointType::kPrismatic ? "prismatic" : "revolute") +
         "\"><parent link=\"l" + std::to_string(j) + "\"/><child link=\"" + l + "\"/>" +
         origin(prev.transpose() * f.E[j] * A[j], prev.transpose() * f.p[j]) + buf +
         "<limit lower=\"-3.141592653589793\" upper=\"3.141592653589793\" effort=\"0\" velocity=\"0\"/></joint>\n";
    const Eigen::Vector3d c = A[j].transpose() * f.com[j];
    const Eigen::Matrix3d I = A[j].transpose() * f.I_com[j] * A[j];
    std::snprintf(buf, sizeof buf,
                  "<inertial>%s<mass value=\"%.17g\"/><inertia ixx=\"%.17g\" iyy=\"%.17g\" izz=\"%.17g\" ixy=\"%.17g\" "
                  "ixz=\"%.17g\" iyz=\"%.17g\"/></inertial>",
                  origin(Eigen::Matrix3d::Identity(), c).c_str(), f.mass[j], I(0, 0), I(1, 1), I(2, 2), I(0, 1),
                  I(0, 2), I(1, 2));
    s += "<link name=\"" + l + "\">" + buf + "</link>\n";
    prev = A[j];
  }
  s += "<joint name=\"tool\" type=\"fixed\"><parent link=\"l" + std::to_string(m.dof()) +
       "\"/><child link=\"flange\"/>" + origin(prev.transpose() * f.E_tool, prev.transpose() * f.p_tool) +
       "</joint>\n<link name=\"flange\"/>\n</robot>\n";
  return s;
}

std::string side_of(const RobotModel& m) {
  std::ostringstream s;
  s.precision(17);
  s << "[robot]\ngravity = [" << m.gravity.x() << ", " << m.gravity.y() << ", " << m.gravity.z() << "]\n";
  for (int j = 0; j < m.dof(); ++j) {
    s << "[joint.j" << j + 1 << "]\nrotor_inertia = " << m.joints[j].rotor_inertia
      << "\ngear_ratio = " << m.joints[j].gear_ratio << "\n";
  }
  return s.str();
}

Eigen::Matrix3d random_rotation(Rng& rng) {
  return Eigen::Quaterniond(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))
      .normalized()
      .toRotationMatrix();
}

// Random chains (both conventions, revolute and prismatic joints, skew axes)
// with a random base and tool transform and gravity, as URDF: the same robot.
TEST(UrdfConversion, RandomChainsWithBaseAndTool) {
  int count = 0;
  for (const auto conv : {DhConvention::kStandard, DhConvention::kModified}) {
    for (const char* types : {"R", "RPR"}) {
      for (const int n : {1, 2, 6}) {
        RobotModel m = random_chain(n, 40 + n, conv, types);
        Rng rng(7 + n);
        m.base_R = random_rotation(rng), m.base_p = rng.uniform_vector(3, -1, 1);
        m.tool_R = random_rotation(rng), m.tool_p = rng.uniform_vector(3, -0.2, 0.2);
        m.gravity = Eigen::Vector3d(rng.uniform(-3, 3), rng.uniform(-3, 3), -9.81);
        for (auto& J : m.joints) J.q_min = -M_PI, J.q_max = M_PI;
        std::vector<Eigen::Matrix3d> A;
        for (int j = 0; j < n; ++j) A.push_back(random_rotation(rng));
        const RobotModel u = load_robot(write_urdf("random" + std::to_string(++count), urdf_of(m, A), side_of(m)));
        SCOPED_TRACE(m.source + " " + to_string(conv));
        expect_same_robot(m, u, 5, n);
      }
    }
  }
}

// The Jacobian of a URDF robot with a base and a tool transform is the
// derivative of its flange's pose (central differences, step 1e-6: error
// O(h^2) ~ 1e-12 of O(1) second derivatives, plus rounding 1e-16 / h).
TEST(UrdfConversion, JacobianIsTheFlangesVelocity) {
  RobotModel m = random_chain(6, 5, DhConvention::kStandard);
  Rng rng(5);
  m.base_R = random_rotation(rng), m.base_p = rng.uniform_vector(3, -1, 1);
  m.tool_R = random_rotation(rng), m.tool_p = rng.uniform_vector(3, -0.2, 0.2);
  std::vector<Eigen::Matrix3d> A;
  for (int j = 0; j < 6; ++j) A.push_back(random_rotation(rng));
  const RobotModel u = load_robot(write_urdf("jacobian", urdf_of(m, A), side_of(m)));
  const Eigen::Matrix<double, 6, 1> q = six(rng.uniform_vector(6, -M_PI, M_PI));
  Eigen::Matrix<double, 6, 6> J;
  geometric_jacobian(u, q, 6, J);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<double, 6, 1> qp = q, qm = q;
    qp[k] += h, qm[k] -= h;
    Eigen::Matrix3d Rp, Rm, R;
    Eigen::Vector3d pp, pm, p;
    forward_kinematics<double>(u, qp, Rp, pp);
    forward_kinematics<double>(u, qm, Rm, pm);
    forward_kinematics<double>(u, q, R, p);
    EXPECT_LT(((pp - pm) / (2 * h) - J.block<3, 1>(0, k)).norm(), 1e-8) << k;
    const Eigen::Matrix3d W = (Rp - Rm) / (2 * h) * R.transpose();  // skew(omega)
    EXPECT_LT((Eigen::Vector3d(W(2, 1), W(0, 2), W(1, 0)) - J.block<3, 1>(3, k)).norm(), 1e-8) << k;
  }
}

// The numerical inverse kinematics reaches a pose given in the URDF's base
// frame (not DH frame 0).
TEST(UrdfConversion, NumericalInverseKinematicsInTheBaseFrame) {
  RobotModel m = random_chain(6, 9, DhConvention::kModified);
  Rng rng(9);
  m.base_R = random_rotation(rng), m.base_p = rng.uniform_vector(3, -1, 1);
  std::vector<Eigen::Matrix3d> A;
  for (int j = 0; j < 6; ++j) A.push_back(random_rotation(rng));
  const RobotModel u = load_robot(write_urdf("ik", urdf_of(m, A), side_of(m)));
  const Eigen::Matrix<double, 6, 1> target = six(rng.uniform_vector(6, -1, 1));
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  forward_kinematics<double>(m, target, R, p);  // the pose from the original model
  Eigen::Matrix<double, 6, 1> q = target + six(rng.uniform_vector(6, -0.05, 0.05));
  const IkSolveResult res = dls_ik(u, 6, p, &R, q, DlsOptions{});
  ASSERT_TRUE(res.converged) << res.error;
  Eigen::Matrix3d Rq;
  Eigen::Vector3d pq;
  forward_kinematics<double>(u, q, Rq, pq);
  EXPECT_LT((pq - p).norm(), 1e-9);
  EXPECT_LT((Rq - R).norm(), 1e-9);
}

// ---------------------------------------------------------------- closed forms

// A fixed joint merges its child into the parent body: link 1 (2 kg at
// (0.1, 0, 0), diag(0.01, 0.02, 0.03)) and, fixed at (0.5, 0, 0.2) turned by
// Rz(pi/2), link 2 (1 kg at (0.1, 0, 0) of its frame: (0.5, 0.1, 0.2) of
// link 1's; diag(0.004, 0.005, 0.006) turned: diag(0.005, 0.004, 0.006)).
// One joint about z through the origin, so DH frame 1 is link 1's frame.
TEST(UrdfClosedForm, FixedJointMergedByTheParallelAxisTheorem) {
  const std::string xml =
      robot(link("base") + joint("j1", "revolute", "base", "l1") +
            link("l1", inertial(2.0, "0.1 0 0", "0 0 0", "0.01 0.02 0.03")) +
            joint("fix", "fixed", "l1", "l2", "0.5 0 0.2", "0 0 1.5707963267948966") +
            link("l2", inertial(1.0, "0.1 0 0", "0 0 0", "0.004 0.005 0.006")));
  const RobotModel m = load_robot(write_urdf("fixed", xml, "[robot]\ngravity = [0.0, -9.81, 0.0]\n"));
  ASSERT_EQ(m.dof(), 1);
  const Eigen::Vector3d c1(0.1, 0, 0), c2(0.5, 0.1, 0.2), c = (2.0 * c1 + 1.0 * c2) / 3.0;
  const Eigen::Vector3d d1 = c1 - c, d2 = c2 - c;
  const Eigen::Matrix3d I3 = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d I = Eigen::Vector3d(0.01, 0.02, 0.03).asDiagonal().toDenseMatrix() +
                            Eigen::Vector3d(0.005, 0.004, 0.006).asDiagonal().toDenseMatrix() +
                            2.0 * (d1.squaredNorm() * I3 - d1 * d1.transpose()) +
                            1.0 * (d2.squaredNorm() * I3 - d2 * d2.transpose());
  EXPECT_DOUBLE_EQ(m.joints[0].mass, 3.0);
  EXPECT_LT((m.joints[0].com - c).norm(), kClosedForm);
  EXPECT_LT((m.joints[0].inertia - I).norm(), kClosedForm);
  // H: the moment about the axis, sum of Izz + m (x^2 + y^2) = 0.03 + 2 (0.01)
  // + 0.006 + 1 (0.25 + 0.01) = 0.316; g with gravity -9.81 along y:
  // dV/dq of V = 9.81 sum m y(q), y = x0 sin q + y0 cos q: 9.81 (0.7 cos q - 0.1 sin q).
  auto b = make_backend("crba", m);
  for (double q : {0.0, 0.4, -2.0}) {
    Eigen::VectorXd qv(1), g(1);
    qv[0] = q;
    Eigen::MatrixXd Hm(1, 1);
    b->mass_matrix(qv, Hm);
    b->gravity(qv, g);
    EXPECT_NEAR(Hm(0, 0), 0.316, kClosedForm) << q;
    EXPECT_NEAR(g[0], 9.81 * (0.7 * std::cos(q) - 0.1 * std::sin(q)), kClosedForm) << q;
  }
}

// A prismatic joint along a tilted axis (1, 0, 1)/sqrt 2 from (0.2, 0, 0.1):
// H = m + Z^2 Im, g = m 9.81 u_z (holding the body against gravity along the
// axis), and the flange (the link's frame) moves along the axis by q.
TEST(UrdfClosedForm, PrismaticJoint) {
  const std::string xml = robot(
      link("base") +
      joint("slide", "prismatic", "base", "l1", "0.2 0 0.1", "0 0 0", "1 0 1",
            "<limit lower=\"0\" upper=\"0.5\" effort=\"0\" velocity=\"0\"/>") +
      link("l1", inertial(3.0, "0 0 0.05", "0 0 0", "0.01 0.01 0.01")));
  const RobotModel m = load_robot(
      write_urdf("prismatic", xml, "[joint.slide]\nrotor_inertia = 1e-5\ngear_ratio = 628.3185307179586\n"));
  ASSERT_EQ(m.dof(), 1);
  EXPECT_TRUE(m.joints[0].prismatic());
  EXPECT_EQ(m.joints[0].q_min, 0.0);
  EXPECT_EQ(m.joints[0].q_max, 0.5);
  const Eigen::Vector3d u = Eigen::Vector3d(1, 0, 1).normalized();
  auto b = make_backend("crba", m);
  for (double q : {0.0, 0.3}) {
    Eigen::VectorXd qv(1), g(1);
    qv[0] = q;
    Eigen::MatrixXd H(1, 1);
    b->mass_matrix(qv, H);
    b->gravity(qv, g);
    EXPECT_NEAR(H(0, 0), 3.0 + 628.3185307179586 * 628.3185307179586 * 1e-5, kClosedForm);
    EXPECT_NEAR(g[0], 3.0 * 9.81 * u.z(), kClosedForm);
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    forward_kinematics<double>(m, qv, R, p);
    EXPECT_LT((p - (Eigen::Vector3d(0.2, 0, 0.1) + q * u)).norm(), kClosedForm);
    EXPECT_LT((R - Eigen::Matrix3d::Identity()).norm(), kClosedForm);
  }
}

// A revolute joint whose axis (1, 2, 2)/3 is no coordinate axis, under an
// origin at (0.1, -0.2, 0.3) turned by rpy (0.3, -0.5, 0.7): the flange (a
// fixed link at (0.5, 0, 0), rpy (0.1, 0.2, 0.3)) by Rodrigues' rotation; a
// point mass m at c (link frame): H = m |u x c|^2, g = 9.81 m (u x r)_z with
// r its offset from the axis' origin in the base frame (its velocity per qd).
TEST(UrdfClosedForm, AxisOffZUnderARotatedOrigin) {
  const std::string xml =
      robot(link("base") + joint("j1", "revolute", "base", "l1", "0.1 -0.2 0.3", "0.3 -0.5 0.7", "1 2 2") +
            link("l1", inertial(2.0, "0.4 0.1 -0.2", "0 0 0", "0 0 0")) +
            joint("tool", "fixed", "l1", "flange", "0.5 0 0", "0.1 0.2 0.3") + link("flange"));
  const RobotModel m = load_robot(write_urdf("offaxis", xml));
  const Eigen::Matrix3d R0 = rpy(0.3, -0.5, 0.7), Rt = rpy(0.1, 0.2, 0.3);
  const Eigen::Vector3d o(0.1, -0.2, 0.3), ul = Eigen::Vector3d(1, 2, 2) / 3.0, c(0.4, 0.1, -0.2);
  auto b = make_backend("crba", m);
  for (double q : {0.0, 1.1, -2.5}) {
    Eigen::VectorXd qv(1), g(1);
    qv[0] = q;
    const Eigen::Matrix3d Rq = R0 * Eigen::AngleAxisd(q, ul).toRotationMatrix();
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    forward_kinematics<double>(m, qv, R, p);
    EXPECT_LT((R - Rq * Rt).norm(), kClosedForm) << q;
    EXPECT_LT((p - (o + Rq * Eigen::Vector3d(0.5, 0, 0))).norm(), kClosedForm) << q;
    Eigen::MatrixXd H(1, 1);
    b->mass_matrix(qv, H);
    b->gravity(qv, g);
    EXPECT_NEAR(H(0, 0), 2.0 * ul.cross(c).squaredNorm(), kClosedForm) << q;
    EXPECT_NEAR(g[0], 9.81 * 2.0 * (R0 * ul).cross(Rq * c).z(), kClosedForm) << q;
  }
}

// Fixed links that branch after the last moving joint leave the flange
// open: refused without a side file's flange (naming the candidates and the
// key; once the branch point was taken silently, as a UR5's wrist_3_link
// beside its ee_link and tool0); with one, the named link's pose, and the
// model says which link it is and why. A chain that does not branch ends at
// its last link.
TEST(UrdfClosedForm, FlangeNamedWhereTheFixedLinksBranch) {
  const std::string xml =
      robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0.3") +
            link("l1", inertial(2.0, "0.4 0.1 -0.2", "0 0 0", "0.01 0.01 0.01")) +
            joint("tool", "fixed", "l1", "flange", "0.5 0 0", "0.1 0.2 0.3") + link("flange") +
            joint("cam", "fixed", "l1", "camera", "0 0.2 0") + link("camera"));
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, 0.8);
  const Eigen::Matrix3d Rq = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  std::string msg;
  try {
    load_robot(write_urdf("branching", xml));
  } catch (const ConfigError& e) {
    msg = e.what();
  }
  for (const char* w : {"link 'l1'", "[robot] flange = ", "'flange'", "'camera'", "branching.urdf.toml"}) {
    EXPECT_NE(msg.find(w), std::string::npos) << w << " in: " << msg;
  }
  const RobotModel named = load_robot(write_urdf("named", xml, "[robot]\nflange = \"flange\"\n"));
  EXPECT_EQ(named.flange, "link 'flange' (the side file's flange)");
  forward_kinematics<double>(named, q, R, p);
  EXPECT_LT((R - Rq * rpy(0.1, 0.2, 0.3)).norm(), kClosedForm);
  EXPECT_LT((p - (Eigen::Vector3d(0, 0, 0.3) + Rq * Eigen::Vector3d(0.5, 0, 0))).norm(), kClosedForm);
  const std::string chain =
      robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0.3") +
            link("l1", inertial(2.0, "0.4 0.1 -0.2", "0 0 0", "0.01 0.01 0.01")) +
            joint("tool", "fixed", "l1", "flange", "0.5 0 0", "0.1 0.2 0.3") + link("flange") +
            joint("tip", "fixed", "flange", "tip", "0 0 0.1") + link("tip"));
  const RobotModel last = load_robot(write_urdf("chain", chain));
  EXPECT_NE(last.flange.find("link 'tip' (the end of the fixed links"), std::string::npos) << last.flange;
  EXPECT_EQ(load_robot("puma560").flange, "the last DH frame (a DH robot file)");
}

// The axis (0, 0, -1) turns the other way: q on it is -q on (0, 0, 1), so
// the flange's pose is the same at (-q1, q2), and H and g change sign with
// the first row and column (H' = S H S, g' = S g, S = diag(-1, 1)).
TEST(UrdfClosedForm, ANegativeAxisFlipsTheJointVariable) {
  const auto two = [](const std::string& axis) {
    return robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0.3", "0 0 0", axis) +
                 link("l1", inertial(2.0, "0.2 0.1 0", "0 0 0", "0.02 0.03 0.04")) +
                 joint("j2", "revolute", "l1", "l2", "0.4 0 0", "1.5707963267948966 0 0", "0 0 1") +
                 link("l2", inertial(1.0, "0.3 0 0.05", "0 0 0", "0.01 0.02 0.02")));
  };
  const RobotModel neg = load_robot(write_urdf("negative", two("0 0 -1")));
  const RobotModel pos = load_robot(write_urdf("positive", two("0 0 1")));
  auto bn = make_backend("crba", neg), bp = make_backend("crba", pos);
  Rng rng(3);
  for (int s = 0; s < 5; ++s) {
    const Eigen::VectorXd q = rng.uniform_vector(2, -3, 3);
    Eigen::VectorXd qf = q;
    qf[0] = -q[0];
    Eigen::Matrix3d Rn, Rp;
    Eigen::Vector3d pn, pp;
    forward_kinematics<double>(neg, q, Rn, pn);
    forward_kinematics<double>(pos, qf, Rp, pp);
    EXPECT_LT((Rn - Rp).norm(), kClosedForm);
    EXPECT_LT((pn - pp).norm(), kClosedForm);
    Eigen::MatrixXd Hn(2, 2), Hp(2, 2);
    Eigen::VectorXd gn(2), gp(2);
    bn->mass_matrix(q, Hn), bp->mass_matrix(qf, Hp);
    bn->gravity(q, gn), bp->gravity(qf, gp);
    const Eigen::Matrix2d S = Eigen::Vector2d(-1, 1).asDiagonal();
    EXPECT_LT((Hn - S * Hp * S).norm(), kClosedForm);
    EXPECT_LT((gn - S * gp).norm(), kClosedForm);
  }
}

// A link without <inertial> has no mass: with the rotor of the side file
// alone, H = Z^2 Im exactly; without a rotor the joint moves nothing and is refused.
TEST(UrdfClosedForm, MissingInertialIsAMasslessLink) {
  const std::string xml = robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1"));
  const RobotModel m = load_robot(write_urdf("massless", xml, "[joint.j1]\nrotor_inertia = 2e-4\ngear_ratio = 50.0\n"));
  EXPECT_EQ(m.joints[0].mass, 0.0);
  EXPECT_TRUE(m.joints[0].inertia.isZero(0));
  Eigen::MatrixXd H(1, 1);
  make_backend("crba", m)->mass_matrix(Eigen::VectorXd::Zero(1), H);
  EXPECT_NEAR(H(0, 0), 50.0 * 50.0 * 2e-4, kClosedForm);
  try {
    load_robot(write_urdf("massless_no_rotor", xml));
    FAIL() << "a joint that moves no mass was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("moves no mass"), std::string::npos) << e.what();
  }
}

// A continuous joint has no limits; a revolute joint's are read.
TEST(UrdfClosedForm, ContinuousJointHasNoLimits) {
  const std::string xml = robot(link("base") +
                                joint("j1", "continuous", "base", "l1", "0 0 0", "0 0 0", "0 0 1", "") +
                                link("l1", inertial(1.0, "0.1 0 0", "0 0 0", "0.01 0.01 0.01")) +
                                joint("j2", "revolute", "l1", "l2", "0.3 0 0", "0 0 0", "0 0 1",
                                      "<limit lower=\"-1.25\" upper=\"2.5\" effort=\"0\" velocity=\"0\"/>") +
                                link("l2", inertial(1.0, "0.1 0 0", "0 0 0", "0.01 0.01 0.01")));
  const RobotModel m = load_robot(write_urdf("continuous", xml));
  EXPECT_EQ(m.joints[0].q_min, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(m.joints[0].q_max, std::numeric_limits<double>::infinity());
  EXPECT_EQ(m.joints[1].q_min, -1.25);
  EXPECT_EQ(m.joints[1].q_max, 2.5);
}

// ---------------------------------------------------------------- refusals

// Loading the robot file at `path` is refused with every fragment in the
// message, which is returned ("" when it loaded).
std::string expect_load_refused(const std::string& path, const std::vector<std::string>& fragments) {
  try {
    load_robot(path);
    ADD_FAILURE() << path << ": accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    for (const auto& f : fragments) EXPECT_NE(what.find(f), std::string::npos) << f << " in: " << what;
    return what;
  }
  return "";
}

// The URDF is refused with every fragment in the message, which starts with
// the file's path; the command line exits with status 2 on it.
void expect_urdf_refused(const std::string& name, const std::string& xml, const std::vector<std::string>& fragments,
                    const std::string& side = "") {
  const std::string path = write_urdf(name, xml, side);
  const std::string what = expect_load_refused(path, fragments);
  EXPECT_EQ(what.rfind(path, 0), 0u) << what;
  std::ostringstream out, err;
  EXPECT_EQ(run_cli({"dynamics", "--robot", path, "--backend", "crba", "--q=0"}, out, err), kExitBadInput) << name;
}

const std::string kInertial = inertial(1.0, "0.1 0 0", "0 0 0", "0.01 0.01 0.01");

TEST(UrdfRefused, ATree) {
  expect_urdf_refused("tree",
                 robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) +
                       joint("j2", "revolute", "l1", "l2") + link("l2", kInertial) +
                       joint("j3", "revolute", "l1", "l3") + link("l3", kInertial)),
                 {"tree.urdf:", "joints 'j2'", "'j3'", "(a tree)", "serial chain"});
  // A branch behind a fixed joint is a tree too.
  expect_urdf_refused("tree_behind_fixed",
                 robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) +
                       joint("j2", "revolute", "l1", "l2") + link("l2", kInertial) +
                       joint("f", "fixed", "l1", "bracket") + link("bracket") +
                       joint("j3", "prismatic", "bracket", "l3") + link("l3", kInertial)),
                 {"(a tree)", "from link 'bracket'"});
}

TEST(UrdfRefused, AClosedLoop) {
  expect_urdf_refused("loop",
                 robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) +
                       joint("j2", "revolute", "base", "l2") + link("l2", kInertial) +
                       joint("j3", "revolute", "l1", "l3") + joint("j4", "revolute", "l2", "l3") +
                       link("l3", kInertial)),
                 {"link 'l3'", "closed loop", "'j3'", "'j4'"});
}

TEST(UrdfRefused, FloatingPlanarAndMimicJoints) {
  expect_urdf_refused("floating", robot(link("base") + joint("f", "floating", "base", "l1") + link("l1", kInertial)),
                 {"joint 'f'", "type=\"floating\""});
  expect_urdf_refused("planar", robot(link("base") + joint("p", "planar", "base", "l1") + link("l1", kInertial)),
                 {"joint 'p'", "type=\"planar\""});
  expect_urdf_refused("mimic",
                 robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) +
                       joint("j2", "revolute", "l1", "l2", "0 0 0", "0 0 0", "0 0 1",
                             "<limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"0\"/><mimic joint=\"j1\"/>") +
                       link("l2", kInertial)),
                 {"joint 'j2'", "mimic"});
}

TEST(UrdfRefused, BadValues) {
  expect_urdf_refused("limits", robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0", "0 0 0", "0 0 1",
                                                      "<limit effort=\"1\" velocity=\"1\"/>") +
                                 link("l1", kInertial)),
                 {"joint 'j1'", "lower < upper", "lower=\"0\" upper=\"0\""});
  expect_urdf_refused("zero_axis", robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0", "0 0 0", "0 0 0") +
                                    link("l1", kInertial)),
                 {"joint 'j1'", "non-zero <axis xyz>"});
  expect_urdf_refused("negative_mass", robot(link("base") + joint("j1", "revolute", "base", "l1") +
                                        link("l1", inertial(-1.0, "0 0 0", "0 0 0", "0.01 0.01 0.01"))),
                 {"link 'l1'", "a mass >= 0"});
  // <dynamics> is read as the scene's friction defaults (UrdfPublished), or
  // refused when the side file says so.
  const std::string damped = robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0", "0 0 0", "0 0 1",
                                                        "<limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"0\"/>"
                                                        "<dynamics damping=\"0.5\"/>") +
                                   link("l1", kInertial));
  expect_urdf_refused("damping", damped, {"joint 'j1'", "damping=\"0.5\"", "refuse_dynamics = true"},
                      "[robot]\nrefuse_dynamics = true\n");
  expect_urdf_refused("negative_damping",
                      robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0", "0 0 0", "0 0 1",
                                                 "<limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"0\"/>"
                                                 "<dynamics damping=\"-0.5\"/>") +
                            link("l1", kInertial)),
                      {"joint 'j1'", "damping >= 0"});
  expect_urdf_refused("no_joint", robot(link("base")), {"at least one revolute"});
  expect_urdf_refused("not_urdf", "<robot><link/></robot>", {"URDF error", "urdfdom"});
  // Principal moments 0.1, 0.1, 0.3: no rigid body's, unless the side file says why.
  const std::string bad = robot(link("base") + joint("j1", "revolute", "base", "l1") +
                                link("l1", inertial(1.0, "0 0 0", "0 0 0", "0.1 0.1 0.3")));
  expect_urdf_refused("inconsistent", bad, {"joint 'j1'", "triangle inequalities", "inconsistent_inertia"});
  EXPECT_EQ(load_robot(write_urdf("excused", bad,
                                  "[joint.j1]\nrotor_inertia = 0.0\ngear_ratio = 1.0\n"
                                  "inconsistent_inertia = \"kept as published\"\n"))
                .dof(),
            1);
}

// urdfdom logs "Could not parse inertial element" for these masses and still
// returns a model, with a mass of 0 (issue 32: 143 of 3,000 mutations of
// shipped and public files passed so): refused, naming the file, the link's
// line and urdfdom's words. A <visual> it cannot parse is no error here:
// pumasim reads no <visual>.
TEST(UrdfRefused, AnElementUrdfdomCouldNotParse) {
  for (const char* mass : {"17.4kg", "nan", "inf", "1e400", ""}) {
    const std::string xml = robot(link("base") + joint("j1", "revolute", "base", "l1") +
                                  "<link name=\"l1\">\n<inertial><mass value=\"" + mass +
                                  "\"/><inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" "
                                  "iyz=\"0\"/></inertial>\n</link>\n");
    const auto line = 1 + std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(xml.find("<link name=\"l1\"")),
                                     '\n');
    expect_urdf_refused(std::string("mass_") + (*mass ? mass : "empty"), xml,
                   {".urdf:" + std::to_string(line) + ": link 'l1'", "Could not parse inertial element",
                    std::string("mass [") + mass + "] is not a float"});
  }
  const std::string visual = robot(link("base") + joint("j1", "revolute", "base", "l1") +
                                   "<link name=\"l1\">\n" + kInertial +
                                   "<visual><geometry><box size=\"x y z\"/></geometry></visual>\n</link>\n");
  EXPECT_EQ(load_robot(write_urdf("bad_visual", visual)).joints[0].mass, 1.0);
}

// An axis whose squared norm overflows, (1e200, 1e200, 0), was normalised to
// (0, 0, 0): it is the direction (1, 1, 0), the same robot to rounding.
TEST(UrdfClosedForm, AHugeAxisIsItsDirection) {
  const auto one = [](const std::string& axis) {
    return robot(link("base") + joint("j1", "revolute", "base", "l1", "0 0 0.3", "0 0 0", axis) +
                 link("l1", inertial(2.0, "0.2 0.1 0", "0 0 0", "0.02 0.03 0.04")) +
                 joint("j2", "revolute", "l1", "l2", "0.4 0 0", "0 0 0", "0 0 1") +
                 link("l2", inertial(1.0, "0.3 0 0.05", "0 0 0", "0.01 0.02 0.02")));
  };
  const RobotModel huge = load_robot(write_urdf("huge_axis", one("1e200 1e200 0")));
  const RobotModel unit = load_robot(write_urdf("unit_axis", one("1 1 0")));
  auto bh = make_backend("crba", huge), bu = make_backend("crba", unit);
  const Eigen::Vector2d q(0.3, -0.7);
  Eigen::MatrixXd Hh(2, 2), Hu(2, 2);
  bh->mass_matrix(q, Hh), bu->mass_matrix(q, Hu);
  EXPECT_LT((Hh - Hu).norm(), kClosedForm) << Hh << "\n" << Hu;
  EXPECT_GT(Hh.norm(), 0.1);
}

// ---------------------------------------------------------------- the pre-scan

// The pre-scan (urdf_file.hpp) before urdfdom and TinyXML read a URDF: each
// limit refused one past it, with the file and the line where it is passed,
// and accepted at it; and what it refuses besides.

// A one-joint robot with `extra` inside <robot>, after the chain.
std::string one_joint(const std::string& extra) {
  return robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) + extra);
}

// The 1-based line of byte `at` of `text`.
std::size_t line_at(const std::string& text, std::size_t at) {
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

// The position of the k-th (1-based) occurrence of `what` in `text`.
std::size_t nth(const std::string& text, const std::string& what, std::size_t k) {
  std::size_t at = text.find(what);
  while (at != std::string::npos && --k > 0) at = text.find(what, at + 1);
  EXPECT_NE(at, std::string::npos) << what;
  return at;
}

// Refused by the pre-scan: "PATH:LINE: expected ..." with every fragment.
void expect_prescan_refused(const std::string& name, const std::string& xml, std::size_t line,
                            const std::vector<std::string>& fragments) {
  const std::string path = write_urdf(name, xml);
  try {
    load_robot(path);
    ADD_FAILURE() << name << ": accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ":" + std::to_string(line) + ": expected ", 0), 0u) << name << ": " << what;
    EXPECT_NE(what.find("before urdfdom"), std::string::npos) << what;
    for (const auto& f : fragments) EXPECT_NE(what.find(f), std::string::npos) << name << ": " << f << " in: " << what;
  }
}

// "<g>" levels inside <robot> (level 1): k of them reach depth 1 + k; each on its own line.
std::string nested(std::size_t k) {
  std::string open, close;
  for (std::size_t i = 0; i < k; ++i) open += "<g>\n", close += "</g>";
  return open + close + "\n";
}

TEST(UrdfPrescan, NestingDepth) {
  const std::size_t levels = static_cast<std::size_t>(kMaxUrdfDepth) - 1;
  EXPECT_EQ(load_robot(write_urdf("depth_at_limit", one_joint(nested(levels)))).dof(), 1);
  const std::string deep = one_joint(nested(levels + 1));
  expect_prescan_refused("depth_past_limit", deep, line_at(deep, nth(deep, "<g>", levels + 1)),
                         {"nested at most 64 deep", "<g> at depth 65"});
  // The issue's reproducer in small: 50,000 levels (TinyXML crashed) refused at once.
  const std::string crash = one_joint(nested(50000));
  expect_prescan_refused("depth_50000", crash, line_at(crash, nth(crash, "<g>", levels + 1)), {"at depth 65"});
}

// One element <g> with k attributes, each on its own line.
std::string attributes(std::size_t k) {
  std::string out = "<g";
  for (std::size_t i = 0; i < k; ++i) out += "\n  a" + std::to_string(i) + "=\"" + std::to_string(i) + "\"";
  return out + "/>\n";
}

TEST(UrdfPrescan, AttributesPerElement) {
  const std::size_t limit = static_cast<std::size_t>(kMaxUrdfAttributes);
  EXPECT_EQ(load_robot(write_urdf("attributes_at_limit", one_joint(attributes(limit)))).dof(), 1);
  const std::string many = one_joint(attributes(limit + 1));
  expect_prescan_refused("attributes_past_limit", many, line_at(many, many.find(" a64=")),
                         {"at most 64 attributes", "'a64' is one past them"});
}

// The elements of a generated text without comments, CDATA or declarations:
// the '<' followed by a letter.
std::size_t count_elements(const std::string& xml) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 1 < xml.size(); ++i) {
    n += xml[i] == '<' && std::isalpha(static_cast<unsigned char>(xml[i + 1]));
  }
  return n;
}

TEST(UrdfPrescan, ElementCount) {
  const std::size_t base = count_elements(one_joint(""));
  ASSERT_GT(base, 10u);
  std::string pad;
  for (std::size_t i = base; i < kMaxUrdfElements; ++i) pad += "<e/>\n";
  const std::string full = one_joint(pad);
  ASSERT_EQ(count_elements(full), kMaxUrdfElements);
  EXPECT_EQ(load_robot(write_urdf("elements_at_limit", full)).dof(), 1);
  const std::string over = one_joint(pad + "<e/>\n");
  expect_prescan_refused("elements_past_limit", over, line_at(over, over.rfind("<e/>")),
                         {"at most 65536 elements", "<e> is one past them"});
}

// A revolute joint, then a chain of fixed joints: `joints` <joint> elements in all.
std::string fixed_chain(std::size_t joints) {
  std::string body = link("base") + joint("j1", "revolute", "base", "l0") + link("l0", kInertial);
  for (std::size_t k = 1; k < joints; ++k) {
    body += joint("f" + std::to_string(k), "fixed", "l" + std::to_string(k - 1), "l" + std::to_string(k)) +
            link("l" + std::to_string(k));
  }
  return robot(body);
}

TEST(UrdfPrescan, JointElements) {
  const std::string at_limit = fixed_chain(kMaxUrdfJointElements);
  EXPECT_EQ(load_robot(write_urdf("joints_at_limit", at_limit)).dof(), 1);
  const std::string over = fixed_chain(kMaxUrdfJointElements + 1);
  expect_prescan_refused("joints_past_limit", over, line_at(over, nth(over, "<joint ", kMaxUrdfJointElements + 1)),
                         {"at most 1024 <joint> elements"});
  // The issue's chain of 300,000 fixed joints (urdfdom crashed) in a file under the size limit:
  // refused at the 1025th.
  std::string chain = link("base") + joint("j1", "revolute", "base", "l0") + link("l0", kInertial);
  for (int k = 1; k < 300000; ++k) chain += "<joint/>\n";
  const std::string huge = robot(chain);
  ASSERT_LT(huge.size(), kMaxUrdfBytes);
  expect_prescan_refused("joints_300000", huge, line_at(huge, nth(huge, "<joint", kMaxUrdfJointElements + 1)),
                         {"<joint> elements"});
}

TEST(UrdfPrescan, FileSize) {
  std::ifstream in(kPumaUrdf);
  const std::string puma((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ifstream side_in(urdf_side_file(kPumaUrdf));
  const std::string side((std::istreambuf_iterator<char>(side_in)), std::istreambuf_iterator<char>());
  const std::size_t end = puma.rfind("</robot>");
  ASSERT_NE(end, std::string::npos);
  // A comment of lines of 'x' fills the file to `size` bytes.
  const auto padded = [&](std::size_t size) {
    const std::string head = puma.substr(0, end) + "<!--\n", tail = "-->\n" + puma.substr(end);
    std::string fill(size - head.size() - tail.size(), 'x');
    for (std::size_t i = 99; i < fill.size(); i += 100) fill[i] = '\n';
    return head + fill + tail;
  };
  const std::string full = padded(kMaxUrdfBytes);
  ASSERT_EQ(full.size(), kMaxUrdfBytes);
  EXPECT_EQ(load_robot(write_urdf("size_at_limit", full, side)).dof(), 6);
  const std::string over = padded(kMaxUrdfBytes + 1);
  // The message names the line of the first byte past the limit.
  expect_prescan_refused("size_past_limit", over, line_at(over, kMaxUrdfBytes),
                         {"at most 4194304 bytes (4 MiB)", "4194305 bytes"});
}

TEST(UrdfPrescan, NulByte) {
  // TinyXML stopped at the NUL and read a whole robot before it.
  const std::string xml = one_joint("") + std::string(1, '\0') + "<robot name=\"second\"/>\n";
  expect_prescan_refused("nul", xml, line_at(xml, xml.find('\0')), {"without a NUL byte"});
  std::string inside = one_joint("<!-- a comment -->\n");
  inside[inside.find("a comment")] = '\0';
  expect_prescan_refused("nul_in_comment", inside, line_at(inside, inside.find('\0')), {"NUL"});
}

// Markup that holds a '<', '>' or "<joint" that is no element is not counted.
TEST(UrdfPrescan, CountsOnlyElements) {
  std::string joints_in_markup;
  for (std::size_t k = 0; k <= kMaxUrdfJointElements; ++k) joints_in_markup += "<joint name='x'>";
  const std::string deep = nested(static_cast<std::size_t>(kMaxUrdfDepth));  // one level too many, as text
  std::string xml =
      one_joint("<!-- " + deep + " -->\n<![CDATA[" + joints_in_markup + deep + "]]>\n"
                "<g note=\"a > b &lt; c &amp; &#x3C;joint&#62; x\" other='<joint name=\"y\"/>'>"
                "text &gt; with <![CDATA[<g>]]> and <!-- <g> --></g>\n" +
                nested(static_cast<std::size_t>(kMaxUrdfDepth) - 1));
  // After the XML declaration: a DOCTYPE, a comment and a processing instruction.
  xml.insert(xml.find('\n') + 1,
             "<!DOCTYPE robot>\n<!-- " + joints_in_markup + " -->\n<?pumasim a <joint name='x' ?>\n");
  EXPECT_EQ(load_robot(write_urdf("markup", xml)).dof(), 1);
  // A byte order mark first, then the same robot, is read as before.
  EXPECT_EQ(load_robot(write_urdf("bom", "\xEF\xBB\xBF" + one_joint(""))).dof(), 1);
}

// What the pre-scan cannot count exactly, or TinyXML reads otherwise than
// XML: refused where it is.
TEST(UrdfPrescan, RefusedMarkup) {
  struct Case {
    std::string name, extra, mark;  // mark: where the message's line is, in `extra`
    std::string fragment;
  };
  const std::vector<Case> cases = {
      {"open_comment", "<!-- never closed\n", "<!--", "a comment <!-- closed by -->"},
      {"open_cdata", "<![CDATA[ never closed\n", "<![CDATA[", "CDATA section closed by ]]>"},
      {"pi_quoted_gt", "<?pumasim a='>' ?>\n", ">'", "no '>' inside a quoted value"},
      {"pi_gt_without_question", "<?pumasim a >\n", ">\n", "'?>' closing"},
      {"doctype_subset", "<!DOCTYPE robot [<!ENTITY m \"1\">]>\n", "[", "without an internal subset"},
      {"other_bang", "<!ENTITY m \"1\">\n", "<!ENTITY", "after '<!'"},
      {"lone_ampersand", "<g a=\"x & y\"/>\n", "& y", "write a lone '&' as &amp;"},
      {"named_entity", "<g>&nbsp;</g>\n", "&nbsp", "&lt; &gt; &amp;"},
      {"reference_without_semicolon", "<g>&#x3C</g>\n", "&#x3C", "character reference"},
      {"reference_too_long", "<g>&#00000000065;</g>\n", "&#0", "at most 7 digits"},
      {"reference_to_nul", "<g a='&#0;'/>\n", "&#0;", "of an XML character"},
      {"unquoted_value", "<g a=1/>\n", "1/>", "a quoted value of the attribute 'a'"},
      {"open_value", "<g a=\"1/>\n", "\"1/>", "closed by its quote"},
      {"no_name", "< g/>\n", "< g", "an element's name"},
      {"mismatched", "<g>\n<h></g></h>\n", "</g>", "</h> closing the element opened on line"},
      {"stray_close", "</g>\n", "</g>", "closing the element"},
      {"slash_space", "<g / >\n", "/ >", "'/>' closing the tag <g>"},
      {"truncated_utf8", "<!-- caf\xC3", "\xC3", "UTF-8 text"},
      {"bad_utf8_lead", "<g a='\xFF'/>\n", "\xFF", "UTF-8 text"},
      {"inner_bom", "<g\xEF\xBB\xBF a='1'/>\n", "\xEF\xBB\xBF", "byte order mark"},
      {"control", "<g a='\x01'/>\n", "\x01", "control characters"},
  };
  for (const Case& c : cases) {
    const std::string xml = one_joint(c.extra);
    const std::size_t at = xml.find(c.mark, xml.find(c.extra));
    ASSERT_NE(at, std::string::npos) << c.name;
    expect_prescan_refused("markup_" + c.name, xml, line_at(xml, at), {c.fragment});
  }
  // A processing instruction without a '>' up to the end of the file.
  const std::string pi = one_joint("") + "<?pumasim never closed\n";
  expect_prescan_refused("open_pi", pi, line_at(pi, pi.find("<?pumasim")), {"<? closed by ?>", "the end of the file"});
  // An element left open: the line of its start tag.
  const std::string open = one_joint("<g>\n<h>\n</h>\n");
  expect_prescan_refused("unclosed", open.substr(0, open.rfind("</robot>")), line_at(open, open.find("<g>")),
                         {"</g> closing the element opened here", "the end of the file"});
}

// A joint back to an earlier link: urdfdom links the links into a loop of
// shared pointers, and leaks it when it refuses the file (two roots here:
// l3 is no joint's child); refused before urdfdom reads it, at the joint
// that closes the loop. (The sanitizer build's LeakSanitizer fails the test
// on a leak.)
TEST(UrdfPrescan, ALoopOfLinks) {
  const std::string back = robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) +
                                 joint("j2", "revolute", "l1", "l2") + link("l2", kInertial) +
                                 joint("j3", "revolute", "l2", "l1") + link("l3", kInertial));
  expect_prescan_refused("loop_back", back, line_at(back, back.find("<joint name=\"j3\"")),
                         {"without a loop", "joint 'j3' closing the loop l1 -> l2 -> l1"});
  // A link its own joint's child, its name written with a character reference.
  const std::string self = robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial) +
                                 joint("j2", "revolute", "l1", "l&#x31;"));
  expect_prescan_refused("loop_self", self, line_at(self, self.find("<joint name=\"j2\"")),
                         {"joint 'j2' closing the loop l1 -> l1"});
}

// The shipped URDF files pass the pre-scan (and load: the models are tested above).
TEST(UrdfPrescan, ShippedFilesPass) {
  EXPECT_EQ(load_robot(kPumaUrdf).dof(), 6);
  EXPECT_EQ(load_robot(std::string(PUMASIM_TEST_ROBOTS_DIR) + "/rp_polar.urdf").dof(), 2);
}

// The side file is read strictly: the file, the line and the key.
TEST(UrdfRefused, SideFileErrors) {
  const std::string xml = robot(link("base") + joint("j1", "revolute", "base", "l1") + link("l1", kInertial));
  const auto side_refused = [&](const std::string& name, const std::string& side,
                                const std::vector<std::string>& fragments) {
    const std::string path = write_urdf(name, xml, side);
    const std::string what = expect_load_refused(path, fragments);
    EXPECT_EQ(what.rfind(urdf_side_file(path), 0), 0u) << what;
  };
  side_refused("side_joint", "[joint.elbow]\nrotor_inertia = 0.0\ngear_ratio = 1.0\n",
               {":1:", "joint.elbow", "a moving joint", "(j1)"});
  side_refused("side_key", "[joint.j1]\nrotor_inertia = 0.0\ngear_ratio = 1.0\ntorque_constant = 0.2\n",
               {":4:", "torque_constant"});
  side_refused("side_gear", "[joint.j1]\nrotor_inertia = 0.0\n", {"gear_ratio"});
  side_refused("side_flange", "[robot]\nflange = \"nowhere\"\n", {"robot.flange", "l1", "'nowhere'"});
  side_refused("side_pose", "[poses]\nhome = [0.0, 1.0]\n", {":2:", "poses.home", "an array of 1 numbers"});
}

// A name without a path is a shipped robot: its robot file, else its URDF
// (the side file's name is no robot's).
TEST(UrdfShipped, ANameFindsAUrdfWithoutRobotFile) {
  const fs::path dir = scratch() / "robots";
  fs::create_directories(dir);
  fs::copy_file(kPumaUrdf, dir / "arm.urdf", fs::copy_options::overwrite_existing);
  fs::copy_file(urdf_side_file(kPumaUrdf), urdf_side_file((dir / "arm.urdf").string()),
                fs::copy_options::overwrite_existing);
  const char* old = std::getenv("PUMASIM_ROBOTS_DIR");
  const std::string saved = old ? old : "";
  ::setenv("PUMASIM_ROBOTS_DIR", dir.c_str(), 1);
  EXPECT_EQ(load_robot("arm").dof(), 6);
  try {
    load_robot("hand");
    ADD_FAILURE() << "an unknown robot was found";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("one of: arm"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("arm.urdf"), std::string::npos) << e.what();
  }
  if (old) {
    ::setenv("PUMASIM_ROBOTS_DIR", saved.c_str(), 1);
  } else {
    ::unsetenv("PUMASIM_ROBOTS_DIR");
  }
}


// ---------------------------------------------------------------- as published

// A revolute joint with <dynamics> after the limit.
std::string damped_joint(const std::string& name, const std::string& parent, const std::string& child,
                         const std::string& xyz, const std::string& dynamics) {
  return joint(name, "revolute", parent, child, xyz, "0 0 0", "0 0 1",
               "<limit lower=\"-3\" upper=\"3\" effort=\"0\" velocity=\"0\"/><dynamics " + dynamics + "/>");
}

// A planar 2R arm about z with <dynamics> and <transmission>s (ros_control's
// form on j1, the older one on j2, and one coupling both: not read).
std::string planar_published() {
  return robot(link("base") + damped_joint("j1", "base", "l1", "0 0 0", "damping=\"0.8\" friction=\"1.5\"") +
               link("l1", inertial(2.0, "0.3 0 0", "0 0 0", "0.01 0.02 0.03")) +
               damped_joint("j2", "l1", "l2", "0.6 0 0", "damping=\"0.3\" friction=\"0.4\"") +
               link("l2", inertial(1.0, "0.2 0 0", "0 0 0", "0.004 0.005 0.006")) +
               "<transmission name=\"t1\">\n  <type>transmission_interface/SimpleTransmission</type>\n"
               "  <joint name=\"j1\"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>\n"
               "  <actuator name=\"m1\"><mechanicalReduction>50</mechanicalReduction>"
               "<motorInertia>2e-4</motorInertia></actuator>\n</transmission>\n"
               "<transmission name=\"t2\" type=\"pr2_mechanism_model/SimpleTransmission\">\n"
               "  <joint name=\"j2\"/><actuator name=\"m2\"/><mechanicalReduction>-20</mechanicalReduction>\n"
               "</transmission>\n"
               "<transmission name=\"wrist\">\n  <joint name=\"j1\"/><joint name=\"j2\"/>\n"
               "  <actuator name=\"a\"/><actuator name=\"b\"/>\n</transmission>\n");
}

bool has_line(const std::vector<std::string>& lines, const std::vector<std::string>& fragments) {
  return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) {
    return std::all_of(fragments.begin(), fragments.end(), [&](const std::string& f) { return l.find(f) != std::string::npos; });
  });
}

TEST(UrdfPublished, DynamicsAndTransmissionsFillTheJoints) {
  const RobotModel m = load_robot(write_urdf("published", planar_published()));
  ASSERT_EQ(m.dof(), 2);
  EXPECT_EQ(m.joints[0].damping, 0.8);
  EXPECT_EQ(m.joints[0].coulomb, 1.5);
  EXPECT_EQ(m.joints[1].damping, 0.3);
  EXPECT_EQ(m.joints[1].coulomb, 0.4);
  EXPECT_EQ(m.joints[0].gear_ratio, 50.0);
  EXPECT_EQ(m.joints[0].rotor_inertia, 2e-4);
  EXPECT_EQ(m.joints[1].gear_ratio, -20.0);
  EXPECT_EQ(m.joints[1].rotor_inertia, 0.0);
  EXPECT_TRUE(has_line(m.provenance, {"'j1'", "gear_ratio 50", "<transmission 't1'>", "mechanicalReduction",
                                      "rotor_inertia 0.0002", "motorInertia", "damping 0.8", "<dynamics>"}));
  EXPECT_TRUE(has_line(m.provenance, {"'j2'", "gear_ratio -20", "<transmission 't2'>", "rotor_inertia 0 kg m^2 (none given)"}));
  EXPECT_TRUE(has_line(m.provenance, {"transmission 'wrist'", "joints j1, j2", "not read"}));
  // The side file wins over a transmission (it gives both values).
  const RobotModel side = load_robot(write_urdf("published_side", planar_published(),
                                                "[joint.j2]\nrotor_inertia = 1e-5\ngear_ratio = 10.0\n"));
  EXPECT_EQ(side.joints[1].gear_ratio, 10.0);
  EXPECT_EQ(side.joints[1].rotor_inertia, 1e-5);
  EXPECT_EQ(side.joints[0].gear_ratio, 50.0);
  EXPECT_TRUE(has_line(side.provenance, {"'j2'", "gear_ratio 10 ([joint.j2] of the side file)"}));
  // A transmission's value that is no number, and two on one joint.
  std::string bad = planar_published();
  bad.replace(bad.find("<motorInertia>2e-4"), 18, "<motorInertia>heavy");
  expect_urdf_refused("bad_inertia", bad, {"transmission 't1'", "<motorInertia>", "a finite number", "'heavy'"});
  std::string twice = planar_published();
  twice.replace(twice.find("<joint name=\"j2\"/><actuator name=\"m2\"/>"), 20, "<joint name=\"j1\"/>");
  expect_urdf_refused("twice", twice, {"transmission 't2'", "one transmission on joint 'j1'", "'t1'"});
}

// The joint-side damping D and Coulomb level F of <dynamics> are the scene's
// [friction] defaults on the motor side, B = D / Z^2 and Fs = Fk = F / |Z|
// (a motor-side law acts on the joint as Z tau_f at motor speed Z qd), so
// the viscous part is the joint torque -D qd: the passive arm's accelerations
// with and without it differ by H^-1 (-D qd) (H without rotor inertia).
TEST(UrdfPublished, JointFrictionIsTheScenesDefaultOnTheMotorSide) {
  const std::string urdf = write_urdf("published_scene", planar_published(), "[robot]\ngravity = [0.0, 0.0, -9.81]\n");
  const std::string scene = std::string(PUMASIM_SCENES_DIR) + "/planar2_passive.toml";
  const std::string robot_key = "scene.robot=\"" + urdf + "\"";
  const Scene viscous = load_scene(scene, {robot_key}, {"friction.viscous"});
  EXPECT_DOUBLE_EQ(viscous.plant.friction[0].viscous, 0.8 / 2500.0);
  EXPECT_DOUBLE_EQ(viscous.plant.friction[1].viscous, 0.3 / 400.0);
  EXPECT_TRUE(has_line(viscous.sources, {"friction.viscous", "the robot file's joint damping", "/ Z^2"}));
  EXPECT_TRUE(has_line(viscous.sources, {"friction.static_torque", "not used", "\"viscous\""}));
  const Scene hybrid = load_scene(scene, {robot_key, "friction.model=\"hybrid\""}, {"friction.viscous"});
  EXPECT_DOUBLE_EQ(hybrid.plant.friction[0].static_torque, 1.5 / 50.0);
  EXPECT_DOUBLE_EQ(hybrid.plant.friction[0].kinetic_torque, 1.5 / 50.0);
  EXPECT_DOUBLE_EQ(hybrid.plant.friction[1].kinetic_torque, 0.4 / 20.0);
  // The scene wins, key by key.
  const Scene given = load_scene(scene, {robot_key, "friction.model=\"hybrid\"", "friction.kinetic_torque=[0.01, 0.02]"});
  EXPECT_EQ(given.plant.friction[1].kinetic_torque, 0.02);
  EXPECT_DOUBLE_EQ(given.plant.friction[1].static_torque, 0.4 / 20.0);
  EXPECT_EQ(given.plant.friction[1].viscous, 0.01);
  EXPECT_TRUE(has_line(given.sources, {"friction.kinetic_torque", "the scene file"}));
  // A scene without [friction] on such a robot chooses a law or says none.
  try {
    load_scene(scene, {robot_key}, {"friction"});
    ADD_FAILURE() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("[friction] section"), std::string::npos) << e.what();
  }
  // The physics: f with and without the robot's damping.
  const Scene off = load_scene(scene, {robot_key, "friction.model=\"none\"", "scene.rotor_inertia=false"},
                               {"friction.viscous"});
  const Scene on = load_scene(scene, {robot_key, "scene.rotor_inertia=false"}, {"friction.viscous"});
  Plant p_on(on.plant), p_off(off.plant);
  std::vector<double> x(static_cast<std::size_t>(p_on.size())), f_on(x.size()), f_off(x.size());
  p_on.initial_state(x.data());
  x[2] = 1.0, x[3] = -0.7;  // qd [rad/s]
  p_on.rhs(0.0, x.data(), f_on.data());
  p_off.rhs(0.0, x.data(), f_off.data());
  const RobotModel rigid = without_rotor_inertia(load_robot(urdf));
  Eigen::MatrixXd H(2, 2);
  make_backend("crba", rigid)->mass_matrix(Eigen::Vector2d(x[0], x[1]), H);
  const Eigen::Vector2d dqdd(f_on[2] - f_off[2], f_on[3] - f_off[3]);
  const Eigen::Vector2d want = H.ldlt().solve(Eigen::Vector2d(-0.8 * 1.0, -0.3 * -0.7));
  EXPECT_LT((dqdd - want).norm(), 1e-12 * want.norm()) << dqdd.transpose() << " vs " << want.transpose();
  // The Coulomb level too: tanh at a tiny speed scale is Fk sign(w_m) at these speeds, so the
  // joint torque is -D qd - F sign(qd), F the URDF's friction.
  const Scene coulomb = load_scene(scene, {robot_key, "scene.rotor_inertia=false", "friction.model=\"tanh\"",
                                           "friction.speed_scale=1e-9"}, {"friction.viscous"});
  Plant p_c(coulomb.plant);
  std::vector<double> f_c(x.size());
  p_c.rhs(0.0, x.data(), f_c.data());
  const Eigen::Vector2d dc(f_c[2] - f_off[2], f_c[3] - f_off[3]);
  const Eigen::Vector2d want_c = H.ldlt().solve(Eigen::Vector2d(-0.8 * 1.0 - 1.5, -0.3 * -0.7 + 0.4));
  EXPECT_LT((dc - want_c).norm(), 1e-12 * want_c.norm()) << dc.transpose() << " vs " << want_c.transpose();
}

// A hand with a mimic gripper and two flange candidates (tcp, camera) on a
// one-joint arm. As a tree it is refused, naming the tip key and the leaves;
// with `tip = "hand"` and `flange = "tcp"` alone it loads: the fingers off
// the chain are held at 0 (within their limits, the mimic finger at its
// leader's 1 x 0 + 0) and merged into the arm's body, the chain's damping
// and friction read. Closed form of H about z: sum Izz + m (x^2 + y^2) with
// l1 0.01 + 2 (0.3^2), the hand 0.002 + 0.6 (0.5^2) and each finger
// 1e-5 + 0.1 (0.5^2 + s^2), the fingers at y = +-s.
std::string gripper() {
  const std::string finger_limit = "<limit lower=\"0\" upper=\"0.04\" effort=\"0\" velocity=\"0\"/>";
  return robot(link("base") + damped_joint("j1", "base", "l1", "0 0 0", "damping=\"0.05\" friction=\"0.1\"") +
               link("l1", inertial(2.0, "0.3 0 0", "0 0 0", "0.01 0.01 0.01")) +
               joint("wrist", "fixed", "l1", "hand", "0.5 0 0") +
               link("hand", inertial(0.6, "0 0 0.05", "0 0 0", "0.001 0.001 0.002")) +
               joint("finger_joint1", "prismatic", "hand", "left", "0 0 0.1", "0 0 0", "0 1 0",
                     finger_limit + "<dynamics damping=\"0.2\"/>") +
               link("left", inertial(0.1, "0 0 0.02", "0 0 0", "1e-5 1e-5 1e-5")) +
               joint("finger_joint2", "prismatic", "hand", "right", "0 0 0.1", "0 0 0", "0 -1 0",
                     finger_limit + "<mimic joint=\"finger_joint1\" multiplier=\"1\" offset=\"0\"/>") +
               link("right", inertial(0.1, "0 0 0.02", "0 0 0", "1e-5 1e-5 1e-5")) +
               joint("tcp_joint", "fixed", "hand", "tcp", "0 0 0.2") + link("tcp") +
               joint("camera_joint", "fixed", "hand", "camera", "0.05 0 0.1") + link("camera"));
}

double gripper_H(double s) { return 0.01 + 2 * 0.09 + 0.002 + 0.6 * 0.25 + 2 * (1e-5 + 0.1 * (0.25 + s * s)); }

TEST(UrdfPublished, AGripperOnATipWithTwoFlanges) {
  expect_urdf_refused("gripper_tree", gripper(),
                      {"(a tree)", "[robot] tip = \"<link>\"", "camera, left, right, tcp", "gripper_tree.urdf.toml"});
  const RobotModel m = load_robot(write_urdf("gripper", gripper(), "[robot]\ntip = \"hand\"\nflange = \"tcp\"\n"));
  ASSERT_EQ(m.dof(), 1);
  EXPECT_NEAR(m.joints[0].mass, 2.8, kClosedForm);
  EXPECT_EQ(m.joints[0].damping, 0.05);
  EXPECT_EQ(m.joints[0].coulomb, 0.1);
  EXPECT_EQ(m.flange, "link 'tcp' (the side file's flange)");
  EXPECT_TRUE(has_line(m.provenance, {"'finger_joint1'", "held at 0 m", "within its limits"}));
  EXPECT_TRUE(has_line(m.provenance, {"'finger_joint2'", "mimics 'finger_joint1'"}));
  auto b = make_backend("crba", m);
  Eigen::MatrixXd H(1, 1);
  Eigen::VectorXd q = Eigen::VectorXd::Constant(1, 0.7);
  b->mass_matrix(q, H);
  EXPECT_NEAR(H(0, 0), gripper_H(0.0), kClosedForm);
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  forward_kinematics<double>(m, q, R, p);
  EXPECT_LT((p - Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(0.5, 0, 0.2)).norm(), kClosedForm);
  // Held apart: the mimic finger follows its leader to -0.02 m along -y, and
  // without a flange line the flange is the tip.
  const RobotModel open = load_robot(write_urdf("gripper_open", gripper(), "[robot]\ntip = \"hand\"\n[held]\nfinger_joint1 = 0.02\n"));
  make_backend("crba", open)->mass_matrix(q, H);
  EXPECT_NEAR(H(0, 0), gripper_H(0.02), kClosedForm);
  // The fingers sit at y = +-s: the centre of mass stays (sum m x, 0, sum m z) / 2.8 in link l1's
  // frame (the DH frame here: one joint on z through the origin, x along the base's).
  const Eigen::Vector3d com((2.0 * 0.3 + 0.6 * 0.5 + 0.2 * 0.5) / 2.8, 0.0, (0.6 * 0.05 + 0.2 * 0.12) / 2.8);
  EXPECT_LT((m.joints[0].com - com).norm(), kClosedForm) << m.joints[0].com.transpose();
  EXPECT_LT((open.joints[0].com - com).norm(), kClosedForm) << open.joints[0].com.transpose();
  EXPECT_EQ(open.flange, "link 'hand' (the side file's tip; no flange in the side file)");
  EXPECT_TRUE(has_line(open.provenance, {"'finger_joint1'", "held at 0.02 m", "[held]"}));
}

TEST(UrdfPublished, TipAndHeldRefusals) {
  const auto refused = [&](const std::string& name, const std::string& xml, const std::string& side,
                           const std::vector<std::string>& fragments) {
    expect_load_refused(write_urdf(name, xml, side), fragments);
  };
  refused("tip_unknown", gripper(), "[robot]\ntip = \"paw\"\n", {"robot.tip", "'paw'", "camera, left, right, tcp"});
  refused("held_on_chain", gripper(), "[robot]\ntip = \"hand\"\n[held]\nj1 = 0.1\n",
          {"held.j1", "a moving joint off the chain", "finger_joint1, finger_joint2"});
  refused("held_out_of_range", gripper(), "[robot]\ntip = \"hand\"\n[held]\nfinger_joint1 = 0.5\n",
          {"held.finger_joint1", "within joint 'finger_joint1''s limits [0, 0.04]"});
  refused("flange_off_body", gripper(), "[robot]\ntip = \"hand\"\nflange = \"base\"\n", {"robot.flange", "'base'", "tcp"});
  // A joint off the chain that mimics one on it would move with it: it needs a held value.
  std::string follower = gripper();
  follower.replace(follower.find("<mimic joint=\"finger_joint1\""), 28, "<mimic joint=\"j1\"");
  refused("mimic_of_chain", follower, "[robot]\ntip = \"hand\"\n", {"joint 'finger_joint2'", "[held]", "mimics joint 'j1' of the chain"});
  // A mimic joint's value must be within its own limits: 2 x 0.03 m is past 0.04 m.
  std::string doubled = gripper();
  doubled.replace(doubled.find("multiplier=\"1\""), 14, "multiplier=\"2\"");
  refused("mimic_out_of_range", doubled, "[robot]\ntip = \"hand\"\n[held]\nfinger_joint1 = 0.03\n",
          {"joint 'finger_joint2'", "within its limits [0, 0.04]", "2 x 0.03 + 0 = 0.06"});
  // A misspelt key is named before the walk, not reported as a tree.
  refused("tip_misspelt", gripper(), "[robot]\ntipp = \"hand\"\n", {"tipp"});
  std::string nosuch = gripper();
  nosuch.replace(nosuch.find("</robot>"), 8,
                 "<transmission name=\"tx\"><joint name=\"nosuch\"/><actuator name=\"a\"><mechanicalReduction>5"
                 "</mechanicalReduction></actuator></transmission>\n</robot>");
  refused("transmission_nosuch", nosuch, "[robot]\ntip = \"hand\"\n", {"transmission 'tx'", "'nosuch'"});
  std::string finger = gripper();
  finger.replace(finger.find("</robot>"), 8,
                 "<transmission name=\"tf\"><joint name=\"finger_joint1\"/><actuator name=\"a\"><mechanicalReduction>5"
                 "</mechanicalReduction></actuator></transmission>\n</robot>");
  const RobotModel m = load_robot(write_urdf("transmission_off_chain", finger, "[robot]\ntip = \"hand\"\n"));
  EXPECT_TRUE(has_line(m.provenance, {"transmission 'tf' not read", "'finger_joint1' is off the chain"}));
}

// A revolute joint off the chain, under an origin with a roll of pi/2, held
// at 0.5 rad: its link's centre of mass is origin * Rz(0.5) (the joint turns
// in its own frame, after the origin), at (0.5, 0, 0) + Rx(pi/2) Rz(0.5)
// (0.1, 0, 0) = (0.5 + 0.1 cos 0.5, 0, 0.1 sin 0.5) in link l1's frame.
TEST(UrdfPublished, AHeldRevoluteBranchTurnsInItsOwnFrame) {
  const std::string xml =
      robot(link("base") + joint("j1", "revolute", "base", "l1") +
            link("l1", inertial(2.0, "0.3 0 0", "0 0 0", "0.01 0.01 0.01")) +
            joint("tilt", "revolute", "l1", "sensor", "0.5 0 0", "1.5707963267948966 0 0") +
            link("sensor", inertial(0.5, "0.1 0 0", "0 0 0", "0.001 0.001 0.001")));
  const RobotModel m = load_robot(write_urdf("held_revolute", xml, "[robot]\ntip = \"l1\"\n[held]\ntilt = 0.5\n"));
  ASSERT_EQ(m.dof(), 1);
  const Eigen::Vector3d sensor(0.5 + 0.1 * std::cos(0.5), 0.0, 0.1 * std::sin(0.5));
  const Eigen::Vector3d com = (2.0 * Eigen::Vector3d(0.3, 0, 0) + 0.5 * sensor) / 2.5;
  EXPECT_NEAR(m.joints[0].mass, 2.5, kClosedForm);
  EXPECT_LT((m.joints[0].com - com).norm(), kClosedForm) << m.joints[0].com.transpose();
  EXPECT_TRUE(has_line(m.provenance, {"'tilt'", "held at 0.5 rad", "[held]"}));
}

}  // namespace
}  // namespace pumasim
