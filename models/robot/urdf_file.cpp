#include "models/robot/urdf_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>

#include "models/robot/input_files.hpp"
#include "models/robot/link_inertia.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/strict_toml.hpp"
#include "models/robot/urdf_transmission.hpp"

namespace pumasim {
namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// As for robot files (robot_file.cpp): a bound before any per-joint work.
constexpr std::size_t kMaxUrdfJoints = 256;
// Two joint axes whose directions' cross product is below this are parallel
// (rounding in a URDF's rotations is ~1e-16); below it a DH form treats them
// as parallel, and the rebuilt frames are checked against the URDF's to
// kRebuildTolerance (relative to the robot's size) all the same.
constexpr double kParallel = 1e-9;
constexpr double kRebuildTolerance = 1e-9;
constexpr double kTwoPi = 6.283185307179586;

// A rigid transform: the rotation R and origin p of a frame in another.
struct Frame {
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
  Frame operator*(const Frame& b) const { return {R * b.R, R * b.p + p}; }
  Frame inverse() const { return {R.transpose(), -(R.transpose() * p)}; }
};

Frame frame_of(const urdf::Pose& pose) {
  const urdf::Rotation& r = pose.rotation;
  const Eigen::Quaterniond q(r.w, r.x, r.y, r.z);
  return {q.normalized().toRotationMatrix(), Vec3(pose.position.x, pose.position.y, pose.position.z)};
}

std::string num(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

std::string vec_str(const Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "(%.6g %.6g %.6g)", v.x(), v.y(), v.z());
  return b;
}

bool finite(const urdf::Pose& p) {
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
         std::isfinite(p.rotation.x) && std::isfinite(p.rotation.y) && std::isfinite(p.rotation.z) &&
         std::isfinite(p.rotation.w);
}

// The URDF's path and text, to name the line of a joint or link in messages
// (urdfdom keeps no line numbers): the line of the element's start tag.
class UrdfText {
 public:
  UrdfText(std::string path, std::string text) : path_(std::move(path)), text_(std::move(text)) {}
  const std::string& path() const { return path_; }
  const std::string& text() const { return text_; }

  // "file:line: joint 'name': " (the line left out when the tag is not found).
  std::string where(const std::string& tag, const std::string& name) const {
    const std::string open = "<" + tag;
    for (std::size_t at = text_.find(open); at != std::string::npos; at = text_.find(open, at + 1)) {
      const std::size_t end = text_.find('>', at);
      const std::string head = text_.substr(at, end == std::string::npos ? std::string::npos : end - at);
      if (head.size() > open.size() && !std::isspace(static_cast<unsigned char>(head[open.size()]))) continue;
      if (head.find("name=\"" + name + "\"") == std::string::npos &&
          head.find("name='" + name + "'") == std::string::npos) {
        continue;
      }
      const auto line = 1 + std::count(text_.begin(), text_.begin() + static_cast<std::ptrdiff_t>(at), '\n');
      return path_ + ":" + std::to_string(line) + ": " + tag + " '" + name + "': ";
    }
    return path_ + ": " + tag + " '" + name + "': ";
  }

  [[noreturn]] void fail(const std::string& tag, const std::string& name, const std::string& expected,
                         const std::string& got) const {
    throw ConfigError(where(tag, name) + "expected " + expected + ", got " + got);
  }

 private:
  std::string path_, text_;
};

// ---------------------------------------------------------------- pre-scan

// One linear pass over a URDF's text before urdfdom and TinyXML see it
// (urdf_file.hpp: what it refuses and why). It reads markup as TinyXML 2.6.2
// does where that is XML, so that its counts are TinyXML's, and refuses the
// rest, saying so: its counts are then an upper bound of what TinyXML parses.
class UrdfPrescan {
 public:
  UrdfPrescan(const std::string& path, const std::string& text) : path_(path), s_(text) {}

  void run() {
    if (s_.size() > kMaxUrdfBytes) {
      fail(kMaxUrdfBytes, "a URDF file of at most " + std::to_string(kMaxUrdfBytes) + " bytes (" +
                              std::to_string(kMaxUrdfBytes >> 20) + " MiB)",
           std::to_string(s_.size()) + " bytes, the limit passed on this line");
    }
    check_bytes();
    check_markup();
    check_loops();
  }

 private:
  static bool space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  // TinyXML's names: a letter, '_' or any non-ASCII byte first; then also
  // digits, '-', '.' and ':'.
  static bool name_start(char c) {
    const auto u = static_cast<unsigned char>(c);
    return (u < 0x80 && std::isalpha(u)) || c == '_' || u >= 0x80;
  }
  static bool name_char(char c) {
    const auto u = static_cast<unsigned char>(c);
    return name_start(c) || (u < 0x80 && std::isdigit(u)) || c == '-' || c == '.' || c == ':';
  }

