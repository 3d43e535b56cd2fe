#include "models/robot/toml_guard.hpp"

#include <algorithm>
#include <cstdio>

namespace pumasim {
namespace {

bool is_ascii(char c) { return static_cast<unsigned char>(c) < 0x80; }

bool is_bare_key_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

// How a message names the byte at `i` (or the end of the text).
std::string describe(std::string_view t, std::size_t i) {
  if (i >= t.size()) return "the end of the text";
  const char c = t[i];
  if (c == '\n' || c == '\r') return "a line break";
  if (!is_ascii(c)) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
    return std::string("a non-ASCII character (first byte ") + hex + ")";
  }
  if (c == ' ' || c == '\t') return "a blank";
  return "'" + std::string(1, c) + "'";
}

// A lexer that knows just enough TOML to tell where toml++ 3.3 would look at
// a character as a key's start or as possible whitespace.
class Scanner {
 public:
  explicit Scanner(std::string_view text) : t_(text) {}
  std::optional<TomlHazard> run();

 private:
  void fail(std::size_t at, std::string expected) {
    if (!hazard_) hazard_ = TomlHazard{line_, std::move(expected), describe(t_, at)};
  }
  bool at(std::size_t i, std::string_view s) const { return t_.substr(i, s.size()) == s; }
  void step();  // one character (or token) outside strings and comments
  void table_header();
  bool at_token_start() const;
  void bare_value();
  void basic_string(bool multi_line);
  void literal_string(bool multi_line);
  void escape(bool multi_line);
  // After a multi-line string's first three closing quotes: up to two more
  // (the content's last quotes) move the end.
  void close_quotes(char q) {
    for (int k = 0; k < 2 && i_ < t_.size() && t_[i_] == q; ++k) ++i_;
  }
  void newline() {
    ++line_;
    line_has_token_ = false;
    if (open_.empty()) in_key_ = true;
  }

