// The plant's state vector as slices that the blocks declare: each block
// appends its components (names and typical magnitudes) and keeps the offset
// it was given.
#pragma once

#include <string>
#include <vector>

namespace pumasim {

struct StateLayout {
  int n = 0;      // simulated joints
  int q = 0;      // offsets of the slices; -1 when absent
  int qd = 0;
  int i = -1;
  int z = -1;
  int zf = -1;    // a friction law's state per joint (LuGre's bristles), when the law has one
  int e = -1;     // energy ledger: e_in, e_copper, e_friction
  int size = 0;
  std::vector<std::string> names;  // q1.., qd1.., i_motor1.., z_piv1.., e_in, e_copper, e_friction
  // A typical magnitude of each component, in its unit (the integrators'
  // absolute tolerance is atol times this).
  std::vector<double> scale;
  // The physically possible range of each component, |x_k| <= bound[k] in
  // its unit (+inf: none), and the formula it came from
  // (models/plant/physical_bounds.hpp).
  std::vector<double> bound;
  std::vector<std::string> bound_why;

  // Appends a slice; returns its offset.
  int add(const std::vector<std::string>& slice_names, const std::vector<double>& slice_scale);
  // Sets component k's bound (a finite bound > 0; others leave it +inf).
  void set_bound(int k, double value, const std::string& why);
  int index(const std::string& name) const;  // -1 if absent
};

// "q1", "q2", ... "q<n>".
std::vector<std::string> joint_names(const char* prefix, int n);

}  // namespace pumasim
