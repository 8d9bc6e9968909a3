// Tests of the explicit DEM in 3D (DynamicSolver3, issue 16): closed forms for spheres.
#include <gtest/gtest.h>

#include "test_scale.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>
#include <type_traits>
#include <utility>
#include <type_traits>
#include <vector>

#include <Eigen/Geometry>

#include "netdem/contact/kinematics.hpp"
#include "netdem/contact/luding_law.hpp"
#include "netdem/dynamic/solver.hpp"

using namespace netdem::dem;
using netdem::contact::LudingParams;

namespace {

constexpr double kRho = 2000.0;  // kg/m^3

LudingParams linear_params() {  // k1 = k2, k_c = 0
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.mu = 0.0;
  p.mu_wall = 0.0;
  return p;
}

double sphere_mass(double a) { return kRho * 4.0 / 3.0 * std::numbers::pi * a * a * a; }

// side^3 spheres on a cubic lattice of the given pitch (centres at (i + 1/2) pitch), radii
// a0 (1 + dr u) and velocity components v u (u uniform in [-1, 1), seed), drawn in that order.
Particles3 cubic_sample(int side, double pitch, double a0, double dr, double v, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles3 P;
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b)
      for (int c = 0; c < side; ++c) {
        const double r = a0 * (1.0 + dr * u(rng));
        std::array<double, 3> vel{0.0, 0.0, 0.0};
        if (v > 0.0)
          for (double& q : vel) q = v * u(rng);
        P.add_sphere((a + 0.5) * pitch, (b + 0.5) * pitch, (c + 0.5) * pitch, r, kRho, vel);
      }
  return P;
}

struct Collision {
  double e = 0.0, tc = 0.0;
};

// Head-on collision of two equal spheres in free space along a skew direction u, relative speed v0.
Collision two_sphere(const LudingParams& p, double steps_per_contact, const Eigen::Vector3d& u) {
  Particles3 P;
  const double a = p.a0, v0 = 0.1;
  const Eigen::Vector3d x1 = (2.0 * a + 1e-6) * u, v = 0.5 * v0 * u;
  P.add_sphere(0.0, 0.0, 0.0, a, kRho, {v.x(), v.y(), v.z()});
  P.add_sphere(x1.x(), x1.y(), x1.z(), a, kRho, {-v.x(), -v.y(), -v.z()});
  Box box;
  box.enabled = false;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  o.steps_per_contact = steps_per_contact;
  DynamicSolver3 s(std::move(P), p, box, o);
  auto overlap = [&] {
    const auto& q = s.particles();
    const Eigen::Vector3d d(q.pos[3] - q.pos[0], q.pos[4] - q.pos[1], q.pos[5] - q.pos[2]);
    return 2.0 * a - d.norm();
  };
  double d_prev = overlap(), t_in = -1.0, t_out = -1.0;
  for (int k = 0; k < 1000000 && t_out < 0.0; ++k) {
    s.step();
    const double d = overlap();
    const double t_cross = s.time() - s.dt() * d / (d - d_prev);
    if (d_prev <= 0.0 && d > 0.0) t_in = t_cross;
    if (t_in >= 0.0 && d_prev > 0.0 && d <= 0.0) t_out = t_cross;
    d_prev = d;
  }
  EXPECT_GT(t_out, 0.0);
  s.run(5);
  const auto& q = s.particles();
  const Eigen::Vector3d dv(q.vel[3] - q.vel[0], q.vel[4] - q.vel[1], q.vel[5] - q.vel[2]);
  return {dv.dot(u) / v0, t_out - t_in};
}

}  // namespace

