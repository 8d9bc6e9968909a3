// Tests that fail if a regularisation is left in the network solver's answer (issue 28): the
// pseudo-transient iteration must end at the undragged equilibrium whatever the drag, while the
// legacy drag of the whole increment stays in its answer (each test shows both, so that it can
// fail).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "network_test_util.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"

using namespace netdem;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

qs::SolverOptions pseudo_transient(qs::SolverOptions so, double scale) {
  so.iteration = qs::Iteration::PseudoTransient;
  so.regularisation_scale = scale;
  so.max_newton = 100;
  return so;
}

// Two disks (radii 1 and 0.6) side by side between the left and right walls, just touching both
// walls and each other; the box is compressed along x only (E11 < 0, E22 = 0).
packing::Packing two_disks_between_walls() {
  packing::Packing p;
  const double r1 = 1.0, r2 = 0.6;
  p.x = {r1, 2 * r1 + r2};
  p.y = {5.0, 5.0};
  p.r = {r1, r2};
  p.box = {0.0, 0.0, 2 * r1 + 2 * r2, 10.0};
  return p;
}

struct WallCase {
  double x1 = 0, x2 = 0, force = 0;  ///< the disks' centres and the common contact force
  bool converged = true;
  int substeps = 0;
  int unconverged_substeps = 0;     ///< of the last increment
  double residual = 0, residual_rms = 0;  ///< the undragged residual the last increment ends with
};

// Compacts the two-disk case by the strain E11 in n increments; `then` (if given) takes over for
// the last increment, which is `last` times as large as the others.
WallCase run_walls(const qs::SolverOptions& so, double E11, int n, const qs::SolverOptions* then = nullptr,
                   double last = 1.0) {
  qs::NetworkSolver first(two_disks_between_walls(), so);
  Eigen::Matrix2d dE = Eigen::Matrix2d::Zero();
  dE(0, 0) = E11 / (n - 1 + last);
  WallCase c;
  for (int k = 0; k < n - 1; ++k) c.converged = c.converged && first.increment(dE).converged;
  qs::NetworkSolver s(first.state(), then ? *then : so);
  dE *= n > 1 ? last : 1.0;
  for (int k = n - 1; k < n; ++k) {
    const auto rep = s.increment(dE);
    c.converged = c.converged && rep.converged;
    c.substeps += rep.substeps;
    c.unconverged_substeps = rep.unconverged_substeps;
    c.residual = rep.residual;
    c.residual_rms = rep.residual_rms;
  }
  c.x1 = s.x()[0];
  c.x2 = s.x()[1];
  for (const auto& ct : s.contacts()) c.force = ct.f_n;
  return c;
}

// The closed form of the two disks between walls compressed by E11 (sigma_y = 1, Eq 2 from u = 0):
// the common force F and the two centres (the comment below derives it).
struct ClosedForm {
  double F, x1, x2;
};
ClosedForm two_disks_closed_form(double E11) {
  const double r1 = 1.0, r2 = 0.6, L0 = 2 * r1 + 2 * r2;
  const double delta = L0 * (1.0 - std::exp(E11));
  const double rs = r1 * r2 / (r1 + r2);
  const double c = delta / (1.0 / r1 + 1.0 / rs + 1.0 / r2);
  return {std::sqrt(72.0 * c), r1 - c / r1, L0 * std::exp(E11) - (r2 - c / r2)};
}

// The two disks' options: walls, sticking, Eq 2 from u = 0 (no first-touch chord), tight tolerances.
qs::SolverOptions two_disk_options() {
  qs::SolverOptions o;
  o.mode = qs::BoundaryMode::Walls;
  o.law.mu = kInf;
  o.law.first_touch = 0.0;
  o.viscosity = 0.1;
  o.residual_tol = 1e-9;
  o.linear_tolerance = 1e-10;
  return o;
}

