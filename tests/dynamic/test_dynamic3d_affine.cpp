// The full 3D affine field of DynamicSolver3 (set_strain_rate3 with shear rates, issue 16 item 3):
// a simple cubic lattice of spheres with every centre prescribed follows x_0 + exp(L t)(X - x_0)
// exactly, and its Eq 13 boundary stress and contact stress equal the closed form of the
// plastic-indentation law on the affinely deformed lattice; the stress rotates with E.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "netdem/dynamic/solver.hpp"

using namespace netdem::dem;
using netdem::contact::LudingParams;

namespace {

constexpr int kN = 4;  // spheres per edge

/// exp(A) by its Taylor series (independent of the solver's eigen-exponential per step).
Eigen::Matrix3d taylor_exp(const Eigen::Matrix3d& A) {
  Eigen::Matrix3d sum = Eigen::Matrix3d::Identity(), term = Eigen::Matrix3d::Identity();
  for (int k = 1; k < 40; ++k) {
    term = term * A / k;
    sum += term;
  }
  return sum;
}

Eigen::Matrix3d rate_matrix(const std::array<double, 6>& e) {  // e11, e22, e33, e23, e13, e12
  Eigen::Matrix3d L;
  L << e[0], e[5], e[4], e[5], e[1], e[3], e[4], e[3], e[2];
  return L;
}

struct LatticeRun {
  Eigen::Matrix3d boundary, contact, F_solver;
  double time = 0.0;
  double position_error = 0.0;  ///< max |x - (x_0 + exp(L t)(X - x_0))| / spacing
  std::size_t pairs = 0;
};

/// kN^3 spheres of radius R = 1 on a cubic lattice of spacing s (s < 2: overlapping), box [0, kN s]^3
/// without contact walls, every centre prescribed (spins held), frictionless reversible plastic
/// indentation (F = 6 pi sigma_y R* u, no damping), driven by L up to time T.
LatticeRun run_lattice(double s, const std::array<double, 6>& e, double T, double gravity_z = 0.0) {
  Particles3 P;
  std::vector<Eigen::Vector3d> X;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j)
      for (int k = 0; k < kN; ++k) {
        X.emplace_back(s * (i + 0.5), s * (j + 0.5), s * (k + 0.5));
        P.add_sphere(X.back().x(), X.back().y(), X.back().z(), 1.0, 1.0);
      }
  Box box;
  box.x_max = box.y_max = box.z_max = s * kN;
  box.contact_walls = false;
  for (MovingWall* w : {&box.right, &box.back, &box.top}) w->mode = WallMode::Affine;
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.sigma_y = 1.0;
  o.plastic.mu = 0.0;
  o.plastic.reversible = true;
  o.gravity_z = gravity_z;
  DynamicSolver3 sv(std::move(P), o.plastic, box, o);
  std::vector<std::uint32_t> all(X.size());
  for (std::uint32_t p = 0; p < all.size(); ++p) all[p] = p;
  sv.set_prescribed(all);
  sv.set_strain_rate3(e[0], e[1], e[2], e[3], e[4], e[5]);
  while (sv.time() < T) sv.step();
  LatticeRun r;
  r.time = sv.time();
  const Stress3 b = sv.boundary_stress(), c = sv.contact_stress();
  for (int a = 0; a < 3; ++a)
    for (int q = 0; q < 3; ++q) {
      r.boundary(a, q) = b.s[a][q];
      r.contact(a, q) = c.s[a][q];
      r.F_solver(a, q) = sv.affine_map3()[static_cast<std::size_t>(3 * a + q)];
    }
  const Eigen::Matrix3d F = taylor_exp(rate_matrix(e) * r.time);
  const auto& Q = sv.particles();
  for (std::size_t p = 0; p < X.size(); ++p) {
    const Eigen::Vector3d want = F * X[p];  // x_0 = 0
    r.position_error = std::fmax(r.position_error, (Q.position(p) - want).norm() / s);
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  sv.touching_pairs(pairs);
  r.pairs = pairs.size();
  return r;
}

/// The closed form: the kN^2 (kN - 1) bonds along each lattice axis a have l_a = s F e_a and the
/// force 6 pi sigma_y R* (2R - |l_a|) along l_a (R* = 1/2), so Sigma = (1/V) sum_a kN^2 (kN - 1)
/// F_a l_a (x) l_a / |l_a|, V = (kN s)^3 det F (compression positive).
Eigen::Matrix3d closed_form(double s, const Eigen::Matrix3d& F) {
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  const double bonds = kN * kN * (kN - 1.0);
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d l = s * F.col(a);
    const double L = l.norm(), f = 6.0 * std::numbers::pi * 0.5 * (2.0 - L);
    if (f > 0.0) S += bonds * f / L * l * l.transpose();
  }
  return S / (std::pow(kN * s, 3) * F.determinant());
}

double max_abs(const Eigen::Matrix3d& A) { return A.cwiseAbs().maxCoeff(); }

}  // namespace

