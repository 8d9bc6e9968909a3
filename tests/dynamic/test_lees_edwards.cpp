// The explicit DEM's periodic cell under a general velocity gradient and its Lees-Edwards
// re-mapping (issue 29, item 3's shear part): simple shear of Bravais lattices far past the tilt at
// which the cell is re-mapped, against the affine closed form (every particle of a Bravais lattice
// is a centre of symmetry, so it follows the affine motion whatever the strain) and against the
// same run without the re-mapping; a rigid spin rotates the stress; a re-mapped cell (negative
// tilt) is written and read back as a packing.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/periodic.hpp"
#include "periodic_lattices.hpp"

using namespace netdem::dem;
namespace packing = netdem::packing;
namespace contact = netdem::contact;

namespace {

// The frictionless reversible plastic law (Eq 2 retraced: the normal force is a function of the
// overlap only, so the lattice's stress is a function of its current shape).
DynamicOptions reversible_options() {
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.sigma_y = 2.0;
  o.plastic.mu = 0.0;
  o.plastic.reversible = true;
  o.plastic.damping_n = o.plastic.damping_t = 0.5;
  return o;
}

template <int D>
DynamicSolverT<D> periodic_solver(const packing::Packing& pk, const DynamicOptions& o) {
  return DynamicSolverT<D>(periodic_particles_from<D>(pk, 1.0), o.plastic, packing::periodic_cell<D>(pk), o);
}

// The contact stress (compression positive) of a Bravais lattice of particles of radius R with
// primitive vectors the columns of B (one particle per primitive cell), deformed by F: every lattice
// vector m with |F m| < 2 R is a bond with the normal force of the law at the overlap 2 R - |F m|,
// Sigma = (1 / (2 V_p)) sum_m f (F m) (x) (F m) / |F m|, V_p = |det F B|.
template <int D>
Eigen::Matrix<double, D, D> lattice_stress(const Eigen::Matrix<double, D, D>& B, const Eigen::Matrix<double, D, D>& F,
                                           double R, const contact::PlasticIndentationParams& law) {
  using Vec = Eigen::Matrix<double, D, 1>;
  Eigen::Matrix<double, D, D> S = Eigen::Matrix<double, D, D>::Zero();
  const int n = 6;
  const int nk = D == 3 ? n : 0;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -nk; k <= nk; ++k) {
        if (i == 0 && j == 0 && k == 0) continue;
        Vec c;
        c[0] = i, c[1] = j;
        if constexpr (D == 3) c[2] = k;
        const Vec l = F * B * c;
        const double L = l.norm();
        if (!(L < 2 * R)) continue;
        const double f = contact::loading_force<D>(law, R / 2, 2 * R - L);
        S += f * l * l.transpose() / L;
      }
  return S / (2.0 * std::abs((F * B).determinant()));
}

template <int D>
Eigen::Matrix<double, D, D> stress_of(const DynamicSolverT<D>& s) {
  Eigen::Matrix<double, D, D> S;
  const auto c = s.contact_stress();
  if constexpr (D == 2) {
    S << c.xx, c.xy, c.yx, c.yy;
  } else {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) S(a, b) = c.s[a][b];
  }
  return S;
}

// Strains the solver along rate L until |rate| t reaches `amount` (t from the start of the leg; the last
// step shortened to land on it), then holds it 20 steps at rest.
template <int D>
void strain_by(DynamicSolverT<D>& s, const Eigen::Matrix<double, D, D>& L, double rate, double amount) {
  s.set_velocity_gradient(L * rate);
  s.set_affine_velocities();
  const double t0 = s.time(), t_end = t0 + amount / std::abs(rate);
  while (s.time() < t_end - 1e-12 * t_end) {
    if (s.time() + s.time_step().dt > t_end) {
      s.step_to(t_end);
      break;
    }
    s.step();
  }
  s.set_velocity_gradient(Eigen::Matrix<double, D, D>::Zero());
  s.set_affine_velocities();
  s.run(20);
}

}  // namespace