  std::size_t line_of(std::size_t at) const {
    at = std::min(at, s_.size());
    return 1 + static_cast<std::size_t>(std::count(s_.begin(), s_.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  }

  // Up to 24 characters from `at` as the message shows them ("the end of the
  // file" there), other bytes than printable ASCII as \xNN.
  std::string shown(std::size_t at) const {
    if (at >= s_.size()) return "the end of the file";
    std::string out = "'";
    for (std::size_t i = at; i < s_.size() && i < at + 24 && s_[i] != '\n'; ++i) {
      const auto u = static_cast<unsigned char>(s_[i]);
      if (u >= 0x20 && u < 0x7f) {
        out += s_[i];
      } else {
        char b[8];
        std::snprintf(b, sizeof b, "\\x%02X", u);
        out += b;
      }
    }
    return out + "'";
  }

  [[noreturn]] void fail(std::size_t at, const std::string& expected, const std::string& got) const {
    throw ConfigError(path_ + ":" + std::to_string(line_of(at)) + ": expected " + expected + ", got " + got +
                      " (pumasim's check of a URDF before urdfdom's XML parser reads it)");
  }

  bool at(std::size_t i, std::string_view what) const { return s_.compare(i, what.size(), what) == 0; }

  // No NUL, no control character but tab and line breaks, UTF-8 sequences
  // complete, and no byte order mark past the start (TinyXML skips one as
  // whitespace anywhere, and U+FFFE and U+FFFF with it).
  void check_bytes() const {
    const std::size_t n = s_.size();
    for (std::size_t i = 0; i < n;) {
      const auto u = static_cast<unsigned char>(s_[i]);
      if (u == 0) fail(i, "text without a NUL byte (TinyXML would stop reading at it)", "one");
      if ((u < 0x20 && u != '\t' && u != '\n' && u != '\r') || u == 0x7f) {
        fail(i, "text without control characters (tab and line breaks only)", shown(i));
      }
      if (u < 0x80) {
        ++i;
        continue;
      }
      const std::size_t len = u >= 0xc2 && u <= 0xdf ? 2 : u >= 0xe0 && u <= 0xef ? 3 : u >= 0xf0 && u <= 0xf4 ? 4 : 0;
      bool whole = len > 0 && i + len <= n;
      for (std::size_t k = 1; whole && k < len; ++k) whole = (static_cast<unsigned char>(s_[i + k]) & 0xc0) == 0x80;
      if (!whole) {
        fail(i, "UTF-8 text (TinyXML steps over a character by its first byte: a truncated one makes it read past "
                "the text)", "the bytes " + shown(i));
      }
      if (u == 0xef && ((at(i, "\xEF\xBB\xBF") && i > 0) || at(i, "\xEF\xBF\xBE") || at(i, "\xEF\xBF\xBF"))) {
        fail(i, "no byte order mark (U+FEFF) past the start, no U+FFFE or U+FFFF (TinyXML reads them as whitespace)",
             "one");
      }
      i += len;
    }
  }

  // Every '&' in text or an attribute value in [from, to): one of XML's
  // five entities or a character reference of an XML character.
  void check_references(std::size_t from, std::size_t to) const {
    for (std::size_t i = s_.find('&', from); i < to; i = s_.find('&', i + 1)) {
      bool ok = false;
      for (const std::string_view e : {"&lt;", "&gt;", "&amp;", "&quot;", "&apos;"}) ok = ok || at(i, e);
      if (!ok && at(i, "&#")) {
        const bool hex = at(i, "&#x");
        std::size_t j = i + (hex ? 3 : 2);
        const std::size_t digits_from = j;
        unsigned long value = 0;
        for (; j < to && j - digits_from < (hex ? 6u : 7u); ++j) {
          const auto d = static_cast<unsigned char>(s_[j]);
          if (!(hex ? std::isxdigit(d) : std::isdigit(d))) break;
          const int digit = std::isdigit(d) ? d - '0' : std::tolower(d) - 'a' + 10;
          value = value * (hex ? 16 : 10) + static_cast<unsigned long>(digit);
        }
        const bool xml_char = value == 0x9 || value == 0xa || value == 0xd || (value >= 0x20 && value <= 0xd7ff) ||
                              (value >= 0xe000 && value <= 0xfffd) || (value >= 0x10000 && value <= 0x10ffff);
        ok = j > digits_from && j < to && s_[j] == ';' && xml_char;
      }
      if (!ok) {
        fail(i, "one of &lt; &gt; &amp; &quot; &apos; or a character reference &#N; (at most 7 digits) or &#xH; "
                "(at most 6) of an XML character after '&' (write a lone '&' as &amp;)", shown(i));
      }
    }
  }

  // A name at i (empty when there is none).
  std::string_view name_at(std::size_t i) const {
    if (i >= s_.size() || !name_start(s_[i])) return {};
    std::size_t j = i + 1;
    while (j < s_.size() && name_char(s_[j])) ++j;
    return std::string_view(s_).substr(i, j - i);
  }

  std::size_t skip_space(std::size_t i) const {
    while (i < s_.size() && space(s_[i])) ++i;
    return i;
  }

  // A processing instruction (<?xml ...?> among them) from i: TinyXML ends it
  // at its first '>', outside quotes for <?xml; so no '>' in quotes, and that
  // '>' is the one of "?>".
  std::size_t processing_instruction(std::size_t i) const {
    char quote = 0;
    std::size_t j = i + 2;
    for (; j < s_.size(); ++j) {
      const char c = s_[j];
      if (quote) {
        if (c == quote) quote = 0;
        if (c == '>') fail(j, "no '>' inside a quoted value of a processing instruction <? ... ?>", "one");
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        break;
      }
    }
    if (j >= s_.size()) fail(i, "a processing instruction <? closed by ?>", "none before the end of the file");
    if (j < i + 3 || s_[j - 1] != '?') {
      fail(j, "'?>' closing the processing instruction that starts with '<?' at its first '>'", shown(j - 1));
    }
    return j + 1;
  }

  // Element tags, and what may hold a '<' that is no tag.
  void check_markup() {
    const std::size_t n = s_.size();
    std::size_t i = at(0, "\xEF\xBB\xBF") ? 3 : 0;
    for (;;) {
      const std::size_t lt = std::min(s_.find('<', i), n);
      check_references(i, lt);
      if (lt == n) break;
      i = lt;
      if (at(i, "<!--")) {
        const std::size_t end = s_.find("-->", i + 4);
        if (end == std::string::npos) fail(i, "a comment <!-- closed by -->", "none before the end of the file");
        i = end + 3;
      } else if (at(i, "<![CDATA[")) {
        const std::size_t end = s_.find("]]>", i + 9);
        if (end == std::string::npos) fail(i, "a CDATA section closed by ]]>", "none before the end of the file");
        i = end + 3;
      } else if (at(i, "<?")) {
        i = processing_instruction(i);
      } else if (at(i, "<!DOCTYPE")) {
        const std::size_t end = s_.find('>', i);
        if (end == std::string::npos) fail(i, "a <!DOCTYPE closed by '>'", "none before the end of the file");
        const std::size_t bracket = s_.find('[', i);
        if (bracket < end) {
          fail(bracket, "a <!DOCTYPE without an internal subset (TinyXML reads none: its entities would not be "
                        "what an XML parser makes of them)", "'['");
        }
        i = end + 1;
      } else if (at(i, "<!")) {
        fail(i, "a comment <!--, a CDATA section <![CDATA[ or a <!DOCTYPE after '<!'", shown(i));
      } else if (at(i, "</")) {
        const std::string_view name = name_at(i + 2);
        const std::size_t j = skip_space(i + 2 + name.size());
        if (open_.empty()) fail(i, "no closing tag where no element is open", shown(i));
        if (name != open_.back().name || j >= n || s_[j] != '>') {
          fail(i, "</" + std::string(open_.back().name) + "> closing the element opened on line " +
                      std::to_string(line_of(open_.back().at)),
               shown(i));
        }
        open_.pop_back();
        i = j + 1;
      } else {
        i = start_tag(i);
      }
    }
    if (!open_.empty()) {
      fail(open_.back().at, "</" + std::string(open_.back().name) + "> closing the element opened here",
           "the end of the file");
    }
  }

  // An attribute value [from, to) as TinyXML reads it: the entities and
  // character references (check_references passed them) replaced.
  std::string decoded(std::size_t from, std::size_t to) const {
    std::string out;
    for (std::size_t i = from; i < to; ++i) {
      if (s_[i] != '&') {
        out += s_[i];
        continue;
      }
      const std::size_t semi = s_.find(';', i);
      const std::string_view ref = std::string_view(s_).substr(i + 1, semi - i - 1);
      i = semi;
      if (ref == "lt") out += '<';
      else if (ref == "gt") out += '>';
      else if (ref == "amp") out += '&';
      else if (ref == "quot") out += '"';
      else if (ref == "apos") out += '\'';
      else {
        const bool hex = ref[1] == 'x';
        const unsigned long c = std::stoul(std::string(ref.substr(hex ? 2 : 1)), nullptr, hex ? 16 : 10);
        if (c < 0x80) {
          out += static_cast<char>(c);
        } else if (c < 0x800) {
          out += static_cast<char>(0xc0 | (c >> 6));
          out += static_cast<char>(0x80 | (c & 0x3f));
        } else if (c < 0x10000) {
          out += static_cast<char>(0xe0 | (c >> 12));
          out += static_cast<char>(0x80 | ((c >> 6) & 0x3f));
          out += static_cast<char>(0x80 | (c & 0x3f));
        } else {
          out += static_cast<char>(0xf0 | (c >> 18));
          out += static_cast<char>(0x80 | ((c >> 12) & 0x3f));
          out += static_cast<char>(0x80 | ((c >> 6) & 0x3f));
          out += static_cast<char>(0x80 | (c & 0x3f));
        }
      }
    }
    return out;
  }

  // The start tag at i. Returns where it ends.
  std::size_t start_tag(std::size_t i) {
    const std::size_t n = s_.size();
    const std::string_view name = name_at(i + 1);
    if (name.empty()) {
      fail(i, "an element's name (a letter or '_' first), a comment <!--, CDATA, <? or <!DOCTYPE after '<' "
              "(write a '<' in text as &lt;)",
           shown(i));
    }
    const std::string tag = "<" + std::string(name) + ">";
    const std::size_t depth = open_.size() + 1;
    if (depth > static_cast<std::size_t>(kMaxUrdfDepth)) {
      fail(i, "elements nested at most " + std::to_string(kMaxUrdfDepth) + " deep",
           tag + " at depth " + std::to_string(depth));
    }
    if (++elements_ > kMaxUrdfElements) {
      fail(i, "at most " + std::to_string(kMaxUrdfElements) + " elements", "more: " + tag + " is one past them");
    }
    const bool joint = name == "joint";
    if (joint && joints_.size() == kMaxUrdfJointElements) {
      fail(i, "at most " + std::to_string(kMaxUrdfJointElements) + " <joint> elements",
           "more: this one is one past them");
    }
    if (joint) joints_.push_back({i, "", "", "", false, false});
    // A <parent> or <child> right inside a <joint>: urdfdom reads the first one's link.
    JointLinks* owner = !open_.empty() && open_.back().joint != kNone ? &joints_[open_.back().joint] : nullptr;
    const bool parent = owner && name == "parent" && !owner->has_parent;
    const bool child = owner && name == "child" && !owner->has_child;
    if (parent) owner->has_parent = true;
    if (child) owner->has_child = true;
    int attributes = 0;
    std::size_t j = i + 1 + name.size();
    for (;;) {
      j = skip_space(j);
      if (j >= n) fail(i, "the tag " + tag + " closed by '>' or '/>'", "the end of the file");
      if (s_[j] == '/') {
        if (j + 1 >= n || s_[j + 1] != '>') fail(j, "'/>' closing the tag " + tag, shown(j));
        return j + 2;
      }
      if (s_[j] == '>') {
        open_.push_back({name, i, joint ? joints_.size() - 1 : kNone});
        return j + 1;
      }
      const std::string_view attribute = name_at(j);
      if (attribute.empty() || (!space(s_[j - 1]) && s_[j - 1] != '"' && s_[j - 1] != '\'')) {
        fail(j, "an attribute's name, '>' or '/>' in the tag " + tag, shown(j));
      }
      if (++attributes > kMaxUrdfAttributes) {
        fail(j, "at most " + std::to_string(kMaxUrdfAttributes) + " attributes on an element",
             "more on " + tag + ": '" + std::string(attribute) + "' is one past them");
      }
      j = skip_space(j + attribute.size());
      if (j >= n || s_[j] != '=') {
        fail(j, "'=' after the attribute '" + std::string(attribute) + "' of " + tag, shown(j));
      }
      j = skip_space(j + 1);
      if (j >= n || (s_[j] != '"' && s_[j] != '\'')) {
        fail(j, "a quoted value of the attribute '" + std::string(attribute) + "' of " + tag, shown(j));
      }
      const std::size_t end = s_.find(s_[j], j + 1);
      if (end == std::string::npos) {
        fail(j, "the value of the attribute '" + std::string(attribute) + "' of " + tag + " closed by its quote",
             "none before the end of the file");
      }
      check_references(j + 1, end);
      if (joint && attribute == "name") joints_.back().name = decoded(j + 1, end);
      if (parent && attribute == "link") owner->parent = decoded(j + 1, end);
      if (child && attribute == "link") owner->child = decoded(j + 1, end);
      j = end + 1;
    }
  }

  // No loop of links through the joints' parent and child links: urdfdom
  // links each parent to its child by a shared pointer (Link::child_links),
  // and when it then refuses the file (another root, a missing link) it drops
  // the model with the loop in it, a leak (tests/fuzz/regressions/urdf/
  // loop-two-roots-leak). Every <joint> with a <parent> and a <child> counts, not
  // only those urdfdom reads (the <robot>'s children): a loop among them is
  // refused too.
  void check_loops() const {
    std::map<std::string, std::vector<std::size_t>> from;  // link -> the joints it is the parent of
    for (std::size_t k = 0; k < joints_.size(); ++k) {
      if (joints_[k].has_parent && joints_[k].has_child) from[joints_[k].parent].push_back(k);
    }
    // Depth-first from every link, iteratively: a joint whose child link is
    // on the current path closes a loop.
    std::map<std::string, int> state;  // 1: on the path, 2: done
    for (const auto& [root, out] : from) {
      if (state[root] != 0) continue;
      std::vector<std::pair<std::string, std::size_t>> path{{root, 0}};  // link, next of its joints
      state[root] = 1;
      while (!path.empty()) {
        auto& [link, next] = path.back();
        const auto it = from.find(link);
        if (it == from.end() || next == it->second.size()) {
          state[link] = 2;
          path.pop_back();
          continue;
        }
        const std::size_t k = it->second[next++];
        const std::string& child = joints_[k].child;
        if (state[child] == 1) {
          std::string loop;
          std::size_t p = 0;
          while (path[p].first != child) ++p;
          for (; p < path.size(); ++p) loop += path[p].first + " -> ";
          fail(joints_[k].at,
               "links joined without a loop (urdfdom leaks the links of a loop when it refuses the file)",
               "joint '" + joints_[k].name + "' closing the loop " + loop + child);
        }
        if (state[child] == 0) {
          state[child] = 1;
          path.push_back({child, 0});
        }
      }
    }
  }

  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  struct Open {
    std::string_view name;
    std::size_t at;
    std::size_t joint;  // its index in joints_ for a <joint>, else kNone
  };
  struct JointLinks {
    std::size_t at;  // where its start tag is
    std::string name, parent, child;
    bool has_parent, has_child;
  };

  const std::string& path_;
  const std::string& s_;
  std::vector<Open> open_;
  std::size_t elements_ = 0;
  std::vector<JointLinks> joints_;
};

// urdfdom reports through console_bridge; its messages are collected while
// it parses (one parse at a time: the handler is global). Errors are kept
// apart: urdfdom may log one ("Could not parse inertial element for Link
// [x]": a mass of "17.4kg" or "nan") and still return a model with that
// element left at its default (a mass of 0).
class CollectedLog : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_WARN) return;
    messages += (messages.empty() ? "" : "; ") + text;
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors.push_back(text);
  }
  std::string messages;
  std::vector<std::string> errors;
};

