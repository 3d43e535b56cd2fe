"""scripts/cpp_functions.py, the C++ function-size check's scanner, on code
written to trip it: each body's first line and length are counted by hand."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import cpp_functions  # noqa: E402

SOURCE = r'''#include <string>
#define BRACES { }
namespace a {
namespace {
const int kTable[] = {1, 2, 3};
struct S {
  int x{0};
  int f() const {
    return x;
  }
};
}  // namespace
S::S(int v)
    : x_(v), y_{v} {
  auto l = [](int k) {
    return k;
  };
  const char* s = "}}}";
  const char* r = R"x(}{)x";
  char c = '}';  // }
  /* } */
}
TEST(Suite, Name) {
  EXPECT_EQ(1'000, 1000);
}
template <class T>
auto g(T t) -> T {
  return t;
}
extern "C" {
int h(void) { return 0; }
}
}  // namespace a
'''


def test_bodies_and_lengths():
    got = cpp_functions.functions(SOURCE)
    assert got == [(8, "f", 3), (13, "S", 10), (23, "TEST", 3), (26, "g", 4), (31, "h", 1)]


def test_literals_and_comments_are_blank_with_their_lines():
    b = cpp_functions.blank(SOURCE)
    assert b.count("\n") == SOURCE.count("\n")
    assert "}}}" not in b and "R\"x" not in b and "'}'" not in b
