// Numerical stress cases of the quasi-static network solver (issue 13, item 7): a localising
// strain path (pure shear at constant volume to a large strain), very large and very small
// tangential stiffness k_t, the yield stress scaled by 1e6 (an exact invariance: S / sigma_y must
// not change beyond round-off), and a single increment. Each case either gives the right answer,
// checked against an invariant (Eq 13 = Love-Weber contact stress at equilibrium, finite values,
// constant volume, the scaling), or reports its increments unconverged: never NaN as if it were
// a result. The command-line side (exit 3 naming the first bad increment) is tests/cli/test_localising.sh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "test_scale.hpp"

using namespace netdem;

namespace {

packing::Packing w20() {  // the W = 20 R packing of `netsolve pack --width 20` (seed 1)
  packing::DepositionOptions d;
  d.width = 20.0;
  d.seed = 1;
  return packing::ballistic_deposition(d);
}

struct RunRecord {
  std::vector<qs::CompactionRow> rows;  ///< increment 0 .. n
  int unconverged = 0, first_unconverged = 0;
  bool all_finite = true;
  const qs::StateMeasures& last() const { return rows.back().state; }
};

bool finite(const qs::StateMeasures& m) {
  for (double v : {m.E11, m.E22, m.E12, m.density, m.S11, m.S22, m.S12, m.S_asym, m.S11_contacts, m.S22_contacts,
                   m.S12_contacts, m.Z, m.mean_normal_force, m.net_force_ratio, m.eq13_vs_contacts})
    if (!std::isfinite(v)) return false;
  return true;
}

/// Runs `co` on the solver as it is, recording every row.
RunRecord run_on(qs::NetworkSolver& s, const qs::CompactionOptions& co) {
  RunRecord r;
  qs::run_compaction(s, co, [&](const qs::CompactionRow& row) {
    r.rows.push_back(row);
    r.all_finite = r.all_finite && finite(row.state);
    if (row.increment > 0 && !row.report.converged) {
      ++r.unconverged;
      if (r.first_unconverged == 0) r.first_unconverged = row.increment;
    }
  });
  return r;
}

RunRecord run(const packing::Packing& pk, const qs::SolverOptions& so, const qs::CompactionOptions& co) {
  qs::NetworkSolver s(pk, so);
  return run_on(s, co);
}

/// |Eq 13 - Love-Weber| / |Love-Weber| (Frobenius norms of the symmetric tensors), written out
/// here to check StateMeasures::eq13_vs_contacts (the value of history.csv and of the exit-3 check).
double eq13_vs_contacts(const qs::StateMeasures& m) {
  const double d11 = m.S11 - m.S11_contacts, d22 = m.S22 - m.S22_contacts, d12 = m.S12 - m.S12_contacts;
  const double n = std::sqrt(m.S11_contacts * m.S11_contacts + m.S22_contacts * m.S22_contacts +
                             2 * m.S12_contacts * m.S12_contacts);
  return std::sqrt(d11 * d11 + d22 * d22 + 2 * d12 * d12) / n;
}

qs::CompactionOptions hydrostatic(double D, int increments) {
  qs::CompactionOptions co;
  co.target_density = D;
  co.increments = increments;
  return co;
}

/// Either every increment converged and the run ends at equilibrium (Eq 13 within 2 % of the
/// contact stress, everything finite), or the run is one that netsolve compact flags with exit 3:
/// an increment unconverged (the first is named), or Eq 13 more than 2 % off the contact stress
/// at the end (apps/netsolve/status.hpp EquilibriumRecord on StateMeasures::eq13_vs_contacts).
/// Returns true for the right answer, false for a flagged run.
bool expect_right_or_flagged(const RunRecord& r, const char* what) {
  EXPECT_FALSE(r.rows.empty()) << what;
  if (r.rows.empty()) return false;
  const double dev = eq13_vs_contacts(r.last());
  EXPECT_NEAR(r.last().eq13_vs_contacts, dev, 1e-12 * std::max(1.0, dev)) << what;
  std::printf("%s: %d of %zu increments unconverged (first %d), Eq 13 vs contacts %.3g %%, S11 = %.6g, S22 = %.6g, Z = %.3f\n",
              what, r.unconverged, r.rows.size() - 1, r.first_unconverged, 100 * dev, r.last().S11, r.last().S22,
              r.last().Z);
  if (r.unconverged == 0 && dev <= 0.02) {
    EXPECT_TRUE(r.all_finite) << what;
    return true;
  }
  // flagged: the caller's exit 3 names the first bad increment, or the deviation
  EXPECT_TRUE(r.first_unconverged >= 1 || dev > 0.02) << what;
  return false;
}

}  // namespace

// --to-strain: the increments of a strain target have Frobenius norm |E| / n along the path, and
// pure shear keeps the volume.
TEST(StressCases, StrainTargetIncrements) {
  qs::CompactionOptions co;
  co.path = qs::StrainPath::parse("1,-1,0");
  co.target_strain = 0.2;
  co.increments = 10;
  EXPECT_NO_THROW(co.validate(0.8));
  const Eigen::Matrix2d dE = co.increment_strain(0.8);
  EXPECT_NEAR(dE.norm(), 0.02, 1e-15);
  EXPECT_DOUBLE_EQ(dE(0, 0), -dE(1, 1));
  EXPECT_EQ(dE(0, 1), 0.0);
  for (double bad : {-1.0, 1.5, std::nan(""), HUGE_VAL, -HUGE_VAL, 1e-300, 4.9e-324}) {
    co.target_strain = bad;
    EXPECT_THROW(co.validate(0.8), std::invalid_argument) << bad;
  }
  co.path = qs::StrainPath::hydrostatic();  // |E| = 1 hydrostatic: D = 0.8 e^sqrt2 > 1
  co.target_strain = 1.0;
  EXPECT_THROW(co.validate(0.8), std::invalid_argument);
  co.target_strain = 0.1;
  EXPECT_NO_THROW(co.validate(0.8));
}

