// Strict reading of TOML configuration (robot files now, scene files later).
//
// Every value is read through a StrictTable, which knows the file and the key
// path; an unknown key, a missing required key, a wrong type or an
// out-of-range value throws ConfigError with "file:line: key: expected X, got Y".
// Call finish() once a table is read: keys that were never asked for are
// unknown and rejected, with the list of the keys that are understood.
#pragma once

#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "core/errors.hpp"
#include "models/robot/bounds.hpp"

namespace pumasim {

// Bad user input in a configuration file: ConfigError (core/errors.hpp).

// A TOML basic string of s: quoted, its backslashes, quotes and control
// characters escaped (what an override's or a sample's text value needs).
std::string toml_string(const std::string& s);

// Parse a whole file; a syntax error becomes a ConfigError naming file and line.
toml::table parse_toml_file(const std::string& path);
// Parse TOML text; origin names it in messages (file:line) and in the
// table's source regions.
toml::table parse_toml_text(const std::string& text, const std::string& origin);

// Command-line overrides "section.key=value" (value in TOML syntax) merged
// into a parsed document before it is checked; a bad value is reported as
// "{{set}} section.key=value: section.key: expected ..." (core/option_words.hpp:
// each caller names the option in its own words). An override longer
// than kMaxOverrideChars is refused; messages show at most 120 characters of one.
inline constexpr std::size_t kMaxOverrideChars = std::size_t{1} << 16;
void apply_overrides(toml::table& doc, const std::vector<std::string>& overrides);

// Command-line removals "section.key" (any depth; a whole table too): each
// must name a key of the parsed document `doc` read from `file`, or
// ConfigError "{{unset}} section.key: FILE has no key 'section.key' ...".
void remove_keys(toml::table& doc, const std::vector<std::string>& keys, const std::string& file);

class StrictTable {
 public:
  StrictTable(const toml::table& table, std::string file, std::string path);

  double number(std::string_view key, Bounds bounds = Bounds::any());
  double number_or(std::string_view key, double fallback, Bounds bounds = Bounds::any());
  std::string string(std::string_view key, const std::vector<std::string>& choices = {});
  bool boolean_or(std::string_view key, bool fallback);
  std::string string_or(std::string_view key, std::string fallback,
                        const std::vector<std::string>& choices = {});
  // An array of numbers; `size` < 0 accepts any length.
  std::vector<double> numbers(std::string_view key, int size, Bounds bounds = Bounds::any());
  std::optional<std::vector<double>> optional_numbers(std::string_view key, int size,
                                                      Bounds bounds = Bounds::any());
  // One number for every joint, or an array of exactly n numbers.
  std::vector<double> per_joint(std::string_view key, int n, Bounds bounds = Bounds::any());
  std::vector<double> per_joint_or(std::string_view key, int n, double fallback,
                                   Bounds bounds = Bounds::any());
  // The node itself (arrays of tables, mixed content); nullptr if absent.
  const toml::node* node(std::string_view key);
  bool has(std::string_view key) const;
  StrictTable table(std::string_view key);
  std::optional<StrictTable> optional_table(std::string_view key);
  std::vector<StrictTable> array_of_tables(std::string_view key);
  // Every key of this table, for tables whose keys are names (poses, ...).
  std::vector<std::string> keys();

  // A key this table knows that does not apply given the values read so far
  // (a friction law's key under another law): still unknown to finish(),
  // whose message then says so, naming the choices read before it and how to
  // remove the key.
  // The key does not apply here because of the key above it, `decider`, whose
  // value (as a message shows it) is decider_value; either may be empty.
  // when: the condition in words, named where decider_value is empty (a per-joint decider).
  void not_applicable(std::string_view key, std::string_view decider = {}, std::string decider_value = {},
                      std::string_view when = {});

  // Rejects every key that no accessor asked for.
  void finish() const;
  // Rejects, before anything is read, every key not among `known` (a
  // misspelt section is then named as unknown, not as a missing partner).
  void expect_only(const std::vector<std::string>& known) const;

  // The file the table was read from (a path as given to the reader).
  const std::string& file() const { return file_; }
  // "file:line: path.key: " -- the prefix of any message about `key`.
  std::string where(std::string_view key) const;
  std::string where() const;  // the table itself
  [[noreturn]] void fail(std::string_view key, const std::string& expected,
                         const std::string& got) const;

  // A number node's value as a double: a floating-point node, or an integer
  // node that a double holds exactly (|i| <= 2^53); empty otherwise (not a
  // number, or an integer such as 2^53 + 1 or -2^63 that a double cannot
  // hold -- toml++'s value<double>() is empty then, never to be dereferenced).
  static std::optional<double> as_double(const toml::node& node);

 private:
  const toml::node* lookup(std::string_view key);
  const toml::node& require(std::string_view key);
  std::string key_path(std::string_view key) const;
  std::string table_origin() const;
  static std::string describe(const toml::node& node);

  const toml::table* table_;
  std::string file_;
  std::string path_;  // "" for the root, "joint[2]" below it
  std::vector<std::string> asked_;
  // Keys that do not apply, each with how many keys had been asked before it.
  struct NotApplicable {
    std::string key, decider, decider_value, when;
  };
  std::vector<NotApplicable> not_applicable_;
  std::string why_not_applicable(const toml::key& k) const;
};

}  // namespace pumasim
