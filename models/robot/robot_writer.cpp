#include "models/robot/robot_writer.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "models/robot/link_inertia.hpp"
#include "models/robot/toml_writer.hpp"

namespace pumasim {
namespace {

toml::array numbers(std::initializer_list<double> v) {
  toml::array a;
  for (double x : v) a.push_back(x);
  return a;
}

}  // namespace

std::string robot_file_text(const RobotModel& m, const std::string& header_comment) {
  if (!has_identity_base_and_tool(m)) {
    throw std::invalid_argument("robot " + m.name + ": a robot file has no base or tool transform; this robot has one");
  }
  toml::table doc;
  doc.insert("robot", toml::table{{"name", m.name},
                                  {"convention", m.convention == DhConvention::kStandard ? "standard" : "modified"},
                                  {"gravity", numbers({m.gravity.x(), m.gravity.y(), m.gravity.z()})}});
  toml::array joints;
  for (const JointParams& J : m.joints) {
    toml::table t;
    t.insert("type", J.prismatic() ? "prismatic" : "revolute");
    t.insert("a", J.a);
    t.insert("alpha", J.alpha);
    if (J.prismatic()) {
      t.insert("theta", J.theta);
    } else {
      t.insert("d", J.d);
    }
    t.insert("offset", J.offset);
    t.insert("mass", J.mass);
    t.insert("com", numbers({J.com.x(), J.com.y(), J.com.z()}));
    const Eigen::Matrix3d& I = J.inertia;
    t.insert("inertia", numbers({I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(1, 2), I(0, 2)}));
    // A published set that is no rigid body's was kept by its file's excuse;
    // the model no longer has the words, so the written file says where it came from.
    if (const InertiaProblem why = inertia_problem(J); !why.key.empty() && why.excusable) {
      t.insert("inconsistent_inertia", "kept as in " + (m.source.empty() ? m.name : m.source));
    }
    t.insert("rotor_inertia", J.rotor_inertia);
    t.insert("gear_ratio", J.gear_ratio);
    if (std::isfinite(J.q_min) && std::isfinite(J.q_max)) t.insert("limits", numbers({J.q_min, J.q_max}));
    joints.push_back(std::move(t));
  }
  doc.insert("joint", std::move(joints));
  if (!m.poses.empty()) {
    toml::table poses;
    for (const NamedPose& p : m.poses) {
      toml::array q;
      for (Eigen::Index j = 0; j < p.q.size(); ++j) q.push_back(p.q[j]);
      poses.insert(p.name, std::move(q));
    }
    doc.insert("poses", std::move(poses));
  }
  std::ostringstream out;
  std::istringstream comment(header_comment);
  for (std::string line; std::getline(comment, line);) out << "# " << line << "\n";
  if (!header_comment.empty()) out << "\n";
  out << write_toml(doc);
  return out.str();
}

}  // namespace pumasim
