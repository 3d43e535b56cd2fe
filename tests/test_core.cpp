// core/: the registries' shape and the invariant macro.
#include <gtest/gtest.h>

#include <array>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/invariant.hpp"
#include "core/option_words.hpp"
#include "core/registry.hpp"

namespace pumasim {
namespace {

struct CoreTestEntry {
  const char* name;
  int value;
};

constexpr std::array<CoreTestEntry, 3> kCoreTestTable{{{"alpha", 1}, {"beta", 2}, {"gamma", 3}}};
static_assert(entries_sorted_unique(kCoreTestTable));
static_assert(!entries_sorted_unique(std::array<CoreTestEntry, 2>{{{"b", 1}, {"a", 2}}}), "out of order");
static_assert(!entries_sorted_unique(std::array<CoreTestEntry, 2>{{{"a", 1}, {"a", 2}}}), "a name twice");
static_assert(sorted_unique(std::array<std::string_view, 3>{"ab", "abc", "b"}));
static_assert(!sorted_unique(std::array<std::string_view, 2>{"abc", "ab"}), "a prefix sorts first");

TEST(CoreRegistry, FindsEveryEntryAndNamesTheValidOnesOtherwise) {
  const std::span<const CoreTestEntry> all(kCoreTestTable);
  for (const CoreTestEntry& e : kCoreTestTable) EXPECT_EQ(&find_entry(all, e.name, "thing"), &e);
  EXPECT_EQ(find_entry_or_null(all, "delta"), nullptr);
  EXPECT_EQ(find_entry_or_null(all, "alph"), nullptr) << "a prefix is not a name";
  EXPECT_EQ(entry_names(all), "alpha, beta, gamma");
  try {
    find_entry(all, "delta", "thing");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown thing 'delta'; expected one of: alpha, beta, gamma");
  }
}

TEST(CoreInvariant, AFalseConditionIsAnInternalErrorNamingItAndWhere) {
  EXPECT_NO_THROW(PUMASIM_DEMAND(1 + 1 == 2, "arithmetic"));
  const int line = __LINE__ + 2;
  try {
    PUMASIM_DEMAND(1 + 1 == 3, std::string("the sum"));
    FAIL() << "expected an error";
  } catch (const InternalError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("a bug in pumasim"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the sum"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1 + 1 == 3 is false"), std::string::npos) << msg;
    EXPECT_NE(msg.find("test_core.cpp:" + std::to_string(line)), std::string::npos) << msg;
  }
}

// The library names an option as {{name}}; each caller's words replace
// exactly those tokens, and nothing else (a TOML inline table's braces, an
// unfinished or empty token, upper-case letters) is touched.
TEST(CoreOptionWords, EachTokenIsTheCallersWordAndNothingElseChanges) {
  const OptionWords cli = [](std::string_view n) {
    std::string w = "--" + std::string(n);
    for (char& c : w) c = c == '_' ? '-' : c;
    return w;
  };
  EXPECT_EQ(option_word("max_steps"), "{{max_steps}}");
  EXPECT_EQ(phrased("more steps: a larger {{max_steps}}; {{dt}} or {{rtol}}", cli),
            "more steps: a larger --max-steps; --dt or --rtol");
  EXPECT_EQ(phrased("{{set}} a={b={c=1}}: x", cli), "--set a={b={c=1}}: x");
  for (const char* kept : {"{{}}", "{{Dt}}", "{{dt", "{dt}", "{{ dt}}", "{{dt}", "}}{{"}) {
    EXPECT_EQ(phrased(kept, cli), kept) << kept;
  }
  EXPECT_EQ(phrased("{{{dt}}}", cli), "{--dt}") << "the first '{{' that starts a token";
  EXPECT_EQ(phrased("{{t_end}} and {{t_end}}", {}), "t_end and t_end") << "no words: the neutral names";
  EXPECT_EQ(phrased("", cli), "");
}

}  // namespace
}  // namespace pumasim