// Restitution and contact duration of two spheres with the linear spring-dashpot (LMM05 Eq 5,
// 6): e = exp(-eta t_c), t_c = pi / sqrt(k2 / m12 - eta^2), with the sphere masses, to the
// integrator's O(dt) (the dashpot is taken at the half-step velocity), in any direction.
TEST(Dynamic3D, TwoSphereRestitutionAndDuration) {
  LudingParams p = linear_params();
  p.gamma_n = 0.5;
  const double m12 = 0.5 * sphere_mass(p.a0);
  const double eta = p.gamma_n / (2.0 * m12);
  const double tc = std::numbers::pi / std::sqrt(p.k2 / m12 - eta * eta);
  const double e = std::exp(-eta * tc);
  double err[2];
  int k = 0;
  for (double spc : {50.0, 200.0}) {
    const Collision c = two_sphere(p, spc, Eigen::Vector3d(1.0, -2.0, 2.0).normalized());
    const double dt = tc / spc;
    err[k] = std::fabs(c.e - e);
    std::printf("  %3.0f steps/contact: e = %.6f (closed form %.6f), t_c = %.6e s (%.6e)\n", spc, c.e, e, c.tc, tc);
    EXPECT_LE(err[k], eta * dt);
    EXPECT_LE(std::fabs(c.tc - tc) / tc, eta * dt);
    ++k;
  }
  EXPECT_GT(err[0], 2.0 * err[1]);  // converges with dt
  // the same collision along x, y or z (the dimension's axes are not special)
  const Collision cx = two_sphere(p, 50.0, Eigen::Vector3d::UnitX());
  const Collision cz = two_sphere(p, 50.0, Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(cx.e, cz.e, 1e-12);
  EXPECT_NEAR(cx.tc, cz.tc, 1e-12 * cx.tc);
}

// Dense random packing of spheres whose contacts never open (pitch 1.85 a0 < 2 a_min, velocities
// small against the overlaps; the walls at half a pitch from the outer centres touch too): a
// smooth Hamiltonian, on which velocity Verlet's energy error is O(dt^2), over 5 contact times
// (short enough that the runs at different dt follow the same trajectory). As the 2D test.
static double lattice_energy_error(double steps_per_contact, double duration, int side) {
  LudingParams p = linear_params();
  p.gamma_n = 0.0;
  p.gamma_t = 0.0;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles3 P;
  const double pitch = 1.85 * p.a0, v = 0.3;
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b)
      for (int c = 0; c < side; ++c) {
        const double r = p.a0 * (1.0 + 0.05 * u(rng));
        const double slack = 0.5 * pitch - r;
        // the draws in a fixed order (GCC's: a call's arguments are evaluated in an unspecified order;
        // a braced list is evaluated first to last)
        const double vx = v * u(rng), vy = v * u(rng), vz = v * u(rng);
        const double z = (c + 0.5) * pitch + 0.5 * slack * u(rng), y = (b + 0.5) * pitch + 0.5 * slack * u(rng),
                     x = (a + 0.5) * pitch + 0.5 * slack * u(rng);
        P.add_sphere(x, y, z, r, kRho, {vx, vy, vz});
      }
  Box box;
  box.x_max = box.y_max = box.z_max = side * pitch;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  o.steps_per_contact = steps_per_contact;
  DynamicSolver3 s(std::move(P), p, box, o);
  const double e0 = s.energies().total();
  double err = 0.0;
  const std::size_t n = static_cast<std::size_t>(duration / s.dt());
  for (std::size_t k = 0; k < n; ++k) {
    s.step();
    err = std::fmax(err, std::fabs(s.energies().total() - e0) / e0);
  }
  return err;
}

TEST(Dynamic3D, EnergyConservedSecondOrder) {
  const int side = netdem::test::small_scale() ? 4 : 5;
  const LudingParams p = linear_params();
  const double duration = 5.0 * contact_duration(p.k2, 0.0, 0.5 * sphere_mass(p.a0));
  const double e1 = lattice_energy_error(25.0, duration, side);
  const double e2 = lattice_energy_error(50.0, duration, side);
  const double e3 = lattice_energy_error(100.0, duration, side);
  const double o1 = std::log2(e1 / e2), o2 = std::log2(e2 / e3);
  std::printf("  %d spheres, persistent contacts: max |dE|/E = %.3e, %.3e, %.3e at 25, 50, 100 steps/contact; "
              "observed orders %.3f, %.3f\n",
              side * side * side, e1, e2, e3, o1, o2);
  EXPECT_GE(o1, 1.8);
  EXPECT_LE(o1, 2.2);
  EXPECT_GE(o2, 1.8);
  EXPECT_LE(o2, 2.2);
}

