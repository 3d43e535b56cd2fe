// The command line as CLI11 parses it: bad input exits with status 2 and one
// line on stderr naming the option and what it expects; the help lists every
// command; negative numbers are values; repeated --set all apply; --unset
// removes keys (and an unknown key after a switch says why); stiffness and
// conditioning write CSV files with a header of named columns; pumasim run's
// stdout is its JSON alone, a step-budget failure names --max-steps and the
// fastest-changing state, meta.json records the run's context, and a run
// folder's resolved scene re-runs from another working directory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "experiments/cli.hpp"
#include "integrators/registry.hpp"
#include "models/dynamics/backend.hpp"
#include "models/robot/robot_file.hpp"
#include "simulation/driver.hpp"
#include "simulation/run_documents.hpp"
#include "tests/cli_capture.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

using testing::cli;
using testing::CliResult;

namespace fs = std::filesystem;

const std::string kScene = std::string(PUMASIM_SCENES_DIR) + "/paper_slow.toml";

// Status 2, nothing on stdout, one line on stderr holding every fragment.
void expect_bad(const std::vector<std::string>& args, const std::vector<std::string>& fragments) {
  const CliResult r = cli(args);
  EXPECT_EQ(r.status, kExitBadInput) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
  EXPECT_EQ(r.err.rfind("pumasim: ", 0), 0u) << r.err;
  for (const auto& f : fragments) EXPECT_NE(r.err.find(f), std::string::npos) << f << " in: " << r.err;
}