// Three unit disks on a line, the middle one 0.01 R off it (the buckling chain).
packing::Packing buckling_chain() {
  packing::Packing pk;
  pk.x = {0.0, 2.0, 4.0};
  pk.y = {0.0, 0.01, 0.0};
  pk.r = {1.0, 1.0, 1.0};
  pk.box = {-1.0, -1.0, 5.0, 1.0};
  return pk;
}

}  // namespace

// The two disks between walls: along x the three contacts (wall-disk 1, disk 1-disk 2, disk 2-wall)
// carry one force F. With Eq 2 (F = 3 sigma_y sqrt(8 u R*), first touch at u = 0) each overlap is
// u = c / R* with c = F^2 / (72 sigma_y^2), R* = r for a wall, r1 r2 / (r1 + r2) for the pair, and
// the three overlaps sum to the box's shortening: a closed form for F and both centres. The legacy
// drag holds the disks near the affine motion, away from it; the pseudo-transient iteration ends
// on it for drags 0.1, 1 and 10 times the default.
TEST(Equilibrium, TwoDisksBetweenWallsMatchClosedFormForEveryDrag) {
  const double E11 = -0.02;
  const auto [F, x1, x2] = two_disks_closed_form(E11);
  qs::SolverOptions base = two_disk_options();
  for (double scale : {0.1, 1.0, 10.0}) {
    const WallCase w = run_walls(pseudo_transient(base, scale), E11, 4);
    std::printf("pseudo-transient, drag x %g: F = %.12f (closed form %.12f), x1 %.3e, x2 %.3e off\n", scale, w.force, F,
                w.x1 - x1, w.x2 - x2);
    EXPECT_TRUE(w.converged);
    EXPECT_NEAR(w.force, F, 1e-7 * F);
    EXPECT_NEAR(w.x1, x1, 1e-9);
    EXPECT_NEAR(w.x2, x2, 1e-9);
  }
  base.max_residual_tol = 1e-9;
  base.max_newton = 100;
  base.regularisation_scale = 10.0;  // the legacy drag at 10x: its answer moves
  const WallCase legacy = run_walls(base, E11, 4);
  std::printf("legacy drag x 10: F = %.12f, x1 %.3e off\n", legacy.force, legacy.x1 - x1);
  EXPECT_GT(std::fabs(legacy.force - F), 1e-3 * F);
}

// The contact work of the increments (IncrementReport::contact_work, the wall contacts included)
// sums to the work of the walls on the two disks: with F = sqrt(72 delta / S) (the closed form
// above, delta the box's shortening) it is the integral of F d delta = 2/3 F delta. 40 increments:
// the trapezoidal rule's error on the square root's first increment is 0.1 %.
TEST(Equilibrium, ContactWorkIsTheWallsWork) {
  const double E11 = -0.02;
  const int n = 40;
  const double delta = (2 * 1.0 + 2 * 0.6) * (1.0 - std::exp(E11));
  const double W = 2.0 / 3.0 * two_disks_closed_form(E11).F * delta;
  qs::NetworkSolver s(two_disks_between_walls(), pseudo_transient(two_disk_options(), 1.0));
  Eigen::Matrix2d dE = Eigen::Matrix2d::Zero();
  dE(0, 0) = E11 / n;
  double work = 0.0;
  for (int k = 0; k < n; ++k) {
    const auto rep = s.increment(dE);
    ASSERT_TRUE(rep.converged) << k;
    work += rep.contact_work;
  }
  std::printf("contact work %.9f, closed form %.9f\n", work, W);
  EXPECT_NEAR(work, W, 5e-3 * W);
}

