#include "models/robot/robot_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>
#include <vector>

#include <Eigen/Eigenvalues>

#include "models/dynamics/backend.hpp"
#include "models/robot/link_inertia.hpp"
#include "models/robot/urdf_file.hpp"

#ifndef PUMASIM_ROBOTS_DIR
#error "PUMASIM_ROBOTS_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

constexpr std::size_t kMaxRobotFileJoints = 256;

Eigen::Vector3d vec3(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

// The inertia [Ixx, Iyy, Izz, Ixy, Iyz, Ixz] about the centre of mass:
// positive semi-definite, and with the mass and centre of mass a rigid
// body's (inertia_problem, link_inertia.hpp) unless the joint says why it is
// not (inconsistent_inertia = "why": a published set kept as published).
void read_inertia(StrictTable& t, JointParams& J) {
  const auto I = t.numbers("inertia", 6);
  J.inertia << I[0], I[3], I[5],  //
      I[3], I[1], I[4],           //
      I[5], I[4], I[2];
  const InertiaProblem why = inertia_problem(J);
  if (!why.excusable) t.fail(why.key, why.expected + " [Ixx, Iyy, Izz, Ixy, Iyz, Ixz]", why.got);
  const std::string excuse = t.string_or("inconsistent_inertia", "");
  if (!why.key.empty() && excuse.empty()) {
    t.fail(why.key, why.expected + ", or inconsistent_inertia = \"why\" to keep a published set as published",
           why.got);
  }
  if (why.key.empty() && t.has("inconsistent_inertia")) {
    t.fail("inconsistent_inertia", "no such key on a link whose mass and inertia are a rigid body's",
           "\"" + excuse + "\"");
  }
}

// The shortest text that reads back as x ("0.3", not "0.29999999999999999").
std::string format_value(double x) {
  char buf[32];
  const auto end = std::to_chars(buf, buf + sizeof buf, x).ptr;
  return std::string(buf, end);
}

// The joint type and the DH row: a revolute joint has d and no theta, a
// prismatic joint theta (default 0) and no d, the variable replacing either
// (robot_model.hpp, JointType); the offset is in rad or m accordingly.
void read_dh_row(StrictTable& t, JointParams& J) {
  const std::string type = t.string_or("type", "revolute", {"revolute", "prismatic"});
  J.type = type == "prismatic" ? JointType::kPrismatic : JointType::kRevolute;
  J.a = t.number("a");
  J.alpha = t.number("alpha", {-2 * M_PI, 2 * M_PI});
  const char* unused = J.prismatic() ? "d" : "theta";
  if (t.has(unused)) {
    const double v = t.number(unused);
    t.fail(unused,
           J.prismatic() ? "no d on a prismatic joint (its d is q + offset [m]; put a constant part in offset)"
                         : "no theta on a revolute joint (its theta is q + offset [rad]; theta is the fixed "
                           "angle of a prismatic joint, type = \"prismatic\")",
           std::string(unused) + " = " + format_value(v));
  }
  if (J.prismatic()) {
    J.theta = t.number_or("theta", 0.0, {-2 * M_PI, 2 * M_PI});
    J.offset = t.number_or("offset", 0.0);  // [m]
  } else {
    J.d = t.number("d");
    J.offset = t.number_or("offset", 0.0, {-2 * M_PI, 2 * M_PI});  // [rad]
  }
}

JointParams read_joint(StrictTable& t) {
  JointParams J;
  read_dh_row(t, J);
  J.mass = t.number("mass", Bounds::non_negative());
  J.com = vec3(t.numbers("com", 3));
  read_inertia(t, J);
  J.rotor_inertia = t.number("rotor_inertia", Bounds::non_negative());
  J.gear_ratio = t.number("gear_ratio");
  if (J.gear_ratio == 0.0) t.fail("gear_ratio", "a non-zero number", "0");
  // [rad] for a revolute joint, [m] for a prismatic one (no bound; none by default).
  const auto lim = t.optional_numbers("limits", 2, J.prismatic() ? Bounds::any() : Bounds{-4 * M_PI, 4 * M_PI});
  if (J.prismatic()) {
    J.q_min = -std::numeric_limits<double>::infinity();
    J.q_max = std::numeric_limits<double>::infinity();
  }
  if (lim) {
    if (!((*lim)[0] < (*lim)[1])) {
      t.fail("limits", "[q_min, q_max] with q_min < q_max", "[" + std::to_string((*lim)[0]) +
                                                                 ", " + std::to_string((*lim)[1]) + "]");
    }
    J.q_min = (*lim)[0];
    J.q_max = (*lim)[1];
  }
  t.finish();
  return J;
}

// Every joint has inertia at every pose when every rotor inertia is > 0 (H is
// the links' positive semi-definite part plus diag(Z^2 Im)). Otherwise H is
// checked at the zero pose and at each named pose: a joint that moves no
// mass there (and has no rotor) is refused at its rotor_inertia.
void check_joints_have_inertia(const RobotModel& model, std::vector<StrictTable>& joints) {
  const auto has_rotor = [](const JointParams& J) { return J.rotor_inertia > 0; };
  if (std::all_of(model.joints.begin(), model.joints.end(), has_rotor)) return;
  std::vector<NamedPose> poses = model.poses;
  poses.insert(poses.begin(), NamedPose{"zero (q = 0)", Eigen::VectorXd::Zero(model.dof())});
  for (const NamedPose& p : poses) {
    const int j = joint_without_inertia(model, p.q);
    if (j < 0) continue;
    const std::string J = std::to_string(j + 1);
    joints[static_cast<std::size_t>(j)].fail(
        "rotor_inertia", "a rotor inertia > 0, or links that give joint " + J + " inertia at every pose",
        "0, and at pose " + p.name + " joint " + J + " moves no mass: the joint-space inertia H(q) is singular");
  }
}

}  // namespace