fs::path scratch(const std::string& name) {
  const fs::path d = testing::scratch_root() / ("pumasim_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream f(p);
  std::vector<std::string> lines;
  for (std::string line; std::getline(f, line);) lines.push_back(line);
  return lines;
}

// `pumasim integrators --json` is the registry, entry by entry, every field
// the scripts read (they decide fixed step or adaptive from "kind").
TEST(CliRegistries, IntegratorsJsonIsTheRegistry) {
  const CliResult r = testing::cli({"integrators", "--json"});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  const nlohmann::json all = nlohmann::json::parse(r.out);
  const auto reg = integrators();
  ASSERT_EQ(all.size(), reg.size());
  for (std::size_t k = 0; k < reg.size(); ++k) {
    const IntegratorInfo& i = reg[k];
    const nlohmann::json& j = all[k];
    EXPECT_EQ(j["name"], i.name);
    EXPECT_EQ(j["kind"], i.kind == IntegratorKind::kAdaptive ? "adaptive" : "fixed-step") << i.name;
    EXPECT_EQ(j["order"], i.order) << i.name;
    EXPECT_EQ(j["implicit"], i.implicit) << i.name;
    EXPECT_EQ(j["set_valued_friction"], i.set_valued_friction) << i.name;
    EXPECT_EQ(j["conservative_only"], i.conservative_only) << i.name;
    EXPECT_EQ(j["residual_form"], i.residual_form) << i.name;
    EXPECT_EQ(j["stability_region"], i.stable_at != nullptr) << i.name;
    if (std::isfinite(i.real_stability)) {
      EXPECT_EQ(j["real_stability"], i.real_stability) << i.name;
    } else {
      EXPECT_EQ(j["real_stability"], "infinity") << i.name;
    }
  }
  const CliResult b = testing::cli({"backends", "--json"});
  ASSERT_EQ(b.status, kExitOk) << b.err;
  EXPECT_EQ(nlohmann::json::parse(b.out).size(), backends().size());
}

TEST(CliParsing, AnUnknownOptionIsNamedWithTheValidOnes) {
  expect_bad({"run", kScene, "--speed=3"}, {"unknown option '--speed'", "expected one of:", "--t-end", "--max-wall"});
  expect_bad({"check", kScene, "--dt", "0.001"}, {"unknown option '--dt'", "--set"});
  expect_bad({"run", kScene, "other.toml"}, {"unexpected argument 'other.toml'"});
}

TEST(CliParsing, AMissingValueNamesTheOption) {
  expect_bad({"run", kScene, "--t-end"}, {"--t-end: expected a value"});
  expect_bad({"stiffness", kScene, "--samples"}, {"--samples: expected a value"});
  expect_bad({"run", kScene, "--set"}, {"--set: expected a value"});
}

TEST(CliParsing, AMissingArgumentSaysWhatWasExpected) {
  expect_bad({"run"}, {"run: missing scene", "expected a scene file"});
  expect_bad({"dynamics", "--robot", "puma560", "--q=qz"}, {"missing --backend", "expected a dynamics back-end"});
}

TEST(CliParsing, AWrongTypeNamesTheOptionAndTheValue) {
  expect_bad({"run", kScene, "--t-end", "abc"}, {"--t-end: expected a number > 0, got 'abc'"});
  expect_bad({"run", kScene, "--dt", "nan"}, {"--dt: expected a number > 0, got 'nan'"});
  expect_bad({"run", kScene, "--rtol=inf"}, {"--rtol: expected a number in [1e-14, 0.1]", "got 'inf'"});
  expect_bad({"stiffness", kScene, "--samples", "2.5"}, {"--samples: expected a whole number in [1, 10000], got '2.5'"});
  expect_bad({"run", kScene, "--integrator", "rk45"}, {"--integrator: unknown integrator 'rk45'; expected one of:"});
  expect_bad({"run", kScene, "--backend", "fast"}, {"--backend: unknown dynamics back-end 'fast'"});
}

TEST(CliParsing, AnOutOfRangeValueNamesTheOptionAndTheRange) {
  expect_bad({"run", kScene, "--t-end=-1"}, {"--t-end: expected a number > 0, got '-1'"});
  expect_bad({"run", kScene, "--max-steps", "-5"}, {"--max-steps: expected a whole number in [0, 1e18] (0: no limit)"});
  // Above the limit, the message says the limit.
  expect_bad({"run", kScene, "--max-steps", "1e19"}, {"--max-steps: expected a whole number in [0, 1e18]", "'1e19'"});
  expect_bad({"run", kScene, "--max-wall", "-1"}, {"--max-wall: expected seconds >= 0 (0: no limit)"});
  expect_bad({"stiffness", kScene, "--samples", "0"}, {"--samples: expected a whole number in [1, 10000], got '0'"});
  expect_bad({"conditioning", kScene, "--samples", "100001"}, {"--samples: expected a whole number in [1, 100000]"});
  expect_bad({"run", kScene, "--late-events", "--stop-at-outputs"}, {"--late-events", "--stop-at-outputs"});
}

TEST(CliParsing, ACsvFileOutsideAnExistingFolderIsRefusedBeforeTheAnalysis) {
  expect_bad({"stiffness", kScene, "--csv", "/nonexistent/folder/s.csv"},
             {"--csv: expected a file in an existing folder, got '/nonexistent/folder/s.csv'"});
}

TEST(CliParsing, NegativeNumbersAreValuesWithOrWithoutEquals) {
  for (const std::vector<std::string>& q : {std::vector<std::string>{"--q", "-0.1,0.2,-0.3,0,0,0"},
                                            std::vector<std::string>{"--q=-0.1,0.2,-0.3,0,0,0"}}) {
    std::vector<std::string> args{"dynamics", "--robot", "puma560", "--backend", "crba", "--tau", "-1,-2,-3,0,0,0"};
    args.insert(args.end(), q.begin(), q.end());
    const CliResult r = cli(args);
    ASSERT_EQ(r.status, kExitOk) << r.err;
    EXPECT_NE(r.out.find("\"q\": [\n    -0.1,"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"tau_in\": [\n    -1.0,"), std::string::npos) << r.out;
  }
}

TEST(CliParsing, EveryRepeatedSetApplies) {
  const CliResult r = cli({"check", kScene, "--set", "motor.inductance=1e-5", "--set=scene.output_interval=0.02"});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  EXPECT_NE(r.out.find("inductance = [ 1.0000000000000001e-05,"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("output_interval = 0.02"), std::string::npos) << r.out;
}

TEST(CliParsing, TheHelpListsEveryCommandOnStdout) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"help"}, std::vector<std::string>{"--help"}, std::vector<std::string>{"-h"}}) {
    const CliResult r = cli(args);
    EXPECT_EQ(r.status, kExitOk) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    for (const char* c : {"dynamics", "check", "run", "stiffness", "conditioning", "integrators", "backends", "help"}) {
      EXPECT_NE(r.out.find("  " + std::string(c) + " "), std::string::npos) << c << " in:\n" << r.out;
    }
  }
}