// A sphere on an inclined plane (gravity tilted by theta against the bottom wall z_min), the
// linear law with wall friction mu_w. Rotation locked: it sticks for tan theta < mu and slides
// with a = g (sin theta - mu cos theta) above. Free (I = 2/5 m r^2): it rolls without slipping,
// a = 5/7 g sin theta, for tan theta < 7 mu / 2, and slides with a = g (sin - mu cos) above.
TEST(Dynamic3D, SphereOnInclineSticksSlidesAndRolls) {
  const double g = 9.81, mu = 0.3;
  auto run = [&](double theta, bool rotation) {
    LudingParams p = linear_params();
    p.mu_wall = mu;
    p.gamma_n = 0.5;
    p.gamma_t = 0.1;
    Particles3 P;
    P.add_sphere(0.05, 0.05, p.a0 + 1e-9, p.a0, kRho);
    Box box;
    box.x_max = 1.0;
    box.y_max = 0.1;
    box.z_max = 0.1;
    DynamicOptions o;
    o.model = ContactModel::Linear;
    o.gravity_x = g * std::sin(theta);
    o.gravity_z = -g * std::cos(theta);
    DynamicSolver3 s(std::move(P), p, box, o);
    s.set_rotations(rotation);
    s.run(static_cast<std::size_t>(0.02 / s.dt()));  // settle on the plane
    const double x0 = s.particles().pos[0], v0 = s.particles().vel[0], t0 = s.time();
    s.run(static_cast<std::size_t>(0.05 / s.dt()));
    const double T = s.time() - t0;
    const double dxs = s.particles().pos[0] - x0;
    return 2.0 * (dxs - v0 * T) / (T * T);  // mean acceleration along the incline
  };
  const double th_stick = std::atan(0.8 * mu), th_slide = std::atan(1.5 * mu), th_roll = std::atan(2.0 * mu),
               th_rslide = std::atan(5.0 * mu);
  const double a_stick = run(th_stick, false), a_slide = run(th_slide, false);
  const double a_roll = run(th_roll, true), a_rslide = run(th_rslide, true);
  const double slide = g * (std::sin(th_slide) - mu * std::cos(th_slide));
  const double roll = 5.0 / 7.0 * g * std::sin(th_roll);
  const double rslide = g * (std::sin(th_rslide) - mu * std::cos(th_rslide));
  std::printf("  locked: tan = 0.8 mu: a = %.3e; tan = 1.5 mu: a = %.5f (closed form %.5f)\n", a_stick, a_slide, slide);
  std::printf("  free:   tan = 2 mu: a = %.5f (rolling 5/7 g sin = %.5f); tan = 5 mu: a = %.5f (sliding %.5f)\n", a_roll,
              roll, a_rslide, rslide);
  EXPECT_LT(std::fabs(a_stick), 1e-3 * g);
  EXPECT_NEAR(a_slide / slide, 1.0, 5e-3);
  EXPECT_NEAR(a_roll / roll, 1.0, 5e-3);
  EXPECT_NEAR(a_rslide / rslide, 1.0, 5e-3);
}

