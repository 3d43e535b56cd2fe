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
// (plus, at worst, a hidden ".<name>.<pid>-<k>.*" folder beside it, which the
// next run to that target removes once its process is gone). Where the file
// system can, the two renames are one atomic exchange (renameat2). The swap
// is made under a lock on the parent folder (flock), so that runs racing to
// one target replace it in turn.
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
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

// A run folder being written: checked (check_run_folder_target) and its
// hidden temporary folder made at construction, the files written into it
// (a stream, for a file written as the run goes), then commit() swaps it in.
// Destroyed without a commit, it removes its temporary folder.
class RunFolderWriter {
 public:
  RunFolderWriter(std::filesystem::path dir, bool force);
  ~RunFolderWriter();
  RunFolderWriter(const RunFolderWriter&) = delete;
  RunFolderWriter& operator=(const RunFolderWriter&) = delete;
  // A file of the folder, written through the stream; checked by commit().
  std::ostream& stream(const std::string& name);
  void write(const std::string& name, const std::string& content);
  // Every stream checked and closed, the marker written, the folder swapped in.
  void commit();
  // A new temporary name beside `dir` (".<name>.<pid>-<k>.<suffix>", k
  // counting in this process; the name shortened with a hash when near the
  // file system's limit of 255 bytes).
  static std::filesystem::path temporary_path(const std::filesystem::path& dir, const char* suffix);

 private:
  std::filesystem::path dir_, tmp_;
  bool force_, committed_ = false;
  std::vector<std::string> names_;
  std::vector<std::pair<std::string, std::unique_ptr<std::ofstream>>> streams_;
};

// Writes `files` (name, content) into `dir` as above; every write is checked.
void write_run_folder(const std::filesystem::path& dir, const std::vector<std::pair<std::string, std::string>>& files,
                      bool force);

// One file, written whole or not at all: into a hidden temporary file beside
// `path`, then renamed over it (a file the user named is replaced). A write
// that fails (a missing folder, a full disk) is a RunFolderError naming `path`.
void write_file_atomically(const std::filesystem::path& path, const std::string& content);

}  // namespace pumasim
