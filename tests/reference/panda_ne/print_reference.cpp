// Prints the reference values of tests/test_reference_values.cpp's
// PublishedValues.PandaDynamicsOfTheShippedSet (H, g, C qd of the Panda's p^
// at its configurations) from independent_ne.hpp, a Newton-Euler code written
// for that cross-check apart from pumasim (README.md beside this file):
//
//   g++ -std=c++17 -O0 -ffp-contract=off -I /usr/include/eigen3 print_reference.cpp -o /tmp/print_reference
//   /tmp/print_reference
#include <cstdio>

#include "independent_ne.hpp"

namespace {

void print(const char* what, const indep::V7& v) {
  std::printf("%s", what);
  for (int i = 0; i < 7; ++i) std::printf(" %.17g", v(i));
  std::printf("\n");
}

}  // namespace

int main() {
  const indep::Model m;
  const double g0 = 9.80665;
  indep::V7 q[4], qd[2];
  q[0].setZero();
  q[1] << 0.3, -0.5, 0.2, -1.8, 0.1, 1.6, 0.7;
  q[2] << -1.0, 0.8, -0.6, -2.2, 0.9, 2.5, -1.4;
  q[3] << 2.0, -1.2, 1.5, -0.5, -2.0, 3.0, 2.2;
  qd[0] << 0.5, -0.4, 0.3, 0.6, -0.7, 0.2, -0.9;
  qd[1] << -0.8, 0.3, 0.9, -0.2, 0.4, -0.6, 1.1;
  const char* names[4] = {"q_a", "q_b", "q_c", "q_d"};
  for (int k = 0; k < 4; ++k) {
    std::printf("%s\n", names[k]);
    print("  g", m.gravity(q[k], g0));
    const indep::M7 H = m.mass_matrix(q[k]);
    for (int i = 0; i < 7; ++i) print("  H row", H.row(i).transpose());
  }
  print("C qd at (q_b, qd_b)", m.coriolis_vec(q[1], qd[0]));
  print("C qd at (q_c, qd_c)", m.coriolis_vec(q[2], qd[1]));
  return 0;
}