// The errors urdfdom logged while returning a model anyway: refused, naming
// the file, the line of the element they concern and urdfdom's words. It
// logs the detail first ("Inertial: mass [17.4kg] is not a float") and then
// the element it dropped ("Could not parse inertial element for Link [l1]").
// An error in a <visual> or <collision> (the group ending with such a
// summary) is not refused: pumasim reads neither, so the model it simulates
// does not depend on them.
void refuse_logged_errors(const std::vector<std::string>& errors, const UrdfText& t) {
  std::vector<std::string> group;
  for (const std::string& e : errors) {
    group.push_back(e);
    const bool summary = e.rfind("Could not parse ", 0) == 0;
    if (!summary) continue;
    const bool ignored = e.find("visual element") != std::string::npos || e.find("collision element") != std::string::npos;
    if (!ignored) break;
    group.clear();
  }
  if (group.empty()) return;
  std::string words;
  for (const std::string& e : group) words += (words.empty() ? "" : "; ") + e;
  const std::string& last = group.back();
  const std::size_t open = last.find('['), close = last.find(']', open == std::string::npos ? 0 : open);
  if (last.rfind("Could not parse ", 0) == 0 && open != std::string::npos && close != std::string::npos) {
    const bool link = last.find("Link [") != std::string::npos;
    t.fail(link ? "link" : "joint", last.substr(open + 1, close - open - 1), "elements urdfdom parses without error",
           "urdfdom's error: " + words);
  }
  throw ConfigError(t.path() + ": URDF error: expected a document urdfdom parses without error, got: " + words);
}

