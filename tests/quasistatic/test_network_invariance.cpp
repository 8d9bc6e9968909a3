// The network solver is invariant under a shift and a mirror of the packing and its box (split
// from test_network_solver.cpp, which holds the other network-solver tests).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "network_test_util.hpp"
#include "test_scale.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"

using namespace netdem;

namespace {

using netdem::test::expect_same_state;
constexpr double kInf = std::numeric_limits<double>::infinity();

packing::Packing transformed(const packing::Packing& pk, double sx, double dx, double dy) {
  packing::Packing q = pk;  // x -> sx x + dx, y -> y + dy (sx = +-1)
  for (std::size_t p = 0; p < q.size(); ++p) {
    q.x[p] = sx * pk.x[p] + dx;
    q.y[p] = pk.y[p] + dy;
  }
  const double a = sx * pk.box.x_min + dx, b = sx * pk.box.x_max + dx;
  q.box = {std::min(a, b), pk.box.y_min + dy, std::max(a, b), pk.box.y_max + dy};
  return q;
}

/// The packing of `netsolve compact --width W` (seed 1, lid rule "centre"). W = 20 at every test
/// scale (0.1 s): with W = 12 8 of the 100 increments are unconverged and a shift of 1e-9 R already
/// changes the final Z, so there is no single network to compare.
packing::Packing netsolve_packing(double width) {
  packing::DepositionOptions d;
  d.width = width;
  d.seed = 1;
  d.lid = packing::Lid::Centre;
  return packing::ballistic_deposition(d);
}

struct InvarianceRun {
  qs::StateMeasures m;
  int unconverged = 0;
  long newton = 0;  ///< Newton iterations of the whole run
  double max_net_force = 0;
};

InvarianceRun invariance_run(const packing::Packing& pk, const qs::StrainPath& path) {
  qs::SolverOptions so = qs::SolverOptions::compact();
  so.law.mu = kInf;
  qs::NetworkSolver s(pk, so);
  qs::CompactionOptions co;
  co.path = path;
  co.target_density = 0.85;
  co.increments = 100;
  InvarianceRun r;
  qs::run_compaction(s, co, [&](const qs::CompactionRow& row) {
    r.m = row.state;
    if (row.increment > 0) {
      r.unconverged += !row.report.converged;
      r.newton += row.report.newton_iterations;
      r.max_net_force = std::max(r.max_net_force, row.state.net_force_ratio);
    }
  });
  return r;
}

double stress_norm(double s11, double s22, double s12) { return std::sqrt(s11 * s11 + s22 * s22 + 2 * s12 * s12); }

/// Relative distance of (a11, a22, a12) from (b11, b22, sign * b12), both symmetric tensors.
double tensor_gap(double a11, double a22, double a12, double b11, double b22, double b12, double sign = 1.0) {
  return stress_norm(a11 - b11, a22 - b22, a12 - sign * b12) / stress_norm(b11, b22, b12);
}

void print_run(const char* name, const InvarianceRun& r) {
  std::printf("%-9s S22 Eq13 %.6f contacts %.6f  S12 Eq13 %+.3e contacts %+.3e  Z %.4f  net force %.3e (max %.3e)  "
              "gap %.3e  unconverged %d  Newton %ld\n",
              name, r.m.S22, r.m.S22_contacts, r.m.S12, r.m.S12_contacts, r.m.Z, r.m.net_force_ratio, r.max_net_force,
              r.m.eq13_vs_contacts, r.unconverged, r.newton);
}

/// Z identical, contact stress within 0.2 %, Eq 13 within 1 % (S12 compared as sign * S12).
void expect_same_state(const InvarianceRun& a, const InvarianceRun& b, double sign) {
  EXPECT_EQ(a.m.contacts, b.m.contacts);
  EXPECT_EQ(a.m.Z, b.m.Z);
  EXPECT_LT(tensor_gap(b.m.S11_contacts, b.m.S22_contacts, b.m.S12_contacts, a.m.S11_contacts, a.m.S22_contacts,
                       a.m.S12_contacts, sign),
            0.002);
  EXPECT_LT(tensor_gap(b.m.S11, b.m.S22, b.m.S12, a.m.S11, a.m.S22, a.m.S12, sign), 0.01);
  EXPECT_NEAR(b.m.S22, a.m.S22, 0.01 * std::fabs(a.m.S22));
  EXPECT_NEAR(b.m.S11, a.m.S11, 0.01 * std::fabs(a.m.S11));
  EXPECT_NEAR(b.m.S22_contacts, a.m.S22_contacts, 0.002 * std::fabs(a.m.S22_contacts));
  EXPECT_NEAR(b.m.S11_contacts, a.m.S11_contacts, 0.002 * std::fabs(a.m.S11_contacts));
}

}  // namespace