// The cut-back: with too few iterations per increment, the increment is redone in halves and
// still ends on the same equilibrium (the reversible law makes the answer independent of the path
// along this monotonic loading). The first-touch chord keeps the stiffness at touch finite.
TEST(Equilibrium, CutIncrementsEndOnTheSameEquilibrium) {
  qs::SolverOptions so;
  so.mode = qs::BoundaryMode::Walls;
  so.law.mu = kInf;
  so.residual_tol = 1e-9;
  so.linear_tolerance = 1e-10;
  so = pseudo_transient(so, 1.0);
  const WallCase full = run_walls(so, -0.05, 2, nullptr, 4.0);
  qs::SolverOptions few = so;  // the second increment (the first brings the contacts past the touch)
  few.max_newton = 2;
  few.max_cuts = 6;
  const WallCase cut = run_walls(so, -0.05, 2, &few, 4.0);
  std::printf("second increment (4x the first): %d sub-increments with 2 iterations each at most; F %.12f against "
              "%.12f\n", cut.substeps, cut.force, full.force);
  EXPECT_TRUE(full.converged);
  EXPECT_TRUE(cut.converged);
  EXPECT_GT(cut.substeps, 1);
  EXPECT_NEAR(cut.force, full.force, 1e-7 * full.force);
  few.max_cuts = 0;  // without cuts the same iteration budget leaves the increment unaccepted
  EXPECT_FALSE(run_walls(so, -0.05, 2, &few, 4.0).converged);
}

// A cut increment whose early sub-increments are not accepted but whose last one is: the first
// touch of the two disks (one increment from u = 0, where Eq 2's stiffness is infinite) in six
// iterations at most per attempt, two cuts. It is accepted, its end state meets the criterion on
// the undragged residual, and (the reversible law's answer does not depend on the path) its force
// is the closed form's. The unaccepted sub-increments are counted. With one cut the last half is
// not accepted either, and neither is the increment.
TEST(Equilibrium, CutIncrementIsAcceptedOnItsEndStateAndCountsItsUnacceptedSubsteps) {
  qs::SolverOptions so = pseudo_transient(two_disk_options(), 1.0);
  so.max_newton = 6;
  so.max_cuts = 2;
  const double E11 = -0.05;
  const auto closed = two_disks_closed_form(E11);
  const WallCase c = run_walls(so, E11, 1);
  std::printf("one increment from the touch, 6 iterations, 2 cuts: accepted %d, %d sub-increments, %d unaccepted, "
              "end residual RMS %.2e, max %.2e, F %.12f (closed form %.12f)\n", c.converged, c.substeps,
              c.unconverged_substeps, c.residual_rms, c.residual, c.force, closed.F);
  EXPECT_TRUE(c.converged);
  EXPECT_EQ(c.substeps, 4);
  EXPECT_GT(c.unconverged_substeps, 0);
  EXPECT_LT(c.unconverged_substeps, c.substeps);
  EXPECT_LE(c.residual_rms, so.residual_tol);
  EXPECT_LE(c.residual, 10.0 * so.residual_tol);
  EXPECT_NEAR(c.force, closed.F, 1e-7 * closed.F);
  so.max_cuts = 1;
  const WallCase halves = run_walls(so, E11, 1);
  EXPECT_FALSE(halves.converged);
  EXPECT_EQ(halves.unconverged_substeps, 2);
  EXPECT_GT(halves.residual_rms, so.residual_tol);
}

// The answer of options o on the sticking case (40 hydrostatic increments) against pure Newton's:
// every increment accepted, S11 and S22 within 1e-4, the same Z.
static void expect_pure_newtons_answer(const char* what, const packing::Packing& pk, const qs::SolverOptions& o, double D,
                                       const test::RunResult& pure) {
  const auto r = test::compact(pk, o, qs::StrainPath::hydrostatic(), D, 40);
  const double d11 = std::fabs(r.m.S11 / pure.m.S11 - 1.0), d22 = std::fabs(r.m.S22 / pure.m.S22 - 1.0);
  std::printf("%s, drag x %g: S11 %.3e, S22 %.3e from pure Newton, Z %.4f against %.4f\n", what,
              o.regularisation_scale, d11, d22, r.m.Z, pure.m.Z);
  EXPECT_EQ(r.unconverged, 0);
  EXPECT_LT(d11, 1e-4);
  EXPECT_LT(d22, 1e-4);
  EXPECT_NEAR(r.m.Z, pure.m.Z, 1e-9);
}

