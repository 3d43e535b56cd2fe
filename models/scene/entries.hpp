// Scene sections as tables of entries (internal to models/scene/).
//
// A section of a scene file is one table: each entry names its key, what the
// value is (number, whole number, flag, text, choice, one number per joint,
// array of numbers, or a custom reader and writer), its bounds or allowed
// values, where it lives in the section's struct, whether it is required, and
// a one-line meaning. read_entries() and write_entries() walk the same table,
// so what is read is what is written, and the resolved scene loads back to the
// same scene by construction. Defaults are the structs' initialisers: an
// optional key that is absent leaves its member untouched.
//
// Accessors are generic lambdas (obj, j) -> member&, with j the joint for
// per-joint and shared entries (0 otherwise); PUMASIM_AT(expr) writes one.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/invariant.hpp"
#include "models/robot/strict_toml.hpp"
#include "models/scene/key_doc.hpp"

#define PUMASIM_AT(expr) [](auto& s, [[maybe_unused]] int j) -> auto& { return expr; }

namespace pumasim::scene_io {

enum class Need {
  kRequired,  // absent: "missing required key"
  kOptional,  // absent: the struct's initialiser; always written
  kIfSet,     // absent: the initialiser (0 or empty: "not given"), written only when set
};

// How one key is read from a StrictTable into T, and written back as TOML;
// n is the number of simulated joints.
template <class T>
struct Codec {
  std::function<void(StrictTable&, std::string_view key, T&, int n)> read;
  std::function<void(toml::table&, std::string_view key, const T&, int n)> write;
  std::function<bool(const T&)> unset;  // the value is 0 or empty (for kIfSet); null: never
  // For the generated reference (pumasim keys): what the value is, as a
  // message would say it ("a number > 0", "one of: ..."), and the names a
  // choice allows (empty: not a choice).
  std::string what;
  std::vector<std::string> names;
};

template <class T>
struct Entry {
  std::string_view key;
  Codec<T> codec;             // type, bounds or allowed values, member
  std::string_view meaning;   // one line: unit and role
  Need need = Need::kOptional;
  // Whether the key means something, from the entry above it named
  // decided_by (null: always); a key that does not is not read (finish()
  // calls it unknown, naming decided_by's value) nor written.
  struct Applies {
    bool (*fn)(const T&) = nullptr;
    std::string_view decided_by;
    // The condition in words, for the reference, where fn reads more than
    // one key (empty: derived from decided_by's values, see applies_text).
    std::string_view when;
  } applies{};
  // After the entry is read (its value or its default): checks and derived values.
  void (*then)(StrictTable&, T&) = nullptr;
};

// The first entry of the table with this key (nullptr: none).
template <class T>
const Entry<T>* find_entry(const std::vector<Entry<T>>& entries, std::string_view key) {
  for (const Entry<T>& e : entries) {
    if (e.key == key) return &e;
  }
  return nullptr;
}

// '"piv"', or '"piv" (the default)' when the file does not give it: the value
// of the entry `key` as read into obj ("" if no entry has it, or it is an
// array or a table). Looks without reading: a decider that does not apply
// itself stays unknown to finish().
template <class T>
std::string decider_value(StrictTable& t, const std::vector<Entry<T>>& entries, std::string_view key,
                          const T& obj, int n) {
  const Entry<T>* d = find_entry(entries, key);
  if (!d) return "";
  toml::table tmp;
  d->codec.write(tmp, key, obj, n);
  const toml::node* v = tmp.get(key);
  if (!v) return "";
  std::ostringstream out;
  if (const auto str = v->value<std::string>()) {
    out << '"' << *str << '"';
  } else if (v->is_boolean()) {
    out << (*v->value<bool>() ? "true" : "false");
  } else if (const auto x = v->value<double>()) {
    out << *x;
  } else {
    return "";  // an array or a table: named by the entries above it instead
  }
  return out.str() + (t.has(key) ? "" : " (the default)");
}

// Reads every entry that applies, in table order, then rejects unknown keys.
template <class T>
void read_entries(StrictTable& t, const std::vector<Entry<T>>& entries, T& obj, int n) {
  for (const Entry<T>& e : entries) {
    if (e.applies.fn && !e.applies.fn(obj)) {
      // finish() says why, should the key be there
      t.not_applicable(e.key, e.applies.decided_by, decider_value(t, entries, e.applies.decided_by, obj, n),
                       e.applies.when);
      continue;
    }
    if (e.need == Need::kRequired || t.node(e.key)) e.codec.read(t, e.key, obj, n);
    if (e.then) e.then(t, obj);
  }
  t.finish();
}

// Writes every entry that applies (and is set, for kIfSet) into a TOML table.
template <class T>
toml::table write_entries(const std::vector<Entry<T>>& entries, const T& obj, int n) {
  toml::table out;
  for (const Entry<T>& e : entries) {
    if (e.applies.fn && !e.applies.fn(obj)) continue;
    if (e.need == Need::kIfSet && e.codec.unset && e.codec.unset(obj)) continue;
    e.codec.write(out, e.key, obj, n);
  }
  return out;
}

// Sets the member for joint 0, or for every joint when `shared` (one value
// kept in each joint's parameters).
template <class T, class At, class V>
void assign(At at, T& obj, int n, bool shared, const V& v) {
  for (int j = 0; j < (shared ? n : 1); ++j) at(obj, j) = v;
}

// '"a", "b" or "c"': the names a choice allows, as the reference shows them.
inline std::string one_of(const std::vector<std::string>& names) {
  std::string r = "one of:";
  for (std::size_t i = 0; i < names.size(); ++i) r += (i ? ", \"" : " \"") + names[i] + "\"";
  return r;
}

// A number within bounds (shared: the same for every joint).
template <class At>
struct NumberCodec {
  Bounds bounds;
  At at;
  bool shared;
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor): the tables convert
    const NumberCodec c = *this;
    return {[c](StrictTable& t, std::string_view key, T& obj, int n) {
              assign(c.at, obj, n, c.shared, t.number(key, c.bounds));
            },
            [c](toml::table& out, std::string_view key, const T& obj, int) { out.insert(key, c.at(obj, 0)); },
            [c](const T& obj) { return c.at(obj, 0) == 0; },
            c.bounds.describe() + (c.shared ? ", one for all joints" : ""),
            {}};
  }
};
template <class At>
NumberCodec<At> number(Bounds b, At at) { return {b, at, false}; }
template <class At>
NumberCodec<At> shared_number(Bounds b, At at) { return {b, at, true}; }