TEST(CliParsing, ACommandsHelpListsItsOptions) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"help", "run"}, std::vector<std::string>{"run", "--help"}}) {
    const CliResult r = cli(args);
    EXPECT_EQ(r.status, kExitOk) << r.err;
    for (const char* o : {"--integrator", "--backend", "--rtol", "--atol", "--dt", "--t-end", "--out", "--force",
                          "--jacobian", "--max-steps", "--max-wall", "--late-events", "--stop-at-outputs",
                          "--set"}) {
      EXPECT_NE(r.out.find(o), std::string::npos) << o << " in:\n" << r.out;
    }
  }
  expect_bad({"help", "fly"}, {"help: unknown command 'fly'; expected one of: dynamics"});
}

// pumasim robot prints the robot as read (the PUMA's gear ratio of joint 1,
// -62.6111 in the Robotics Toolbox's mdl_puma560.m, its sign RTB's sense), and
// --random N a robot file that reads back as an N-joint robot.
TEST(CliRobot, PrintsTheRobotAsReadAndARandomChainsFile) {
  const CliResult r = cli({"robot", "puma560"});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["dof"], 6);
  EXPECT_DOUBLE_EQ(doc["joints"][0]["gear_ratio"].get<double>(), -62.6111);
  const CliResult rnd = cli({"robot", "--random", "9", "--seed", "4", "--types", "RRP"});
  ASSERT_EQ(rnd.status, kExitOk) << rnd.err;
  const auto file = testing::scratch_root() / "cli_random9.toml";
  std::ofstream(file) << rnd.out;
  const RobotModel m = load_robot_file(file.string());
  EXPECT_EQ(m.dof(), 9);
  EXPECT_TRUE(m.joints[2].prismatic() && !m.joints[1].prismatic());
  expect_bad({"robot"}, {"robot: expected a robot name or file, or --random N"});
  expect_bad({"robot", "--random", "0"}, {"--random"});
  expect_bad({"robot", "--random", "3", "--types", "RX"}, {"expected letters R and P"});
}

