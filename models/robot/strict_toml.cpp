#include "models/robot/strict_toml.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "models/robot/input_files.hpp"
#include "models/robot/toml_guard.hpp"

namespace pumasim {
namespace {

// The shortest text that reads back as x (0.1, not 0.10000000000000001); a
// whole number below 1e15 in full (100000, not 1e+05).
std::string format_number(double x) {
  char buf[32];
  const bool whole = x == std::floor(x) && std::abs(x) < 1e15;
  const auto r = whole ? std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed)
                       : std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

std::string line_of(const toml::source_region& src) {
  return src.begin.line > 0 ? std::to_string(src.begin.line) : "?";
}

}  // namespace

bool Bounds::contains(double x) const {
  if (or_infinity && x == std::numeric_limits<double>::infinity()) return true;
  if (!std::isfinite(x)) return false;
  const bool lo_ok = lo_open ? x > lo : x >= lo;
  const bool hi_ok = hi_open ? x < hi : x <= hi;
  return lo_ok && hi_ok;
}

std::string Bounds::describe() const {
  if (or_infinity) {
    Bounds finite = *this;
    finite.or_infinity = false;
    return finite.describe() + " or inf";
  }
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    return std::string("a number in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " +
           format_number(hi) + (hi_open ? ")" : "]");
  }
  if (has_lo) return std::string("a number ") + (lo_open ? "> " : ">= ") + format_number(lo);
  if (has_hi) return std::string("a number ") + (hi_open ? "< " : "<= ") + format_number(hi);
  return "a finite number";
}

std::string toml_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\', out += c;
    } else if (u < 0x20 || u == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(u));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

toml::table parse_toml_file(const std::string& path) {
  const std::optional<std::string> text = read_input_file(path);
  if (!text) throw ConfigError(path + ": cannot be read (" + unreadable_reason(path) + "); expected a readable TOML file");
  return parse_toml_text(*text, path);
}

toml::table parse_toml_text(const std::string& text, const std::string& origin) {
  // What toml++ 3.3 would mishandle is refused first (models/robot/toml_guard.hpp);
  // the guard and the parser read the same bytes.
  if (const auto hazard = find_toml_hazard(text)) {
    throw ConfigError(origin + ":" + std::to_string(hazard->line) + ": TOML syntax error: expected " +
                      hazard->expected + ", got " + hazard->got);
  }
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw ConfigError(origin + ":" + line_of(e.source()) + ": TOML syntax error: " + std::string(e.description()));
  }
}

namespace {
// Puts every leaf of `from` into `into`, creating or replacing along the path.
void merge_into(toml::table& into, const toml::table& from) {
  for (const auto& [k, v] : from) {
    if (const toml::table* sub = v.as_table()) {
      toml::table* dst = into.get_as<toml::table>(k);
      if (!dst) {
        into.insert_or_assign(k, toml::table{});
        dst = into.get_as<toml::table>(k);
      }
      merge_into(*dst, *sub);
    } else {
      into.erase(k.str());  // re-inserted with the override's key, which names its source
      into.insert_or_assign(k, v);
    }
  }
}
}  // namespace

// An override as messages show it: whole up to kEchoChars characters, else its
// start and its length (a value of a million characters is not echoed).
std::string echoed_override(const std::string& o) {
  constexpr std::size_t kEchoChars = 120;
  if (o.size() <= kEchoChars) return o;
  return o.substr(0, kEchoChars - 40) + "... (" + std::to_string(o.size()) + " characters)";
}

void apply_overrides(toml::table& doc, const std::vector<std::string>& overrides) {
  for (const std::string& full : overrides) {
    if (full.size() > kMaxOverrideChars) {
      throw ConfigError("{{set}} " + echoed_override(full) + ": expected at most " + std::to_string(kMaxOverrideChars) +
                        " characters (a longer value belongs in the scene file)");
    }
    const std::string o = echoed_override(full);  // in messages and as the values' source name
    const auto eq = full.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw ConfigError("{{set}} " + o + ": expected section.key=value (a TOML value, e.g. motor.inductance=1e-5)");
    }
    const std::string text = full.substr(0, eq) + " = " + full.substr(eq + 1);
    if (const auto hazard = find_toml_hazard(text)) {
      throw ConfigError("{{set}} " + o + ": expected section.key=value with a TOML value (expected " +
                        hazard->expected + ", got " + hazard->got + ")");
    }
    toml::table t;
    try {
      t = toml::parse(text, "{{set}} " + o);
    } catch (const toml::parse_error& e) {
      throw ConfigError("{{set}} " + o + ": expected section.key=value with a TOML value (" +
                        std::string(e.description()) + ")");
    }
    merge_into(doc, t);
  }
}