// A triangular lattice of 6 x 6 disks (compressed hydrostatically by 1.5 %) in a cell whose second
// vector is tilted by half the first, (6 R ... ) = the re-mapping limit, sheared along x, L = [[0, g],
// [0, 0]], to gamma = 0.3 and back to -0.3: the cell is re-mapped once each way (to a tilt of -0.24
// and +0.24 of its width). (Past gamma of about 0.5 the sheared triangular lattice is unstable: the
// rounding grows and the disks leave the affine motion, so the lattice starts at the limit.) At
// gamma = 0.15, 0.3, 0, -0.3 (held at rest) the stress is the closed form to 1e-9, the cell is the
// sheared cell's lattice of images, reduced, and the same run without re-mapping agrees to 1e-11.
TEST(LeesEdwards, SimpleShearOfATriangularLatticeMatchesTheAffineClosedForm) {
  const int nc = 6, nr = 6;
  const double R = 1.0, E = -0.015;
  packing::Packing pk = netdem::test::triangular_lattice(nc, nr, R);
  const double Lx = pk.box.width(), Ly = pk.box.height(), tilt = 0.5 * Lx;
  pk.cell = {Lx, 0.0, tilt, Ly};
  pk.box.x_max += tilt;
  for (std::size_t i = 0; i < pk.size(); ++i)  // into the tilted cell
    pk.x[i] -= Lx * std::floor((pk.x[i] - tilt * pk.y[i] / Ly) / Lx);
  ASSERT_NO_THROW(packing::validate(pk));
  const DynamicOptions o = reversible_options();
  DynamicOptions o_off = o;
  o_off.cell_remap = false;
  DynamicSolver s = periodic_solver<2>(pk, o), s_off = periodic_solver<2>(pk, o_off);
  ASSERT_EQ(s.cell_remaps(), 0u) << "the limit itself is not re-mapped";
  const Eigen::Matrix2d hydro = Eigen::Matrix2d::Identity(), shear = (Eigen::Matrix2d() << 0, 1, 0, 0).finished();
  for (DynamicSolver* x : {&s, &s_off}) strain_by<2>(*x, hydro, -0.02, -E);
  Eigen::Matrix2d B;
  B << 2 * R, R, 0, std::sqrt(3.0) * R;
  B *= std::exp(E);
  double gamma = 0.0;
  for (double g : {0.1, 0.2, 0.0, -0.15}) {
    for (DynamicSolver* x : {&s, &s_off}) strain_by<2>(*x, g > gamma ? shear : Eigen::Matrix2d(-shear), 0.05, std::abs(g - gamma));
    gamma = g;
    const Eigen::Matrix2d F = (Eigen::Matrix2d() << 1, gamma, 0, 1).finished();
    const Eigen::Matrix2d expect = lattice_stress<2>(B, F, R, o.plastic), got = stress_of<2>(s);
    const double scale = expect.cwiseAbs().maxCoeff();
    EXPECT_LT((got - expect).cwiseAbs().maxCoeff(), 1e-9 * scale) << "gamma " << gamma << "\n" << got << "\n" << expect;
    EXPECT_LT((stress_of<2>(s_off) - got).cwiseAbs().maxCoeff(), 1e-11 * scale) << "gamma " << gamma;
    // the cell: the same lattice of images as the sheared cell, reduced (tilt within half the width)
    const Eigen::Matrix2d h = s.cell().h, h_off = s_off.cell().h;
    const Eigen::Matrix2d U = h_off.inverse() * h;  // integer and unimodular
    for (int a = 0; a < 4; ++a) EXPECT_NEAR(U(a), std::round(U(a)), 1e-9) << "gamma " << gamma;
    EXPECT_NEAR(U.determinant(), 1.0, 1e-9);
    // (re-mapped at table builds: past the limit by at most the shear since the last build)
    EXPECT_LE(std::abs(h.col(1).dot(h.col(0))), 0.6 * h.col(0).squaredNorm()) << "gamma " << gamma;
    EXPECT_NEAR(h_off(0, 1), (tilt + gamma * Ly) * std::exp(E), 1e-9 * Ly);
  }
  EXPECT_EQ(s.cell_remaps(), 2u);
  EXPECT_EQ(s_off.cell_remaps(), 0u);
  const auto k = s.kinetic_stress();
  EXPECT_LT(std::abs(k.xx) + std::abs(k.yy), 1e-15 * std::abs(stress_of<2>(s)(0, 0))) << "the fluctuations stay zero";
}

// A simple cubic lattice (4^3 spheres, compressed by 1 %) sheared in the x-z plane, L_xz = g, to
// gamma = 1.2: one re-mapping at gamma = 0.5; the stress is the closed form to 1e-9 at gamma =
// 0.4, 0.8, 1.2, and the run without re-mapping agrees to 1e-11.
TEST(LeesEdwards, SimpleShearOfACubicLatticeMatchesTheAffineClosedForm) {
  const int n = 4;
  const double R = 1.0, E = -0.01;
  const packing::Packing pk = netdem::test::cubic_lattice(n, R);
  const DynamicOptions o = reversible_options();
  DynamicOptions o_off = o;
  o_off.cell_remap = false;
  DynamicSolver3 s = periodic_solver<3>(pk, o), s_off = periodic_solver<3>(pk, o_off);
  Eigen::Matrix3d shear = Eigen::Matrix3d::Zero();
  shear(0, 2) = 1.0;
  for (DynamicSolver3* x : {&s, &s_off}) strain_by<3>(*x, Eigen::Matrix3d::Identity(), -0.01, -E);
  const Eigen::Matrix3d B = 2 * R * std::exp(E) * Eigen::Matrix3d::Identity();
  double gamma = 0.0;
  for (double g : {0.4, 0.8, 1.2}) {
    for (DynamicSolver3* x : {&s, &s_off}) strain_by<3>(*x, shear, 0.05, g - gamma);
    gamma = g;
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    F(0, 2) = gamma;
    const Eigen::Matrix3d expect = lattice_stress<3>(B, F, R, o.plastic), got = stress_of<3>(s);
    const double scale = expect.cwiseAbs().maxCoeff();
    EXPECT_LT((got - expect).cwiseAbs().maxCoeff(), 1e-9 * scale) << "gamma " << gamma << "\n" << got << "\n" << expect;
    EXPECT_LT((stress_of<3>(s_off) - got).cwiseAbs().maxCoeff(), 1e-11 * scale) << "gamma " << gamma;
  }
  EXPECT_EQ(s.cell_remaps(), 1u);
}