int joint_without_inertia(const RobotModel& model, const Eigen::VectorXd& q) {
  const int n = model.dof();
  Eigen::MatrixXd H(n, n);
  make_backend("crba", model)->mass_matrix(q, H);
  const double tol = 1e-12 * H.diagonal().cwiseAbs().maxCoeff();
  // Cholesky in joint order: the first pivot that vanishes is the first joint
  // whose motion, the earlier joints' aside, carries no inertia.
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) {
    const double d = H(j, j) - L.row(j).head(j).squaredNorm();
    if (!(d > tol)) return j;
    L(j, j) = std::sqrt(d);
    for (int i = j + 1; i < n; ++i) L(i, j) = (H(i, j) - L.row(i).head(j).dot(L.row(j).head(j))) / L(j, j);
  }
  return -1;
}

std::string robots_dir() {
  if (const char* env = std::getenv("PUMASIM_ROBOTS_DIR"); env && *env) return env;
  return PUMASIM_ROBOTS_DIR;
}

RobotModel load_robot_file(const std::string& path) {
  const toml::table doc = parse_toml_file(path);
  StrictTable root(doc, path, "");
  RobotModel model;
  model.source = path;
  StrictTable robot = root.table("robot");
  model.name = robot.string("name");
  const std::string conv = robot.string("convention", {"standard", "modified"});
  model.convention = conv == "standard" ? DhConvention::kStandard : DhConvention::kModified;
  model.gravity = vec3(robot.numbers("gravity", 3));
  robot.finish();

  std::vector<StrictTable> joints = root.array_of_tables("joint");
  // Bounded before any per-joint work (the inertia check below is O(n^3)):
  // the longest chains the benchmark uses have 48 joints.
  if (joints.size() > kMaxRobotFileJoints) {
    root.fail("joint", "at most " + std::to_string(kMaxRobotFileJoints) + " [[joint]] tables",
              std::to_string(joints.size()));
  }
  for (StrictTable& jt : joints) model.joints.push_back(read_joint(jt));
  if (model.joints.empty()) root.fail("joint", "at least one [[joint]] table", "none");

  if (auto poses = root.optional_table("poses")) {
    for (const std::string& name : poses->keys()) {
      const auto q = poses->numbers(name, model.dof());
      model.poses.push_back({name, Eigen::Map<const Eigen::VectorXd>(q.data(), model.dof())});
    }
    poses->finish();
  }
  root.finish();
  check_joints_have_inertia(model, joints);
  return model;
}

bool is_robot_path(const std::string& name_or_path) {
  return name_or_path.find('/') != std::string::npos ||
         (name_or_path.size() > 5 && name_or_path.compare(name_or_path.size() - 5, 5, ".toml") == 0) ||
         is_urdf_path(name_or_path);
}

namespace {

RobotModel load_robot_path(const std::string& path) {
  return is_urdf_path(path) ? load_urdf_file(path) : load_robot_file(path);
}

// The shipped robots' names: robot files <name>.toml (not a URDF's side file
// <name>.urdf.toml) and URDF files <name>.urdf.
std::string shipped_robots() {
  std::set<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(robots_dir(), ec)) {
    const std::filesystem::path& p = e.path();
    if (p.extension() == ".urdf" || (p.extension() == ".toml" && p.stem().extension() != ".urdf")) {
      names.insert(p.stem().string());
    }
  }
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  return known;
}

}  // namespace

RobotModel load_robot(const std::string& name_or_path) {
  if (is_robot_path(name_or_path)) return load_robot_path(name_or_path);
  // A shipped robot: its robot file, else its URDF file. The non-throwing
  // overload: a name too long for the file system (or otherwise unusable as
  // a file name) is an unknown robot, not an internal "filesystem error".
  std::error_code ec;
  for (const char* ext : {".toml", ".urdf"}) {
    const std::filesystem::path file = std::filesystem::path(robots_dir()) / (name_or_path + ext);
    if (std::filesystem::exists(file, ec)) return load_robot_path(file.string());
  }
  const std::string known = shipped_robots();
  throw ConfigError("unknown robot '" + name_or_path + "'; expected a robot file path or one of: " +
                    (known.empty() ? "(none found in " + robots_dir() + ")" : known));
}

}  // namespace pumasim
