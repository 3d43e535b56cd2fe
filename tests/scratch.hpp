// The test process's own folder for the files its tests write, under the
// system's temporary folder: /tmp/pumasim_tests_<pid>/ (CTest runs each test
// in a process of its own, in parallel). It is removed when the process ends
// if every test in it passed; a failing test's files are kept for a look, and
// their folder is named on standard error.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

namespace pumasim::testing {

inline const std::filesystem::path& scratch_root() {
  struct Root {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("pumasim_tests_" + std::to_string(::getpid()));
    Root() {
      // A folder of this name is a test process's whose pid this one reuses.
      std::filesystem::remove_all(path);
      std::filesystem::create_directories(path);
    }
    ~Root() {
      // Destroyed before gtest's UnitTest, which was built before the first call.
      if (::testing::UnitTest::GetInstance()->Passed()) {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
      } else {
        std::fprintf(stderr, "the failing tests' files are kept in %s\n", path.c_str());
      }
    }
  };
  static const Root root;
  return root.path;
}

// A fresh, empty folder `name` under scratch_root().
inline std::filesystem::path scratch_dir(const std::string& name) {
  const std::filesystem::path d = scratch_root() / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace pumasim::testing