// urdfdom's model, released without leaking: joints that make a loop of
// links (a joint from a link back to one before it) become links that hold
// each other in their child_links (shared pointers), which nothing then
// frees (LeakSanitizer, tests/fuzz/regressions/urdf/loop-back-leak).
// The pre-scan refuses such loops (check_loops: it has to, for urdfdom leaks
// the loop itself when it then refuses the file); the lists are cleared here
// too, so that a model that reaches the loader never leaks, whatever ends
// the load.
class UrdfModel {
 public:
  explicit UrdfModel(urdf::ModelInterfaceSharedPtr m) : m_(std::move(m)) {}
  ~UrdfModel() {
    for (auto& [name, link] : m_->links_) {
      if (!link) continue;
      link->child_links.clear();
      link->child_joints.clear();
    }
  }
  UrdfModel(const UrdfModel&) = delete;
  UrdfModel& operator=(const UrdfModel&) = delete;
  const urdf::ModelInterface& operator*() const { return *m_; }

 private:
  urdf::ModelInterfaceSharedPtr m_;
};

// The model urdfdom returns (ConfigError when none), and the errors it
// logged while returning it (for refuse_logged_errors).
urdf::ModelInterfaceSharedPtr parse_urdf(const UrdfText& t, std::vector<std::string>& errors) {
  static std::mutex one_at_a_time;
  const std::lock_guard<std::mutex> lock(one_at_a_time);
  CollectedLog log;
  console_bridge::useOutputHandler(&log);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(t.text());
  } catch (const std::exception& e) {
    log.messages += std::string(log.messages.empty() ? "" : "; ") + e.what();
    model.reset();
  }
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    throw ConfigError(t.path() + ": URDF error: expected a URDF document that urdfdom reads, got: " +
                      (log.messages.empty() ? "(urdfdom gave no message)" : log.messages));
  }
  errors = log.errors;
  return model;
}

// Every joint one of a serial chain's kinds and each link the child of one
// joint at most (two: a closed loop). Mimic joints and <dynamics> are
// checked once the chain is known (check_chain_joints): off the chain, a
// mimic joint is held and its friction has no effect.
void check_joints(const urdf::ModelInterface& m, const UrdfText& t) {
  std::map<std::string, std::string> parent_joint;  // child link -> joint
  for (const auto& [name, j] : m.joints_) {
    if (j->type == urdf::Joint::FLOATING || j->type == urdf::Joint::PLANAR || j->type == urdf::Joint::UNKNOWN) {
      t.fail("joint", name, "a revolute, continuous, prismatic or fixed joint (pumasim simulates fixed-base serial chains)",
             j->type == urdf::Joint::FLOATING ? "type=\"floating\"" : j->type == urdf::Joint::PLANAR ? "type=\"planar\"" : "an unknown type");
    }
    if (!finite(j->parent_to_joint_origin_transform)) t.fail("joint", name, "a finite <origin>", "a non-finite number");
    const auto [it, first] = parent_joint.emplace(j->child_link_name, name);
    if (!first) {
      t.fail("link", j->child_link_name, "a serial chain: each link the child of one joint",
             "the child of joints '" + it->second + "' and '" + name + "' (a closed loop)");
    }
  }
}

// ---------------------------------------------------------------- side file

struct SideFile {
  std::string path;  // empty: none
  toml::table doc;   // as parsed, read twice: peek_side_file, read_side_file
  Vec3 gravity{0.0, 0.0, -9.81};
  std::string flange;
  std::string tip;               // [robot] tip: the chain is the path from the root link to it
  bool refuse_dynamics = false;  // [robot] refuse_dynamics: a <dynamics> damping or friction is an error
  std::map<std::string, std::pair<double, double>> drive;  // joint -> (rotor inertia, gear ratio)
  std::map<std::string, std::string> excuse;                // joint -> inconsistent_inertia
  std::map<std::string, double> held;                       // [held]: a moving joint off the chain -> its value
  std::vector<NamedPose> poses;
};

[[noreturn]] void side_fail(const SideFile& s, const std::string& table, const std::string& key,
                            const std::string& expected, const std::string& got) {
  StrictTable root(s.doc, s.path, "");
  if (table.empty()) root.fail(key, expected, got);
  root.table(table).fail(key, expected, got);
}

// What the chain's walk needs of the side file (tip, refuse_dynamics,
// [held]), read with their types checked; read_side_file reads the rest and
// refuses unknown keys once the chain is known.
SideFile peek_side_file(const std::string& urdf_path) {
  SideFile s;
  std::error_code ec;
  if (!std::filesystem::exists(urdf_side_file(urdf_path), ec)) return s;
  s.path = urdf_side_file(urdf_path);
  s.doc = parse_toml_file(s.path);
  StrictTable root(s.doc, s.path, "");
  // An unknown key before the walk: a misspelt tip is named as such, not as a tree.
  root.expect_only({"robot", "joint", "held", "poses"});
  if (auto robot = root.optional_table("robot")) {
    robot->expect_only({"gravity", "flange", "tip", "refuse_dynamics"});
    s.tip = robot->string_or("tip", "");
    s.refuse_dynamics = robot->boolean_or("refuse_dynamics", false);
  }
  if (auto held = root.optional_table("held")) {
    for (const std::string& name : held->keys()) s.held[name] = held->number(name);
  }
  return s;
}

std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The links no joint leaves (the tips a chain may end at), sorted.
std::vector<std::string> leaf_links(const urdf::ModelInterface& m) {
  std::vector<std::string> out;
  for (const auto& [name, l] : m.links_) {
    if (l->child_joints.empty()) out.push_back(name);
  }
  return out;
}

// ---------------------------------------------------------------- the chain

// Which links the chain runs through: with the side file's tip, the path
// from the root link to it; without, every link (a serial chain, or refused
// as a tree).
struct ChainPath {
  const urdf::Link* tip = nullptr;
  std::set<const urdf::Link*> links;
  bool on(const urdf::Link* l) const { return !tip || links.count(l) > 0; }
};

ChainPath chain_path(const urdf::ModelInterface& m, const SideFile& s) {
  ChainPath p;
  if (s.tip.empty()) return p;
  const auto it = m.links_.find(s.tip);
  if (it == m.links_.end()) {
    side_fail(s, "robot", "tip", "a link of the URDF (its leaves: " + listed(leaf_links(m)) + ")", "'" + s.tip + "'");
  }
  p.tip = it->second.get();
  for (const urdf::Link* l = p.tip; l; l = l->getParent().get()) p.links.insert(l);
  return p;
}

// The joint's unit axis, or ConfigError for a zero or non-finite one.
Vec3 unit_axis(const urdf::Joint& j, const UrdfText& t) {
  const Vec3 axis(j.axis.x, j.axis.y, j.axis.z);
  // Scaled by its largest component before the norm: (1e200, 1e200, 0)'s
  // squared norm overflows, and normalized() then returned (0, 0, 0).
  const double largest = axis.allFinite() ? axis.cwiseAbs().maxCoeff() : 0.0;
  if (!axis.allFinite() || !(largest > 0) || largest * (axis / largest).norm() < 1e-12) {
    t.fail("joint", j.name, "a non-zero <axis xyz>", vec_str(axis));
  }
  return (axis / largest).normalized();
}