void remove_keys(toml::table& doc, const std::vector<std::string>& keys, const std::string& file) {
  for (const std::string& key : keys) {
    // The path's parts: bare TOML keys (letters, digits, '_', '-'), '.'-separated.
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (true) {
      const std::size_t dot = key.find('.', start);
      parts.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    for (const std::string& p : parts) {
      const bool bare = !p.empty() && std::all_of(p.begin(), p.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
      });
      if (!bare) {
        throw ConfigError("{{unset}} " + key +
                          ": expected section.key (names of the scene file, e.g. friction.static_torque)");
      }
    }
    toml::table* table = &doc;
    std::string at;  // the path so far
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      at += (at.empty() ? "" : ".") + parts[i];
      table = table->get_as<toml::table>(parts[i]);
      if (!table) throw ConfigError("{{unset}} " + key + ": " + file + " has no table [" + at + "]");
    }
    if (!table->contains(parts.back())) {
      std::string present;
      for (const auto& [k, v] : *table) present += (present.empty() ? "" : ", ") + std::string(k.str());
      const std::string where = at.empty() ? std::string("its top level") : "[" + at + "]";
      throw ConfigError("{{unset}} " + key + ": " + file + " has no key '" + key + "'" +
                        (present.empty() ? std::string() : "; " + where + " has: " + present));
    }
    table->erase(parts.back());
  }
}

StrictTable::StrictTable(const toml::table& table, std::string file, std::string path)
    : table_(&table), file_(std::move(file)), path_(std::move(path)) {}

std::string StrictTable::key_path(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

namespace {
// The override a key came from ("{{set}} a.b=1": core/option_words.hpp), or "". (Keys
// keep their source when merged; values copied into a table do not.)
std::string override_of(const toml::key& k) {
  const auto& p = k.source().path;
  return p && p->rfind("{{set}}", 0) == 0 ? *p : std::string();
}
}  // namespace

std::string StrictTable::where(std::string_view key) const {
  const auto it = table_->find(key);
  if (it != table_->end()) {
    if (const std::string o = override_of(it->first); !o.empty()) return o + ": " + key_path(key) + ": ";
  }
  const toml::node* node = table_->get(key);
  const auto& src = node ? node->source() : table_->source();
  if (src.begin.line == 0) return table_origin() + ": " + key_path(key) + ": ";
  return file_ + ":" + line_of(src) + ": " + key_path(key) + ": ";
}

std::string StrictTable::where() const {
  if (table_->source().begin.line == 0) return table_origin() + ": " + (path_.empty() ? "(top level)" : path_) + ": ";
  return file_ + ":" + line_of(table_->source()) + ": " + (path_.empty() ? "(top level)" : path_) +
         ": ";
}

// A table with no line of the file made it from the command line: the
// override that did ("{{set}} a.b=1"), else the file alone.
std::string StrictTable::table_origin() const {
  for (const auto& [k, v] : *table_) {
    if (const std::string o = override_of(k); !o.empty()) return o;
  }
  return file_;
}

void StrictTable::fail(std::string_view key, const std::string& expected,
                       const std::string& got) const {
  throw ConfigError(where(key) + "expected " + expected + ", got " + got);
}

std::string StrictTable::describe(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "the string \"" + std::string(*node.value<std::string_view>()) + "\"";
    case toml::node_type::integer: return "the integer " + std::to_string(*node.value<int64_t>());
    case toml::node_type::floating_point: return "the number " + format_number(*node.value<double>());
    case toml::node_type::boolean: return *node.value<bool>() ? "true" : "false";
    case toml::node_type::array: return "an array of " + std::to_string(node.as_array()->size());
    case toml::node_type::table: return "a table";
    default: return "a date or time";
  }
}

const toml::node* StrictTable::lookup(std::string_view key) {
  if (std::find(asked_.begin(), asked_.end(), key) == asked_.end()) asked_.emplace_back(key);
  return table_->get(key);
}

const toml::node& StrictTable::require(std::string_view key) {
  const toml::node* node = lookup(key);
  if (!node) {
    throw ConfigError(where() + "missing required key '" + std::string(key) + "'");
  }
  return *node;
}