// A rigidly rotating pair (velocities w x x, spins w) with a loaded tangential spring: the step's
// kinematics give no slip, and step_transport carries the spring with the pair (second order per
// step, law.hpp transport_small: the error after one radian is O(dt^2), and the length is kept to
// O(dt^3) after one radian without a rescale).
TEST(Dynamic3D, RigidRotationCarriesTheSpring) {
  using V3 = Eigen::Vector3d;
  const V3 w = V3(0.3, -0.5, 0.8).normalized();  // rad/s
  const V3 xi0(0.1, 0.2, -0.1), xj0 = xi0 + 1.9e-3 * V3(1.0, 0.4, -0.3).normalized();
  const double ri = 1e-3, rj = 1e-3;
  double err[2];
  int k = 0;
  for (int steps : {1000, 4000}) {
    const double dt = 1.0 / steps;
    const netdem::contact::PairGeometry3 g0 = netdem::contact::pair_geometry(xi0, xj0, ri, rj);
    V3 spring = 1e-6 * g0.n.unitOrthogonal();
    const V3 s0 = spring;
    double slip = 0.0;
    for (int q = 1; q <= steps; ++q) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(q * dt, w).toRotationMatrix();
      const V3 xi = R * xi0, xj = R * xj0;
      const netdem::contact::PairGeometry3 g = netdem::contact::pair_geometry(xi, xj, ri, rj);
      // the solver's step kinematics (solver.cpp compute_forces, 3D)
      const V3 vrel = w.cross(xj - xi), W = g.d_i * w + g.d_j * w;
      const V3 vc = vrel - W.cross(g.n);
      slip += (vc - g.n * vc.dot(g.n)).norm() * dt;
      const auto t = netdem::contact::step_transport(g.n, (g.n.cross(vrel) + W.dot(g.n) * g.n) * (dt / g.L));
      spring = t.apply(spring);
    }
    const V3 exact = Eigen::AngleAxisd(1.0, w).toRotationMatrix() * s0;
    err[k++] = (spring - exact).norm() / s0.norm();
    std::printf("  %d steps: slip %.2e m, |spring - R spring0| / |spring0| = %.3e, length %.15f\n", steps, slip,
                err[k - 1], spring.norm() / s0.norm());
    EXPECT_LT(slip, 1e-15);
    EXPECT_NEAR(spring.norm(), s0.norm(), 1e-9 * s0.norm());  // O(theta^4) per step
  }
  EXPECT_LT(err[0], 1e-6);
  EXPECT_LT(err[1], 0.1 * err[0]);  // O(dt^2): 1/16 for 4x the steps
}

// Stress-controlled walls in 3D (Eq 1 with the wall's area): a frictionless damped sample of
// spheres settles with each moving wall's force = p x its current area, and the contact stress
// carries the same pressure on the diagonal.
TEST(Dynamic3D, StressControlledWallsSettleToPressure) {
  LudingParams p = linear_params();
  p.gamma_n = 1.0;
  const int side = netdem::test::small_scale() ? 3 : 4;
  const double pitch = 2.2 * p.a0;
  Particles3 P = cubic_sample(side, pitch, p.a0, 0.2, 0.0, 5);
  Box box;
  box.x_max = box.y_max = box.z_max = side * pitch;
  const double pressure = 1e5;  // N/m^2
  for (MovingWall* w : {&box.right, &box.back, &box.top}) {
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->mass = 1e-3;
    w->damping = 2.0;
  }
  DynamicOptions o;
  o.model = ContactModel::Linear;
  DynamicSolver3 s(std::move(P), p, box, o);
  const double nu0 = s.density();
  s.run(static_cast<std::size_t>(0.06 / s.dt()));
  const auto& b = s.box();
  const double e[3] = {b.x_max - b.x_min, b.y_max - b.y_min, b.z_max - b.z_min};
  const Stress3 sw = s.wall_stress(), sc = s.contact_stress();
  std::printf("  %d spheres: nu %.3f -> %.3f; wall stress %.5f %.5f %.5f p; contact stress %.4f %.4f %.4f p, "
              "off-diagonal max %.1e p\n",
              side * side * side, nu0, s.density(), sw.s[0][0] / pressure, sw.s[1][1] / pressure,
              sw.s[2][2] / pressure, sc.s[0][0] / pressure, sc.s[1][1] / pressure, sc.s[2][2] / pressure,
              std::fmax(std::fabs(sc.s[0][1]), std::fmax(std::fabs(sc.s[0][2]), std::fabs(sc.s[1][2]))) / pressure);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(s.wall_force(2 * a + 1) / (pressure * e[(a + 1) % 3] * e[(a + 2) % 3]), 1.0, 1e-3);
    EXPECT_NEAR(sc.s[a][a] / pressure, 1.0, 1e-2);
  }
  EXPECT_GT(s.density(), nu0);
}

