// The one shape of pumasim's registries (integrators, dynamics back-ends,
// friction and controller laws): a table of entries sorted by name, each
// entry's `name` a C string, looked up by binary search. Lookup failures name
// the valid entries; the tables' order is checked where they are built
// (sorted_unique, at compile time where the names are constants).
#pragma once

#include <algorithm>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace pumasim {

// True if the names are strictly increasing: sorted, no name twice.
template <class Range>
constexpr bool sorted_unique(const Range& names) {
  auto it = std::begin(names);
  if (it == std::end(names)) return true;
  for (auto prev = it++; it != std::end(names); prev = it++) {
    if (!(std::string_view(*prev) < std::string_view(*it))) return false;
  }
  return true;
}

// "a, b, c": the entries' names, for messages.
template <class Entry>
std::string entry_names(std::span<const Entry> all) {
  std::string s;
  for (const Entry& e : all) {
    if (!s.empty()) s += ", ";
    s += e.name;
  }
  return s;
}

// The entry called `name`, or nullptr.
template <class Entry>
const Entry* find_entry_or_null(std::span<const Entry> all, std::string_view name) {
  const auto it = std::lower_bound(all.begin(), all.end(), name, [](const Entry& e, std::string_view key) {
    return std::string_view(e.name) < key;
  });
  return it == all.end() || std::string_view(it->name) != name ? nullptr : &*it;
}

// The entry called `name`; std::invalid_argument "unknown <what> 'name';
// expected one of: a, b, c" otherwise.
template <class Entry>
const Entry& find_entry(std::span<const Entry> all, std::string_view name, std::string_view what) {
  if (const Entry* e = find_entry_or_null(all, name)) return *e;
  throw std::invalid_argument("unknown " + std::string(what) + " '" + std::string(name) +
                              "'; expected one of: " + entry_names(all));
}

// True if the entries' names are strictly increasing (a constexpr table's
// order is checked with static_assert).
template <class Range>
constexpr bool entries_sorted_unique(const Range& entries) {
  return std::adjacent_find(std::begin(entries), std::end(entries), [](const auto& a, const auto& b) {
           return !(std::string_view(a.name) < std::string_view(b.name));
         }) == std::end(entries);
}

}  // namespace pumasim