  std::string_view t_;
  std::size_t i_ = 0;
  int line_ = 1;
  std::size_t start_ = 0;        // after a byte order mark
  std::string open_;             // the open '[' and '{' of values, innermost last
  bool in_key_ = true;           // where a key is read (before '=', in a table header)
  bool line_has_token_ = false;  // something other than blanks on this line (outside values)
  std::optional<TomlHazard> hazard_;
};

std::optional<TomlHazard> Scanner::run() {
  if (at(0, "\xEF\xBB\xBF")) i_ = start_ = 3;
  while (i_ < t_.size() && !hazard_) step();
  return hazard_;
}

void Scanner::step() {
  const char c = t_[i_];
  if (c == '\n') {
    newline();
    ++i_;
  } else if (c == ' ' || c == '\t' || c == '\r') {
    ++i_;
  } else if (c == '#') {
    while (i_ < t_.size() && t_[i_] != '\n') ++i_;  // a comment may hold any character
  } else if ((c == '"' || c == '\'') && at_token_start()) {
    const bool multi = at(i_, c == '"' ? "\"\"\"" : "'''");
    i_ += multi ? 3 : 1;
    if (c == '"') {
      basic_string(multi);
    } else {
      literal_string(multi);
    }
    line_has_token_ = true;
  } else if (!is_ascii(c)) {
    fail(i_, "ASCII outside strings and comments (TOML 1.0 keys are ASCII: quote a key with other characters)");
  } else if (c == '[' && open_.empty() && !line_has_token_) {
    table_header();
  } else if (!in_key_ && std::string_view(" \t\n\r\v\f,]}#\"'[{").find(c) == std::string_view::npos) {
    bare_value();
  } else if (c == '}' && !open_.empty() && open_.back() == '[') {
    fail(i_, "a value, ',' or ']' in the array opened before");
  } else {
    if (c == '[' || c == '{') open_.push_back(c);
    if ((c == ']' || c == '}') && !open_.empty()) open_.pop_back();
    // Keys come first on a line outside values, and after '{' or ',' in an inline table.
    if (c == '=' || c == '[' || c == ']' || c == '}') in_key_ = false;
    if (c == '{' || (c == ',' && !open_.empty() && open_.back() == '{')) in_key_ = true;
    line_has_token_ = true;
    ++i_;
  }
}

// A value that is not a string, an array or an inline table (a number, a
// date, true, ...): toml++ reads it up to a blank, ',', ']', '}' or '#',
// quotes and brackets included, asking of each character whether it is
// whitespace.
void Scanner::bare_value() {
  while (i_ < t_.size() && std::string_view(" \t\n\r\v\f,]}#").find(t_[i_]) == std::string_view::npos) {
    if (!is_ascii(t_[i_])) return fail(i_, "ASCII in a value that is not a string (a number, a date, true or false)");
    ++i_;
  }
  line_has_token_ = true;
  // "1979-05-27 0" then a blank, ',', ']' or '}': toml++ takes the space for a
  // date-time's 'T' and scans on from the digit at a value terminator (an
  // assertion, TOML_ASSERT_ASSUME). Valid TOML has hh:mm:ss there.
  const std::string_view end(" \t\n\r\v\f,]}#");
  if (i_ + 2 < t_.size() && t_[i_] == ' ' && t_[i_ + 1] >= '0' && t_[i_ + 1] <= '9' &&
      end.find(t_[i_ + 2]) != std::string_view::npos) {
    fail(i_ + 1, "a time hh:mm:ss after a date and a space");
  }
}

// A quote opens a string only where a token starts; after other characters
// (a = 0"x") toml++ reads it as part of a bare value, up to a blank, ',', ']',
// '}' or '#', asking of each character whether it is whitespace.
bool Scanner::at_token_start() const {
  if (i_ == start_) return true;
  const char p = t_[i_ - 1];
  return p == ' ' || p == '\t' || p == '\n' || p == '\r' || p == '=' || p == '[' || p == '{' || p == ',' ||
         (p == '.' && in_key_);  // a dotted key's next part; in a value, 665."x" is one bare token
}

// '[' or '[[' first on a line outside any value: a table header, whose key
// must start (after blanks) with a bare key's character or a quote.
void Scanner::table_header() {
  std::size_t j = i_ + 1;
  if (j < t_.size() && t_[j] == '[') ++j;
  const std::string brackets(t_.substr(i_, j - i_));
  while (j < t_.size() && (t_[j] == ' ' || t_[j] == '\t')) ++j;
  if (j < t_.size() && (is_bare_key_char(t_[j]) || t_[j] == '"' || t_[j] == '\'')) {
    i_ = j;
    line_has_token_ = true;
    in_key_ = true;
    return;
  }
  fail(j, "a table name after '" + brackets + "' (a bare key of A-Z a-z 0-9 _ - or a quoted key)");
}

// After the opening quote(s); ends after the closing ones, or at the line
// break that ends an unterminated single-line string (toml++ refuses it).
void Scanner::basic_string(bool multi_line) {
  while (i_ < t_.size() && !hazard_) {
    const char c = t_[i_];
    if (c == '\\') {
      escape(multi_line);
    } else if (multi_line && at(i_, "\"\"\"")) {
      i_ += 3;
      close_quotes('"');
      return;
    } else if (!multi_line && (c == '"' || c == '\n')) {
      if (c == '"') ++i_;
      return;
    } else {
      if (c == '\n') newline();
      ++i_;
    }
  }
}

// At a backslash in a basic string. toml++ asks whether the next character is
// whitespace (multi-line strings) and, after a line-ending backslash, whether
// the first character after the blanks and line breaks is.
void Scanner::escape(bool multi_line) {
  ++i_;
  if (i_ >= t_.size()) return;
  if (!is_ascii(t_[i_])) return fail(i_, "an escape sequence after '\\' (\\n, \\t, \\\", \\\\, \\uXXXX, ...)");
  const char c = t_[i_];
  if (!multi_line || !(c == ' ' || c == '\t' || c == '\r' || c == '\n')) {
    if (c != '\n') ++i_;  // the escaped character (a line break ends the string instead)
    return;
  }
  while (i_ < t_.size() && (t_[i_] == ' ' || t_[i_] == '\t' || t_[i_] == '\r' || t_[i_] == '\n')) {
    if (t_[i_] == '\n') newline();
    ++i_;
  }
  if (i_ < t_.size() && !is_ascii(t_[i_])) {
    fail(i_, "an ASCII character first after a line-ending backslash (toml++ 3.3 misreads a non-ASCII one; "
             "write it as \\uXXXX)");
  }
}

void Scanner::literal_string(bool multi_line) {
  while (i_ < t_.size()) {
    const char c = t_[i_];
    if (multi_line && at(i_, "'''")) {
      i_ += 3;
      close_quotes('\'');
      return;
    }
    if (!multi_line && (c == '\'' || c == '\n')) {
      if (c == '\'') ++i_;
      return;
    }
    if (c == '\n') newline();
    ++i_;
  }
}

}  // namespace

std::optional<TomlHazard> find_toml_hazard(std::string_view text) { return Scanner(text).run(); }

}  // namespace pumasim