bool StrictTable::has(std::string_view key) const { return table_->get(key) != nullptr; }

std::optional<double> StrictTable::as_double(const toml::node& node) {
  if (const auto* f = node.as_floating_point()) return f->get();
  if (const auto* i = node.as_integer()) {
    constexpr std::int64_t kExact = std::int64_t{1} << 53;
    const std::int64_t v = i->get();
    if (v >= -kExact && v <= kExact) return static_cast<double>(v);
  }
  return std::nullopt;
}

namespace {
constexpr const char* kInexact = " (an integer beyond +-2^53 is not exactly a double)";
}

double StrictTable::number(std::string_view key, Bounds bounds) {
  const toml::node& node = require(key);
  const auto v = as_double(node);
  if (!v) fail(key, bounds.describe() + (node.is_integer() ? kInexact : ""), describe(node));
  const double x = *v;
  if (!bounds.contains(x)) fail(key, bounds.describe(), format_number(x));
  return x;
}

double StrictTable::number_or(std::string_view key, double fallback, Bounds bounds) {
  if (!lookup(key)) return fallback;
  return number(key, bounds);
}

std::string StrictTable::string(std::string_view key, const std::vector<std::string>& choices) {
  const toml::node& node = require(key);
  std::string expected = "a string";
  if (!choices.empty()) {
    expected = "one of";
    for (std::size_t i = 0; i < choices.size(); ++i) {
      expected += (i ? ", \"" : " \"") + choices[i] + "\"";
    }
  }
  if (!node.is_string()) fail(key, expected, describe(node));
  std::string s(*node.value<std::string_view>());
  if (!choices.empty() && std::find(choices.begin(), choices.end(), s) == choices.end()) {
    fail(key, expected, "\"" + s + "\"");
  }
  return s;
}

std::string StrictTable::string_or(std::string_view key, std::string fallback,
                                   const std::vector<std::string>& choices) {
  if (!lookup(key)) return fallback;
  return string(key, choices);
}

bool StrictTable::boolean_or(std::string_view key, bool fallback) {
  if (!lookup(key)) return fallback;
  const toml::node& node = require(key);
  const auto v = node.value<bool>();
  if (!node.is_boolean() || !v) fail(key, "true or false", describe(node));
  return *v;
}

std::vector<double> StrictTable::numbers(std::string_view key, int size, Bounds bounds) {
  const toml::node& node = require(key);
  const std::string expected =
      (size >= 0 ? "an array of " + std::to_string(size) + " numbers" : "an array of numbers") +
      (std::isfinite(bounds.lo) || std::isfinite(bounds.hi) ? ", each " + bounds.describe() : "");
  const toml::array* arr = node.as_array();
  if (!arr) fail(key, expected, describe(node));
  if (size >= 0 && arr->size() != static_cast<std::size_t>(size)) fail(key, expected, describe(node));
  std::vector<double> out;
  out.reserve(arr->size());
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = *arr->get(i);
    const auto v = as_double(e);
    if (!v) fail(key, expected + (e.is_integer() ? kInexact : ""), describe(e) + " at index " + std::to_string(i));
    const double x = *v;
    if (!bounds.contains(x)) fail(key, expected, format_number(x) + " at index " + std::to_string(i));
    out.push_back(x);
  }
  return out;
}

std::optional<std::vector<double>> StrictTable::optional_numbers(std::string_view key, int size,
                                                                 Bounds bounds) {
  if (!lookup(key)) return std::nullopt;
  return numbers(key, size, bounds);
}

std::vector<double> StrictTable::per_joint(std::string_view key, int n, Bounds bounds) {
  const toml::node& nd = require(key);
  if (nd.is_number()) {
    const auto v = as_double(nd);
    if (!v) fail(key, bounds.describe() + kInexact, describe(nd));
    const double x = *v;
    if (!bounds.contains(x)) fail(key, bounds.describe(), format_number(x));
    return std::vector<double>(static_cast<std::size_t>(n), x);
  }
  if (!nd.is_array()) {
    fail(key, "a number or an array of " + std::to_string(n) + " numbers (one per joint)",
         describe(nd));
  }
  return numbers(key, n, bounds);
}

std::vector<double> StrictTable::per_joint_or(std::string_view key, int n, double fallback,
                                              Bounds bounds) {
  if (!lookup(key)) return std::vector<double>(static_cast<std::size_t>(n), fallback);
  return per_joint(key, n, bounds);
}

