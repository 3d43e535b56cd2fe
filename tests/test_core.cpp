// core/: the registries' shape and the invariant macro.
#include <gtest/gtest.h>

#include <array>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/invariant.hpp"
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

}  // namespace
}  // namespace pumasim