// A localising path: pure shear at constant volume to |E| = 0.2, after a hydrostatic
// precompaction to D = 0.84 in the same solver (the path turns: the shear loads a loaded
// network). The compact preset leaves most shear increments unconverged (flagged: see
// tests/cli/test_localising.sh); 200 Newton iterations converge every increment. The drag then
// decides how far the converged state is from equilibrium: with --viscosity 0.02 the (origin-free)
// Eq 13 is 0.35 % off the contact stress (the right answer), with 0.5 it is 4.3 % off, which
// netsolve compact flags (exit 3, "the Eq 13 stress differs from the contact stress"). With lever
// arms from the origin 0.05 was 4.5 % off and flagged; about the box centre it is 0.78 % off.
TEST(StressCases, PureShearToLargeStrain) {
  const auto pk = w20();
  const double E_target = netdem::test::small_scale() ? 0.05 : 0.2;
  for (double viscosity : {0.02, 0.5}) {
    qs::SolverOptions so = qs::SolverOptions::compact();
    so.max_newton = 200;
    so.viscosity = viscosity;
    qs::NetworkSolver s(pk, so);
    qs::run_compaction(s, hydrostatic(0.84, 20), [](const qs::CompactionRow&) {});
    const double D_before = s.measures().density;
    qs::CompactionOptions co;
    co.path = qs::StrainPath::parse("1,-1,0");
    co.target_strain = E_target;
    co.increments = netdem::test::small_scale() ? 25 : 100;
    const RunRecord r = run_on(s, co);
    char what[96];
    std::snprintf(what, sizeof what, "pure shear |E| = %g after D = 0.84, viscosity %g", E_target, viscosity);
    const bool right = expect_right_or_flagged(r, what);
    if (!netdem::test::small_scale()) {
      EXPECT_EQ(right, viscosity == 0.02) << what;
    }
    EXPECT_TRUE(r.all_finite) << what;
    EXPECT_NEAR(r.last().density, D_before, 1e-12) << what;  // trace-free: the volume is kept exactly
    const double E = std::hypot(r.last().E11 - r.rows[0].state.E11, r.last().E22 - r.rows[0].state.E22);
    EXPECT_NEAR(E, co.target_strain, 1e-12) << what;
    // the shear loads the network deviatorically: S11 - S22 (tension positive, E11 > 0) grows
    EXPECT_GT(r.last().S11 - r.last().S22, r.rows[0].state.S11 - r.rows[0].state.S22) << what;
  }
}

// k_t from 1e-3 to 1e9 sigma_y / R (default 1e3): the answer stays an equilibrium, or the run
// says it is not one.
TEST(StressCases, ExtremeTangentialStiffness) {
  const auto pk = w20();
  for (double kt : {1e-3, 1e9}) {
    qs::SolverOptions so = qs::SolverOptions::compact();
    so.law.k_t = kt;
    const RunRecord r = run(pk, so, hydrostatic(0.84, 20));
    char what[64];
    std::snprintf(what, sizeof what, "k_t = %g", kt);
    expect_right_or_flagged(r, what);
    EXPECT_TRUE(r.all_finite) << what;
  }
}

// sigma_y x 1e6: every force scales with sigma_y (Eq 2, k_t in sigma_y / R, the tolerance and the
// drag relative to the mean contact force and stiffness), so S / sigma_y, Z and the convergence
// record must be the same up to round-off.
TEST(StressCases, YieldStressScalesExactly) {
  const auto pk = w20();
  qs::SolverOptions a = qs::SolverOptions::compact(), b = a;
  b.law.sigma_y = a.law.sigma_y * 1e6;
  const RunRecord ra = run(pk, a, hydrostatic(0.84, 20)), rb = run(pk, b, hydrostatic(0.84, 20));
  ASSERT_EQ(ra.rows.size(), rb.rows.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < ra.rows.size(); ++k) {
    const auto &ma = ra.rows[k].state, &mb = rb.rows[k].state;
    EXPECT_EQ(ma.contacts, mb.contacts) << "increment " << k;
    EXPECT_EQ(ra.rows[k].report.converged, rb.rows[k].report.converged) << "increment " << k;
    for (auto [x, y] : {std::pair{ma.S11, mb.S11}, {ma.S22, mb.S22}, {ma.S12, mb.S12}, {ma.S11_contacts, mb.S11_contacts},
                        {ma.S22_contacts, mb.S22_contacts}}) {
      const double sa = x / a.law.sigma_y, sb = y / b.law.sigma_y;
      const double rel = std::fabs(sa - sb) / std::max(1e-300, std::fabs(ma.S11 / a.law.sigma_y));
      worst = std::max(worst, rel);
    }
  }
  std::printf("sigma_y x 1e6: largest |S/sigma_y difference| / |S11/sigma_y| = %.3g over %zu increments\n", worst,
              ra.rows.size());
  EXPECT_LT(worst, 1e-9);
}

// One increment to the target: converged to an equilibrium, or reported unconverged.
TEST(StressCases, SingleIncrement) {
  const auto pk = w20();
  const RunRecord r = run(pk, qs::SolverOptions::compact(), hydrostatic(0.84, 1));
  ASSERT_EQ(r.rows.size(), 2u);
  expect_right_or_flagged(r, "--increments 1");
  EXPECT_TRUE(r.all_finite || r.unconverged > 0);
}