// A rigid spin (L = W antisymmetric) carries an anisotropically compressed lattice through 0.7 rad:
// the frictionless stress is rotated, Sigma = Q Sigma_0 Q^T, to 1e-9; the density does not change;
// the particles spin at the affine rate W_21; the cell's Gram matrix is unchanged (no re-mapping).
TEST(LeesEdwards, RigidSpinRotatesTheStress) {
  const packing::Packing pk = netdem::test::triangular_lattice(6, 6);
  const DynamicOptions o = reversible_options();
  DynamicSolver s = periodic_solver<2>(pk, o);
  strain_by<2>(s, (Eigen::Matrix2d() << 1.0, 0, 0, 0.4).finished(), -0.02, 0.012);
  const Eigen::Matrix2d S0 = stress_of<2>(s);
  const double D0 = s.density();
  const Eigen::Matrix2d W = (Eigen::Matrix2d() << 0, -1, 1, 0).finished();
  const double theta = 0.7;
  s.set_velocity_gradient(0.05 * W);
  s.set_affine_velocities();
  EXPECT_DOUBLE_EQ(s.particles().spin[3], 0.05);
  const double t_end = s.time() + theta / 0.05;
  while (s.time() + s.time_step().dt < t_end) s.step();
  s.step_to(t_end);
  const Eigen::Matrix2d Q = (Eigen::Matrix2d() << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta)).finished();
  const Eigen::Matrix2d expect = Q * S0 * Q.transpose();
  EXPECT_LT((stress_of<2>(s) - expect).cwiseAbs().maxCoeff(), 1e-9 * S0.cwiseAbs().maxCoeff())
      << stress_of<2>(s) << "\n" << expect;
  EXPECT_NEAR(s.density(), D0, 1e-12 * D0);
  EXPECT_EQ(s.cell_remaps(), 0u);
}

// A re-mapped cell has a negative tilt: the packing written from it reads back (the box is the
// cell's bounding box, the first corner above its lower corner) with the same cell and positions.
TEST(LeesEdwards, RemappedCellRoundTripsThroughThePackingFile) {
  const packing::Packing pk = netdem::test::triangular_lattice(6, 6);
  DynamicSolver s = periodic_solver<2>(pk, reversible_options());
  strain_by<2>(s, (Eigen::Matrix2d() << 0, 1, 0, 0).finished(), 0.05, 0.8);
  ASSERT_EQ(s.cell_remaps(), 1u);
  ASSERT_LT(s.cell().h(0, 1), 0.0) << "a negative tilt after the re-mapping";
  const packing::Packing out = s.periodic_packing();
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("netdem_remapped_" + std::to_string(::getpid()) + ".csv");
  packing::write_packing_csv(out, file);
  const packing::Packing back = packing::read_packing_csv(file);
  std::filesystem::remove(file);
  EXPECT_NO_THROW(packing::validate(back));
  const packing::PeriodicCellT<2> c = packing::periodic_cell<2>(back);
  EXPECT_LT((c.h - s.cell().h).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((c.origin - s.cell().origin).cwiseAbs().maxCoeff(), 1e-12);
  ASSERT_EQ(back.size(), out.size());
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_NEAR(back.x[i], out.x[i], 1e-12);
}

TEST(LeesEdwards, RefusesAGeneralVelocityGradientWithoutACell) {
  const packing::Packing pk = netdem::test::triangular_lattice(4, 4);
  packing::Packing walled = pk;
  walled.periodic = false;
  DynamicOptions o = reversible_options();
  DynamicSolver s(particles_from(walled, 1.0), o.plastic, Box(walled.box), o);
  EXPECT_THROW(s.set_velocity_gradient((Eigen::Matrix2d() << 0, 1, 0, 0).finished()), std::invalid_argument);
  DynamicSolver p = periodic_solver<2>(pk, o);
  EXPECT_THROW(p.set_velocity_gradient((Eigen::Matrix2d() << 0, NAN, 0, 0).finished()), std::invalid_argument);
}