// A moving joint's motion at value q: a turn about its axis, or a slide along it.
Frame motion(const urdf::Joint& j, double q, const UrdfText& t) {
  const Vec3 u = unit_axis(j, t);
  if (j.type == urdf::Joint::PRISMATIC) return {Mat3::Identity(), q * u};
  return {Eigen::AngleAxisd(q, u).toRotationMatrix(), Vec3::Zero()};
}

// A moving joint off the chain, held: its value and why. The side file's
// [held] value; else a mimic joint's multiplier x its leader's held value +
// offset; else 0, or the limit nearest 0 when 0 is outside its limits.
struct Held {
  double q = 0.0;
  std::string why;
};

Held held_value(const urdf::ModelInterface& m, const urdf::Joint& j, const SideFile& s, const ChainPath& p,
                const UrdfText& t, int depth = 0) {
  const bool limited = j.type != urdf::Joint::CONTINUOUS && j.limits;
  const double lo = limited ? j.limits->lower : -HUGE_VAL, hi = limited ? j.limits->upper : HUGE_VAL;
  if (!(lo <= hi)) t.fail("joint", j.name, "<limit> with lower <= upper", "lower=\"" + num(lo) + "\" upper=\"" + num(hi) + "\"");
  if (const auto it = s.held.find(j.name); it != s.held.end()) {
    if (!(it->second >= lo && it->second <= hi)) {
      side_fail(s, "held", j.name, "a value within joint '" + j.name + "''s limits [" + num(lo) + ", " + num(hi) + "]",
                num(it->second));
    }
    return {it->second, "the side file's [held]"};
  }
  if (j.mimic) {
    const auto leader = m.joints_.find(j.mimic->joint_name);
    if (leader == m.joints_.end() || leader->second->type == urdf::Joint::FIXED) {
      t.fail("joint", j.name, "a <mimic joint> naming a moving joint of the URDF", "'" + j.mimic->joint_name + "'");
    }
    const urdf::Joint& L = *leader->second;
    const std::string side = urdf_side_file(t.path());
    if (p.on(m.links_.at(L.child_link_name).get())) {
      t.fail("joint", j.name,
             "a value for it in [held] of " + side + ": it mimics joint '" + L.name +
                 "' of the chain, whose motion a mass merged at a fixed pose cannot follow",
             "none");
    }
    if (depth > 16) t.fail("joint", j.name, "mimic joints that lead back to a joint of their own (no cycle)", "a cycle");
    const Held h = held_value(m, L, s, p, t, depth + 1);
    const double q = j.mimic->multiplier * h.q + j.mimic->offset;
    if (!std::isfinite(q)) t.fail("joint", j.name, "a finite <mimic multiplier offset>", "a non-finite value");
    if (!(q >= lo && q <= hi)) {
      t.fail("joint", j.name,
             "a mimic value within its limits [" + num(lo) + ", " + num(hi) + "], or a value for it in [held] of " + side,
             num(j.mimic->multiplier) + " x " + num(h.q) + " + " + num(j.mimic->offset) + " = " + num(q) +
                 " (it mimics '" + L.name + "')");
    }
    return {q, "mimics '" + L.name + "' (" + h.why + "): " + num(j.mimic->multiplier) + " x " + num(h.q) + " + " +
                   num(j.mimic->offset)};
  }
  const double q = std::clamp(0.0, lo, hi);
  return {q, q == 0.0 ? "0, within its limits (no value in [held])" : "its limit nearest 0 (no value in [held])"};
}

// One rigid body: the links joined by fixed joints to the child link of a
// moving joint (or to the root: the ground), and the links off the chain
// behind them (held: ChainPath, held_value), each with its frame in the
// body's frame (the first link's), and the moving joint that leaves it.
struct Cluster {
  std::vector<std::pair<const urdf::Link*, Frame>> links;
  const urdf::Joint* next = nullptr;
  Frame next_origin;  // the next joint's frame at q = 0, in this body's frame
  std::string next_from;
};

Cluster gather(const urdf::ModelInterface& m, const urdf::Link& first, const ChainPath& path, const SideFile& s,
               const UrdfText& t, std::vector<std::string>& merged) {
  Cluster c;
  std::vector<std::pair<const urdf::Link*, Frame>> todo{{&first, Frame{}}};
  while (!todo.empty()) {
    const auto [link, T] = todo.back();
    todo.pop_back();
    c.links.push_back({link, T});
    for (const auto& j : link->child_joints) {
      const Frame Tj = T * frame_of(j->parent_to_joint_origin_transform);
      const urdf::Link* child = m.links_.at(j->child_link_name).get();
      if (j->type == urdf::Joint::FIXED) {
        todo.push_back({child, Tj});
        continue;
      }
      if (!path.on(child)) {
        const Held h = held_value(m, *j, s, path, t);
        todo.push_back({child, Tj * motion(*j, h.q, t)});
        merged.push_back("joint '" + j->name + "' (off the chain) held at " + num(h.q) +
                         (j->type == urdf::Joint::PRISMATIC ? " m" : " rad") + " (" + h.why + "): link '" +
                         child->name + "' and the links after it merged into the body of link '" + first.name + "'");
        continue;
      }
      if (c.next) {
        t.fail("joint", j->name,
               "a serial chain: one moving joint leaving each rigid body; for a tree, the chain's tip in the side "
               "file " + urdf_side_file(t.path()) + ": [robot] tip = \"<link>\", the chain's last link (the URDF's leaves: " +
                   listed(leaf_links(m)) + "; the links off the chain are then merged as fixed masses)",
               "joints '" + c.next->name + "' (from link '" + c.next_from + "') and '" + j->name + "' (from link '" +
                   link->name + "') both leaving the body of link '" + first.name + "' (a tree)");
      }
      c.next = j.get();
      c.next_origin = Tj;
      c.next_from = link->name;
    }
  }
  return c;
}

// The chain from the root: clusters[0] is the ground, clusters[k] the body
// moved by joints[k - 1]; merged: the joints held off the chain, as
// provenance lines.
struct UrdfChain {
  std::vector<Cluster> clusters;
  std::vector<const urdf::Joint*> joints;
  std::vector<std::string> merged;
};

UrdfChain walk(const urdf::ModelInterface& m, const ChainPath& path, const SideFile& s, const UrdfText& t) {
  UrdfChain c;
  const urdf::Link* link = m.getRoot().get();
  std::size_t visited = 0;
  for (;;) {
    c.clusters.push_back(gather(m, *link, path, s, t, c.merged));
    visited += c.clusters.back().links.size();
    const urdf::Joint* next = c.clusters.back().next;
    if (!next) break;
    if (c.joints.size() == kMaxUrdfJoints) {
      t.fail("joint", next->name, "at most " + std::to_string(kMaxUrdfJoints) + " moving joints", "more");
    }
    c.joints.push_back(next);
    link = m.links_.at(next->child_link_name).get();
  }
  if (c.joints.empty()) {
    throw ConfigError(t.path() + ": robot '" + m.getName() +
                      "': expected at least one revolute, continuous or prismatic joint" +
                      (path.tip ? " between the root link and the tip '" + path.tip->name + "'" : "") + ", got none");
  }
  if (visited != m.links_.size()) {
    std::set<std::string> seen;
    for (const Cluster& cl : c.clusters) {
      for (const auto& l : cl.links) seen.insert(l.first->name);
    }
    for (const auto& [name, l] : m.links_) {
      if (!seen.count(name)) {
        t.fail("link", name, "a link connected to the root link '" + m.getRoot()->name + "'", "one that is not");
      }
    }
  }
  return c;
}