// --unset removes keys of the scene file before --set and the checks: the
// scene switches its friction law from the command line.
TEST(CliParsing, UnsetRemovesKeysSoThatASceneSwitchesItsFrictionLaw) {
  const CliResult r = cli({"check", kScene, "--set", "friction.model=\"viscous\"", "--unset", "friction.static_torque",
                        "--unset", "friction.kinetic_torque", "--unset=friction.zero_speed"});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  EXPECT_NE(r.out.find("[friction]\nmodel = 'viscous'\nviscous = [ 0.00148,"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("static_torque"), std::string::npos) << r.out;
  // A table as a whole; then --set puts back what it names.
  const CliResult t = cli({"check", kScene, "--unset", "friction", "--set", "friction.model=\"none\""});
  ASSERT_EQ(t.status, kExitOk) << t.err;
  EXPECT_NE(t.out.find("[friction]\nmodel = 'none'\n\n"), std::string::npos) << t.out;
}

// A key that the switch left without meaning: unknown, and the message says
// why (the choice it does not apply to, and the --set that made it) and how
// to remove every such key.
TEST(CliParsing, AKeyLeftWithoutMeaningByASwitchSaysWhyAndHowToRemoveIt) {
  expect_bad({"check", kScene, "--set", "friction.model=\"viscous\""},
             {"paper_slow.toml:", "unknown key 'friction.kinetic_torque'; expected one of: model, viscous",
              "does not apply to friction.model = \"viscous\" (--set friction.model=\"viscous\")",
              "--unset friction.kinetic_torque --unset friction.static_torque --unset friction.zero_speed"});
  expect_bad({"check", kScene, "--set", "friction.model=\"viscous\"", "--unset", "friction.kinetic_torque",
              "--unset", "friction.static_torque"},
             {"paper_slow.toml:", "unknown key 'friction.zero_speed'", "with --unset friction.zero_speed)"});
  // Set by --set itself: the override is named, and dropping it is the remedy.
  expect_bad({"check", kScene, "--set", "friction.model=\"viscous\"", "--unset", "friction.kinetic_torque",
              "--unset", "friction.static_torque", "--unset", "friction.zero_speed", "--set", "friction.zero_speed=1"},
             {"--set friction.zero_speed=1: unknown key 'friction.zero_speed'", "does not apply to friction.model",
              "drop --set friction.zero_speed=1"});
  // In the file itself (no switch): the same reason, from the file's own choice.
  expect_bad({"check", kScene, "--set", "reference.timing=\"quintic\"", "--set", "reference.traversal_time=20"},
             {"unknown key 'reference.max_speed'", "does not apply to reference.timing = \"quintic\"",
              "--unset reference.max_speed --unset reference.profile"});
}

// The choice that decides is named with its value even when the file does
// not give it (the default), and a table the command line made is named by
// the --set that made it (it has no line in the file).
TEST(CliParsing, TheDecidingChoiceIsNamedAtItsDefaultAndATableFromSetByItsSet) {
  const std::string ct = std::string(PUMASIM_SCENES_DIR) + "/computed_torque.toml";
  expect_bad({"check", ct, "--unset", "controller.law"},
             {"computed_torque.toml:", "unknown key 'controller.kd'",
              "does not apply to controller.law = \"piv\" (the default)", "with --unset controller.kd)"});
  expect_bad({"check", kScene, "--set", "controller.law=\"computed_torque\"", "--set", "controller.kd=1"},
             {"does not apply to controller.law = \"computed_torque\" (--set controller.law=\"computed_torque\")"});
  expect_bad({"check", ct, "--unset", "controller", "--set", "controller.law=\"piv\""},
             {"--set controller.law=\"piv\": controller: missing required key 'mode'"});
}

TEST(CliParsing, UnsetOfAKeyTheSceneDoesNotHaveIsNamed) {
  expect_bad({"check", kScene, "--unset", "friction.static_torq"},
             {"--unset friction.static_torq: ", "paper_slow.toml has no key 'friction.static_torq'",
              "[friction] has: kinetic_torque, model, static_torque, viscous, zero_speed"});
  expect_bad({"run", kScene, "--unset", "planning.grid"}, {"paper_slow.toml has no table [planning]"});
  expect_bad({"check", kScene, "--unset", "friction..model"}, {"--unset friction..model: expected section.key"});
  expect_bad({"check", kScene, "--unset"}, {"--unset: expected a value"});
}

TEST(CliParsing, VersionPrintsTheBuild) {
  const CliResult r = cli({"--version"});
  EXPECT_EQ(r.status, kExitOk) << r.err;
  EXPECT_EQ(r.out, version_text() + "\n");
  EXPECT_EQ(r.out.rfind("pumasim ", 0), 0u) << r.out;
}

// stdout is the JSON document alone, parsed whole; with --quiet stderr is
// empty (no "results:" line; no progress line either, which also needs a
// terminal: tests/test_cli_process.py checks it on one).
TEST(CliOutput, RunPrintsOnlyItsJsonOnStdout) {
  const fs::path d = scratch("stdout");
  const CliResult r = cli({"run", kScene, "--t-end", "0.05", "--out", (d / "run").string()});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  const auto doc = nlohmann::json::parse(r.out);  // throws on anything but one JSON document
  EXPECT_EQ(doc["scene"], "paper_slow");
  EXPECT_EQ(r.err, "results: " + (d / "run").string() + "/\n");
  const CliResult q = cli({"run", kScene, "--t-end", "0.05", "--out", (d / "run").string(), "--force", "--quiet"});
  ASSERT_EQ(q.status, kExitOk) << q.err;
  EXPECT_EQ(nlohmann::json::parse(q.out)["ok"], true);
  EXPECT_TRUE(q.err.empty()) << q.err;
  fs::remove_all(d);
}

// The library names an option neutrally ({{name}}: core/option_words.hpp);
// the command line phrases every such message in its own words, whichever
// layer wrote it: the scene overrides (models), the run's options and the
// run folder (simulation), a failed run (the driver, in stats.json too).
TEST(CliOutput, EveryMessageNamesTheOptionsAsTheCommandLineSpellsThem) {
  const fs::path d = scratch("words");
  fs::create_directories(d / "mine");
  { std::ofstream(d / "mine" / "notes.txt") << "keep"; }
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"check", kScene, "--set", "scene.duration"}, "--set scene.duration: expected section.key=value"},
      {{"check", kScene, "--unset", "scene.no_such_key"}, "--unset scene.no_such_key: "},
      {{"run", kScene, "--integrator", "cvode-bdf", "--dt", "1e-3", "--out", (d / "a").string()},
       "--dt: cvode-bdf is adaptive; expected --rtol and --atol"},
      {{"run", kScene, "--t-end", "0.01", "--out", (d / "mine").string(), "--force"}, "--out " + (d / "mine").string()},
      {{"run", kScene, "--integrator", "rk4", "--dt", "1e-3", "--max-steps", "3", "--out", (d / "b").string(),
        "--quiet"},
       "a larger --max-steps"},
  };
  for (const auto& [args, expected] : cases) {
    const CliResult r = cli(args);
    EXPECT_NE(r.status, kExitOk) << args[0];
    EXPECT_NE(r.err.find(expected), std::string::npos) << expected << " in: " << r.err;
    EXPECT_EQ(r.err.find("{{"), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("{{"), std::string::npos) << r.out;  // stats.json's failure
  }
  fs::remove_all(d);
}

