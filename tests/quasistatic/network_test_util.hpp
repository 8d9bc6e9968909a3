#pragma once
// Shared by the network-solver tests (test_network_solver.cpp, test_network_invariance.cpp,
// test_equilibrium.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "test_scale.hpp"

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

// Square lattice of nc x nr touching disks of radius R filling the box [0, 2 R nc] x [0, 2 R nr].
inline packing::Packing square_lattice(int nc, int nr, double R = 1.0) {
  packing::Packing p;
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c < nc; ++c) {
      p.x.push_back(R + 2 * R * c);
      p.y.push_back(R + 2 * R * r);
      p.r.push_back(R);
    }
  p.box = {0.0, 0.0, 2 * R * nc, 2 * R * nr};
  return p;
}

struct RunResult {
  qs::StateMeasures m;
  int unconverged = 0;
  double max_residual = 0;
};

// The random test packing: r = R[0.9, 1.1], deposited in a box of the given width.
inline packing::Packing random_packing(double width, std::uint64_t seed) {
  packing::DepositionOptions d;
  d.width = width;
  d.seed = seed;
  return packing::ballistic_deposition(d);
}

inline RunResult compact(const packing::Packing& pk, const qs::SolverOptions& so, const qs::StrainPath& path, double D,
                         int increments) {
  qs::NetworkSolver s(pk, so);
  qs::CompactionOptions co;
  co.path = path;
  co.target_density = D;
  co.increments = increments;
  RunResult rr;
  qs::run_compaction(s, co, [&](const qs::CompactionRow& row) {
    rr.m = row.state;
    if (row.increment > 0) {
      rr.unconverged += !row.report.converged;
      rr.max_residual = std::max(rr.max_residual, row.report.residual);
    }
  });
  return rr;
}

// Pure Newton (no drag) to 1e-5 of the mean contact force with sticking friction on the small
// random packing (seed 3), compacted hydrostatically by 0.02 in density.
struct NewtonCase {
  packing::Packing pk;
  qs::SolverOptions so;
  double D = 0;
};
inline NewtonCase sticking_newton_case() {
  NewtonCase c;
  c.pk = random_packing(small_scale() ? 12.0 : 20.0, 3);
  c.so.law.mu = std::numeric_limits<double>::infinity();
  c.so.viscosity = 0.0;
  c.so.residual_tol = 1e-5;
  c.so.max_residual_tol = 1e-5;
  c.so.max_newton = 300;
  c.D = c.pk.density() + 0.02;
  return c;
}

}  // namespace netdem::test
