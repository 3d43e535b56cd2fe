// The one way the models read a user's file, so that every file a scene reads
// is known by its content.
//
// read_input_file() reads a whole file and records it (absolute path, size,
// FNV-1a 64 of the bytes read) in every InputRecord open on this thread. A
// reader of a new kind of file (a new file-valued scene key) calls it and is
// recorded with no other edit: load_scene opens a record around the whole load,
// and the resolved scene's footer, meta.json and the sweep key are made from
// that record. The bytes hashed are the bytes parsed, not a second read.
// (tests/test_input_files: no file in models/ opens a file another way, and a
// run under strace opens no user file that is not recorded.)
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pumasim {

// A file a load read.
struct InputFile {
  std::string path;         // absolute, lexically normal
  std::size_t bytes = 0;    // its size as read
  std::uint64_t fnv1a64 = 0;  // FNV-1a 64 of the bytes read
  bool operator==(const InputFile&) const = default;
};

// FNV-1a, 64 bits (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
std::uint64_t fnv1a64(std::string_view bytes);

// 16 lower-case hex digits.
std::string hex64(std::uint64_t h);

// The largest input file pumasim reads (a scene, robot, URDF, side file or
// CSV): 16 MiB, over a hundred times the largest shipped one's size, so that
// /dev/zero or a mistaken file fails at once instead of filling memory.
inline constexpr std::size_t kMaxInputBytes = std::size_t{16} << 20;

// The whole file, or nothing when it cannot be read (absent, a directory,
// unreadable); recorded in the open records when read. A file longer than
// kMaxInputBytes is a ConfigError naming it, read no further.
std::optional<std::string> read_input_file(const std::string& path);

// f recorded in the open records as if read now: what a reader that keeps
// a file's product (SceneTemplate) gives its later loads, so that their
// records list the file it read once.
void record_input_file(const InputFile& f);

// Why read_input_file(path) gave nothing, for a message: "no such file",
// "a folder, not a file", "permission denied", ...
std::string unreadable_reason(const std::string& path);

// Collects the files read on this thread while it is alive (records nest: an
// inner one's files are in the outer one's too). A file read twice with the
// same bytes is listed once, in the order first read.
class InputRecord {
 public:
  InputRecord();
  ~InputRecord();
  InputRecord(const InputRecord&) = delete;
  InputRecord& operator=(const InputRecord&) = delete;

  const std::vector<InputFile>& files() const { return files_; }
  void add(const InputFile& f);

 private:
  std::vector<InputFile> files_;
  InputRecord* outer_ = nullptr;
};

// "PATH (fnv1a64 H, N bytes)": how the resolved scene's footer names a file.
std::string describe(const InputFile& f);

}  // namespace pumasim