const toml::node* StrictTable::node(std::string_view key) { return lookup(key); }

StrictTable StrictTable::table(std::string_view key) {
  const toml::node& node = require(key);
  if (!node.is_table()) fail(key, "a table", describe(node));
  return StrictTable(*node.as_table(), file_, key_path(key));
}

std::optional<StrictTable> StrictTable::optional_table(std::string_view key) {
  if (!lookup(key)) return std::nullopt;
  return table(key);
}

std::vector<StrictTable> StrictTable::array_of_tables(std::string_view key) {
  const toml::node& node = require(key);
  const toml::array* arr = node.as_array();
  if (!arr || !arr->is_array_of_tables()) {
    fail(key, "an array of tables ([[" + std::string(key) + "]])", describe(node));
  }
  std::vector<StrictTable> out;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    out.emplace_back(*arr->get(i)->as_table(), file_,
                     key_path(key) + "[" + std::to_string(i + 1) + "]");
  }
  return out;
}

std::vector<std::string> StrictTable::keys() {
  std::vector<std::string> out;
  for (const auto& [k, v] : *table_) {
    out.emplace_back(k.str());
    lookup(k.str());
  }
  return out;
}

void StrictTable::not_applicable(std::string_view key, std::string_view decider, std::string decider_value,
                                 std::string_view when) {
  not_applicable_.push_back({std::string(key), std::string(decider), std::move(decider_value), std::string(when)});
}

// " (friction.static_torque does not apply to friction.model = "viscous"
// (--set friction.model="viscous"); remove it from the file or with --unset
// friction.static_torque --unset friction.kinetic_torque)" for a key that
// does not apply, or "". The choice named is the key above it that decides
// (with "(the default)" when the file does not give it); the --unset list has
// every key of the table that does not apply.
std::string StrictTable::why_not_applicable(const toml::key& k) const {
  const auto find = [this](std::string_view key) {
    return std::find_if(not_applicable_.begin(), not_applicable_.end(),
                        [&](const auto& e) { return e.key == key; });
  };
  const auto it = find(k.str());
  if (it == not_applicable_.end()) return "";
  std::string choices;
  if (!it->decider.empty() && !it->decider_value.empty()) {
    choices = key_path(it->decider) + " = " + it->decider_value;
    if (const auto c = table_->find(it->decider); c != table_->end()) {
      if (const std::string o = override_of(c->first); !o.empty()) choices += " (" + o + ")";
    }
  }
  const std::string applies = !choices.empty()    ? " does not apply to " + choices
                              : !it->when.empty() ? " applies only when " + it->when
                                                  : std::string(" does not apply to the values above it");
  if (const std::string o = override_of(k); !o.empty()) {
    return " (" + key_path(k.str()) + applies + "; drop " + o + ")";
  }
  std::string unsets;  // every key of the file here that does not apply
  for (const auto& [key, v] : *table_) {
    const bool asked = std::find(asked_.begin(), asked_.end(), key.str()) != asked_.end();
    if (asked || find(key.str()) == not_applicable_.end() || !override_of(key).empty()) continue;
    unsets += " {{unset}} " + key_path(key.str());
  }
  return " (" + key_path(k.str()) + applies + "; remove it from the file or with" + unsets + ")";
}

void StrictTable::finish() const {
  for (const auto& [k, v] : *table_) {
    if (std::find(asked_.begin(), asked_.end(), k.str()) != asked_.end()) continue;
    std::string known;
    for (const auto& a : asked_) known += (known.empty() ? "" : ", ") + a;
    const std::string o = override_of(k);
    throw ConfigError((o.empty() ? file_ + ":" + line_of(k.source()) : o) + ": unknown key '" +
                      key_path(k.str()) + "'; expected one of: " + known + why_not_applicable(k));
  }
}

}  // namespace pumasim

namespace pumasim {

void StrictTable::expect_only(const std::vector<std::string>& known) const {
  for (const auto& [k, v] : *table_) {
    if (std::find(known.begin(), known.end(), k.str()) != known.end()) continue;
    std::string list;
    for (const auto& a : known) list += (list.empty() ? "" : ", ") + a;
    const std::string o = override_of(k);
    throw ConfigError((o.empty() ? file_ + ":" + line_of(k.source()) : o) + ": unknown key '" + key_path(k.str()) +
                      "'; expected one of: " + list);
  }
}

}  // namespace pumasim