// Sticking friction on the small random packing, die mode: the pseudo-transient answer equals pure
// Newton (no drag at all) for drags 0.1, 1 and 10 times 0.1 of the mean stiffness, while the
// legacy drag at that size moves S22.
TEST(Equilibrium, RandomPackingAnswerIsIndependentOfTheDrag) {
  auto [pk, so, D] = test::sticking_newton_case();
  const auto pure = test::compact(pk, so, qs::StrainPath::hydrostatic(), D, 40);
  ASSERT_EQ(pure.unconverged, 0);
  so.viscosity = 0.1;
  so.max_residual_tol = kInf;
  for (double scale : {0.1, 1.0, 10.0}) expect_pure_newtons_answer("pseudo-transient", pk, pseudo_transient(so, scale), D, pure);
  so.regularisation_scale = 10.0;
  const auto legacy = test::compact(pk, so, qs::StrainPath::hydrostatic(), D, 40);
  const double dl = std::fabs(legacy.m.S22 / pure.m.S22 - 1.0);
  std::printf("legacy drag x 10: S22 %.3e from pure Newton\n", dl);
  EXPECT_GT(dl, 1e-3);
  // the trust region on the incremental potential with friction (the tangential springs' stiffness
  // and limit frozen at each iterate) ends there too, at the tolerance it reaches (at 1e-5, 17-25
  // of the 40 increments stall: the frozen potential matches the law to first order in the step)
  so.energy_merit = true;
  so.friction_energy_merit = true;
  so.residual_tol = 1e-4;
  so.max_residual_tol = 1e-3;
  for (double scale : {0.1, 1.0, 10.0}) {
    qs::SolverOptions o = pseudo_transient(so, scale);
    o.max_newton = 300;
    ASSERT_TRUE(o.uses_energy_merit());
    ASSERT_STREQ(o.merit_name(), "energy-friction");
    expect_pure_newtons_answer("energy merit with friction", pk, o, D, pure);
  }
}

// A rattler loose in the cage of a square lattice has no stiffness and a zero residual: it must not
// stall the iteration, and it stays where the predictor puts it (the affine motion), whatever the
// drag.
TEST(Equilibrium, RattlerDoesNotStallTheIteration) {
  auto pk = test::square_lattice(6, 6);
  const int hole = 2 * 6 + 2;
  pk.r[hole] = 0.4;
  const double x0 = pk.x[hole], y0 = pk.y[hole];
  qs::SolverOptions so;
  so.law.mu = kInf;
  so.viscosity = 0.1;
  so.linear_tolerance = 1e-8;
  qs::CompactionOptions co;
  co.target_density = pk.density() * 1.03;
  co.increments = 10;
  for (double scale : {0.1, 10.0}) {
    qs::NetworkSolver s(pk, pseudo_transient(so, scale));
    int unconverged = 0;
    qs::run_compaction(s, co, [&](const qs::CompactionRow& row) { unconverged += row.increment > 0 && !row.report.converged; });
    EXPECT_EQ(unconverged, 0);
    const Eigen::Vector2d affine = s.box_deformation() * Eigen::Vector2d(x0, y0);
    EXPECT_NEAR(s.x()[hole], affine.x(), 1e-12);
    EXPECT_NEAR(s.y()[hole], affine.y(), 1e-12);
    for (const auto& c : s.contacts()) EXPECT_TRUE(c.i != hole && c.j != hole);
  }
}

