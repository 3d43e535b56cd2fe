#include <gtest/gtest.h>
#include "models/backend.hpp"
#include "models/robot_file.hpp"
TEST(Smoke, Loads) { auto m = pumasim::load_robot("puma560"); EXPECT_EQ(m.dof(), 6); }