// The chain's joints: none a mimic joint (off the chain one is held), and
// <dynamics> damping and friction finite and >= 0, or none when the side
// file refuses them.
void check_chain_joints(const UrdfChain& c, const SideFile& s, const UrdfText& t) {
  for (const urdf::Joint* j : c.joints) {
    if (j->mimic) {
      t.fail("joint", j->name,
             "a joint of the chain with its own variable (pumasim has no coupled joints; a mimic joint off the "
             "chain, past the side file's [robot] tip, is held)",
             "<mimic joint=\"" + j->mimic->joint_name + "\">");
    }
    if (!j->dynamics || (j->dynamics->damping == 0.0 && j->dynamics->friction == 0.0)) continue;
    const std::string got = "damping=\"" + num(j->dynamics->damping) + "\" friction=\"" + num(j->dynamics->friction) + "\"";
    if (s.refuse_dynamics) {
      t.fail("joint", j->name, "no <dynamics> damping or friction ([robot] refuse_dynamics = true in " + s.path + ")", got);
    }
    if (!(j->dynamics->damping >= 0.0 && j->dynamics->friction >= 0.0) || !std::isfinite(j->dynamics->damping) ||
        !std::isfinite(j->dynamics->friction)) {
      t.fail("joint", j->name, "<dynamics> with finite damping >= 0 and friction >= 0", got);
    }
  }
}

// Mass, centre of mass and inertia about it of a cluster's links, in the
// body's frame: the parallel-axis theorem about the common centre of mass.
JointParams body_inertia(const Cluster& c, const UrdfText& t) {
  struct Part {
    double m;
    Vec3 c;
    Mat3 I;
  };
  std::vector<Part> parts;
  double mass = 0;
  Vec3 first_moment = Vec3::Zero();
  for (const auto& [link, T] : c.links) {
    const urdf::Inertial* in = link->inertial.get();
    if (!in) continue;  // no <inertial>: a link without mass
    Mat3 I;
    I << in->ixx, in->ixy, in->ixz, in->ixy, in->iyy, in->iyz, in->ixz, in->iyz, in->izz;
    if (!finite(in->origin) || !I.allFinite() || !std::isfinite(in->mass)) {
      t.fail("link", link->name, "a finite <inertial>", "a non-finite number");
    }
    if (in->mass < 0) t.fail("link", link->name, "a mass >= 0", num(in->mass));
    const Frame F = T * frame_of(in->origin);
    parts.push_back({in->mass, F.p, F.R * I * F.R.transpose()});
    mass += in->mass;
    first_moment += in->mass * F.p;
  }
  JointParams J;
  J.mass = mass;
  J.com = mass > 0 ? Vec3(first_moment / mass) : Vec3::Zero();
  for (const Part& p : parts) {
    const Vec3 d = p.c - J.com;
    J.inertia += p.I + p.m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  return J;
}

// ---------------------------------------------------------------- DH form

struct AxisLine {
  Vec3 o, u;  // a point on the axis and its unit direction, in the base frame
};

// A unit vector normal to u: hint without its component along u, or, when
// that vanishes, the base x or y axis without theirs.
Vec3 normal_to(const Vec3& u, const Vec3& hint) {
  const Vec3 x = hint - hint.dot(u) * u;
  if (x.norm() > 1e-6) return x.normalized();
  const Vec3 ex = Vec3::UnitX() - u.x() * u, ey = Vec3::UnitY() - u.y() * u;
  return (ex.norm() >= ey.norm() ? ex : ey).normalized();
}

// Modified DH frame k at q = 0 (Craig): z on axis k; x on the common normal
// to axis k+1 and the origin at its foot on axis k. Parallel axes (and the
// last axis) have no unique normal: the origin is then the point of axis k
// nearest the previous frame's origin (the URDF joint's origin for k = 0),
// so that d_k = 0, and x the normal towards axis k+1 through it, or the
// previous x (coincident axes, the last axis; the base x axis for k = 0).
std::vector<Frame> dh_frames(const std::vector<AxisLine>& L) {
  const std::size_t n = L.size();
  std::vector<Frame> D(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3& u = L[k].u;
    const Vec3 ref = k == 0 ? L[0].o : D[k - 1].p;
    Vec3 O = L[k].o + (ref - L[k].o).dot(u) * u;
    Vec3 hint = k == 0 ? Vec3(Vec3::UnitX()) : Vec3(D[k - 1].R.col(0));
    if (k + 1 < n) {
      const Vec3& v = L[k + 1].u;
      const Vec3 w = u.cross(v);
      if (w.norm() > kParallel) {  // skew or intersecting: the common normal, from the closest points
        const Vec3 r = L[k].o - L[k + 1].o;
        const double b = u.dot(v), d = u.dot(r), e = v.dot(r), den = 1 - b * b;
        O = L[k].o + ((b * e - d) / den) * u;
        const Vec3 gap = L[k + 1].o + ((e - b * d) / den) * v - O;
        hint = gap.dot(w) < 0 && gap.norm() > 1e-12 ? Vec3(-w) : w;
      } else {
        const Vec3 gap = L[k + 1].o - O, across = gap - gap.dot(u) * u;
        if (across.norm() > 1e-12) hint = across;
      }
    }
    const Vec3 x = normal_to(u, hint);
    D[k].R.col(0) = x;
    D[k].R.col(1) = u.cross(x);
    D[k].R.col(2) = u;
    D[k].p = O;
  }
  return D;
}

// The DH rows between consecutive frames: row 0 is the identity (DH frame 0
// is frame 1 at q = 0, placed by the base transform).
void dh_rows(const std::vector<Frame>& D, RobotModel& model) {
  for (std::size_t k = 1; k < D.size(); ++k) {
    const Frame& P = D[k - 1];
    const Frame& C = D[k];
    JointParams& J = model.joints[k];
    J.alpha = std::atan2(P.R.col(2).cross(C.R.col(2)).dot(P.R.col(0)), P.R.col(2).dot(C.R.col(2)));
    J.a = (C.p - P.p).dot(P.R.col(0));
    const double along = (C.p - P.p).dot(C.R.col(2));
    const double angle = std::atan2(P.R.col(0).cross(C.R.col(0)).dot(C.R.col(2)), P.R.col(0).dot(C.R.col(0)));
    if (J.prismatic()) {
      J.theta = angle;
      J.offset = along;
    } else {
      J.d = along;
      J.offset = angle;
    }
  }
  model.base_R = D[0].R;
  model.base_p = D[0].p;
}

// The DH rows rebuild the frames they came from (a check of the conversion:
// nearly parallel axes, taken as parallel, are the one way they could not).
void check_rebuilt(const RobotModel& model, const std::vector<Frame>& D, const std::vector<AxisLine>& L,
                   const UrdfChain& c, const UrdfText& t) {
  double size = 1.0;
  for (const AxisLine& l : L) size = std::max(size, l.o.norm());
  Eigen::Matrix4d T = base_transform(model);
  for (std::size_t k = 0; k < D.size(); ++k) {
    T = T * dh_transform(model, static_cast<int>(k), 0.0);
    const double dR = (T.topLeftCorner<3, 3>() - D[k].R).norm();
    const double dp = (T.topRightCorner<3, 1>() - D[k].p).norm();
    if (dR > kRebuildTolerance || dp > kRebuildTolerance * size) {
      t.fail("joint", c.joints[k]->name,
             "joint axes that a modified DH form describes to " + num(kRebuildTolerance) + " (relative)",
             "a frame off by " + num(dR) + " (rotation), " + num(dp) +
                 " m: the axes before it are nearly parallel (angle below " + num(kParallel) + " rad, taken as 0)");
    }
  }
}

// ---------------------------------------------------------------- the model

// Joint k's type and limits: revolute [rad] and prismatic [m] from <limit>,
// within +-4 pi for a revolute one as in robot files; continuous: none.
void read_joint(const urdf::Joint& j, const UrdfText& t, JointParams& J) {
  J.type = j.type == urdf::Joint::PRISMATIC ? JointType::kPrismatic : JointType::kRevolute;
  if (j.type == urdf::Joint::CONTINUOUS) {
    J.q_min = -std::numeric_limits<double>::infinity();
    J.q_max = std::numeric_limits<double>::infinity();
    return;
  }
  const double lo = j.limits->lower, hi = j.limits->upper;
  const bool revolute = j.type == urdf::Joint::REVOLUTE;
  const double bound = revolute ? 4 * M_PI : std::numeric_limits<double>::infinity();
  if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi && lo >= -bound && hi <= bound)) {
    t.fail("joint", j.name,
           std::string("<limit> with finite lower < upper") + (revolute ? ", within +-4 pi rad" : "") +
               " (a joint without limits is type=\"continuous\")",
           "lower=\"" + num(lo) + "\" upper=\"" + num(hi) + "\"");
  }
  J.q_min = lo;
  J.q_max = hi;
}

