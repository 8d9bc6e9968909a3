// The 3D network solver (NetworkSolverT<3>, spheres, 12x12 elements): physics that could fail.
//  * an affine hydrostatic increment on a simple cubic lattice of equal spheres gives every contact
//    the force of the plastic-indentation law at the affine overlap (the law's evaluate, closed
//    form), and the Eq 13 stress (1/V) sum f x l of that force;
//  * an affine increment is invariant under a rigid rotation of the input (frictionless: nothing
//    free) and, with friction and free rotations in die mode, under a rotation that maps the box
//    to itself (the peripheral layer with it) and under a renumbering of the particles;
//  * a die-mode run on a jittered sphere packing converges and its Eq 13 stress agrees with the
//    Love-Weber contact stress;
//  * six rigid walls (BoundaryMode::Walls): a simple cubic lattice between them stays affine (the
//    law is linear in R* u: a wall contact, R* = r, carries the chain force at half a pair's
//    overlap) and its stress is the periodic closed form, Eq 13 of the walls' reactions equal to
//    the contact stress with the wall contacts; a prestressed jittered lattice between walls
//    converges, is invariant under a rotation that maps the box to itself and a renumbering;
//  * a packing of the other dimension is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/network_solver.hpp"

namespace {

namespace qs = netdem::qs;
namespace ct = netdem::contact;
using netdem::packing::Packing;
using M3 = Eigen::Matrix3d;
using V3 = Eigen::Vector3d;

/// m^3 spheres of radius r on a simple cubic lattice of spacing 2r (touching), box [0, 2 r m]^3.
Packing cubic_lattice(int m, double r) {
  Packing pk;
  pk.dim = 3;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        pk.x.push_back((2 * i + 1) * r);
        pk.y.push_back((2 * j + 1) * r);
        pk.z.push_back((2 * k + 1) * r);
        pk.r.push_back(r);
      }
  pk.box = {0.0, 0.0, 2 * r * m, 2 * r * m, 0.0, 2 * r * m};
  return pk;
}

/// A simple cubic lattice (spacing 2) of m^3 spheres centred on the origin, the centres jittered by
/// up to `jitter`, radii 1 - gap u (u uniform in [0, 1)); box the cube [-m - 1, m + 1]^3.
Packing jittered(int m, double jitter, double gap, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing pk;
  pk.dim = 3;
  const double c = m - 1.0;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        pk.x.push_back(2 * i - c + jitter * (2 * u(rng) - 1));
        pk.y.push_back(2 * j - c + jitter * (2 * u(rng) - 1));
        pk.z.push_back(2 * k - c + jitter * (2 * u(rng) - 1));
        pk.r.push_back(1.0 - gap * u(rng));
      }
  const double h = m + 1.0;
  pk.box = {-h, -h, h, h, -h, h};
  return pk;
}

Packing rotated(const Packing& pk, const M3& R) {
  Packing out = pk;
  for (std::size_t p = 0; p < pk.size(); ++p) {
    const V3 x = R * V3(pk.x[p], pk.y[p], pk.z[p]);
    out.x[p] = x.x();
    out.y[p] = x.y();
    out.z[p] = x.z();
  }
  return out;
}

Packing renumbered(const Packing& pk, const std::vector<int>& perm) {  // old p is new perm[p]
  Packing out = pk;
  for (std::size_t p = 0; p < pk.size(); ++p) {
    const auto q = static_cast<std::size_t>(perm[p]);
    out.x[q] = pk.x[p];
    out.y[q] = pk.y[p];
    out.z[q] = pk.z[p];
    out.r[q] = pk.r[p];
  }
  return out;
}

double rel(const M3& a, const M3& b) { return (a - b).norm() / b.norm(); }

/// The law's normal force on a fresh bond of two spheres of radius r at centre distance L.
double bond_force(const qs::SolverOptions& o, double r, double L) {
  ct::Kinematics<3> kin;
  kin.overlap = 2 * r - L;
  kin.r_eff = 0.5 * r;
  return ct::PlasticIndentationLaw3(o.law).evaluate(ct::PlasticIndentationHistoryT<3>{}, kin, nullptr).f_n;
}

