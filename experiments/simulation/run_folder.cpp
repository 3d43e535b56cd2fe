#include "experiments/simulation/run_folder.hpp"

#include <fstream>
#include <set>
#include <sstream>

#include <unistd.h>

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
    throw RunFolderError("--out " + d + ": exists and is not a folder; pumasim writes a run into a new folder");
  }
  if (!fs::exists(dir / kRunMarker)) {
    throw RunFolderError("--out " + d + ": the folder exists and is not a pumasim run folder (no " +
                         std::string(kRunMarker) + " marker); pumasim never replaces what it did not write: "
                         "choose a new folder");
  }
  if (!force) {
    throw RunFolderError("--out " + d + ": a pumasim run folder is already there; pass --force to replace it");
  }
  const std::set<std::string> ours = marker_entries(dir);
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name != kRunMarker && !ours.count(name)) {
      throw RunFolderError("--out " + d + ": holds " + name + ", which pumasim did not write; it is not replaced "
                           "(move that file, or choose a new folder)");
    }
  }
}

void write_run_folder(const fs::path& dir, const std::vector<std::pair<std::string, std::string>>& files,
                      bool force) {
  check_run_folder_target(dir, force);
  const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
  std::string base(1, '.');  // built piecewise: GCC 12 warns falsely on "." + string (bug 105329)
  base.append(dir.filename().string()).append(1, '.').append(std::to_string(::getpid()));
  const fs::path tmp = parent / (base + ".partial"), old = parent / (base + ".old");
  try {
    fs::create_directories(parent);
    fs::remove_all(tmp);  // only a leftover of this very process id's earlier attempt
    fs::create_directory(tmp);
    std::ostringstream marker;
    marker << "# a pumasim run folder: the files pumasim wrote here (it replaces the folder only with --force,\n"
              "# and only while nothing else is in it)\n";
    for (const auto& [name, content] : files) {
      write_file(tmp / name, content);
      marker << name << "\n";
    }
    write_file(tmp / kRunMarker, marker.str());
    check_run_folder_target(dir, force);  // again: the folder may have changed during the run
    const bool replace = fs::exists(fs::symlink_status(dir));
    if (replace) fs::rename(dir, old);
    fs::rename(tmp, dir);
    if (replace) fs::remove_all(old);
  } catch (const fs::filesystem_error& e) {  // a folder that cannot be made or renamed: the path, not "internal"
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw RunFolderError("--out " + dir.string() + ": " + e.code().message() + " (" + e.path1().string() +
                         "); no run folder written");
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
}

void write_file_atomically(const fs::path& path, const std::string& content) {
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::string base(1, '.');  // built piecewise, as above (GCC bug 105329)
  base.append(path.filename().string()).append(1, '.').append(std::to_string(::getpid())).append(".partial");
  const fs::path tmp = parent / base;
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
