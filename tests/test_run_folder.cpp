// `pumasim run --out DIR` never destroys what it did not write: a folder
// holding a user's file, the working directory itself, a scene named "..",
// and --force on a folder that is not a run folder are refused (exit 2) with
// the user's file intact; a run folder is replaced only with --force, and only
// while it holds nothing pumasim did not write.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "experiments/cli.hpp"
#include "experiments/simulation/run_folder.hpp"

#ifndef PUMASIM_SCENES_DIR
#error "PUMASIM_SCENES_DIR must be defined by the build"
#endif

namespace pumasim {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(PUMASIM_SCENES_DIR) + "/paper_slow.toml";

// A fresh folder of this test's own (CTest runs tests in parallel processes).
fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("pumasim_run_folder_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write(const fs::path& p, const std::string& s) { std::ofstream(p) << s; }

std::string read(const fs::path& p) {
  std::ifstream f(p);
  return {std::istreambuf_iterator<char>(f), {}};
}

int run(std::vector<std::string> extra, std::string* err_text = nullptr) {
  std::vector<std::string> args{"run", kScene, "--integrator", "rk4", "--dt", "0.0005", "--t-end", "0.02"};
  args.insert(args.end(), extra.begin(), extra.end());
  std::ostringstream out, err;
  const int code = run_cli(args, out, err);
  if (err_text) *err_text = err.str();
  return code;
}

TEST(RunFolder, AFolderHoldingAUsersFileIsNotTouched) {
  const fs::path d = scratch("user");
  write(d / "thesis.tex", "my work");
  std::string err;
  EXPECT_EQ(run({"--out", d.string()}, &err), kExitBadInput);
  EXPECT_NE(err.find("not a pumasim run folder"), std::string::npos) << err;
  EXPECT_EQ(read(d / "thesis.tex"), "my work");
  EXPECT_EQ(run({"--out", d.string(), "--force"}, &err), kExitBadInput) << "--force on a folder pumasim did not write";
  EXPECT_EQ(read(d / "thesis.tex"), "my work");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), {}), 1) << "nothing added beside the user's file";
  fs::remove_all(d);
}

TEST(RunFolder, TheWorkingDirectoryIsNotEmptied) {
  const fs::path d = scratch("cwd");
  write(d / "notes.txt", "keep");
  const fs::path before = fs::current_path();
  fs::current_path(d);
  std::string err;
  EXPECT_EQ(run({"--out", "."}, &err), kExitBadInput);
  EXPECT_EQ(run({"--out", ".", "--force"}, &err), kExitBadInput);
  fs::current_path(before);
  EXPECT_EQ(read(d / "notes.txt"), "keep");
  fs::remove_all(d);
}

TEST(RunFolder, ASceneNamedDotDotIsRejected) {
  const fs::path d = scratch("dotdot");
  write(d / "keep.txt", "keep");
  const fs::path before = fs::current_path();
  fs::current_path(d);
  for (const char* name : {"\"..\"", "\".\"", "\"a/b\"", "\"\""}) {
    std::string err;
    EXPECT_EQ(run({"--set", std::string("scene.name=") + name}, &err), kExitBadInput) << name;
    EXPECT_NE(err.find("scene.name: expected a plain name"), std::string::npos) << err;
  }
  fs::current_path(before);
  EXPECT_EQ(read(d / "keep.txt"), "keep");
  EXPECT_FALSE(fs::exists(d / "runs"));
  fs::remove_all(d);
}

TEST(RunFolder, ARunFolderIsReplacedOnlyWithForceAndOnlyWhileItHoldsOnlyWhatPumasimWrote) {
  const fs::path root = scratch("replace"), d = root / "run";
  ASSERT_EQ(run({"--out", d.string()}), kExitOk);
  EXPECT_TRUE(fs::exists(d / kRunMarker));
  EXPECT_TRUE(fs::exists(d / "trajectory.csv"));
  std::string err;
  EXPECT_EQ(run({"--out", d.string()}, &err), kExitBadInput);
  EXPECT_NE(err.find("--force"), std::string::npos) << err;
  EXPECT_EQ(run({"--out", d.string(), "--force"}), kExitOk);
  EXPECT_TRUE(fs::exists(d / "stats.json"));
  write(d / "my_plot.png", "mine");
  EXPECT_EQ(run({"--out", d.string(), "--force"}, &err), kExitBadInput);
  EXPECT_NE(err.find("my_plot.png"), std::string::npos) << err;
  EXPECT_EQ(read(d / "my_plot.png"), "mine");
  EXPECT_TRUE(fs::exists(d / "trajectory.csv")) << "the refused replacement removed nothing";
  // Nothing left beside the folder: no temporary or old copies.
  EXPECT_EQ(std::distance(fs::directory_iterator(root), {}), 1);
  fs::remove_all(root);
}

}  // namespace
}  // namespace pumasim