// A run over its step budget: a reported failure (exit 1, files written)
// naming --max-steps, the time, the last step and the state changing fastest
// relative to its typical magnitude. (On a smooth scene: on the paper's rule
// the budget is diagnosed as chattering instead, tests/test_named_failures.cpp.)
TEST(CliOutput, AStepBudgetFailureNamesMaxStepsAndTheFastestState) {
  const fs::path d = scratch("budget");
  const CliResult r = cli({"run", std::string(PUMASIM_SCENES_DIR) + "/paper_slow_viscous.toml", "--integrator",
                        "cvode-bdf", "--rtol", "1e-6", "--atol", "1e-9", "--max-steps", "300", "--out",
                        (d / "run").string(), "--quiet"});
  EXPECT_EQ(r.status, kExitInternal) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  const std::string failure = doc["failure"];
  EXPECT_EQ(doc["ok"], false);
  EXPECT_EQ(doc["steps"], 301);
  for (const char* f : {"cvode-bdf: step budget of 300 steps exhausted at t = ", "(last step h = ",
                        "fastest-changing component ", "(|f| / scale = ", "a larger --max-steps"}) {
    EXPECT_NE(failure.find(f), std::string::npos) << f << " in: " << failure;
  }
  EXPECT_EQ(r.err, "pumasim run: " + failure + "\n");
  EXPECT_TRUE(fs::exists(d / "run" / "stats.json"));
  fs::remove_all(d);
}

// The measure is |f_i| / scale_i, the plant's tolerance scales: a component
// with the larger |f| but a larger typical magnitude is not the fastest.
TEST(CliOutput, TheFastestStateIsTheLargestRateOverItsScale) {
  struct Two final : OdeSystem {
    int size() const override { return 2; }
    void rhs(double, const double*, double* f) override { f[0] = 10, f[1] = -1; }
    std::string state_name(int i) const override { return i == 0 ? "big" : "small"; }
    double tolerance_scale(int i) const override { return i == 0 ? 100.0 : 0.01; }
  } sys;
  const double x[2] = {3, 0.5};
  EXPECT_EQ(fastest_scaled_component(sys, 0, x), "small = 0.5 (|f| / scale = 100 1/s, scale 0.01)");
}

