#pragma once
// Shared by the network-solver tests (test_network_solver.cpp, test_network_invariance.cpp).
#include <gtest/gtest.h>

#include "netdem/quasistatic/network_solver.hpp"

namespace netdem::test {

// Every field of the measures and the positions, compared exactly.
inline void expect_same_state(const qs::NetworkSolver& a, const qs::NetworkSolver& b) {
  const auto ma = a.measures(), mb = b.measures();
  EXPECT_EQ(ma.S11, mb.S11);
  EXPECT_EQ(ma.S22, mb.S22);
  EXPECT_EQ(ma.S12, mb.S12);
  EXPECT_EQ(ma.S11_contacts, mb.S11_contacts);
  EXPECT_EQ(ma.density, mb.density);
  EXPECT_EQ(ma.contacts, mb.contacts);
  EXPECT_EQ(ma.sliding, mb.sliding);
  EXPECT_EQ(ma.dev_normal_mean_ratio, mb.dev_normal_mean_ratio);
  EXPECT_EQ(ma.dev_tangential_rotations, mb.dev_tangential_rotations);
  EXPECT_EQ(a.x(), b.x());
  EXPECT_EQ(a.y(), b.y());
  EXPECT_EQ(a.theta(), b.theta());
}

}  // namespace netdem::test
