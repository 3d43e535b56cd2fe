#include "simulation/run_folder.hpp"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include "models/robot/input_files.hpp"  // fnv1a64, hex64

namespace pumasim {
namespace fs = std::filesystem;

namespace {

std::set<std::string> marker_entries(const fs::path& dir) {
  std::ifstream in(dir / kRunMarker);
  std::set<std::string> names;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') names.insert(line);
  }
  return names;
}

void write_file(const fs::path& p, const std::string& content) {
  std::ofstream f(p, std::ios::binary);
  f << content;
  f.close();
  if (!f) throw RunFolderError("could not write " + p.string() + " (disk full or not writable?); no run folder written");
}

}  // namespace

void check_run_folder_target(const fs::path& dir, bool force) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(dir, ec);
  if (!fs::exists(st)) return;
  const std::string d = dir.string();
  if (!fs::is_directory(st)) {
    throw RunFolderError("{{out}} " + d + ": exists and is not a folder; pumasim writes a run into a new folder");
  }
  if (!fs::exists(dir / kRunMarker)) {
    throw RunFolderError("{{out}} " + d + ": the folder exists and is not a pumasim run folder (no " +
                         std::string(kRunMarker) +
                         " marker); pumasim never replaces what it did not write: "
                         "choose a new folder");
  }
  if (!force) {
    throw RunFolderError("{{out}} " + d + ": a pumasim run folder is already there; pass {{force}} to replace it");
  }
  const std::set<std::string> ours = marker_entries(dir);
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name != kRunMarker && !ours.count(name)) {
      throw RunFolderError("{{out}} " + d + ": holds " + name +
                           ", which pumasim did not write; it is not replaced "
                           "(move that file, or choose a new folder)");
    }
  }
}

namespace {

// A target's name longer than this is shortened in its temporary names, so
// that ".<name>.<pid>.partial" stays within the file system's 255 bytes.
constexpr std::size_t kMaxBaseName = 200;

std::string base_name(const fs::path& dir) {
  const std::string name = dir.filename().string();
  if (name.size() <= kMaxBaseName) return name;
  return name.substr(0, kMaxBaseName - 17) + "~" + hex64(fnv1a64(name));
}

fs::path parent_of(const fs::path& dir) { return dir.has_parent_path() ? dir.parent_path() : fs::path("."); }

// An exclusive lock on a folder while alive (flock on the folder itself: no
// lock file left behind); none where the folder cannot be opened.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& folder) : fd_(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd_ >= 0) {
      while (::flock(fd_, LOCK_EX) != 0 && errno == EINTR) {
      }
    }
  }
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_;
};

// Removes a folder of pumasim's (its marker inside), the marker last, so
// that a process killed at any instant of it leaves the folder either still
// marked or empty: both are known as pumasim's by remove_leftovers.
void remove_marked_folder(const fs::path& dir, std::error_code& ec) {
  std::vector<fs::path> entries;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().filename() != kRunMarker) entries.push_back(it->path());
  }
  if (ec) return;
  for (const fs::path& e : entries) {
    fs::remove_all(e, ec);
    if (ec) return;
  }
  fs::remove(dir / kRunMarker, ec);
  if (!ec) fs::remove(dir, ec);
}

void remove_marked_folder(const fs::path& dir) {
  std::error_code ec;
  remove_marked_folder(dir, ec);
  if (ec) throw fs::filesystem_error("cannot remove", dir, ec);
}

// The temporary folders of earlier runs to this target
// (".<name>.<pid>-<k>.partial" or ".old", with pumasim's marker, or empty)
// whose process is gone: a run killed before its swap, or after the exchange.
void remove_leftovers(const fs::path& parent, const std::string& base) {
  const std::string prefix = "." + base + ".";
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = name.substr(prefix.size());
    const std::size_t dash = rest.find('-'), dot = rest.find('.');
    if (dash == 0 || dash > 9 || dot == std::string::npos || dot < dash) continue;
    const std::string pid = rest.substr(0, dash), k = rest.substr(dash + 1, dot - dash - 1),
                      suffix = rest.substr(dot + 1);
    if (pid.find_first_not_of("0123456789") != std::string::npos || k.empty() ||
        k.find_first_not_of("0123456789") != std::string::npos || (suffix != "partial" && suffix != "old")) {
      continue;
    }
    const long p = std::stol(pid);
    if (p == ::getpid() || ::kill(static_cast<pid_t>(p), 0) == 0 || errno != ESRCH) continue;  // alive, or unknown
    std::error_code e2;
    if (fs::exists(it->path() / kRunMarker, e2)) {
      remove_marked_folder(it->path(), e2);
      continue;
    }
    // No marker: a run killed between making its folder and writing the
    // marker into it leaves the folder empty. Removed only if it is (rmdir
    // refuses a folder with anything in it), so nobody's file can go.
    fs::remove(it->path(), e2);
  }
}

}  // namespace

