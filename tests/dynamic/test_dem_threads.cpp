// The explicit DEM on threads (DynamicOptions::threads, issue 31): the pair loop and the integration
// run on several threads, and every result is the same to the last bit as on one thread: the
// positions, velocities, spins, forces and torques of every particle, the contact stress, the
// energies and the walls. Four scenes that take the threaded path (more than 4096 table rows and
// 2048 particles): the full Luding law between stress-controlled walls with gravity (2D), the linear
// law between walls (3D), and the plastic-indentation law compacted in a periodic cell (2D, 3D).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/periodic.hpp"
#include "test_scale.hpp"

using namespace netdem::dem;
namespace packing = netdem::packing;

namespace {

std::size_t steps() { return netdem::test::small_scale() ? 100 : 300; }

template <class V>
std::size_t bit_differences(const V& a, const V& b) {
  if (a.size() != b.size()) return a.size() + b.size();
  std::size_t d = 0;
  for (std::size_t k = 0; k < a.size(); ++k) d += std::memcmp(&a[k], &b[k], sizeof(a[k])) != 0 ? 1 : 0;
  return d;
}

template <int D>
void expect_same(const DynamicSolverT<D>& a, const DynamicSolverT<D>& b, const char* what) {
  const auto &P = a.particles(), &Q = b.particles();
  EXPECT_EQ(bit_differences(P.pos, Q.pos), 0u) << what;
  EXPECT_EQ(bit_differences(P.vel, Q.vel), 0u) << what;
  EXPECT_EQ(bit_differences(P.spin, Q.spin), 0u) << what;
  EXPECT_EQ(bit_differences(P.force, Q.force), 0u) << what;
  EXPECT_EQ(bit_differences(P.torque, Q.torque), 0u) << what;
  const auto sa = a.contact_stress(), sb = b.contact_stress();
  EXPECT_EQ(std::memcmp(&sa, &sb, sizeof(sa)), 0) << what << ": contact stress";
  const Energies ea = a.energies(), eb = b.energies();
  EXPECT_EQ(ea.elastic, eb.elastic) << what;
  EXPECT_EQ(ea.kinetic, eb.kinetic) << what;
  for (int w = 0; w < 2 * D; ++w) EXPECT_EQ(a.wall_force(w), b.wall_force(w)) << what << ": wall " << w;
  for (int ax = 0; ax < D; ++ax) EXPECT_EQ(a.wall_velocity(ax), b.wall_velocity(ax)) << what;
  EXPECT_EQ(a.rebuilds(), b.rebuilds()) << what;
}

// Runs `make(threads)` for `steps` steps on 1, 2 and 3 threads and compares the states; the scene
// must take the threaded path (rows and particles above the thresholds) and must move.
template <class Make>
void same_on_threads(Make make, std::size_t steps, const char* what) {
  const auto t0 = std::chrono::steady_clock::now();
  auto one = make(1);
  EXPECT_EQ(one.threads_used(), 1);
  ASSERT_GE(one.table_size(), 4096u) << what << ": too few rows for the threaded path";
  ASSERT_GE(one.particles().size(), 2048u) << what;
  const auto start = one.particles().pos;
  one.run(steps);
  const auto t1 = std::chrono::steady_clock::now();
  std::printf("  1 thread: %.3f s\n", std::chrono::duration<double>(t1 - t0).count());
  double moved = 0.0;
  for (std::size_t k = 0; k < start.size(); ++k) moved = std::fmax(moved, std::fabs(one.particles().pos[k] - start[k]));
  EXPECT_GT(moved, 0.0) << what;
  const auto sc = one.contact_stress();
  double trace = 0.0;
  if constexpr (requires { sc.xx; })
    trace = sc.xx + sc.yy;
  else
    trace = sc.s[0][0] + sc.s[1][1] + sc.s[2][2];
  EXPECT_GT(std::fabs(trace), 0.0) << what << ": no contact force";
  for (int t : {2, 3}) {
    const auto s0 = std::chrono::steady_clock::now();
    auto other = make(t);
    other.run(steps);
    std::printf("  %d threads: %.3f s (wall clock, not a test)\n", t,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - s0).count());
    EXPECT_EQ(other.threads_used(), t) << what << ": the pair loop's team";
    expect_same(one, other, what);
  }
  std::printf("  %s: %zu particles, %zu rows, %zu steps, %zu table builds, largest displacement %.3g\n", what,
              one.particles().size(), one.table_size(), steps, one.rebuilds(), moved);
}