// A buckling chain: a frictionless disk between two prescribed disks, slightly off their line,
// compressed along the line (die mode: the outer disks follow the strain). The chain buckles: the
// only equilibria have the middle disk out of both contacts, at least at the height
// h = sqrt((2r)^2 - (d/2)^2) above the line for outer centres d apart, where it just touches both.
// The pseudo-transient iteration ends there (zero force, and no further: a disk without a loaded
// contact keeps the affine predictor) for every drag; the legacy drag holds it near its affine
// motion, still pressed between its neighbours.
TEST(Equilibrium, BucklingChainEndsAtTheTouchingHeight) {
  const packing::Packing pk = buckling_chain();
  qs::SolverOptions so;
  so.law.mu = 0.0;
  so.viscosity = 0.1;
  so.energy_merit = false;  // the residual iteration (the energy's is tested below)
  auto run = [&](const qs::SolverOptions& o, int& unconverged, double& force) {
    auto st = qs::NetworkSolver(pk, o).state();
    st.peripheral = {1, 0, 1};  // the outer disks prescribed, the middle one free
    qs::NetworkSolver s(st, o);
    Eigen::Matrix2d dE = Eigen::Matrix2d::Zero();
    dE(0, 0) = -0.002;
    unconverged = 0;
    for (int k = 0; k < 10; ++k) unconverged += !s.increment(dE).converged;
    force = 0.0;
    for (const auto& c : s.contacts()) force = std::max(force, c.f_n);
    return Eigen::Vector2d(s.x()[1], s.y()[1]);
  };
  const double d = 4.0 * std::exp(-0.02), h = std::sqrt(4.0 - d * d / 4.0);
  for (double scale : {0.1, 1.0, 10.0}) {
    int unconverged = 0;
    double force = 0.0;
    const Eigen::Vector2d p = run(pseudo_transient(so, scale), unconverged, force);
    std::printf("pseudo-transient, drag x %g: middle disk at (%.9f, %.9f), touching height %.9f, force %.2e\n", scale,
                p.x(), p.y(), h, force);
    EXPECT_EQ(unconverged, 0);
    EXPECT_NEAR(p.x(), d / 2.0, 1e-9);
    EXPECT_NEAR(p.y(), h, 1e-6);
    EXPECT_LT(force, 1e-6);
  }
  int unconverged = 0;
  double force = 0.0;
  const Eigen::Vector2d legacy = run(so, unconverged, force);
  std::printf("legacy drag: middle disk at height %.6f, force %.3e\n", legacy.y(), force);
  EXPECT_LT(legacy.y(), h - 0.05);
  EXPECT_GT(force, 1e-3);
}

// The trust region on the energy (energy_merit, frictionless): the two disks between walls without
// friction carry the same closed-form force (the contacts lie along x: no tangential load), so the
// energy iteration, over the pair and the two wall contacts' potentials, must end on it for every
// drag; and the buckling chain's middle disk must end free (zero force) and not overlapping, i.e.
// at or above the touching height. (Above it every height is an equilibrium of zero force: the
// energy iteration's Newton step may carry the disk past touch, where the residual iteration,
// which holds a disk without a loaded contact at its affine predictor, stops at it.)
TEST(Equilibrium, EnergyTrustRegionEndsOnTheFrictionlessEquilibria) {
  const double E11 = -0.02;
  const auto [F, x1, x2] = two_disks_closed_form(E11);
  qs::SolverOptions base;
  base.mode = qs::BoundaryMode::Walls;
  base.law.mu = 0.0;
  base.law.first_touch = 0.0;
  base.viscosity = 0.1;
  base.residual_tol = 1e-9;
  base.energy_merit = true;
  for (double scale : {0.1, 1.0, 10.0}) {
    const WallCase w = run_walls(pseudo_transient(base, scale), E11, 4);
    std::printf("energy trust region, drag x %g: F = %.12f (closed form %.12f), x1 %.3e, x2 %.3e off\n", scale,
                w.force, F, w.x1 - x1, w.x2 - x2);
    EXPECT_TRUE(w.converged);
    EXPECT_NEAR(w.force, F, 1e-7 * F);
    EXPECT_NEAR(w.x1, x1, 1e-9);
    EXPECT_NEAR(w.x2, x2, 1e-9);
  }
  const packing::Packing pk = buckling_chain();
  qs::SolverOptions so;
  so.law.mu = 0.0;
  so.viscosity = 0.1;
  so.energy_merit = true;
  const double d = 4.0 * std::exp(-0.02), h = std::sqrt(4.0 - d * d / 4.0);
  for (double scale : {0.1, 1.0, 10.0}) {
    const qs::SolverOptions o = pseudo_transient(so, scale);
    auto st = qs::NetworkSolver(pk, o).state();
    st.peripheral = {1, 0, 1};
    qs::NetworkSolver s(st, o);
    Eigen::Matrix2d dE = Eigen::Matrix2d::Zero();
    dE(0, 0) = -0.002;
    int unconverged = 0;
    for (int k = 0; k < 10; ++k) unconverged += !s.increment(dE).converged;
    double force = 0.0;
    for (const auto& ct : s.contacts()) force = std::max(force, ct.f_n);
    std::printf("energy trust region, drag x %g: middle disk at (%.9f, %.9f), touching height %.9f, force %.2e\n",
                scale, s.x()[1], s.y()[1], h, force);
    EXPECT_EQ(unconverged, 0);
    EXPECT_NEAR(s.x()[1], d / 2.0, 1e-9);
    EXPECT_GE(s.y()[1], h - 1e-9);
    EXPECT_LT(s.y()[1], h + 0.05);  // one Newton step past touch at most
    EXPECT_LT(force, 1e-6);
  }
}