// The in-place update of the 3D force loop (LudingLaw::update: the linear sets written out, the
// explicit step's second-order transport) against the law's evaluate() (reference_contact_path):
// a frictional, cohesive sample of spheres under gravity with stress-controlled walls gives the same
// state to the last bit for the three Luding models.
TEST(Dynamic3D, InPlaceUpdateIsBitIdentical) {
  for (ContactModel model : {ContactModel::Linear, ContactModel::Hysteretic, ContactModel::Full}) {
    LudingParams p;  // Table 1: friction, cohesion, damping
    p.mu_wall = 0.3;
    const int side = netdem::test::small_scale() ? 3 : 4;
    const double pitch = 2.02 * p.a0;
    const Particles3 P0 = cubic_sample(side, pitch, p.a0, 0.05, 0.05, 9);
    Box box;
    box.x_max = box.y_max = box.z_max = side * pitch;
    for (MovingWall* w : {&box.right, &box.back, &box.top}) {
      w->mode = WallMode::Stress;
      w->pressure = 5e4;
      w->mass = 1e-3;
      w->damping = 2.0;
    }
    SolverState out[2];
    for (int ref = 0; ref < 2; ++ref) {
      DynamicOptions o;
      o.model = model;
      o.reference_contact_path = ref == 1;
      o.gravity_z = -9.81;
      DynamicSolver3 s(Particles3(P0), p, box, o);
      s.run(netdem::test::small_scale() ? 3000 : 10000);
      out[ref] = s.state();
    }
    const auto& a = out[0].particles_of<3>();
    const auto& b = out[1].particles_of<3>();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(std::memcmp(&a.pos[3 * i], &b.pos[3 * i], sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&a.pos[3 * i + 2], &b.pos[3 * i + 2], sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&a.vel[3 * i + 1], &b.vel[3 * i + 1], sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&a.spin[3 * i], &b.spin[3 * i], sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&a.spin[3 * i + 2], &b.spin[3 * i + 2], sizeof(double)), 0);
    }
    using H3 = netdem::contact::LudingHistoryT<3>;
    const auto &p0 = out[0].histories_of<H3>().pair, &p1 = out[1].histories_of<H3>().pair;
    ASSERT_EQ(p0.size(), p1.size());
    std::size_t loaded = 0;
    for (std::size_t k = 0; k < p0.size(); ++k) {
      const auto &h0 = p0[k], &h1 = p1[k];
      loaded += h0.xi.squaredNorm() > 0.0 ? 1 : 0;
      EXPECT_EQ(std::memcmp(h0.xi.data(), h1.xi.data(), 3 * sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&h0.delta_max, &h1.delta_max, sizeof(double)), 0);
      EXPECT_EQ(h0.sliding, h1.sliding);
    }
    std::printf("  model %d: %zu spheres, %zu contacts with a loaded spring\n", static_cast<int>(model), a.size(),
                loaded);
    EXPECT_GT(loaded, 0u);
  }
}