fs::path RunFolderWriter::temporary_path(const fs::path& dir, const char* suffix) {
  static std::atomic<long> count{0};  // threads of one process writing one target: apart
  std::string name(1, '.');  // built piecewise: GCC 12 warns falsely on "." + string (bug 105329)
  name.append(base_name(dir)).append(1, '.').append(std::to_string(::getpid())).append(1, '-');
  name.append(std::to_string(count++)).append(1, '.').append(suffix);
  return parent_of(dir) / name;
}

RunFolderWriter::RunFolderWriter(fs::path dir, bool force) : dir_(std::move(dir)), force_(force) {
  check_run_folder_target(dir_, force_);
  tmp_ = temporary_path(dir_, "partial");
  try {
    fs::create_directories(parent_of(dir_));
    fs::create_directory(tmp_);
    // The marker first, so that a leftover of a killed run is known as pumasim's.
    write_file(tmp_ / kRunMarker, "# a pumasim run folder being written by process " + std::to_string(::getpid()) +
                                      "\n");
  } catch (const fs::filesystem_error& e) {  // a folder that cannot be made: the path, not "internal"
    std::error_code ec;
    fs::remove_all(tmp_, ec);
    throw RunFolderError("{{out}} " + dir_.string() + ": " + e.code().message() + " (" + e.path1().string() +
                         "); no run folder written");
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp_, ec);
    throw;
  }
}

RunFolderWriter::~RunFolderWriter() {
  if (committed_) return;
  streams_.clear();
  std::error_code ec;
  remove_marked_folder(tmp_, ec);
}

std::ostream& RunFolderWriter::stream(const std::string& name) {
  auto f = std::make_unique<std::ofstream>(tmp_ / name, std::ios::binary);
  if (!*f) throw RunFolderError("could not write " + (tmp_ / name).string() + " (not writable?); no run folder written");
  names_.push_back(name);
  streams_.emplace_back(name, std::move(f));
  return *streams_.back().second;
}

void RunFolderWriter::write(const std::string& name, const std::string& content) {
  write_file(tmp_ / name, content);
  names_.push_back(name);
}

void RunFolderWriter::commit() {
  for (auto& [name, f] : streams_) {
    f->close();
    if (!*f) {
      throw RunFolderError("could not write " + (tmp_ / name).string() +
                           " (disk full or not writable?); no run folder written");
    }
  }
  streams_.clear();
  std::ostringstream marker;
  marker << "# a pumasim run folder: the files pumasim wrote here (it replaces the folder only with --force,\n"
            "# and only while nothing else is in it)\n";
  for (const std::string& name : names_) marker << name << "\n";
  write_file(tmp_ / kRunMarker, marker.str());
  const fs::path parent = parent_of(dir_);
  try {
    const FolderLock lock(parent);  // runs racing to one target swap in turn
    remove_leftovers(parent, base_name(dir_));
    check_run_folder_target(dir_, force_);  // again: the folder may have changed during the run
    if (!fs::exists(fs::symlink_status(dir_))) {
      fs::rename(tmp_, dir_);
    } else if (::renameat2(AT_FDCWD, tmp_.c_str(), AT_FDCWD, dir_.c_str(), RENAME_EXCHANGE) == 0) {
      remove_marked_folder(tmp_);  // the old folder, under the temporary name
    } else {  // a file system without the exchange: two renames
      const fs::path old = temporary_path(dir_, "old");
      fs::rename(dir_, old);
      fs::rename(tmp_, dir_);
      remove_marked_folder(old);
    }
    committed_ = true;
  } catch (const fs::filesystem_error& e) {  // a folder that cannot be renamed: the path, not "internal"
    throw RunFolderError("{{out}} " + dir_.string() + ": " + e.code().message() + " (" + e.path1().string() +
                         "); no run folder written");
  }
}

void write_run_folder(const fs::path& dir, const std::vector<std::pair<std::string, std::string>>& files,
                      bool force) {
  RunFolderWriter w(dir, force);
  for (const auto& [name, content] : files) w.write(name, content);
  w.commit();
}

void write_file_atomically(const fs::path& path, const std::string& content) {
  const fs::path tmp = RunFolderWriter::temporary_path(path, "partial");
  std::ofstream f(tmp, std::ios::binary);
  f << content;
  f.close();
  std::error_code ec;
  if (f) fs::rename(tmp, path, ec);
  if (!f || ec) {
    fs::remove(tmp, ec);
    throw RunFolderError(path.string() + ": could not write the file (missing folder, not writable, or disk full)");
  }
}

}  // namespace pumasim