// A whole number within bounds into an int; `fractional` is what a message
// says was expected of a number that is not whole.
template <class At>
struct WholeCodec {
  Bounds bounds;
  std::string fractional;
  At at;
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor)
    const WholeCodec c = *this;
    return {[c](StrictTable& t, std::string_view key, T& obj, int) {
              const double x = t.number(key, c.bounds);
              if (x != std::floor(x)) t.fail(key, c.fractional, std::to_string(x));
              c.at(obj, 0) = static_cast<int>(x);
            },
            [c](toml::table& out, std::string_view key, const T& obj, int) { out.insert(key, c.at(obj, 0)); },
            [c](const T& obj) { return c.at(obj, 0) == 0; },
            "a whole " + c.bounds.describe().substr(2),  // "a whole number in [1, 100000]"
            {}};
  }
};
template <class At>
WholeCodec<At> whole(Bounds b, std::string fractional, At at) { return {b, std::move(fractional), at}; }

// true or false.
template <class At>
struct FlagCodec {
  At at;
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor)
    const At a = at;
    return {[a](StrictTable& t, std::string_view key, T& obj, int) { a(obj, 0) = t.boolean_or(key, a(obj, 0)); },
            [a](toml::table& out, std::string_view key, const T& obj, int) { out.insert(key, a(obj, 0)); },
            nullptr,
            "true or false",
            {}};
  }
};
template <class At>
FlagCodec<At> flag(At at) { return {at}; }

// A string, one of `allowed` unless that is empty.
template <class At>
struct TextCodec {
  std::vector<std::string> allowed;
  At at;
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor)
    const TextCodec c = *this;
    return {[c](StrictTable& t, std::string_view key, T& obj, int) { c.at(obj, 0) = t.string(key, c.allowed); },
            [c](toml::table& out, std::string_view key, const T& obj, int) { out.insert(key, c.at(obj, 0)); },
            [c](const T& obj) { return c.at(obj, 0).empty(); },
            c.allowed.empty() ? std::string("a string") : one_of(c.allowed), c.allowed};
  }
};
template <class At>
TextCodec<At> text(At at, std::vector<std::string> allowed = {}) { return {std::move(allowed), at}; }

// One of a few names, each standing for a value of the member (an enum, a
// flag); shared: the same for every joint.
template <class V, class At>
struct ChoiceCodec {
  std::vector<std::pair<std::string, V>> options;
  At at;
  bool shared;
  std::vector<std::string> names() const {
    std::vector<std::string> r;
    for (const auto& o : options) r.push_back(o.first);
    return r;
  }
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor)
    const ChoiceCodec c = *this;
    return {[c](StrictTable& t, std::string_view key, T& obj, int n) {
              const std::string s = t.string(key, c.names());
              for (const auto& o : c.options) {
                if (o.first == s) assign(c.at, obj, n, c.shared, o.second);
              }
            },
            [c](toml::table& out, std::string_view key, const T& obj, int) {
              for (const auto& o : c.options) {
                if (o.second == c.at(obj, 0)) out.insert(key, o.first);
              }
            },
            nullptr, one_of(c.names()) + (c.shared ? ", one for all joints" : ""), c.names()};
  }
};
template <class V, class At>
ChoiceCodec<V, At> choice(std::vector<std::pair<std::string, V>> options, At at) {
  return {std::move(options), at, false};
}
template <class V, class At>
ChoiceCodec<V, At> shared_choice(std::vector<std::pair<std::string, V>> options, At at) {
  return {std::move(options), at, true};
}