// Hydrostatic: shift and mirror. The shifted Eq 13 within 1 % of the unshifted one is the check
// the origin-dependent formula failed (S22 -0.532 against -0.839).
TEST(NetworkSolverInvariance, ShiftAndMirrorOfPackingAndBox) {
  const auto pk = netsolve_packing(20.0);  // also at small scale: W = 12 does not converge
  const auto path = qs::StrainPath::hydrostatic();
  const auto orig = invariance_run(pk, path);
  const auto shifted = invariance_run(transformed(pk, 1.0, 1e3, 1e3), path);
  const auto mirrored = invariance_run(transformed(pk, -1.0, 0.0, 0.0), path);
  print_run("original", orig);
  print_run("shifted", shifted);
  print_run("mirrored", mirrored);
  for (const auto* r : {&orig, &shifted, &mirrored}) {
    ASSERT_EQ(r->unconverged, 0);  // converged runs: the comparison is between equilibria of one network
    EXPECT_LT(r->m.S22, 0.0);
    // the case has the net force the old formula turned into an origin-dependent stress
    EXPECT_GT(r->max_net_force, 1e-3);
  }
  expect_same_state(orig, shifted, 1.0);
  expect_same_state(orig, mirrored, -1.0);
  // the mirror changes the sign of S12 of both stresses: compare with the S12 of the disorder
  EXPECT_NEAR(mirrored.m.S12_contacts, -orig.m.S12_contacts, 0.002 * std::fabs(orig.m.S22_contacts));
  EXPECT_NEAR(mirrored.m.S12, -orig.m.S12, 0.01 * std::fabs(orig.m.S22));
}

// The Newton path is origin-free too: the predictor of the free DOFs is this increment's affine
// motion plus the previous increment's non-affine part (boundary.cpp prescribe). With the whole
// previous displacement reused instead (before 2026-12-01), the shifted and the mirrored+shifted
// runs took 346 and 441 Newton iterations against 119 and their stresses differed by up to 9e-4
// relative; now the runs differ by rounding only (about 1e-12 relative).
TEST(NetworkSolverInvariance, ShiftLeavesNewtonPathUnchanged) {
  const auto pk = netsolve_packing(20.0);
  const auto path = qs::StrainPath::hydrostatic();
  const auto orig = invariance_run(pk, path);
  const auto shifted = invariance_run(transformed(pk, 1.0, 1e3, 1e3), path);
  const auto both = invariance_run(transformed(pk, -1.0, 1e3, -1e3), path);  // mirrored and shifted
  print_run("original", orig);
  print_run("shifted", shifted);
  print_run("mirr+shft", both);
  ASSERT_EQ(orig.unconverged, 0);
  const auto rel = [](double a, double b) { return std::fabs(a - b) / std::fabs(b); };
  for (const auto* r : {&shifted, &both}) {
    std::printf("relative differences: S11 %.2e S22 %.2e S11_contacts %.2e S22_contacts %.2e\n", rel(r->m.S11, orig.m.S11),
                rel(r->m.S22, orig.m.S22), rel(r->m.S11_contacts, orig.m.S11_contacts),
                rel(r->m.S22_contacts, orig.m.S22_contacts));
    EXPECT_EQ(r->unconverged, orig.unconverged);
    EXPECT_EQ(r->newton, orig.newton);
    EXPECT_EQ(r->m.contacts, orig.m.contacts);
    EXPECT_LT(rel(r->m.S22, orig.m.S22), 1e-9);
    EXPECT_LT(rel(r->m.S11, orig.m.S11), 1e-9);
    EXPECT_LT(rel(r->m.S22_contacts, orig.m.S22_contacts), 1e-9);
    EXPECT_LT(rel(r->m.S11_contacts, orig.m.S11_contacts), 1e-9);
  }
}

// A path with shear (E12 != 0), mirrored with E12 -> -E12: S12 is a sizeable part of the stress,
// so the sign flip of S12 under the mirror is tested, not the noise of a hydrostatic S12.
TEST(NetworkSolverInvariance, MirrorFlipsShearStress) {
  const auto pk = netsolve_packing(20.0);  // also at small scale: W = 12 does not converge
  qs::StrainPath p = qs::StrainPath::parse("-1,-1,0.5"), pm = qs::StrainPath::parse("-1,-1,-0.5");
  const auto orig = invariance_run(pk, p);
  const auto mirrored = invariance_run(transformed(pk, -1.0, 0.0, 0.0), pm);
  print_run("original", orig);
  print_run("mirrored", mirrored);
  ASSERT_EQ(orig.unconverged, 0);
  ASSERT_EQ(mirrored.unconverged, 0);
  ASSERT_GT(std::fabs(orig.m.S12_contacts), 0.05 * std::fabs(orig.m.S22_contacts));  // shear is loaded
  expect_same_state(orig, mirrored, -1.0);
  EXPECT_NEAR(mirrored.m.S12_contacts, -orig.m.S12_contacts, 0.002 * std::fabs(orig.m.S12_contacts));
  EXPECT_NEAR(mirrored.m.S12, -orig.m.S12, 0.01 * std::fabs(orig.m.S12));
}