struct RunResult {
  qs::StressMeasuresT<3> s;
  int unconverged = 0;
  double max_rms = 0.0;  ///< the largest accepted undragged RMS residual / mean contact force
};

RunResult run(const Packing& pk, const qs::SolverOptions& o, const M3& dE, int increments) {
  qs::NetworkSolver3 solver(pk, o);
  RunResult r;
  for (int k = 0; k < increments; ++k) {
    const qs::IncrementReport rep = solver.increment(dE);
    r.unconverged += !rep.converged;
    r.max_rms = std::max(r.max_rms, rep.residual_rms);
  }
  r.s = solver.stress();
  return r;
}

}  // namespace

TEST(Network3D, AffineHydrostaticLatticeGivesTheClosedForm) {
  const int m = 4;
  const double r = 1.0, e = 1e-3;
  qs::SolverOptions o;
  o.mode = qs::BoundaryMode::Affine;
  qs::NetworkSolver3 solver(cubic_lattice(m, r), o);
  EXPECT_EQ(solver.free_dofs(), 3 * (m - 2) * (m - 2) * (m - 2));  // the interior rotations
  const M3 dE = -e * M3::Identity();
  const qs::IncrementReport rep = solver.increment(dE);
  EXPECT_TRUE(rep.converged);
  // the affine motion: every lattice bond shortened to L = 2 r exp(-e)
  const double L = 2 * r * std::exp(-e);
  const double fn = bond_force(o, r, L);
  ASSERT_GT(fn, 0.0);
  const auto contacts = solver.contacts();
  ASSERT_EQ(contacts.size(), static_cast<std::size_t>(3 * m * m * (m - 1)));
  for (const auto& c : contacts) {
    EXPECT_NEAR(c.f_n, fn, 1e-12 * fn);
    EXPECT_NEAR(c.f_t, 0.0, 1e-12 * fn);
    EXPECT_NEAR(c.overlap, 2 * r - L, 1e-12);
  }
  // Eq 13: each axis carries m^2 (m - 1) bonds of force fn and length L in V = (2 r m)^3 exp(-3e)
  const double V = std::pow(2 * r * m, 3) * std::exp(-3 * e);
  const double S = -m * m * (m - 1) * fn * L / V;
  const auto st = solver.stress();
  EXPECT_LT(rel(st.eq13, S * M3::Identity()), 1e-10);
  EXPECT_LT(rel(st.contacts, S * M3::Identity()), 1e-10);
  EXPECT_NEAR(st.density, m * m * m * 4.0 / 3.0 * M_PI / V, 1e-12);
  EXPECT_NEAR(st.Z, 2.0 * 3 * m * m * (m - 1) / (m * m * m), 1e-12);
}

