#include "models/scene/joint_csv.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "models/robot/input_files.hpp"
#include "models/robot/strict_toml.hpp"

namespace pumasim {
namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) out.push_back(trim(field));
  if (!line.empty() && line.back() == ',') out.emplace_back();  // a trailing empty field
  return out;
}

std::string columns_expected(int n, std::string_view column) {
  const std::string c(column);
  return std::to_string(n + 1) + " columns (t, then " + c + "1 ... " + c + std::to_string(n) + " for the scene's " +
         std::to_string(n) + " simulated joints)";
}

// The row's values, each a finite number.
std::vector<double> parse_row(const std::vector<std::string>& fields, const std::vector<std::string>& header,
                              const std::string& at) {
  std::vector<double> row;
  for (std::size_t c = 0; c < fields.size(); ++c) {
    const std::string& f = fields[c];
    double x = 0;
    const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), x);
    if (f.empty() || ec != std::errc() || end != f.data() + f.size() || !std::isfinite(x)) {
      throw ConfigError(at + "column " + std::to_string(c + 1) + " (" + header[c] +
                        "): expected a finite number, got \"" + f + "\"");
    }
    row.push_back(x);
  }
  return row;
}

// Why the curve through rows a then b (t, then the values) cannot be finite,
// or "": a time step below kMinRowStep or above kMaxRowStep, or a value jump
// dq whose scales dq/dt^e, e = 0 ... 4, overflow within a factor of 1e3: the
// splines' coefficients and knot equations are sums of a few such terms from
// neighbouring segments with integer weights (the quintic's knot equations
// reach 360 dq/dt^4), so a point of 1e308 rad, finite itself, gave an
// infinite curve, and so did a jump of 1e290 rad in 1e-6 s (fuzz_joint_csv).
std::string step_problem(const std::vector<double>& a, const std::vector<double>& b, std::string_view column) {
  const double dt = b[0] - a[0];
  if (!(dt >= kMinRowStep)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "expected a time at least %g s after the previous row's %.17g s, got %.17g s",
                  kMinRowStep, a[0], b[0]);
    return buf;
  }
  if (!(dt <= kMaxRowStep)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "expected a time at most %g s after the previous row's %.17g s, got %.17g s "
                  "(the curve's terms in the step's fourth power overflow)", kMaxRowStep, a[0], b[0]);
    return buf;
  }
  for (std::size_t c = 1; c < a.size() && c < b.size(); ++c) {
    const double dq = b[c] - a[c];
    bool finite = std::isfinite(dq);
    double scale = dq;  // dq / dt^e
    for (int e = 0; finite && e <= 4; ++e, scale /= dt) finite = std::isfinite(1e3 * scale);
    if (!finite) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "expected values whose curve is finite, got %s%zu going from %.6g to %.6g in "
                    "%.6g s (its slope or curvature overflows)", std::string(column).c_str(), c, a[c], b[c], dt);
      return buf;
    }
  }
  return {};
}

}  // namespace

void check_joint_rows(const std::vector<std::vector<double>>& rows, int n, const std::string& where,
                      std::string_view column) {
  if (rows.size() < 2) {
    throw ConfigError(where + "expected at least two points (rows t, " + std::string(column) + "1 ... " +
                      std::string(column) + "n), got " + std::to_string(rows.size()));
  }
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::string row = "row " + std::to_string(k + 1) + ": ";
    if (rows[k].size() != static_cast<std::size_t>(n + 1)) {
      throw ConfigError(where + row + "expected " + columns_expected(n, column) + ", got " +
                        std::to_string(rows[k].size()));
    }
    for (double x : rows[k]) {
      if (!std::isfinite(x)) throw ConfigError(where + row + "expected finite numbers, got " + std::to_string(x));
    }
    if (k == 0 && rows[0][0] != 0.0) {
      throw ConfigError(where + row + "expected the first point at t = 0, got t = " + std::to_string(rows[0][0]));
    }
    if (k > 0 && !(rows[k][0] > rows[k - 1][0])) {
      throw ConfigError(where + row + "expected t after the previous row's " + std::to_string(rows[k - 1][0]) +
                        " s (strictly increasing times), got " + std::to_string(rows[k][0]));
    }
    if (k > 0) {
      if (const std::string why = step_problem(rows[k - 1], rows[k], column); !why.empty()) {
        throw ConfigError(where + row + why);
      }
    }
  }
}

std::vector<std::vector<double>> read_joint_csv(const std::string& path, int n, std::string_view column) {
  const std::optional<std::string> text = read_input_file(path);
  if (!text) throw ConfigError(path + ": cannot be read (" + unreadable_reason(path) + "); expected a CSV file");
  std::istringstream in(*text);
  std::vector<std::vector<double>> rows;
  std::vector<std::string> header;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (trim(line).empty()) continue;
    const std::string at = path + ":" + std::to_string(number) + ": ";
    const std::vector<std::string> fields = split(line);
    if (fields.size() != static_cast<std::size_t>(n + 1)) {
      throw ConfigError(at + "expected " + columns_expected(n, column) + ", got " + std::to_string(fields.size()));
    }
    if (header.empty()) {
      header = fields;
      continue;
    }
    rows.push_back(parse_row(fields, header, at));
    // The time checks here too, to name the line.
    const std::size_t k = rows.size() - 1;
    if (k == 0 && rows[0][0] != 0.0) {
      throw ConfigError(at + "column 1 (" + header[0] + "): expected the first point at t = 0, got " + fields[0]);
    }
    if (k > 0 && !(rows[k][0] > rows[k - 1][0])) {
      throw ConfigError(at + "column 1 (" + header[0] + "): expected a time after the previous row's " +
                        std::to_string(rows[k - 1][0]) + " s (strictly increasing), got " + fields[0]);
    }
    if (k > 0) {
      if (const std::string why = step_problem(rows[k - 1], rows[k], column); !why.empty()) {
        throw ConfigError(at + why);
      }
    }
  }
  if (header.empty()) {
    throw ConfigError(path + ": expected a header line, then rows t, " + std::string(column) + "1 ... " +
                      std::string(column) + "n; the file is empty");
  }
  check_joint_rows(rows, n, path + ": ", column);
  return rows;
}

}  // namespace pumasim
