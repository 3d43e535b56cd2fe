// A TOML document as text, without toml++ 3.3's toml_formatter for arrays.
//
// toml++ 3.3 decides whether an array fits on one line by estimating each
// element's width (toml_formatter_count_inline_columns) with
// static_cast<size_t>(log10(x)): for a float below 1 in magnitude (0.0005),
// inf or nan, a negative double converted to size_t, undefined behaviour that
// UndefinedBehaviorSanitizer reports (float-cast-overflow); INT64_MIN
// overflows there too. write_toml prints the structure itself -- tables,
// arrays of tables, arrays (on one line), inline tables -- and only each
// leaf value through toml++, whose leaf printing is not affected, so that
// numbers and strings read back exactly as before.
#pragma once

#include <string>

#include <toml++/toml.h>

namespace pumasim {

std::string write_toml(const toml::table& doc);

}  // namespace pumasim
