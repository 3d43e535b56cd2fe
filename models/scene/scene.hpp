// Scenes: which joints, which blocks, which back-end and integrator, the
// reference, duration and output interval, in one TOML file read strictly
// (format in experiments/scenes/README.md). A scene resolves to a
// PlantConfig; resolved_toml() writes it back with every default filled in.
#pragma once

#include <memory>
#include <string>

#include "models/plant/plant.hpp"
#include "models/reference/time_optimal.hpp"
#include "models/robot/input_files.hpp"
#include "models/robot/strict_toml.hpp"
#include "models/scene/key_doc.hpp"

namespace pumasim {

// The relative tolerances a run accepts: below 1e-14 a tolerance asks for
// less than about 50 units of rounding (2.2e-16) of a state, which no method
// can deliver; above 0.1 it controls no digit. (`--rtol` and integrator.rtol.)
inline constexpr double kRtolMin = 1e-14;
inline constexpr double kRtolMax = 0.1;
// The output rows a run holds in memory until it ends: duration /
// output_interval is bounded by it once the run's end time is known
// (check_run_size; nothing sized by the duration is made before).
inline constexpr double kMaxOutputRows = 1e7;

// `--rtol` without `--atol`: atol = kAtolPerRtol * rtol, times each state's
// typical magnitude (tolerance_scales), as the sweeps set it.
inline constexpr double kAtolPerRtol = 1e-3;

struct IntegratorSettings {
  std::string name = "rk4";  // checked against the integrator registry by the command line
  std::string name_where;    // "file:line: integrator.name: " when the scene sets it (for that check's message)
  double dt = 5e-4;          // [s] fixed-step methods
  double rtol = 1e-6;        // adaptive methods
  double atol = 1e-8;
};

struct ReferenceSettings {
  // A joint-space source instead of the Cartesian path: a CSV file (made
  // absolute, relative to the scene's folder) or via-points in the scene;
  // either way `points` holds the rows t, q1 ... qn.
  std::string joints_file;
  std::vector<std::vector<double>> via_points;
  std::vector<std::vector<double>> points;
  double height = 0.0;                   // plane z [m]
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  double heading = 0.0;                  // [rad]
  std::vector<PathSegment> segments;
  // Timing law (models/reference/timing.hpp): "table" (the paper's piecewise-linear
  // speed: profile with max_speed or traversal_time), "trapezoid", "scurve",
  // "quintic" (traversal_time; blend, jerk_fraction), "time-optimal" ([planning]);
  // a joint-space source also "explicit" (its own times, the default).
  std::string timing = "table";
  std::vector<Eigen::Vector2d> profile;  // (t/T, v/v_max)
  double max_speed = 0.0;                // [m/s] (table; 0: from traversal_time)
  double traversal_time = 0.0;           // [s] (0: from max_speed)
  double blend = 0.2;                    // trapezoid, scurve: acceleration phase / T
  double jerk_fraction = 0.25;           // scurve: jerk phase / acceleration phase
  Interpolation interpolation = Interpolation::kCartesian;
  int via_segments = 10;                 // joint-space interpolation
  // time-optimal: the drives' limits as the planner uses them.
  double voltage_fraction = 0.8;         // of min(K_A u_max, V_max), the rest left to feedback
  std::vector<double> current_limit;     // [A] per joint (inf: none)
  std::vector<double> joint_speed_limit; // [rad/s] per joint (inf: none)
  int grid = 1000;                       // arc-length grid intervals
  IkMethod ik = IkMethod::kClosedForm;  // Cartesian path: closed form (the PUMA) or numerical
  std::vector<double> ik_guess;          // numerical: the first path point's guess [rad] (empty: mid-range)
  PumaConfig config;
  // 6 joints: the flange's fixed orientation (default: its z axis pointing down).
  Eigen::Matrix3d orientation = (Eigen::Matrix3d() << 1, 0, 0, 0, -1, 0, 0, 0, -1).finished();
  // Not keys: what reading the keys needs to know of the scene.
  std::string scene_dir;       // the scene file's folder (joints is relative to it)
  std::string closed_form_why; // why the robot has no closed-form IK ("" if it has)
  bool joint_source() const { return !joints_file.empty() || !via_points.empty(); }
  // Every member, so that a member added is compared with no other edit
  // (SceneTemplate shares a reference between equal settings).
  bool operator==(const ReferenceSettings&) const = default;
};

struct Scene {
  std::string name;
  std::string file;
  std::string robot_spec;  // as written in the file; a file path made absolute
  bool rotor_inertia = true;  // false: the robot's rotor inertias removed (scene.rotor_inertia)
  double duration = 0.0;         // [s]
  // Where the duration came from, for messages about it: "scene.duration",
  // the reference's timing, the input's last time, or a run's end time.
  std::string duration_source = "scene.duration";
  double output_interval = 0.01; // [s]
  IntegratorSettings integrator;
  bool has_reference = false;
  ReferenceSettings reference;
  PlantConfig plant;
  // Every file the load read (the scene file, the robot file, a URDF's side
  // file, every CSV), by content: read through read_input_file, so a reader
  // of a new kind of file is here with no other edit.
  std::vector<InputFile> inputs;
  // Where values the scene file does not give came from (the robot file's
  // joint friction as [friction]'s defaults), one line each, for `pumasim check`.
  std::vector<std::string> sources;
};

// What reference.timing = "time-optimal" plans with: the path's reference at
// unit speed (its derivatives q'(s), q''(s)) and the planner with the drives'
// limits (a fraction of min(K_A u_max, V_max), current and speed limits).
struct PlanningSetup {
  std::unique_ptr<Reference> unit;
  std::unique_ptr<TimeOptimalPlanner> planner;
};
PlanningSetup time_optimal_setup(const PlantConfig& pc, int n, const ReferenceSettings& r);

// Loads and checks a scene; ConfigError naming file, line and key otherwise.
// unsets: "section.key", keys of the file removed first (one that is not
// there is an error); overrides: "section.key=value" (TOML value syntax),
// applied next; then the checks.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {},
                 const std::vector<std::string>& unsets = {});

