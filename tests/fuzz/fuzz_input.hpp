// Shared by the libFuzzer harnesses (docs/developer-guide/sanitizers-and-fuzzing.md): the input written
// to a file the loaders can read (the loaders take paths, and their messages
// name them), in memory when /dev/shm exists.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <unistd.h>

namespace pumasim::fuzz {

// A file of this process's own: <dir>/pumasim-fuzz-<pid>/<name>.
inline std::string input_path(const std::string& name) {
  const std::filesystem::path base = std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm")
                                                                                : std::filesystem::temp_directory_path();
  const std::filesystem::path dir = base / ("pumasim-fuzz-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// Writes the bytes to `path`; aborts when it cannot (the harness is broken, not the input).
inline void write_input(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) {
    std::perror(path.c_str());
    std::abort();
  }
}

}  // namespace pumasim::fuzz