TEST(CliOutput, ShellQuotingAndTheRobotFileHash) {
  EXPECT_EQ(shell_quoted({"pumasim", "run", "a b.toml", "--set", "friction.model=\"tanh\"", "it's", ""}),
            "pumasim run 'a b.toml' --set 'friction.model=\"tanh\"' 'it'\\''s' ''");
  // FNV-1a 64 test vectors (Fowler, Noll, Vo: the reference implementation's).
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ULL);
}

// meta.json: the command line as given, when, where, on what, and the robot
// file with the hash of its bytes.
TEST(CliOutput, MetaJsonRecordsTheRunsContext) {
  const fs::path d = scratch("meta");
  const std::vector<std::string> args{"run", kScene, "--t-end", "0.02", "--set", "scene.output_interval=0.01",
                                      "--out", (d / "run").string(), "--quiet"};
  std::ostringstream out, err;
  ASSERT_EQ(run_cli(args, out, err, "/opt/my pumasim"), kExitOk) << err.str();
  std::ifstream f(d / "run" / "meta.json");
  const auto meta = nlohmann::json::parse(f);
  std::vector<std::string> argv{"/opt/my pumasim"};
  argv.insert(argv.end(), args.begin(), args.end());
  EXPECT_EQ(meta["command_line"], shell_quoted(argv));
  EXPECT_EQ(meta["working_directory"], fs::current_path().string());
  EXPECT_TRUE(std::regex_match(meta["started_utc"].get<std::string>(),
                               std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")))
      << meta["started_utc"];
  EXPECT_FALSE(meta["cpu_model"].get<std::string>().empty());
  EXPECT_EQ(meta["cpu_model"], cpu_model());
  for (const char* k : {"git_revision", "compiler", "flags", "build_type"}) EXPECT_TRUE(meta.contains(k)) << k;
  const fs::path robot = fs::path(PUMASIM_SCENES_DIR) / ".." / ".." / "models" / "robots" / "puma560.toml";
  EXPECT_TRUE(fs::equivalent(meta["robot_file"]["path"].get<std::string>(), robot)) << meta["robot_file"];
  std::ifstream rf(robot, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(rf)), std::istreambuf_iterator<char>());
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(bytes)));
  EXPECT_EQ(meta["robot_file"]["fnv1a64"], hex);
  fs::remove_all(d);
}

// Changes the working directory for one scope.
struct InFolder {
  explicit InFolder(const fs::path& p) : old(fs::current_path()) { fs::current_path(p); }
  ~InFolder() { fs::current_path(old); }
  fs::path old;
};

// A scene whose robot is a file beside it (named without a folder, and by a
// relative path): it runs from another working directory, and its run
// folder's scene.resolved.toml, which names the robot file by its absolute
// path, re-runs from a third one to the same trajectory. A shipped robot's
// name stays a name.
TEST(CliOutput, TheResolvedSceneOfARunFolderReRunsFromAnyFolder) {
  const fs::path d = scratch("rerun");
  fs::create_directories(d / "scenes" / "robots");
  fs::create_directories(d / "elsewhere");
  fs::create_directories(d / "third");
  const fs::path robots = fs::path(PUMASIM_SCENES_DIR) / ".." / ".." / "models" / "robots";
  fs::copy_file(robots / "puma560.toml", d / "scenes" / "arm.toml");
  fs::copy_file(robots / "puma560.toml", d / "scenes" / "robots" / "arm.toml");
  std::ifstream in(kScene);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string named = "robot = \"puma560\"";
  const auto at = text.find(named);
  ASSERT_NE(at, std::string::npos);
  for (const char* robot : {"arm.toml", "robots/arm.toml"}) {
    std::string scene = text;
    scene.replace(at, named.size(), "robot = \"" + std::string(robot) + "\"");
    std::ofstream(d / "scenes" / "mine.toml") << scene;
    fs::remove_all(d / "elsewhere" / "first");
    fs::remove_all(d / "third" / "second");
    {
      InFolder here(d / "elsewhere");
      const CliResult r = cli({"run", "../scenes/mine.toml", "--t-end", "0.3", "--out", "first", "--quiet"});
      ASSERT_EQ(r.status, kExitOk) << robot << ": " << r.err;
    }
    std::ifstream rs(d / "elsewhere" / "first" / "scene.resolved.toml");
    const std::string resolved((std::istreambuf_iterator<char>(rs)), std::istreambuf_iterator<char>());
    EXPECT_NE(resolved.find("robot = '" + (d / "scenes").string() + "/" + robot + "'"), std::string::npos)
        << robot << ":\n" << resolved;
    {
      InFolder here(d / "third");
      const CliResult r = cli({"run", "../elsewhere/first/scene.resolved.toml", "--out", "second", "--quiet"});
      ASSERT_EQ(r.status, kExitOk) << robot << ": " << r.err;
    }
    const auto a = lines_of(d / "elsewhere" / "first" / "trajectory.csv");
    const auto b = lines_of(d / "third" / "second" / "trajectory.csv");
    EXPECT_EQ(a.size(), 32u) << robot;  // the header, t = 0, 0.01, ..., 0.3
    EXPECT_EQ(a, b) << robot;
  }
  const CliResult c = cli({"check", kScene});
  EXPECT_NE(c.out.find("robot = 'puma560'"), std::string::npos) << c.out;
  fs::remove_all(d);
}

