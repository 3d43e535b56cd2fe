// The workarounds of toml++ 3.3's defects. The guard in front of its parser
// (models/robot/toml_guard.hpp): the inputs that reach its four parser defects are
// refused with a message naming file, line and what was expected; valid TOML
// that looks like them still parses. The writer (models/robot/toml_writer.hpp):
// arrays printed without toml++'s width estimate, which is undefined
// behaviour for floats below 1, inf and nan (the sanitizer build fails there).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <fstream>
#include <sstream>

#include "experiments/cli.hpp"
#include "models/robot/robot_file.hpp"
#include "models/robot/toml_guard.hpp"
#include "models/robot/toml_writer.hpp"
#include "models/scene/scene.hpp"
#include "tests/scene_paths.hpp"
#include "tests/scratch.hpp"

namespace pumasim {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const auto dir = testing::scratch_root() / "pumasim_test_toml_guard";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / (name + ".toml")).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// load_robot_file refuses `text` with every fragment in its message, and
// `pumasim dynamics` exits with status 2 on it.
void expect_toml_refused(const std::string& name, const std::string& text, const std::vector<std::string>& fragments) {
  const std::string path = write_temp(name, text);
  try {
    load_robot_file(path);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << f << "\n in: " << msg;
  }
  std::ostringstream out, err;
  EXPECT_EQ(run_cli({"dynamics", "--robot", path, "--backend", "crba", "--q=0"}, out, err), kExitBadInput);
  EXPECT_TRUE(out.str().empty());
}

constexpr const char* kHead = "[robot]\nname = \"one\"\nconvention = \"standard\"\ngravity = [0.0, 0.0, -9.81]\n";
constexpr const char* kNoKey = ": TOML syntax error: expected a table name after '";

// toml++ 3.3 calls parse_key() on a character that cannot start a key: an
// assertion with asserts on, undefined behaviour (an assumption) without.
TEST(TomlGuard, TableHeaderWithoutAKeyIsRefusedBeforeToml) {
  expect_toml_refused("bracket_newline", std::string(kHead) + "[\n", {"bracket_newline.toml:5", kNoKey, "got a line break"});
  expect_toml_refused("bracket_eof", "[", {"bracket_eof.toml:1", kNoKey, "got the end of the text"});
  expect_toml_refused("brackets_newline", std::string(kHead) + "[[\njoint]]\n", {":5", "after '[['", "got a line break"});
  expect_toml_refused("three_brackets", "[[[1]]]\n", {":1", "after '[['", "got '['"});
  expect_toml_refused("bracket_equals", "a = 1\n  [ =\n", {":2", "after '['", "got '='"});
  expect_toml_refused("bracket_hash", "[# a comment\n", {":1", "after '['", "got '#'"});
}

// toml++ 3.3 calls parse_value() on a '}' where an array expects a value: an
// assertion with asserts on, an assumption without (found by fuzz_scene).
TEST(TomlGuard, ClosingBraceInAnArrayIsRefused) {
  const std::string expected = ": TOML syntax error: expected a value, ',' or ']' in the array opened before, got '}'";
  expect_toml_refused("brace_in_array", "a = [}\n", {"brace_in_array.toml:1" + expected});
  expect_toml_refused("brace_after_comma", "a = [ 1,\n  }\n", {"brace_after_comma.toml:2" + expected});
  expect_toml_refused("brace_in_nested_array", "a = { b = [}] }\n", {":1" + expected});
}

// A date, a space and one digit: toml++ 3.3 scans for a time from a value
// terminator, an asserted precondition (found by fuzz_robot's long run).
TEST(TomlGuard, DateSpaceDigitIsRefused) {
  const std::string expected = ": TOML syntax error: expected a time hh:mm:ss after a date and a space, got '0'";
  expect_toml_refused("date_space_digit", "d = 1979-05-27 0\n", {"date_space_digit.toml:1" + expected});
  expect_toml_refused("date_space_digit_in_array", "d = [1979-05-27 0]\n", {":1" + expected});
  const std::string ok = "d = 1979-05-27 07:32:00\ne = 1979-05-27 # 0\nf = [1979-05-27 ]\n";
  EXPECT_FALSE(find_toml_hazard(ok).has_value());
  const toml::table t = toml::parse(std::string_view(ok), std::string_view("dates"));
  EXPECT_TRUE(t["d"].is_date_time());
  EXPECT_TRUE(t["e"].is_date());
}