// The 3D solver refuses what it does not do yet, with one line.
TEST(Dynamic3D, RefusesTheTwoDOnlyParts) {
  LudingParams p = linear_params();
  Particles3 P;
  P.add_sphere(0.005, 0.005, 0.005, p.a0, kRho);
  Box box;
  box.x_max = box.y_max = box.z_max = 0.01;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  DynamicSolver3 s(P, p, box, o);
  EXPECT_THROW(s.set_strain_rate(-1.0, -1.0), std::logic_error);
  // disks into a 3D solver, spheres into a 2D one: the particles' type has the dimension
  static_assert(!std::is_constructible_v<DynamicSolver3, Particles, LudingParams, Box, DynamicOptions>);
  static_assert(!std::is_constructible_v<DynamicSolver, Particles3, LudingParams, Box, DynamicOptions>);
  Box flat = box;
  flat.z_max = 0.0;
  EXPECT_THROW(DynamicSolver3(P, p, flat, o), std::invalid_argument);
}

// A simple cubic lattice of n^3 equal touching spheres (spacing 2R), every centre prescribed
// (spins held), compacted by the diagonal affine field exp(E' t), E' = -e I (set_strain_rate3),
// with the plastic-indentation law of spheres: every one of the 3 n^2 (n - 1) contacts has the
// overlap u = 2R - a, a = 2R exp(-e t), and the force F = 6 pi sigma_y R* u (R* = R/2, loading);
// the reactions' stress about the box centre (boundary_stress, Eq 13) and the contact stress are
// (n - 1)/n F / a^2 on the diagonal and 0 off it. (Kinematics imposed: this checks the 3D law,
// the exact affine motion and the stress sums, not a dynamics.)
TEST(Dynamic3D, CubicLatticeAffineCompactionClosedForm) {
  const int n = 4;
  const double R = 1.0, rho = 1.0;
  Particles3 P;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) P.add_sphere(R + 2 * R * i, R + 2 * R * j, R + 2 * R * k, R, rho);
  Box box;
  box.x_max = box.y_max = box.z_max = 2.0 * R * n;
  box.contact_walls = false;
  for (MovingWall* w : {&box.right, &box.back, &box.top}) w->mode = WallMode::Affine;
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.sigma_y = 1.0;
  DynamicSolver3 s(std::move(P), o.plastic, box, o);
  std::vector<std::uint32_t> all(static_cast<std::size_t>(n * n * n));
  for (std::uint32_t p = 0; p < all.size(); ++p) all[p] = p;
  s.set_prescribed(all);
  const double e = 1e-3;
  s.set_strain_rate3(-e, -e, -e);
  const double eps = 0.01;
  while (s.time() < eps / e) s.step();
  const double a = 2.0 * R * std::exp(-e * s.time()), u = 2.0 * R - a;
  const double F = 6.0 * std::numbers::pi * o.plastic.sigma_y * 0.5 * R * u;
  const double sigma = (n - 1.0) / n * F / (a * a);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  s.touching_pairs(pairs);
  EXPECT_EQ(pairs.size(), static_cast<std::size_t>(3 * n * n * (n - 1)));
  const auto& q = s.particles();
  double du = 0.0;
  for (const auto& [i, j] : pairs) {
    const double L = (q.position(j) - q.position(i)).norm();
    du = std::fmax(du, std::fabs(2.0 * R - L - u));
  }
  EXPECT_LT(du, 1e-12 * R);  // the affine motion is exact (to the rounding of the drifts)
  const Stress3 sb = s.boundary_stress(), sc = s.contact_stress();
  std::printf("  %d spheres at strain %.4f: u = %.6e R, closed form sigma = %.8f sigma_y; boundary %.8f %.8f %.8f, "
              "contact %.8f\n",
              n * n * n, e * s.time(), u, sigma, sb.s[0][0], sb.s[1][1], sb.s[2][2], sc.s[2][2]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const double want = r == c ? sigma : 0.0;
      EXPECT_NEAR(sb.s[r][c], want, 1e-9 * sigma) << r << c;
      EXPECT_NEAR(sc.s[r][c], want, 1e-9 * sigma) << r << c;
    }
  const auto& F3 = s.box_deformation3();
  EXPECT_NEAR(F3[0], std::exp(-e * s.time()), 1e-12);
}