// The joints' axes at q = 0 in the base frame, and each body's URDF frame
// there (bodies[0]: the root link's, the identity).
void place_axes(const UrdfChain& c, const UrdfText& t, std::vector<AxisLine>& L, std::vector<Frame>& bodies) {
  bodies.assign(1, Frame{});
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    const Frame F = bodies.back() * c.clusters[k].next_origin;  // joint frame = child link frame at q = 0
    L.push_back({F.p, F.R * unit_axis(*c.joints[k], t)});
    bodies.push_back(F);
  }
}

// ---------------------------------------------------------------- side file, the rest

void read_side_joint(StrictTable& jt, const std::string& name, SideFile& s) {
  const double rotor = jt.number("rotor_inertia", Bounds::non_negative());
  const double gear = jt.number("gear_ratio");
  if (gear == 0.0) jt.fail("gear_ratio", "a non-zero number", "0");
  s.drive[name] = {rotor, gear};
  if (jt.has("inconsistent_inertia")) s.excuse[name] = jt.string("inconsistent_inertia");
  jt.finish();
}

// The whole side file, strictly, once the chain is known: [joint.NAME]
// tables name the chain's moving joints, [held] the moving joints off it,
// the flange a link of the last body (fixed to it, or merged into it).
void read_side_file(SideFile& s, const std::string& urdf_path, const std::vector<std::string>& joints,
                    const std::vector<std::string>& off_chain, const std::vector<std::string>& flanges) {
  if (s.path.empty()) return;
  StrictTable root(s.doc, s.path, "");
  if (auto robot = root.optional_table("robot")) {
    if (auto g = robot->optional_numbers("gravity", 3)) s.gravity = Vec3((*g)[0], (*g)[1], (*g)[2]);
    s.flange = robot->string_or("flange", "");
    if (!s.flange.empty() && std::find(flanges.begin(), flanges.end(), s.flange) == flanges.end()) {
      robot->fail("flange", "a link of the last body of " + urdf_path + " (fixed to its last moving joint's link, or "
                  "merged into it past the tip: " + listed(flanges) + ")", "'" + s.flange + "'");
    }
    robot->string_or("tip", "");               // read by peek_side_file
    robot->boolean_or("refuse_dynamics", false);
    robot->finish();
  }
  if (auto table = root.optional_table("joint")) {
    for (const std::string& name : table->keys()) {
      if (std::find(joints.begin(), joints.end(), name) == joints.end()) {
        table->fail(name, "a table named after a moving joint of the chain of " + urdf_path + " (" + listed(joints) + ")",
                    "'" + name + "'");
      }
      StrictTable jt = table->table(name);
      read_side_joint(jt, name, s);
    }
    table->finish();
  }
  if (auto held = root.optional_table("held")) {
    for (const std::string& name : held->keys()) {
      if (std::find(off_chain.begin(), off_chain.end(), name) == off_chain.end()) {
        held->fail(name, "a moving joint off the chain of " + urdf_path + " (" +
                             (off_chain.empty() ? std::string("none: the chain has no [robot] tip, or every moving joint is on it")
                                                : listed(off_chain)) + ")",
                   "'" + name + "'");
      }
      held->number(name);
    }
    held->finish();
  }
  if (auto poses = root.optional_table("poses")) {
    const int n = static_cast<int>(joints.size());
    for (const std::string& name : poses->keys()) {
      const auto q = poses->numbers(name, n);
      s.poses.push_back({name, Eigen::Map<const Eigen::VectorXd>(q.data(), n)});
    }
    poses->finish();
  }
  root.finish();
}

// The flange: the side file's link (read_side_file checked that it is fixed
// to the last body), or the end of the fixed joints after the last moving
// joint when they do not branch. Fixed links that branch there (a UR5's
// ee_link beside its tool0) leave the choice open: refused, naming the
// candidates and the side file's key, so that no flange is taken silently
// (a Cartesian path once failed as "out of reach" of a flange nobody chose).
// Its frame in the last body's frame, and what it is and why (RobotModel::flange).
Frame flange_frame(const UrdfChain& c, const SideFile& s, const UrdfText& t, std::string& why) {
  const Cluster& last = c.clusters.back();
  for (const auto& [link, T] : last.links) {
    if (!s.flange.empty() && link->name == s.flange) {
      why = "link '" + link->name + "' (the side file's flange)";
      return T;
    }
  }
  if (s.flange.empty() && !s.tip.empty()) {
    for (const auto& [link, T] : last.links) {
      if (link->name == s.tip) {
        why = "link '" + link->name + "' (the side file's tip; no flange in the side file)";
        return T;
      }
    }
  }
  const urdf::Link* link = last.links.front().first;
  Frame T;
  while (link->child_joints.size() == 1) {
    T = T * frame_of(link->child_joints.front()->parent_to_joint_origin_transform);
    link = link->child_links.front().get();
  }
  if (!link->child_joints.empty()) {
    std::string names;
    for (const auto& [l, X] : last.links) names += (names.empty() ? "'" : ", '") + l->name + "'";
    t.fail("link", link->name,
           "one flange: the links fixed to the last moving joint branch at this link, so name the flange in the "
           "side file " + t.path() + ".toml: [robot] flange = \"<link>\", one of " + names,
           std::to_string(link->child_joints.size()) + " fixed joints leaving it");
  }
  why = "link '" + link->name + "' (the end of the fixed links after the last moving joint; no flange in the side file)";
  return T;
}

// Each body a rigid body's mass and inertia, or the side file's excuse.
void check_bodies(const RobotModel& model, const UrdfChain& c, const SideFile& s, const UrdfText& t) {
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    const std::string& name = c.joints[k]->name;
    const InertiaProblem why = inertia_problem(model.joints[k]);
    const bool excused = s.excuse.count(name) > 0;
    const std::string body = "the body it moves (link '" + c.joints[k]->child_link_name + "' and the links fixed to it) ";
    if (!why.key.empty() && (!why.excusable || !excused)) {
      t.fail("joint", name, body + "with " + why.expected +
                                (why.excusable ? ", or inconsistent_inertia = \"why\" in [joint." + name + "] of " +
                                                     urdf_side_file(t.path()) + " to keep it"
                                               : ""),
             why.got);
    }
    if (why.key.empty() && excused) {
      throw ConfigError(s.path + ": joint." + name +
                        ".inconsistent_inertia: expected no such key on a joint whose body is a rigid body's, got \"" +
                        s.excuse.at(name) + "\"");
    }
  }
}

