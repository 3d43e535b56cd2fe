// Scenes: which joints, which blocks, which back-end and integrator, the
// reference, duration and output interval, in one TOML file read strictly
// (format in experiments/scenes/README.md). A scene resolves to a
// PlantConfig; resolved_toml() writes it back with every default filled in.
#pragma once

#include <memory>
#include <string>

#include "models/plant.hpp"
#include "models/strict_toml.hpp"

namespace pumasim {

struct IntegratorSettings {
  std::string name = "rk4";  // checked against the integrator registry when run
  double dt = 5e-4;          // [s] fixed-step methods
  double rtol = 1e-6;        // adaptive methods
  double atol = 1e-8;
};

struct ReferenceSettings {
  double height = 0.0;                   // plane z [m]
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  double heading = 0.0;                  // [rad]
  std::vector<PathSegment> segments;
  std::vector<Eigen::Vector2d> profile;  // (t/T, v/v_max)
  double max_speed = 0.1;                // [m/s]
  PumaConfig config;
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();  // 6 joints: flange orientation
};

struct Scene {
  std::string name;
  std::string file;
  std::string robot_spec;  // as written in the file
  bool rotor_inertia = true;  // false: the robot's rotor inertias removed (scene.rotor_inertia)
  double duration = 0.0;         // [s]
  double output_interval = 0.01; // [s]
  IntegratorSettings integrator;
  bool has_reference = false;
  ReferenceSettings reference;
  PlantConfig plant;
};

// Loads and checks a scene; ConfigError naming file, line and key otherwise.
// overrides: "section.key=value" (TOML value syntax), applied before the checks.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});

// The scene with every default filled in, as TOML.
std::string resolved_toml(const Scene& scene);

}  // namespace pumasim
