// Bounds on a number read from a file, and how a message says them
// (definitions in strict_toml.cpp). Light: the plant's controller laws
// declare their keys' bounds with it.
#pragma once

#include <limits>
#include <string>

namespace pumasim {

// Closed or half-open interval for a number, with how to say it in a message.
struct Bounds {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;  // lo itself is not allowed
  bool hi_open = false;
  bool or_infinity = false;  // +inf allowed too (a limit that means "none")

  static Bounds any() { return {}; }
  static Bounds non_negative() { return {0.0}; }
  static Bounds positive() { return {0.0, std::numeric_limits<double>::infinity(), true}; }
  static Bounds positive_or_infinity() { return {0.0, std::numeric_limits<double>::infinity(), true, false, true}; }
  bool contains(double x) const;
  std::string describe() const;  // "a number > 0", "a number > 0 or inf"
};

}  // namespace pumasim