TEST(CliOutput, StiffnessWritesCsvFilesWithNamedColumns) {
  const fs::path d = scratch("stiffness");
  const CliResult r = cli({"stiffness", kScene, "--t-end", "0.01", "--samples", "2", "--csv", (d / "s.csv").string(),
                        "--steps-csv", (d / "steps.csv").string()});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  const auto s = lines_of(d / "s.csv");
  ASSERT_EQ(s.size(), 4u) << "header, then t = 0, 0.005, 0.01";
  EXPECT_EQ(s[0],
            "t [s],spectral_radius [1/s],stiffness_ratio [-],fastest_tau [s],fastest_re [1/s],fastest_im [1/s],"
            "fastest_state,slowest_tau [s],slowest_re [1/s],slowest_im [1/s],slowest_state,unstable_modes [-]");
  EXPECT_EQ(s[1].rfind("0,", 0), 0u) << s[1];
  EXPECT_EQ(std::count(s[3].begin(), s[3].end(), ','), 11) << s[3];
  const auto b = lines_of(d / "steps.csv");
  ASSERT_EQ(b.size(), 6u);
  EXPECT_EQ(b[0], "integrator,predicted_step [s],measured_step [s],note");
  EXPECT_EQ(b[1].rfind("euler,", 0), 0u) << b[1];
  EXPECT_NE(r.out.find("largest spectral radius"), std::string::npos) << r.out;
  // A named file is replaced (the user asked for it); no temporary file is left beside it.
  ASSERT_EQ(cli({"stiffness", kScene, "--t-end", "0.01", "--samples", "1", "--csv", (d / "s.csv").string()}).status,
            kExitOk);
  EXPECT_EQ(lines_of(d / "s.csv").size(), 3u);
  EXPECT_EQ(std::distance(fs::directory_iterator(d), {}), 2);
  fs::remove_all(d);
}

TEST(CliOutput, ConditioningWritesACsvFileWithNamedColumns) {
  const fs::path d = scratch("conditioning");
  const CliResult r = cli({"conditioning", kScene, "--samples", "4", "--csv", (d / "c.csv").string()});
  ASSERT_EQ(r.status, kExitOk) << r.err;
  const auto c = lines_of(d / "c.csv");
  ASSERT_EQ(c.size(), 6u) << "header, then 5 samples";
  EXPECT_EQ(c[0].rfind("t [s],q1 [rad],q2 [rad],q3 [rad],cond_H [-],min_eig_H [kg m^2],qdd_error_", 0), 0u) << c[0];
  EXPECT_NE(c[0].find(",qdd_error_crba [-]"), std::string::npos) << c[0];
  EXPECT_NE(r.out.find("largest cond(H)"), std::string::npos) << r.out;
  fs::remove_all(d);
}

}  // namespace
}  // namespace pumasim