// Pure shear E' = e (e1 e2 + e2 e1) of a lattice pre-compressed to spacing s = 1.98: exp(L t) =
// cosh(et) (e1 e1 + e2 e2) + sinh(et) (e1 e2 + e2 e1) + e3 e3, so the x and y bonds stretch to
// s q, q = sqrt(cosh 2et), the z bonds keep s, and by hand Sigma11 = Sigma22 = N s F_1 q / V,
// Sigma12 = N s F_1 sinh(2et) / (q V), Sigma33 = N s F_3 / V, N = kN^2 (kN - 1), V = (kN s)^3,
// F_1 = 3 pi (2 - s q), F_3 = 3 pi (2 - s). Eq 13 (the reactions of the prescribed centres) and the
// contact stress give it to 1e-9, the positions are x_0 + exp(L t)(X - x_0) to 1e-12.
TEST(Dynamic3DAffine, PureShearOfALatticeByHand) {
  const double s = 1.98, e = 1e-3, T = 5.0;
  const LatticeRun r = run_lattice(s, {0, 0, 0, 0, 0, e}, T);
  const double et = e * r.time, q = std::sqrt(std::cosh(2.0 * et));
  const double N = kN * kN * (kN - 1.0), V = std::pow(kN * s, 3);
  const double F1 = 3.0 * std::numbers::pi * (2.0 - s * q), F3 = 3.0 * std::numbers::pi * (2.0 - s);
  Eigen::Matrix3d want = Eigen::Matrix3d::Zero();
  want(0, 0) = want(1, 1) = N * s * F1 * q / V;
  want(0, 1) = want(1, 0) = N * s * F1 * std::sinh(2.0 * et) / (q * V);
  want(2, 2) = N * s * F3 / V;
  std::printf("  pure shear et = %.4f: Sigma11 = %.10f, Sigma12 = %.10e, Sigma33 = %.10f (by hand %.10f %.10e %.10f)\n",
              et, r.boundary(0, 0), r.boundary(0, 1), r.boundary(2, 2), want(0, 0), want(0, 1), want(2, 2));
  EXPECT_EQ(r.pairs, static_cast<std::size_t>(3 * N));
  EXPECT_LT(r.position_error, 1e-12);
  const double scale = max_abs(want);
  EXPECT_LT(max_abs(r.boundary - want), 1e-9 * scale);
  EXPECT_LT(max_abs(r.contact - want), 1e-9 * scale);
  EXPECT_GT(std::fabs(want(0, 1)), 1e-3 * scale);  // the shear stress is there to be seen
  // the same closed form through the general formula with the Taylor exponential
  EXPECT_LT(max_abs(closed_form(s, taylor_exp(rate_matrix({0, 0, 0, 0, 0, e}) * r.time)) - want), 1e-12 * scale);
}

// A general symmetric E' (negative definite: every bond shortens) on the touching lattice, with
// gravity on the prescribed spheres: the contact stress is the closed form with exp(L t) from its
// Taylor series; Eq 13 about the centre of the deformed domain x_0 + F (c_0 - x_0) (the lattice's
// centroid, so the gravity forces add no moment) equals it (about the box centre it would be off
// by N m g (x) (F - diag F)(c_0 - x_0) / V, a quarter of Sigma here); the accumulated map of some
// 300 steps is exp(L t) to 1e-12.
TEST(Dynamic3DAffine, GeneralStrainRateClosedForm) {
  const double e = 1e-3, T = 10.0;
  const std::array<double, 6> E = {-1.0 * e, -0.8 * e, -1.2 * e, -0.25 * e, 0.2 * e, 0.3 * e};
  const LatticeRun r = run_lattice(2.0, E, T, -1.0);
  const Eigen::Matrix3d F = taylor_exp(rate_matrix(E) * r.time);
  const Eigen::Matrix3d want = closed_form(2.0, F);
  std::printf("  general E at t = %.4f: Sigma = [%.9f %.9f %.9f; %.9f %.9f; %.9f], |F - exp(Lt)| = %.2e\n", r.time,
              want(0, 0), want(0, 1), want(0, 2), want(1, 1), want(1, 2), want(2, 2), max_abs(r.F_solver - F));
  EXPECT_EQ(r.pairs, static_cast<std::size_t>(3 * kN * kN * (kN - 1)));
  EXPECT_LT(max_abs(r.F_solver - F), 1e-12);
  EXPECT_LT(r.position_error, 1e-12);
  const double scale = max_abs(want);
  EXPECT_LT(max_abs(r.contact - want), 1e-9 * scale);
  EXPECT_LT(max_abs(r.boundary - want), 1e-9 * scale);
  EXPECT_GT(std::fabs(want(0, 2)), 1e-3 * scale);
  // about the box centre instead, the gravity forces N m g e_z would add (N m g e_z) (x) (F - diag F) c_0 / V
  const Eigen::Vector3d c0(4.0, 4.0, 4.0);
  const Eigen::Matrix3d Fd = F.diagonal().asDiagonal();
  const double wrong = kN * kN * kN * (4.0 / 3.0 * std::numbers::pi) * ((F - Fd) * c0).cwiseAbs().maxCoeff() /
                       (std::pow(8.0, 3) * F.determinant());
  std::printf("  Eq 13 - contact stress: %.2e (about the box centre it would be %.2e)\n", max_abs(r.boundary - r.contact), wrong);
  EXPECT_GT(wrong, 1e-3 * scale);
}