// The state file holds the wall contacts (issue 28: `netsolve yield --compact-bc walls` probes from
// a saved state): a walls-mode solver restored from the file continues bit-identically to the
// uninterrupted run, and the same state without its wall histories does not (the wall contacts'
// plastic flats are part of the state: with the elastic unloading branch, a wall contact that
// rearrangement relieves unloads along its flat).
TEST(Equilibrium, WallsStateFileContinuesBitIdentically) {
  packing::Packing pk = netdem::test::random_packing(12.0, 4);
  for (std::size_t i = 0; i < pk.size(); ++i) {  // the walls enclose every disk
    pk.box.y_max = std::max(pk.box.y_max, pk.y[i] + pk.r[i]);
    pk.box.y_min = std::min(pk.box.y_min, pk.y[i] - pk.r[i]);
  }
  qs::SolverOptions so = qs::SolverOptions::compact();
  so.mode = qs::BoundaryMode::Walls;
  so.law.reversible = false;  // the elastic unloading branch: an unloading contact reads its flat (u_max)
  const Eigen::Matrix2d dE = -4e-3 * Eigen::Matrix2d::Identity();
  qs::NetworkSolver ref(pk, so), first(pk, so);
  for (int k = 0; k < 10; ++k) ref.increment(dE);
  for (int k = 0; k < 6; ++k) ref.increment(dE);
  for (int k = 0; k < 10; ++k) first.increment(dE);
  const auto st = first.state();
  int loaded = 0;
  for (double f : st.wall_f_n) loaded += f > 0.0;
  ASSERT_GT(loaded, 3) << "the walls must carry load when the state is saved";
  const std::string file = testing::TempDir() + "/netdem_walls_state.txt";
  qs::save_state(st, file);
  const auto back = qs::load_state(file);
  std::remove(file.c_str());
  EXPECT_EQ(back.wall_f_n, st.wall_f_n);
  qs::NetworkSolver restored(back, so);
  auto bare = back;
  bare.wall_history.clear();
  bare.wall_f_n.clear();
  qs::NetworkSolver forgetful(bare, so);
  for (int k = 0; k < 6; ++k) {
    restored.increment(dE);
    forgetful.increment(dE);
  }
  netdem::test::expect_same_state(ref, restored);
  std::printf("walls state: %d loaded wall contacts saved; S22 %.9g restored, %.9g without the wall histories\n", loaded,
              restored.measures().S22, forgetful.measures().S22);
  EXPECT_NE(forgetful.measures().S22, ref.measures().S22);
}
