#include "models/robot/urdf_transmission.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string_view>

#include <tinyxml.h>

#include "models/robot/strict_toml.hpp"

namespace pumasim {
namespace {

std::string at_line(const std::string& path, const TiXmlElement& e) {
  return path + ":" + std::to_string(e.Row()) + ": ";
}

// The element's text as a finite number, or ConfigError naming the line.
double number_of(const std::string& path, const TiXmlElement& e, const std::string& transmission) {
  const char* text = e.GetText();
  const std::string s = text ? text : "";
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  std::string_view rest(end ? end : "");
  while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.front()))) rest.remove_prefix(1);
  if (s.empty() || end == s.c_str() || !rest.empty() || !std::isfinite(x)) {
    throw ConfigError(at_line(path, e) + "transmission '" + transmission + "': <" + e.Value() +
                      ">: expected a finite number, got '" + s.substr(0, 40) + "'");
  }
  return x;
}

// The reduction and motor inertia inside `parent` (an <actuator>, or the
// <transmission> itself in the older form), into t.
void read_values(const std::string& path, const TiXmlElement& parent, UrdfTransmission& t) {
  for (const TiXmlElement* e = parent.FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->Value();
    if (tag == "mechanicalReduction") {
      const double z = number_of(path, *e, t.name);
      if (z == 0.0) {
        throw ConfigError(at_line(path, *e) + "transmission '" + t.name +
                          "': <mechanicalReduction>: expected a non-zero gear ratio, got 0");
      }
      t.gear_ratio = z;
    } else if (tag == "motorInertia") {
      const double im = number_of(path, *e, t.name);
      if (im < 0.0) {
        throw ConfigError(at_line(path, *e) + "transmission '" + t.name +
                          "': <motorInertia>: expected a rotor inertia >= 0 [kg m^2], got " + std::to_string(im));
      }
      t.rotor_inertia = im;
    }
  }
}

}  // namespace

UrdfTransmissions read_urdf_transmissions(const std::string& path, const std::string& text) {
  UrdfTransmissions out;
  TiXmlDocument doc;
  doc.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc.Error() || !doc.RootElement()) {
    // urdfdom parsed the same text with the same parser before this read.
    throw ConfigError(path + ":" + std::to_string(doc.ErrorRow()) + ": expected XML that TinyXML reads, got: " +
                      doc.ErrorDesc());
  }
  for (const TiXmlElement* e = doc.RootElement()->FirstChildElement("transmission"); e;
       e = e->NextSiblingElement("transmission")) {
    UrdfTransmission t;
    const char* name = e->Attribute("name");
    t.name = name ? name : "";
    t.line = e->Row();
    std::vector<std::string> joints;
    int actuators = 0;
    for (const TiXmlElement* j = e->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
      const char* jn = j->Attribute("name");
      joints.push_back(jn ? jn : "");
    }
    read_values(path, *e, t);  // the older form's reduction, directly inside
    for (const TiXmlElement* a = e->FirstChildElement("actuator"); a; a = a->NextSiblingElement("actuator")) {
      ++actuators;
      read_values(path, *a, t);
    }
    if (joints.size() != 1 || actuators > 1) {
      std::string names;
      for (const auto& j : joints) names += (names.empty() ? "" : ", ") + j;
      out.coupled.push_back("'" + t.name + "' (joints " + (names.empty() ? "none" : names) + "; " +
                            std::to_string(actuators) + " actuators)");
      continue;
    }
    const auto [it, first] = out.by_joint.emplace(joints.front(), t);
    if (!first) {
      throw ConfigError(at_line(path, *e) + "transmission '" + t.name + "': expected one transmission on joint '" +
                        joints.front() + "', got a second (the first: '" + it->second.name + "', line " +
                        std::to_string(it->second.line) + ")");
    }
  }
  return out;
}

}  // namespace pumasim
