// Run folders: what `pumasim run` writes, created atomically and never
// replacing anything pumasim did not write.
//
// A run folder holds a marker file (kRunMarker) listing the files pumasim (or
// its plot script) wrote there. An existing folder is replaced only with
// `force`, only if it carries the marker, and only if every entry in it is
// one the marker lists; otherwise RunFolderError (bad input: exit status 2),
// and nothing is touched. The new folder is filled under a temporary name
// beside the target and swapped in by renames: the old one is renamed aside,
// the new one renamed in, then the old one is removed -- a kill at any
// instant leaves either the old complete folder or the new complete one
// (plus, at worst, a hidden ".<name>.*" folder beside it).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace pumasim {

inline constexpr const char* kRunMarker = ".pumasim-run";

class RunFolderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws RunFolderError unless `dir` is free (absent) or a replaceable run folder with force.
void check_run_folder_target(const std::filesystem::path& dir, bool force);

// Writes `files` (name, content) into `dir` as above; every write is checked.
void write_run_folder(const std::filesystem::path& dir, const std::vector<std::pair<std::string, std::string>>& files,
                      bool force);

// One file, written whole or not at all: into a hidden temporary file beside
// `path`, then renamed over it (a file the user named is replaced). A write
// that fails (a missing folder, a full disk) is a RunFolderError naming `path`.
void write_file_atomically(const std::filesystem::path& path, const std::string& content);

}  // namespace pumasim