// toml++ 3.3's is_non_ascii_horizontal_whitespace reaches TOML_UNREACHABLE
// for 'é' (U+00E9) and others.
TEST(TomlGuard, NonAsciiWhereTomlAsksForWhitespaceIsRefused) {
  const std::string ascii = "expected ASCII outside strings and comments";
  expect_toml_refused("bare_key", std::string(kHead) + "\xC3\xA9 = 1\n", {":5: TOML syntax error: " + ascii,
                                                                      "got a non-ASCII character (first byte 0xC3)"});
  expect_toml_refused("after_value", "a = 1\xC3\xA9\n", {":1", "expected ASCII in a value that is not a string"});
  expect_toml_refused("in_header", "[r\xC3\xA9]\n", {":1", ascii});
  expect_toml_refused("after_quoted_key", "\"a\"\xE2\x80\x83= 1\n", {":1", ascii});
  expect_toml_refused("escape", "a = \"\"\"x\n\\\xC3\xA9\"\"\"\n", {":2", "expected an escape sequence after '\\'"});
  expect_toml_refused("escape_single_line", "a = \"\\\xC3\xA9\"\n", {":1", "expected an escape sequence"});
  // A quote after a value's first characters opens no string: toml++ reads on (found by fuzz_robot).
  expect_toml_refused("quote_inside_bare_value", "a = 0[offso\"x\xC3\xA9 \"ro]\n", {":1", "expected ASCII in a value"});
  const std::string bare = "expected ASCII in a value that is not a string";
  expect_toml_refused("quote_after_dot_in_value", "a = [3, 665.\"x\xEF\xBB\xB5\"]\n", {":1", bare});
  expect_toml_refused("quote_after_equals_in_value", "a=+a=+OOa=\"off\xEF\xB5\xBF\"\n", {":1", bare});
  expect_toml_refused("after_line_ending_backslash", "a = \"\"\"x \\\n\n   \xC3\xA9\"\"\"\n",
                 {":3", "expected an ASCII character first after a line-ending backslash", "\\uXXXX"});
}

// Valid TOML that looks like the refused input: the guard finds nothing and
// toml++ reads the values.
TEST(TomlGuard, ValidLookAlikesParse) {
  const std::string text =
      "\xEF\xBB\xBF# \xC3\xA9 in a comment [\n"
      "nested = [\n  [1, 2],\n  [\n    3],\n  [ ]\n]\n"
      "table = { a = [[1], [2]] }\n"
      "\"k\xC3\xA9y\" = '\\\xC3\xA9'\n"
      "basic = \"\xC3\xA9 \\u00e9 [\"\n"
      "multi = \"\"\"\n[\n\\\"\xC3\xA9\"\"\"\n"
      "cont = \"\"\"a \\\n    b\xC3\xA9\"\"\"\n"
      "lit = '''\n[\n\\\xC3\xA9'''\n"
      "quotes = \"\"\"x\"\"\"\"\"\n"
      "dotted.\"k\xC3\xA9y\" = { x.\"\xC3\xA9\" = 1, y . '\xC3\xA9' = [\"\xC3\xA9\"] }\n"
      "[ \"a b\" . c ]\n"
      "[[ list ]]\n"
      "[\t'l' ]\n";
  EXPECT_FALSE(find_toml_hazard(text).has_value()) << find_toml_hazard(text)->expected;
  const toml::table t = toml::parse(std::string_view(text), std::string_view("look-alikes"));
  EXPECT_EQ(t["nested"][1][0].value_or(0), 3);
  EXPECT_EQ(t["nested"][2].as_array()->size(), 0u);
  EXPECT_EQ(t["table"]["a"][1][0].value_or(0), 2);
  EXPECT_EQ(t["k\xC3\xA9y"].value_or(std::string()), "\\\xC3\xA9");
  EXPECT_EQ(t["basic"].value_or(std::string()), "\xC3\xA9 \xC3\xA9 [");
  EXPECT_EQ(t["multi"].value_or(std::string()), "[\n\"\xC3\xA9");
  EXPECT_EQ(t["cont"].value_or(std::string()), "a b\xC3\xA9");
  EXPECT_EQ(t["lit"].value_or(std::string()), "[\n\\\xC3\xA9");
  EXPECT_EQ(t["quotes"].value_or(std::string()), "x\"\"");
  EXPECT_TRUE(t["a b"]["c"].is_table());
  EXPECT_EQ(t["dotted"]["k\xC3\xA9y"]["y"]["\xC3\xA9"][0].value_or(std::string()), "\xC3\xA9");
  EXPECT_TRUE(t["list"].is_array_of_tables());
  EXPECT_TRUE(t["l"].is_table());
}