// One number per simulated joint (an array of exactly n, checked before any
// member is written), or one number for all of them; written as the array.
template <class At>
struct PerJointCodec {
  Bounds bounds;
  At at;
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor)
    const PerJointCodec c = *this;
    return {[c](StrictTable& t, std::string_view key, T& obj, int n) {
              const std::vector<double> v = t.per_joint(key, n, c.bounds);
              for (int j = 0; j < n; ++j) c.at(obj, j) = v[static_cast<std::size_t>(j)];
            },
            [c](toml::table& out, std::string_view key, const T& obj, int n) {
              toml::array a;
              for (int j = 0; j < n; ++j) a.push_back(c.at(obj, j));
              out.insert(key, a);
            },
            nullptr,
            c.bounds.describe() + ", one per joint (an array) or one for all",
            {}};
  }
};
template <class At>
PerJointCodec<At> per_joint(Bounds b, At at) { return {b, at}; }

// An array of size(obj, n) numbers, each within bounds, got and set as a vector.
template <class Size, class Get, class Set>
struct NumbersCodec {
  Size size;
  Bounds bounds;
  Get get;
  Set set;
  template <class T>
  operator Codec<T>() const {  // NOLINT(google-explicit-constructor)
    const NumbersCodec c = *this;
    return {[c](StrictTable& t, std::string_view key, T& obj, int n) {
              c.set(obj, t.numbers(key, c.size(obj, n), c.bounds));
            },
            [c](toml::table& out, std::string_view key, const T& obj, int n) {
              toml::array a;
              for (double x : c.get(obj, n)) a.push_back(x);
              out.insert(key, a);
            },
            [c](const T& obj) { return c.get(obj, 0).empty(); },
            "an array of numbers, each " + c.bounds.describe(),
            {}};
  }
};
template <class Size, class Get, class Set>
NumbersCodec<Size, Get, Set> numbers(Size size, Bounds b, Get get, Set set) {
  return {size, b, get, set};
}

inline std::string need_name(Need n) {
  switch (n) {
    case Need::kRequired:
      return "required";
    case Need::kIfSet:
      return "if set";
    case Need::kOptional:
      break;
  }
  return "optional";
}

// When entry e means something: its `when`; else the values of the entry it
// is decided by (decided_by) for which its fn holds, each read into a copy of
// every one of `prototypes` (the section's struct at its defaults, sized for
// one joint, in each of its shapes: a Cartesian path and a joint-space
// reference) by that entry's own codec; a decider that is not a choice (a
// file, a pose): whether it is given. Where the answer differs between the
// prototypes, fn reads more than its decider, and the entry must say its
// condition in words (`when`): an InternalError until it does. Empty: always.
template <class T>
std::string applies_text(const std::vector<Entry<T>>& entries, const Entry<T>& e, const std::vector<T>& prototypes) {
  if (!e.applies.fn) return "";
  if (!e.applies.when.empty()) return std::string(e.applies.when);
  const std::string key(e.key), by(e.applies.decided_by);
  const Entry<T>* decider = find_entry(entries, e.applies.decided_by);
  PUMASIM_DEMAND(decider != nullptr, "scene entry " + key + ": decided by '" + by + "', no such entry");
  const auto holds = [&](const auto& set) -> bool {  // fn on each prototype after set(obj): the same on all
    std::vector<bool> r;
    for (T obj : prototypes) r.push_back((set(obj), e.applies.fn(obj)));
    PUMASIM_DEMAND(std::all_of(r.begin(), r.end(), [&](bool b) { return b == r[0]; }),
                   "scene entry " + key + ": its condition reads more than '" + by + "'; give it applies.when");
    return r[0];
  };
  if (decider->codec.names.empty()) return by + (holds([](T&) {}) ? " not given" : " given");
  std::string yes;
  for (const std::string& name : decider->codec.names) {
    const bool applies = holds([&](T& obj) {
      toml::table doc;
      doc.insert(by, name);
      StrictTable t(doc, "(reference)", "");
      decider->codec.read(t, by, obj, 1);
    });
    if (applies) yes += (yes.empty() ? "" : " or ") + ("\"" + name + "\"");
  }
  PUMASIM_DEMAND(!yes.empty(), "scene entry " + key + ": applies under no value of '" + by + "'");
  return by + " = " + yes;
}

// The reference's rows for one section's table.
template <class T>
void add_key_docs(std::vector<SceneKeyDoc>& out, std::string_view section, const std::vector<Entry<T>>& entries,
                  const std::vector<T>& prototypes) {
  for (const Entry<T>& e : entries) {
    out.push_back({std::string(section), std::string(e.key), need_name(e.need), e.codec.what, std::string(e.meaning),
                   applies_text(entries, e, prototypes)});
  }
}

}  // namespace pumasim::scene_io
