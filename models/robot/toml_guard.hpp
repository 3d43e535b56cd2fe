// Input that Debian 12's toml++ 3.3 mishandles, found before toml++ sees it.
//
// Four defects of toml++ 3.3 (found by the fuzz harnesses, tests/fuzz/) are
// undefined behaviour in a release build, where toml++'s own checks are
// compiled out; the release binary happens to print a syntax error today:
//
//   1. A table header whose '[' or '[[' is not followed (after blanks) by a
//      key: "[" then a line break, "[[[1]]]", "[=". toml++ calls parse_key()
//      on a character that is not a key's first character, a precondition it
//      only asserts (TOML_ASSERT_ASSUME: an assumption when NDEBUG is set).
//      Fixed upstream in toml++ pull request #301 (after 3.3).
//   2. A non-ASCII character where toml++ asks whether it is whitespace:
//      outside strings and comments (a quote right after a value's first
//      characters, as in a = 0"x", opens no string: toml++ reads on to a
//      blank, ',', ']', '}' or '#'), after a backslash in a multi-line basic
//      string, or first after a line-ending backslash there. Its unicode
//      table (is_non_ascii_horizontal_whitespace) reaches TOML_UNREACHABLE
//      for U+00A1..U+0499, U+2C5E..U+3057 but U+3000, and U+FB26..U+FEFE
//      (e.g. 'é'). The scan refuses every non-ASCII character in those
//      places, not only these ranges: simpler, and not tied to 3.3's tables.
//   3. A '}' where an array expects a value ("a = [}", "a = [1, }"):
//      parse_value() is called on a value terminator, a precondition it
//      only asserts (TOML_ASSERT_ASSUME), as in 1.
//   4. A date, a space and one digit before a value terminator
//      ("d = 1979-05-27 0"): toml++ reads on for a date-time's time and calls
//      its scan on the terminator, another asserted precondition.
//
// find_toml_hazard scans the text as TOML lexes it (strings of the four
// kinds, comments, the brackets of values) and reports the first such input.
// Every hazard it reports is invalid TOML 1.0 (bare keys are ASCII, escapes
// are ASCII letters, a table header holds a key, brackets match) except one: a non-ASCII
// character first after a line-ending backslash, which is valid TOML that
// has to be written another way here (a \uXXXX escape).
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace pumasim {

struct TomlHazard {
  int line = 1;          // 1-based, as toml++ counts (line breaks '\n')
  std::string expected;  // "expected X, got Y" parts of the message
  std::string got;
};

// The first hazard in `text`, or nothing. A leading UTF-8 byte order mark is skipped
// (toml++ skips it too).
std::optional<TomlHazard> find_toml_hazard(std::string_view text);

}  // namespace pumasim