TEST(TomlGuard, EveryShippedFilePassesTheGuard) {
  std::vector<std::filesystem::path> files;
  for (const std::string& dir : {robots_dir(), std::string(PUMASIM_SCENES_DIR)}) {
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      if (e.path().extension() == ".toml") files.push_back(e.path());
    }
  }
  EXPECT_GE(files.size(), 10u);
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto hazard = find_toml_hazard(text);
    EXPECT_FALSE(hazard.has_value()) << f << ":" << hazard->line << ": " << hazard->expected;
  }
}

// The --set text goes through the same guard: "KEY = VALUE" is what toml++ parses.
// The library names the option neutrally ({{set}}: core/option_words.hpp).
TEST(TomlGuard, SetOverridesAreGuardedToo) {
  const std::string scene = test::scene_path("paper_slow");
  auto message = [&](const std::string& set) -> std::string {
    try {
      load_scene(scene, {set});
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(message("x\n[=1").find("{{set}} x\n[=1: expected section.key=value with a TOML value (expected a table "
                                   "name after '['"),
            std::string::npos)
      << message("x\n[=1");
  EXPECT_NE(message("scene.\xC3\xA9=1").find("(expected ASCII outside strings and comments"), std::string::npos);
  // In a string the guard lets it through: the scene's own check of the name answers.
  EXPECT_NE(message("scene.name=\"\xC3\xA9\"").find("scene.name: expected a plain name"), std::string::npos)
      << message("scene.name=\"\xC3\xA9\"");
}

TEST(TomlWriter, EveryValueReadsBackExactly) {
  const double inf = std::numeric_limits<double>::infinity();
  toml::table doc;
  doc.insert("top", toml::table{{"small", toml::array{0.0005, -2.5e-300, 0.1, inf, -inf}},
                                {"ints", toml::array{std::numeric_limits<std::int64_t>::min(), 0, 7}},
                                {"nan", toml::array{std::numeric_limits<double>::quiet_NaN()}},
                                {"mixed", toml::array{toml::table{{"a", 0.25}}, toml::array{"x", "\xC3\xA9"}}},
                                {"key with space", true}});
  doc.insert("list", toml::array{toml::table{{"q", toml::array{0.3, 0.4}}}, toml::table{{"q", toml::array{}}}});
  const std::string text = write_toml(doc);
  const toml::table back = toml::parse(std::string_view(text), std::string_view("written"));
  const toml::array& small = *back["top"]["small"].as_array();
  ASSERT_EQ(small.size(), 5u) << text;
  EXPECT_EQ(small[0].value_or(0.0), 0.0005);
  EXPECT_EQ(small[1].value_or(0.0), -2.5e-300);
  EXPECT_EQ(small[3].value_or(0.0), inf);
  EXPECT_EQ(small[4].value_or(0.0), -inf);
  EXPECT_EQ(back["top"]["ints"][0].value_or(std::int64_t{0}), std::numeric_limits<std::int64_t>::min());
  EXPECT_TRUE(std::isnan(back["top"]["nan"][0].value_or(0.0)));
  EXPECT_EQ(back["top"]["mixed"][0]["a"].value_or(0.0), 0.25);
  EXPECT_EQ(back["top"]["mixed"][1][1].value_or(std::string()), "\xC3\xA9");
  EXPECT_TRUE(back["top"]["key with space"].value_or(false));
  EXPECT_EQ(back["list"][0]["q"][1].value_or(0.0), 0.4);
  EXPECT_EQ(back["list"][1]["q"].as_array()->size(), 0u);
  EXPECT_EQ(back, doc) << text;
}

}  // namespace
}  // namespace pumasim