// The scene in `text` (a scene file's TOML, such as resolved_toml's), as if
// read from `path`: named by it in messages, relative paths taken from its
// folder. No file is read for the scene itself, so sc.inputs lists only the
// other files read (the robot's, an input's).
Scene load_scene_text(const std::string& text, const std::string& path);

// Many loads of one scene file, each with its own overrides (an ensemble's
// samples, issue 35): the file parsed once, and what every load would build
// again from the same inputs built once and shared. Shared: the robot model
// of each scene.robot, and the reference, keyed by everything its
// construction reads (scene.robot, scene.rotor_inertia, the simulated
// joints, the held pose, every [reference] setting); not the time-optimal
// timing's, whose planner also reads the drive, the friction and the
// controller. load(overrides) gives the Scene that
// load_scene(path, sets + overrides) gives: the same values, the same
// inputs, the same errors (tests/test_scene_template.cpp). A file is read
// once, by the first load that needs it, so that every load of a template
// sees the same bytes. Thread-safe: what is shared is immutable, and at most
// kShared references are kept (a sample that varies the reference builds its
// own when they are taken). What a load still does itself: parse the
// text it holds (the messages' line numbers live in the parsed document),
// apply the overrides, read and check every section.
class SceneTemplate {
 public:
  static constexpr std::size_t kShared = 8;
  // ConfigError as load_scene gives it (the file, a set).
  explicit SceneTemplate(const std::string& path, const std::vector<std::string>& sets = {});
  ~SceneTemplate();
  SceneTemplate(const SceneTemplate&) = delete;
  SceneTemplate& operator=(const SceneTemplate&) = delete;
  Scene load(const std::vector<std::string>& overrides = {}) const;
  // The same load from the text parsed again: the values' source lines, for
  // a message that names them (load's own, when it refuses; the check of
  // the integrator's name, made after a load).
  Scene load_exact(const std::vector<std::string>& overrides = {}) const;
  const std::string& path() const { return path_; }
  struct Shared;  // the robots and references built (scene.cpp)

 private:
  std::string path_;
  // The file's text as read, parsed again by load_exact: toml++ copies a
  // table without its source positions, which the messages name.
  std::string text_;
  std::vector<std::string> sets_;
  InputFile file_;  // the scene file as read
  std::unique_ptr<Shared> shared_;
};

// The scene with every default filled in, as TOML, then a footer naming
// every input file with its hash ("# input file: PATH (fnv1a64 H, N bytes)").
std::string resolved_toml(const Scene& scene);

// What the plant's right-hand side depends on besides (t, x): discrete state
// that changes only at events (a sampled controller's held output, a held
// set-point, the hybrid friction's stuck and slipping modes), named with the
// scene keys that ask for it, "; "-separated; "" when f(t, x) alone is the
// plant (its time events are then the reference's breakpoints, where f has
// kinks, and an open-loop input's rows, where f jumps or kinks).
std::string discrete_state(const Scene& scene);

// What an adaptive method meets in this scene's right-hand side: "" when f is
// smooth between events; else a note naming the friction law that is
// discontinuous in the state without events (a set-valued law such as the
// paper's rule or Karnopp's: the friction jumps at |w_m| = zero_speed), why
// adaptive methods stall on it (their error estimate sees the jump at the
// switching surface, and the step collapses there), and what to use instead:
// a fixed step, friction.model = "hybrid" (exact events) or moreau-jean.
std::string discontinuity_note(const Scene& scene);

}  // namespace pumasim
