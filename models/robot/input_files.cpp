#include "models/robot/input_files.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "models/robot/strict_toml.hpp"

namespace pumasim {

namespace {
thread_local InputRecord* innermost = nullptr;

std::string absolute_path(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::absolute(path, ec);
  return ec ? path : p.lexically_normal().string();
}
}  // namespace

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string hex64(std::uint64_t h) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

std::optional<std::string> read_input_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return std::nullopt;
  std::string text;
  char buf[65536];
  std::size_t got = 0;
  while ((got = std::fread(buf, 1, sizeof buf, f)) > 0) {
    text.append(buf, got);
    if (text.size() > kMaxInputBytes) {
      std::fclose(f);
      throw ConfigError(path + ": expected an input file of at most " + std::to_string(kMaxInputBytes >> 20) +
                          " MiB (pumasim's limit on a scene, robot or CSV file), got more");
    }
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return std::nullopt;
  record_input_file(InputFile{absolute_path(path), text.size(), fnv1a64(text)});
  return text;
}

void record_input_file(const InputFile& f) {
  if (innermost) innermost->add(f);
}

std::string unreadable_reason(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec) return ec == std::errc::no_such_file_or_directory ? "no such file" : ec.message();
  if (std::filesystem::is_directory(st)) return "a folder, not a file";
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return std::strerror(errno);
  std::fclose(f);
  return "a read error";
}

InputRecord::InputRecord() : outer_(innermost) { innermost = this; }

InputRecord::~InputRecord() { innermost = outer_; }

void InputRecord::add(const InputFile& f) {
  bool known = false;
  for (const InputFile& g : files_) known = known || (g.path == f.path && g.fnv1a64 == f.fnv1a64);
  if (!known) files_.push_back(f);
  if (outer_) outer_->add(f);
}

std::string describe(const InputFile& f) {
  return f.path + " (fnv1a64 " + hex64(f.fnv1a64) + ", " + std::to_string(f.bytes) + " bytes)";
}

}  // namespace pumasim