// Invariance: E' rotated by 90 degrees about z (Q E Q^T; the lattice maps onto itself about the box
// centre) gives the rotated stress Q Sigma Q^T, and a mirror x -> -x (E13, E12 change sign) the
// mirrored one, to 1e-9.
TEST(Dynamic3DAffine, StressRotatesAndMirrorsWithTheStrainRate) {
  const double e = 1e-3, T = 8.0;
  const std::array<double, 6> E = {-1.0 * e, -0.6 * e, -1.3 * e, 0.15 * e, -0.2 * e, 0.35 * e};
  Eigen::Matrix3d Qz;
  Qz << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d Mx = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  auto six = [](const Eigen::Matrix3d& L) {
    return std::array<double, 6>{L(0, 0), L(1, 1), L(2, 2), L(1, 2), L(0, 2), L(0, 1)};
  };
  const LatticeRun r = run_lattice(2.0, E, T);
  const double scale = max_abs(r.contact);
  for (const Eigen::Matrix3d& Q : {Qz, Mx}) {
    const LatticeRun rq = run_lattice(2.0, six(Q * rate_matrix(E) * Q.transpose()), T);
    ASSERT_EQ(rq.time, r.time);
    EXPECT_LT(max_abs(rq.contact - Q * r.contact * Q.transpose()), 1e-9 * scale);
    EXPECT_LT(max_abs(rq.boundary - Q * r.boundary * Q.transpose()), 1e-9 * scale);
  }
}

// A shear rate needs a box without contact walls (the walls stay axis-aligned), as in 2D; the
// diagonal rates still work with walls.
TEST(Dynamic3DAffine, ShearRateRefusedWithContactWalls) {
  Particles3 P;
  P.add_sphere(2.0, 2.0, 2.0, 1.0, 1.0);
  Box box;
  box.x_max = box.y_max = box.z_max = 4.0;
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  DynamicSolver3 sv(P, o.plastic, box, o);
  EXPECT_THROW(sv.set_strain_rate3(-1e-3, -1e-3, -1e-3, 0.0, 1e-4, 0.0), std::invalid_argument);
  EXPECT_NO_THROW(sv.set_strain_rate3(-1e-3, -1e-3, -1e-3));
  EXPECT_THROW(sv.set_strain_rate3(-1e-3, -1e-3, -1e-3, std::nan(""), 0.0, 0.0), std::invalid_argument);
}

// The affine velocity field is the full L (x - x_0): set_affine_velocities() gives it (by hand for
// a sphere at d = x - x_0 = (3, 2, 1)), and the affine drag, measured by unbalanced_force_rms()
// (which adds the drag c m (v - L d) back), sees no motion relative to it; against the diagonal
// field alone the shear part w of the velocity shows as c m |w| (the RMS per sphere of the force and
// the torque / radius, the spin at rest).
TEST(Dynamic3DAffine, AffineVelocitiesAndDragUseTheFullField) {
  Particles3 P;
  P.add_sphere(3.0, 2.0, 1.0, 0.5, 1.0);
  Box box;
  box.x_max = box.y_max = box.z_max = 6.0;
  box.contact_walls = false;
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.affine_drag = 2.0;
  DynamicSolver3 sv(P, o.plastic, box, o);
  const double e11 = -1e-3, e22 = -2e-3, e33 = 5e-4, e23 = 3e-4, e13 = -4e-4, e12 = 6e-4;
  sv.set_strain_rate3(e11, e22, e33, e23, e13, e12);
  sv.set_affine_velocities();
  const auto& q = sv.particles();
  EXPECT_DOUBLE_EQ(q.vel[0], e11 * 3 + e12 * 2 + e13 * 1);
  EXPECT_DOUBLE_EQ(q.vel[1], e12 * 3 + e22 * 2 + e23 * 1);
  EXPECT_DOUBLE_EQ(q.vel[2], e13 * 3 + e23 * 2 + e33 * 1);
  EXPECT_EQ(sv.unbalanced_force_rms(), 0.0);
  EXPECT_DOUBLE_EQ(sv.strain_rate3(0, 2), e13);
  EXPECT_DOUBLE_EQ(sv.strain_rate3(2, 1), e23);
  // the diagonal field alone would leave the shear part of the velocity as relative motion
  sv.set_strain_rate3(e11, e22, e33);
  const double m = q.mass[0], w = std::hypot(e12 * 2 + e13, e12 * 3 + e23, e13 * 3 + e23 * 2);
  EXPECT_NEAR(sv.unbalanced_force_rms(), o.affine_drag * m * w, 1e-12 * m * w);
}