// Every joint has inertia at the zero pose and at each named pose (as for
// robot files, robot_file.cpp): H(q) is invertible there.
void check_joints_have_inertia(const RobotModel& model, const UrdfChain& c, const UrdfText& t) {
  std::vector<NamedPose> poses = model.poses;
  poses.insert(poses.begin(), NamedPose{"zero (q = 0)", Eigen::VectorXd::Zero(model.dof())});
  for (const NamedPose& p : poses) {
    const int j = joint_without_inertia(model, p.q);
    if (j < 0) continue;
    const std::string& name = c.joints[static_cast<std::size_t>(j)]->name;
    t.fail("joint", name,
           "a rotor inertia > 0 ([joint." + name + "] of " + urdf_side_file(t.path()) +
               "), or links that give it inertia at every pose",
           "none, and at pose " + p.name + " it moves no mass: the joint-space inertia H(q) is singular");
  }
}

// Joint k's drive and friction values and where each came from (a
// provenance line): the gear ratio and rotor inertia from the side file's
// [joint.NAME] (which gives both), else from a <transmission> on the joint,
// else a direct drive (1) without rotor inertia; damping and friction from
// its <dynamics> (check_chain_joints checked them).
std::string drive_values(const urdf::Joint& j, int k, const SideFile& s, const UrdfTransmissions& tr, JointParams& J) {
  std::string gear_from = "the default: a direct drive", rotor_from = "none given";
  if (const auto it = s.drive.find(j.name); it != s.drive.end()) {
    J.rotor_inertia = it->second.first;
    J.gear_ratio = it->second.second;
    gear_from = rotor_from = "[joint." + j.name + "] of the side file";
  } else if (const auto tt = tr.by_joint.find(j.name); tt != tr.by_joint.end()) {
    const std::string where = "<transmission '" + tt->second.name + "'> (line " + std::to_string(tt->second.line) + ")";
    if (tt->second.gear_ratio) J.gear_ratio = *tt->second.gear_ratio, gear_from = where + " mechanicalReduction";
    if (tt->second.rotor_inertia) J.rotor_inertia = *tt->second.rotor_inertia, rotor_from = where + " motorInertia";
  }
  if (j.dynamics) {
    J.damping = j.dynamics->damping;
    J.coulomb = j.dynamics->friction;
  }
  const bool slide = j.type == urdf::Joint::PRISMATIC;
  return "joint '" + j.name + "' (q" + std::to_string(k + 1) + "): gear_ratio " + num(J.gear_ratio) + " (" + gear_from +
         "), rotor_inertia " + num(J.rotor_inertia) + " kg m^2 (" + rotor_from + "); damping " + num(J.damping) +
         (slide ? " N s/m" : " N m s/rad") + ", friction " + num(J.coulomb) + (slide ? " N" : " N m") +
         (j.dynamics ? " (<dynamics>, joint side)" : " (no <dynamics>)");
}

// The model: joints with their limits and drives, the DH form of their axes,
// each body's inertia moved into its DH frame, the flange as the tool.
RobotModel build_model(const urdf::ModelInterface& m, const UrdfChain& c, const SideFile& s, const UrdfText& t) {
  RobotModel model;
  model.name = m.getName();
  model.source = t.path();
  model.convention = DhConvention::kModified;
  model.gravity = s.gravity;
  model.poses = s.poses;
  model.joints.resize(c.joints.size());
  const UrdfTransmissions tr = read_urdf_transmissions(t.path(), t.text());
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    read_joint(*c.joints[k], t, model.joints[k]);
    model.provenance.push_back(drive_values(*c.joints[k], static_cast<int>(k), s, tr, model.joints[k]));
  }
  for (const std::string& line : c.merged) model.provenance.push_back(line);
  for (const auto& [joint, one] : tr.by_joint) {
    const auto it = m.joints_.find(joint);
    if (it == m.joints_.end()) {
      throw ConfigError(t.path() + ":" + std::to_string(one.line) + ": transmission '" + one.name +
                        "': expected a <joint name> of the URDF, got '" + joint + "'");
    }
    if (std::find(c.joints.begin(), c.joints.end(), it->second.get()) == c.joints.end()) {
      model.provenance.push_back("transmission '" + one.name + "' not read: its joint '" + joint + "' is off the chain");
    }
  }
  for (const std::string& coupled : tr.coupled) {
    model.provenance.push_back("transmission " + coupled + " not read: it couples joints or actuators, and pumasim "
                               "drives each joint by its own motor (a gear ratio per joint)");
  }
  std::vector<AxisLine> L;
  std::vector<Frame> bodies;
  place_axes(c, t, L, bodies);
  const std::vector<Frame> D = dh_frames(L);
  dh_rows(D, model);
  check_rebuilt(model, D, L, c, t);
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    // Body k's URDF frame in its DH frame (both move with joint k: a constant).
    const Frame X = D[k].inverse() * bodies[k + 1];
    const JointParams b = body_inertia(c.clusters[k + 1], t);
    JointParams& J = model.joints[k];
    J.mass = b.mass;
    J.com = b.mass > 0 ? Vec3(X.R * b.com + X.p) : Vec3::Zero();
    J.inertia = X.R * b.inertia * X.R.transpose();
  }
  const Frame tool = D.back().inverse() * bodies.back() * flange_frame(c, s, t, model.flange);
  model.tool_R = tool.R;
  model.tool_p = tool.p;
  return model;
}

}  // namespace

bool is_urdf_path(const std::string& path) {
  return path.size() > 5 && path.compare(path.size() - 5, 5, ".urdf") == 0;
}

std::string urdf_side_file(const std::string& urdf_path) { return urdf_path + ".toml"; }

RobotModel load_urdf_file(const std::string& path) {
  const std::optional<std::string> text = read_input_file(path);
  if (!text) throw ConfigError(path + ": cannot be read (" + unreadable_reason(path) + "); expected a readable URDF file");
  UrdfPrescan(path, *text).run();
  const UrdfText t(path, *text);  // an empty file: urdfdom then says what it expected
  std::vector<std::string> errors;
  const UrdfModel m(parse_urdf(t, errors));
  refuse_logged_errors(errors, t);
  check_joints(*m, t);
  SideFile side = peek_side_file(path);
  const ChainPath on_path = chain_path(*m, side);
  const UrdfChain chain = walk(*m, on_path, side, t);
  check_chain_joints(chain, side, t);
  std::vector<std::string> names, off_chain, flanges;
  for (const urdf::Joint* j : chain.joints) names.push_back(j->name);
  for (const auto& [name, j] : (*m).joints_) {
    if (j->type != urdf::Joint::FIXED && std::find(names.begin(), names.end(), name) == names.end()) {
      off_chain.push_back(name);
    }
  }
  for (const auto& l : chain.clusters.back().links) flanges.push_back(l.first->name);
  read_side_file(side, path, names, off_chain, flanges);
  RobotModel model = build_model(*m, chain, side, t);
  check_bodies(model, chain, side, t);
  check_joints_have_inertia(model, chain, t);
  return model;
}

}  // namespace pumasim
