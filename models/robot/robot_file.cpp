#include "models/robot/robot_file.hpp"

#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include <Eigen/Eigenvalues>

#ifndef PUMASIM_ROBOTS_DIR
#error "PUMASIM_ROBOTS_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

Eigen::Vector3d vec3(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

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
  const auto I = t.numbers("inertia", 6);  // Ixx Iyy Izz Ixy Iyz Ixz
  J.inertia << I[0], I[3], I[5],  //
      I[3], I[1], I[4],           //
      I[5], I[4], I[2];
  const double min_eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(J.inertia,
                                                                        Eigen::EigenvaluesOnly)
                             .eigenvalues()
                             .minCoeff();
  if (min_eig < -1e-12 * std::max(1.0, J.inertia.norm())) {
    t.fail("inertia", "a positive semi-definite inertia [Ixx, Iyy, Izz, Ixy, Iyz, Ixz]",
           "a matrix with eigenvalue " + std::to_string(min_eig));
  }
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

}  // namespace

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

  for (StrictTable& jt : root.array_of_tables("joint")) model.joints.push_back(read_joint(jt));
  if (model.joints.empty()) root.fail("joint", "at least one [[joint]] table", "none");

  if (auto poses = root.optional_table("poses")) {
    for (const std::string& name : poses->keys()) {
      const auto q = poses->numbers(name, model.dof());
      model.poses.push_back({name, Eigen::Map<const Eigen::VectorXd>(q.data(), model.dof())});
    }
    poses->finish();
  }
  root.finish();
  return model;
}

bool is_robot_path(const std::string& name_or_path) {
  return name_or_path.find('/') != std::string::npos ||
         (name_or_path.size() > 5 && name_or_path.compare(name_or_path.size() - 5, 5, ".toml") == 0);
}

RobotModel load_robot(const std::string& name_or_path) {
  if (is_robot_path(name_or_path)) return load_robot_file(name_or_path);
  const std::filesystem::path file = std::filesystem::path(robots_dir()) / (name_or_path + ".toml");
  // The non-throwing overload: a name too long for the file system (or
  // otherwise unusable as a file name) is an unknown robot, not an internal
  // "filesystem error".
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    std::string known;
    if (std::filesystem::is_directory(robots_dir())) {
      for (const auto& e : std::filesystem::directory_iterator(robots_dir())) {
        if (e.path().extension() == ".toml") {
          known += (known.empty() ? "" : ", ") + e.path().stem().string();
        }
      }
    }
    throw ConfigError("unknown robot '" + name_or_path + "'; expected a robot file path or one of: " +
                      (known.empty() ? "(none found in " + robots_dir() + ")" : known));
  }
  return load_robot_file(file.string());
}

}  // namespace pumasim
