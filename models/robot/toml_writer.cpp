#include "models/robot/toml_writer.hpp"

#include <sstream>

namespace pumasim {
namespace {

bool is_bare(std::string_view key) {
  if (key.empty()) return false;
  for (const char c : key) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

std::string key_text(std::string_view key) {
  if (is_bare(key)) return std::string(key);
  std::ostringstream s;
  s << toml::value<std::string>(std::string(key));  // a quoted, escaped string
  return s.str();
}

void write_value(std::ostream& out, const toml::node& v);

void write_inline(std::ostream& out, const toml::table& t) {
  if (t.empty()) {
    out << "{}";
    return;
  }
  out << "{ ";
  bool first = true;
  for (const auto& [k, v] : t) {
    out << (first ? "" : ", ") << key_text(k.str()) << " = ";
    write_value(out, v);
    first = false;
  }
  out << " }";
}

void write_value(std::ostream& out, const toml::node& v) {
  if (const toml::array* a = v.as_array()) {
    if (a->empty()) {
      out << "[]";
      return;
    }
    out << "[ ";
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (i) out << ", ";
      write_value(out, *a->get(i));
    }
    out << " ]";
  } else if (const toml::table* t = v.as_table()) {
    write_inline(out, *t);
  } else {
    v.visit([&](const auto& leaf) { out << toml::toml_formatter(leaf); });
  }
}

bool is_section(const toml::node& v) { return v.is_table() || v.is_array_of_tables(); }

void write_table(std::ostream& out, const toml::table& t, const std::string& path) {
  for (const auto& [k, v] : t) {
    if (is_section(v)) continue;
    out << key_text(k.str()) << " = ";
    write_value(out, v);
    out << "\n";
  }
  for (const auto& [k, v] : t) {
    const std::string sub = (path.empty() ? "" : path + ".") + key_text(k.str());
    if (const toml::table* st = v.as_table()) {
      out << "\n[" << sub << "]\n";
      write_table(out, *st, sub);
    } else if (v.is_array_of_tables()) {
      for (const toml::node& e : *v.as_array()) {
        out << "\n[[" << sub << "]]\n";
        write_table(out, *e.as_table(), sub);
      }
    }
  }
}

}  // namespace

std::string write_toml(const toml::table& doc) {
  std::ostringstream out;
  write_table(out, doc, "");
  return out.str();
}

}  // namespace pumasim