// side^D particles on a jittered square (cubic) lattice of pitch 1.98 a0, radii a0 (1 +- 0.05),
// random velocities of scale v.
template <int D>
ParticlesT<D> lattice(int side, double a0, double v, double rho, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticlesT<D> P;
  const double pitch = 1.98 * a0;
  const int sz = D == 3 ? side : 1;
  for (int c = 0; c < sz; ++c)
    for (int b = 0; b < side; ++b)
      for (int a = 0; a < side; ++a) {
        const double r = a0 * (1.0 + 0.05 * u(rng));
        const double vx = v * u(rng), vy = v * u(rng), vz = v * u(rng);
        const double x = (a + 0.5) * pitch + 0.01 * a0 * u(rng), y = (b + 0.5) * pitch + 0.01 * a0 * u(rng);
        if constexpr (D == 2) {
          P.add_disk(x, y, r, rho, vx, vy);
        } else {
          const double z = (c + 0.5) * pitch + 0.01 * a0 * u(rng);
          P.add_sphere(x, y, z, r, rho, {vx, vy, vz});
        }
      }
  return P;
}

}  // namespace

// 2D, the full Luding law (Table 1 at 80 deg C), stress-controlled right and top walls, gravity.
TEST(DemThreads, FullLawWalls2D) {
  const LudingParams p;
  const int side = 52;
  auto make = [&](int threads) {
    Box box;
    box.x_max = box.y_max = side * 1.98 * p.a0;
    for (MovingWall* w : {&box.right, &box.top}) {
      w->mode = WallMode::Stress;
      w->pressure = 50.0;
    }
    DynamicOptions o;
    o.model = ContactModel::Full;
    o.gravity_x = -0.0;  // (a -0 component: no force accumulator may start at -0, solver_setup.cpp)
    o.gravity_y = -9.81;
    o.threads = threads;
    ParticlesT<2> P;
    const ParticlesT<2> L = lattice<2>(side, p.a0, 0.05, p.rho_p, 3);
    for (std::size_t i = 0; i < L.size(); ++i)
      P.add(L.pos[2 * i], L.pos[2 * i + 1], L.r[i], p, L.vel[2 * i], L.vel[2 * i + 1]);
    return DynamicSolverT<2>(std::move(P), p, box, o);
  };
  same_on_threads(make, steps(), "2D full law, walls");
}

// 3D, the linear law, six walls (the three at the maxima stress-controlled).
TEST(DemThreads, LinearLawWalls3D) {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  const int side = 13;
  auto make = [&](int threads) {
    Box box;
    box.x_max = box.y_max = box.z_max = side * 1.98 * p.a0;
    for (MovingWall* w : {&box.right, &box.back, &box.top}) {
      w->mode = WallMode::Stress;
      w->pressure = 1e4;
    }
    DynamicOptions o;
    o.model = ContactModel::Linear;
    o.threads = threads;
    return DynamicSolverT<3>(lattice<3>(side, p.a0, 0.05, 2000.0, 5), p, box, o);
  };
  same_on_threads(make, steps(), "3D linear law, walls");
}

// The plastic-indentation law (friction 0.3) in a periodic cell under hydrostatic compaction.
template <int D>
void periodic_plastic(int side, const char* what) {
  auto make = [&](int threads) {
    ParticlesT<D> P = lattice<D>(side, 1.0, 0.02, 1.0, 9);
    const double Lc = side * 1.98;
    packing::PeriodicCellT<D> cell;
    cell.h = Lc * Eigen::Matrix<double, D, D>::Identity();
    DynamicOptions o;
    o.model = ContactModel::PlasticIndentation;
    o.plastic.sigma_y = 2.0;
    o.plastic.mu = 0.3;
    o.plastic.damping_n = o.plastic.damping_t = 0.5;
    o.threads = threads;
    DynamicSolverT<D> s(std::move(P), o.plastic, cell, o);
    if constexpr (D == 2)
      s.set_strain_rate(-0.02, -0.02, 0.0);
    else
      s.set_strain_rate3(-0.02, -0.02, -0.02);
    s.set_affine_velocities();
    return s;
  };
  same_on_threads(make, steps(), what);
}

TEST(DemThreads, PlasticLawPeriodic2D) { periodic_plastic<2>(52, "2D plastic law, periodic"); }
TEST(DemThreads, PlasticLawPeriodic3D) { periodic_plastic<3>(13, "3D plastic law, periodic"); }

// The option's range.
TEST(DemThreads, RefusesAbsurdThreadCounts) {
  DynamicOptions o;
  for (int t : {0, -1, 257}) {
    o.threads = t;
    EXPECT_THROW(o.validate(), std::invalid_argument) << t;
  }
  o.threads = 2;
  EXPECT_NO_THROW(o.validate());
}