TEST(Network3D, AffineIncrementsAreInvariantUnderARigidRotation) {
  qs::SolverOptions o;
  o.mode = qs::BoundaryMode::Affine;
  o.law.mu = 0.0;  // frictionless: no free DOF, the rotation of the input changes nothing
  const Packing pk = jittered(4, 0.05, 0.03, 5);
  M3 dE;
  dE << -0.010, 0.002, 0.001, 0.002, -0.004, 0.0005, 0.001, 0.0005, -0.007;
  const M3 R = Eigen::AngleAxisd(0.7, V3(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  const RunResult a = run(pk, o, dE, 6);
  const RunResult b = run(rotated(pk, R), o, R * dE * R.transpose(), 6);
  ASSERT_GT(a.s.contact_count, 20);
  EXPECT_EQ(a.s.contact_count, b.s.contact_count);
  EXPECT_LT(rel(b.s.eq13, R * a.s.eq13 * R.transpose()), 1e-9);
  EXPECT_LT(rel(b.s.contacts, R * a.s.contacts * R.transpose()), 1e-9);
}

TEST(Network3D, DieModeWithFrictionIsInvariantUnderRotationAndRenumbering) {
  qs::SolverOptions o;  // die mode, Coulomb friction, free interior rotations
  o.law.mu = 0.3;
  o.max_newton = 30;
  const Packing pk = jittered(5, 0.01, 0.005, 9);
  M3 dE;
  dE << -0.003, 0.0008, 0.0, 0.0008, -0.0015, 0.0005, 0.0, 0.0005, -0.002;
  const RunResult a = run(pk, o, dE, 8);
  ASSERT_GT(a.s.contact_count, 100);
  EXPECT_EQ(a.unconverged, 0);
  // the cyclic permutation of the axes maps the cube to itself, and the peripheral layer with it
  M3 P;
  P << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  const RunResult b = run(rotated(pk, P), o, P * dE * P.transpose(), 8);
  EXPECT_EQ(a.s.contact_count, b.s.contact_count);
  EXPECT_LT(rel(b.s.eq13, P * a.s.eq13 * P.transpose()), 1e-6);
  std::vector<int> perm(pk.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(4));
  const RunResult c = run(renumbered(pk, perm), o, dE, 8);
  EXPECT_EQ(a.s.contact_count, c.s.contact_count);
  std::printf("3D die with friction: %d contacts; rotated %.3g, renumbered %.3g (relative Eq 13 difference)\n",
              a.s.contact_count, rel(b.s.eq13, P * a.s.eq13 * P.transpose()), rel(c.s.eq13, a.s.eq13));
  EXPECT_LT(rel(c.s.eq13, a.s.eq13), 1e-6);
  EXPECT_LT(rel(c.s.contacts, a.s.contacts), 1e-6);
}

TEST(Network3D, DieModeConvergesAndEq13AgreesWithTheContactStress) {
  qs::SolverOptions o;  // die mode, the default law (sticking up to the shear cap)
  o.max_newton = 30;
  const Packing pk = jittered(5, 0.01, 0.005, 21);
  qs::NetworkSolver3 solver(pk, o);
  EXPECT_EQ(solver.free_dofs(), 6 * 27);  // the 3^3 interior spheres: translations and rotations
  const M3 dE = -0.001 * M3::Identity();
  for (int k = 0; k < 25; ++k) {
    const qs::IncrementReport rep = solver.increment(dE);
    EXPECT_TRUE(rep.converged) << "increment " << k << ": " << rep.newton_iterations << " Newton iterations, residual "
                               << rep.residual_rms;
  }
  const auto st = solver.stress();
  ASSERT_GT(st.contact_count, 100);
  EXPECT_LT(st.eq13(0, 0), 0.0);  // compression
  std::printf("3D die: %d contacts, Eq 13 vs contacts %.3g, net force ratio %.3g, S11 %.6g\n", st.contact_count,
              st.eq13_vs_contacts, st.net_force_ratio, st.eq13(0, 0));
  EXPECT_LT(st.eq13_vs_contacts, 0.02);
  EXPECT_LT(st.net_force_ratio, 0.02);
  // a copy continues bit-identically (the 3D state)
  qs::NetworkSolver3 copy(solver);
  const auto r1 = solver.increment(dE), r2 = copy.increment(dE);
  EXPECT_EQ(r1.newton_iterations, r2.newton_iterations);
  EXPECT_EQ(solver.stress().eq13, copy.stress().eq13);
}

TEST(Network3D, WallsKeepACubicLatticeAffineWithThePeriodicClosedForm) {
  const int m = 4;
  const double r = 1.0, e = 1e-3;
  qs::SolverOptions o;
  o.mode = qs::BoundaryMode::Walls;
  qs::NetworkSolver3 solver(cubic_lattice(m, r), o);
  EXPECT_EQ(solver.free_dofs(), 6 * m * m * m);  // nothing prescribed
  const M3 dE = -e * M3::Identity();
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(solver.increment(dE).converged);
  // every bond at the affine length 2 r exp(-3e): the wall overlap is half a pair's, R* twice
  const double L = 2 * r * std::exp(-3 * e);
  const double fn = bond_force(o, r, L);
  ASSERT_GT(fn, 0.0);
  const auto contacts = solver.contacts();
  ASSERT_EQ(contacts.size(), static_cast<std::size_t>(3 * m * m * (m - 1)));
  for (const auto& c : contacts) EXPECT_NEAR(c.f_n, fn, 1e-9 * fn);
  for (std::size_t p = 0; p < solver.size(); ++p) {
    EXPECT_NEAR(solver.particles().coord(p, 0), (2 * (p % m) + 1) * r * std::exp(-3 * e), 1e-9 * r);
  }
  // m^2 chains per axis of force fn over the face (2 r m)^2 exp(-6e): the periodic cell's stress,
  // no (m - 1) / m (the walls carry the outer half-bonds)
  const double S = -fn / (4 * r * r * std::exp(-6 * e));
  const auto st = solver.stress();
  std::printf("3D walls lattice: S = %.9g (closed form %.9g), contacts %.9g\n", st.eq13(0, 0), S, st.contacts(0, 0));
  EXPECT_LT(rel(st.eq13, S * M3::Identity()), 1e-9);
  EXPECT_LT(rel(st.contacts, S * M3::Identity()), 1e-9);
  EXPECT_LT(st.net_force_ratio, 1e-9);
  EXPECT_EQ(st.rattlers, 0);  // the corner spheres rest on three walls
  EXPECT_NEAR(st.Z, 2.0 * 3 * m * m * (m - 1) / (m * m * m), 1e-12);  // pairs only, as in 2D
}

TEST(Network3D, WallsConvergeAndAreInvariantUnderRotationAndRenumbering) {
  qs::SolverOptions o = qs::SolverOptions::compact();  // netsolve compact's, which runs walls pseudo-transient:
  o.mode = qs::BoundaryMode::Walls;
  o.iteration = qs::Iteration::PseudoTransient;  // accepted on the undragged residual
  o.law.mu = 0.3;
  // overlapping radii (gap < 0): a prestressed network between the walls of the spheres' box
  Packing pk = jittered(4, 0.05, -0.06, 13);
  pk.box = {-4.0, -4.0, 4.0, 4.0, -4.0, 4.0};
  for (std::size_t p = 0; p < pk.size(); ++p) {  // the walls touch the outer spheres
    const double lim = 4.0 - pk.r[p];
    pk.x[p] = std::clamp(pk.x[p], -lim, lim);
    pk.y[p] = std::clamp(pk.y[p], -lim, lim);
    pk.z[p] = std::clamp(pk.z[p], -lim, lim);
  }
  const M3 dE = M3(V3(-0.002, -0.001, -0.0015).asDiagonal());
  const RunResult a = run(pk, o, dE, 8);
  ASSERT_GT(a.s.contact_count, 100);
  EXPECT_EQ(a.unconverged, 0);
  EXPECT_LE(a.max_rms, o.residual_tol);
  EXPECT_LT(a.s.eq13_vs_contacts, 0.01);  // the walls' Eq 13 and the Love-Weber sum with the wall contacts
  EXPECT_LT(a.s.net_force_ratio, 0.01);
  EXPECT_LT(a.s.eq13(0, 0), 0.0);
  M3 P;  // the cyclic permutation of the axes maps the cube and its walls to themselves
  P << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  const RunResult b = run(rotated(pk, P), o, P * dE * P.transpose(), 8);
  std::vector<int> perm(pk.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(8));
  const RunResult c = run(renumbered(pk, perm), o, dE, 8);
  std::printf("3D walls with friction: %d contacts, RMS residual %.3g, Eq 13 vs contacts %.3g; rotated %.3g, "
              "renumbered %.3g\n", a.s.contact_count, a.max_rms, a.s.eq13_vs_contacts, rel(b.s.eq13, P * a.s.eq13 * P.transpose()),
              rel(c.s.eq13, a.s.eq13));
  EXPECT_EQ(a.s.contact_count, b.s.contact_count);
  EXPECT_EQ(a.s.contact_count, c.s.contact_count);
  EXPECT_LT(rel(b.s.eq13, P * a.s.eq13 * P.transpose()), 1e-6);
  EXPECT_LT(rel(c.s.eq13, a.s.eq13), 1e-6);
}

TEST(Network3D, RefusesAPackingOfTheOtherDimension) {
  qs::SolverOptions o;
  o.mode = qs::BoundaryMode::Die;
  Packing flat;
  flat.x = {1.0};
  flat.y = {1.0};
  flat.r = {1.0};
  flat.box = {0.0, 0.0, 2.0, 2.0};
  EXPECT_THROW(qs::NetworkSolver3(flat, o), std::invalid_argument);
  EXPECT_THROW(qs::NetworkSolver(cubic_lattice(3, 1.0), o), std::invalid_argument);
}
