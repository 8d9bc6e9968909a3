// 3D ballistic deposition (issue 16; ballistic3d.hpp, docs/packing.md "3D ballistic deposition"),
// the 3D packing queries and the 3D file format. The rest check is independent of the
// implementation: for every sphere, only the spheres deposited before it, the floor and the walls
// are obstacles, and -g must lie in the cone of its contact normals (a non-negative combination).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "netdem/packing/ballistic3d.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"

namespace {

using netdem::packing::Deposition3dOptions;
using netdem::packing::Deposition3dReport;
using netdem::packing::Lateral;
using netdem::packing::Packing;
using V = std::array<double, 3>;

double dot(const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// Minimum-image separation of spheres i and j (periodic in x, y) or the plain one.
V separation(const Packing& p, std::size_t i, std::size_t j, bool periodic) {
  V d{p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j]};
  if (periodic) {
    const double w = p.box.width(), h = p.box.height();
    d[0] -= w * std::round(d[0] / w);
    d[1] -= h * std::round(d[1] / h);
  }
  return d;
}

/// Solves the n x n system (n <= 3) by Cramer / elimination; false if singular.
bool solve(int n, const double (&A)[3][3], const double (&b)[3], double (&x)[3]) {
  double M[3][4];
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) M[i][j] = A[i][j];
    M[i][n] = b[i];
  }
  for (int c = 0; c < n; ++c) {
    int piv = c;
    for (int i = c + 1; i < n; ++i)
      if (std::fabs(M[i][c]) > std::fabs(M[piv][c])) piv = i;
    if (std::fabs(M[piv][c]) < 1e-10) return false;
    for (int j = 0; j <= n; ++j) std::swap(M[c][j], M[piv][j]);
    for (int i = 0; i < n; ++i)
      if (i != c) {
        const double f = M[i][c] / M[c][c];
        for (int j = 0; j <= n; ++j) M[i][j] -= f * M[c][j];
      }
  }
  for (int i = 0; i < n; ++i) x[i] = M[i][n] / M[i][i];
  return true;
}

/// True if (0, 0, 1) is a non-negative combination of one, two or three of the normals (within
/// 1e-9 on the weights, 1e-7 on the residual).
bool up_in_cone(const std::vector<V>& ns) {
  const V up{0, 0, 1};
  const std::size_t m = ns.size();
  for (std::size_t a = 0; a < m; ++a)
    if (std::fabs(ns[a][0]) < 1e-7 && std::fabs(ns[a][1]) < 1e-7 && ns[a][2] > 0) return true;
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b) {  // least squares in span(n_a, n_b)
      const double A[3][3] = {{dot(ns[a], ns[a]), dot(ns[a], ns[b]), 0}, {dot(ns[a], ns[b]), dot(ns[b], ns[b]), 0}, {0, 0, 0}};
      const double rhs[3] = {ns[a][2], ns[b][2], 0};
      double l[3];
      if (!solve(2, A, rhs, l) || l[0] < -1e-9 || l[1] < -1e-9) continue;
      V r{};
      for (int k = 0; k < 3; ++k) r[static_cast<std::size_t>(k)] = l[0] * ns[a][static_cast<std::size_t>(k)] + l[1] * ns[b][static_cast<std::size_t>(k)] - up[static_cast<std::size_t>(k)];
      if (std::sqrt(dot(r, r)) < 1e-7) return true;
    }
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b)
      for (std::size_t c = b + 1; c < m; ++c) {
        const double A[3][3] = {{ns[a][0], ns[b][0], ns[c][0]}, {ns[a][1], ns[b][1], ns[c][1]}, {ns[a][2], ns[b][2], ns[c][2]}};
        const double rhs[3] = {0, 0, 1};
        double l[3];
        if (solve(3, A, rhs, l) && l[0] >= -1e-9 && l[1] >= -1e-9 && l[2] >= -1e-9) return true;
      }
  return false;
}

/// The independent checks of every deposited sphere; returns the largest relative overlap.
double check_every_sphere_rests(const Packing& p, bool periodic) {
  const double W = p.box.width();
  double worst = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i];
    // inside the box (walls: entirely; periodic: the centre in the period, the sphere below the lid)
    if (periodic) {
      EXPECT_TRUE(p.x[i] >= 0 && p.x[i] < W && p.y[i] >= 0 && p.y[i] < W) << "sphere " << i;
    } else {
      EXPECT_TRUE(p.x[i] - r >= -1e-9 * r && p.x[i] + r <= W + 1e-9 * r && p.y[i] - r >= -1e-9 * r &&
                  p.y[i] + r <= W + 1e-9 * r)
          << "sphere " << i << " pokes through a side wall";
    }
    EXPECT_GE(p.z[i] - r, -1e-9 * r) << "sphere " << i << " below the floor";
    EXPECT_LE(p.z[i] + r, p.box.z_max + 1e-9 * r) << "sphere " << i << " above the lid";
    std::vector<V> ns;
    bool floor = p.z[i] - r <= 1e-9 * r;
    for (std::size_t j = 0; j < p.size(); ++j) {
      if (j == i) continue;
      const V d = separation(p, i, j, periodic);
      const double dist = std::sqrt(dot(d, d)), s = r + p.r[j];
      worst = std::max(worst, (s - dist) / s);
      if (j < i && dist <= s * (1 + 1e-9)) ns.push_back({d[0] / dist, d[1] / dist, d[2] / dist});
    }
    if (!periodic) {
      if (p.x[i] - r <= 1e-9 * r) ns.push_back({1, 0, 0});
      if (W - p.x[i] - r <= 1e-9 * r) ns.push_back({-1, 0, 0});
      if (p.y[i] - r <= 1e-9 * r) ns.push_back({0, 1, 0});
      if (W - p.y[i] - r <= 1e-9 * r) ns.push_back({0, -1, 0});
    }
    EXPECT_TRUE(floor || up_in_cone(ns)) << "sphere " << i << " at (" << p.x[i] << ", " << p.y[i] << ", " << p.z[i]
                                         << ") with " << ns.size() << " contacts is not held against gravity";
  }
  return worst;
}

/// Exact volume of a sphere (centre height zc, radius r) between z = a and z = b.
double slab_volume(double zc, double r, double a, double b) {
  auto below = [&](double h) {  // volume of the sphere below z = zc + h
    h = std::clamp(h, -r, r);
    return std::numbers::pi * (r * r * (h + r) - (h * h * h + r * r * r) / 3.0);
  };
  return std::max(0.0, below(b - zc) - below(a - zc));
}

/// Bulk density (slab z in [a, b], whole x-y period) and bulk coordination (spheres with centre
/// in the slab and, for walls, at least `margin` from every side wall) of a deposit.
struct Bulk {
  double density = 0, coordination = 0;
  std::size_t spheres = 0;
};
Bulk bulk(const Packing& p, bool periodic, double a, double b, double margin) {
  Bulk out;
  const double W = p.box.width();
  double v = 0;
  for (std::size_t i = 0; i < p.size(); ++i) v += slab_volume(p.z[i], p.r[i], a, b);
  out.density = v / (W * W * (b - a));
  const auto pairs = periodic ? netdem::packing::touching_pairs_periodic_xy(p, 1e-9) : netdem::packing::touching_pairs(p, 1e-9);
  std::vector<int> deg(p.size(), 0);
  for (auto [i, j] : pairs) ++deg[static_cast<std::size_t>(i)], ++deg[static_cast<std::size_t>(j)];
  long sum = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.z[i] < a || p.z[i] > b) continue;
    if (!periodic && (p.x[i] < margin || p.x[i] > W - margin || p.y[i] < margin || p.y[i] > W - margin)) continue;
    sum += deg[i];
    ++out.spheres;
  }
  out.coordination = out.spheres ? static_cast<double>(sum) / static_cast<double>(out.spheres) : 0.0;
  return out;
}

Deposition3dOptions opts(double w, std::uint64_t seed, Lateral lat, double rmin = 0.9, double rmax = 1.1) {
  Deposition3dOptions o;
  o.width = w;
  o.seed = seed;
  o.lateral = lat;
  o.r_min = rmin;
  o.r_max = rmax;
  return o;
}

Packing base_box(double w, double h) {
  Packing b;
  b.dim = 3;
  b.box = {0, 0, w, w, 0, h};
  return b;
}
void add(Packing& p, double x, double y, double z, double r) {
  p.x.push_back(x), p.y.push_back(y), p.z.push_back(z), p.r.push_back(r);
}

}  // namespace

TEST(Ballistic3d, EverySphereRestsNoOverlapInsideBox) {
  struct Case {
    double w;
    Lateral lat;
    double rmin, rmax;
    std::uint64_t seed;
  };
  for (const Case& c : {Case{10, Lateral::Walls, 0.9, 1.1, 1}, Case{10, Lateral::Periodic, 0.9, 1.1, 2},
                        Case{8, Lateral::Walls, 1.0, 1.0, 3}, Case{8, Lateral::Periodic, 1.0, 1.0, 4},
                        Case{9, Lateral::Walls, 0.5, 1.5, 5}, Case{6, Lateral::Periodic, 0.5, 1.5, 6}}) {
    SCOPED_TRACE(testing::Message() << "W " << c.w << (c.lat == Lateral::Periodic ? " periodic" : " walls") << " r ["
                                    << c.rmin << ", " << c.rmax << "] seed " << c.seed);
    Deposition3dReport rep;
    const Packing p = netdem::packing::ballistic_deposition_3d(opts(c.w, c.seed, c.lat, c.rmin, c.rmax), &rep);
    ASSERT_EQ(p.dim, 3);
    ASSERT_GT(p.size(), 20u);
    EXPECT_NO_THROW(netdem::packing::validate(p));
    EXPECT_LE(check_every_sphere_rests(p, c.lat == Lateral::Periodic), 1e-9);
    EXPECT_EQ(rep.unresolved, 0u);
    EXPECT_EQ(rep.floor + rep.three + rep.two, p.size());
  }
}

TEST(Ballistic3d, DeterministicForSeedAndSensitiveToIt) {
  const auto o = opts(8, 11, Lateral::Periodic);
  const Packing a = netdem::packing::ballistic_deposition_3d(o), b = netdem::packing::ballistic_deposition_3d(o);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.z, b.z);
  EXPECT_EQ(a.r, b.r);
  auto o2 = o;
  o2.seed = 12;
  EXPECT_NE(netdem::packing::ballistic_deposition_3d(o2).x, a.x);
}

TEST(Ballistic3d, DocumentedDrawOrder) {
  // the first sphere falls freely onto the floor at its drop point: r, then x, then y
  const auto o = opts(10, 5, Lateral::Walls);
  const Packing p = netdem::packing::ballistic_deposition_3d(o);
  std::mt19937_64 rng(5);
  auto u = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  const double r = 0.9 + 0.2 * u(), x = r + (10 - 2 * r) * u(), y = r + (10 - 2 * r) * u();
  EXPECT_EQ(p.r[0], r);
  EXPECT_EQ(p.x[0], x);
  EXPECT_EQ(p.y[0], y);
  EXPECT_EQ(p.z[0], r);
  // periodic: x = W U
  const Packing q = netdem::packing::ballistic_deposition_3d(opts(10, 5, Lateral::Periodic));
  std::mt19937_64 rng2(5);
  auto u2 = [&] { return static_cast<double>(rng2() >> 11) * 0x1.0p-53; };
  const double r2 = 0.9 + 0.2 * u2(), x2 = 10 * u2(), y2 = 10 * u2();
  EXPECT_EQ(q.r[0], r2);
  EXPECT_EQ(q.x[0], x2);
  EXPECT_EQ(q.y[0], y2);
}

TEST(Ballistic3d, TetrahedronOnThreeTouchingSpheres) {
  // three equal touching spheres on the floor (an equilateral triangle of side 2r); a fourth of the
  // same radius dropped anywhere over the triangle rests at the apex of a regular tetrahedron,
  // z = r + 2 r sqrt(2/3), above the triangle's centroid
  const double r = 1.0, cx = 5, cy = 5;
  Packing b = base_box(10, 10);
  const double rc = 2 * r / std::sqrt(3.0);  // circumradius of the triangle
  for (int k = 0; k < 3; ++k) {
    const double a = 2 * std::numbers::pi * k / 3 + 0.3;
    add(b, cx + rc * std::cos(a), cy + rc * std::sin(a), r, r);
  }
  const double z_apex = r + 2 * r * std::sqrt(2.0 / 3.0);
  for (auto [dx, dy] : {std::pair{0.0, 0.0}, {0.2, 0.1}, {-0.3, 0.25}, {0.05, -0.4}, {0.5, 0.3}}) {
    const auto c = netdem::packing::drop_sphere(b, cx + dx, cy + dy, r, Lateral::Walls);
    EXPECT_NEAR(c[2], z_apex, 1e-12) << "drop offset " << dx << ", " << dy;
    EXPECT_NEAR(c[0], cx, 1e-12);
    EXPECT_NEAR(c[1], cy, 1e-12);
  }
  // a smaller sphere (r/2) sits lower: distance 1.5 r to each centre, z = r + sqrt(2.25 - rc^2) r
  const auto s = netdem::packing::drop_sphere(b, cx + 0.1, cy, 0.5 * r, Lateral::Walls);
  EXPECT_NEAR(s[2], r + std::sqrt(2.25 * r * r - rc * rc), 1e-12);
}

TEST(Ballistic3d, RollsOffOneSphereOntoTheFloor) {
  // one sphere of radius 1 on the floor at (5, 5); a sphere of radius 1 dropped 0.3 off its axis
  // rolls down the meridian in the drop direction, falls off at the equator and lands on the
  // floor touching it: centre at z = 1, horizontal distance 2, on the same ray from the axis
  Packing b = base_box(10, 10);
  add(b, 5, 5, 1, 1);
  const double ang = 0.7;
  const auto c = netdem::packing::drop_sphere(b, 5 + 0.3 * std::cos(ang), 5 + 0.3 * std::sin(ang), 1.0, Lateral::Walls);
  EXPECT_NEAR(c[2], 1.0, 1e-12);
  EXPECT_NEAR(std::hypot(c[0] - 5, c[1] - 5), 2.0, 1e-12);
  EXPECT_NEAR(std::atan2(c[1] - 5, c[0] - 5), ang, 1e-12);
  // on two touching spheres: rolls along the groove circle and then off it (both lift off at the
  // height of their centres) and lands on the floor beside the pair
  Packing b2 = base_box(10, 10);
  add(b2, 4, 5, 1, 1);
  add(b2, 6, 5, 1, 1);
  const auto g = netdem::packing::drop_sphere(b2, 5.0, 5.4, 1.0, Lateral::Walls);
  EXPECT_NEAR(g[2], 1.0, 1e-12);
  EXPECT_NEAR(g[0], 5.0, 1e-12);              // symmetric: stays in the mid plane
  EXPECT_NEAR(g[1], 5.0 + std::sqrt(3.0), 1e-12);  // touching both: distance 2 from (4, 5) and (6, 5)
}

TEST(Ballistic3d, RestsInACornerOnOneSphere) {
  // sphere A (r = 1) on the floor at (a, a) near the corner x = y = 0; a sphere of r = 1 dropped
  // between A's top and the corner rolls off A towards the corner, along the wall it meets first,
  // and rests on A and both walls: centre (1, 1, 1 + sqrt(4 - 2 (a - 1)^2)). (On one sphere and
  // one wall alone no stable rest exists: it rolls along the wall.)
  const double a = 1.8;
  Packing b = base_box(10, 10);
  add(b, a, a, 1, 1);
  const auto c = netdem::packing::drop_sphere(b, 1.3, 1.2, 1.0, Lateral::Walls);
  EXPECT_NEAR(c[0], 1.0, 1e-12);
  EXPECT_NEAR(c[1], 1.0, 1e-12);
  EXPECT_NEAR(c[2], 1.0 + std::sqrt(4.0 - 2 * (a - 1) * (a - 1)), 1e-12);
  // with the wall y = 0 far away (A at y = 5), the sphere rolls along the wall x = 0 and lands on
  // the floor touching A and the wall: x = 1, (y - 5)^2 + 0.64 = 4
  Packing b2 = base_box(10, 10);
  add(b2, a, 5, 1, 1);
  const auto d = netdem::packing::drop_sphere(b2, 1.3, 5.1, 1.0, Lateral::Walls);
  EXPECT_NEAR(d[0], 1.0, 1e-12);
  EXPECT_NEAR(d[2], 1.0, 1e-12);
  EXPECT_NEAR(d[1], 5.0 + std::sqrt(4.0 - (a - 1) * (a - 1)), 1e-12);
}

TEST(Ballistic3d, UnstableTwoSupportEquilibriumRollsOff) {
  // two touching spheres on the floor against the wall x = 0; a third dropped at x = 1 exactly
  // over their contact lands on both with gravity in the plane of the normals (all three centres
  // in the wall's plane): an equilibrium at the top of their circle, unstable. It rolls away from
  // the wall along the circle (centre (1, 5, 1), radius sqrt(3)) down to the floor.
  Packing b = base_box(10, 10);
  add(b, 1, 4, 1, 1);
  add(b, 1, 6, 1, 1);
  const auto c = netdem::packing::drop_sphere(b, 1.0, 5.0, 1.0, Lateral::Walls);
  EXPECT_NEAR(c[0], 1.0 + std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(c[1], 5.0, 1e-12);
  EXPECT_NEAR(c[2], 1.0, 1e-12);
}

TEST(Ballistic3d, PeriodicSupportsAcrossTheBoundary) {
  // three spheres of a touching triangle, two of them stored across x = 0 (at x near W): a sphere
  // dropped near x = 0 over the triangle's centroid finds all three supports across the boundary
  // and rests at the tetrahedron apex, its stored centre wrapped into [0, W)
  const double W = 10, r = 1;
  Packing b = base_box(W, W);
  const double rc = 2 * r / std::sqrt(3.0), cx = 0.1, cy = 5;
  for (int k = 0; k < 3; ++k) {
    const double a = 2 * std::numbers::pi * k / 3;
    double x = cx + rc * std::cos(a);
    x -= W * std::floor(x / W);
    add(b, x, cy + rc * std::sin(a), r, r);
  }
  EXPECT_GT(b.x[1], W / 2);  // stored on the far side
  const auto c = netdem::packing::drop_sphere(b, cx + 0.05, cy - 0.1, r, Lateral::Periodic);
  EXPECT_NEAR(c[2], r + 2 * r * std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_NEAR(c[0], cx, 1e-12);
  // the same drop with walls: no image, the sphere cannot rest there (falls off to the floor)
  const auto w = netdem::packing::drop_sphere(b, 1.0, cy - 0.3, r, Lateral::Walls);
  EXPECT_LT(w[2], r + 2 * r * std::sqrt(2.0 / 3.0) - 0.1);
}

TEST(Ballistic3d, MirrorSymmetry) {
  // drops onto a deposit and onto its mirror image (x -> W - x) at mirrored points end mirrored
  const Packing p = netdem::packing::ballistic_deposition_3d(opts(8, 21, Lateral::Walls));
  Packing m = p;
  const double W = p.box.width();
  for (double& x : m.x) x = W - x;
  std::mt19937_64 rng(3);
  auto u = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  // the base without its top layer, so that drops move a lot
  Packing bp = p, bm = m;
  for (Packing* q : {&bp, &bm}) {
    Packing k;
    k.dim = 3;
    k.box = q->box;
    for (std::size_t i = 0; i < q->size(); ++i)
      if (q->z[i] < 4) add(k, q->x[i], q->y[i], q->z[i], q->r[i]);
    *q = k;
  }
  int n = 0;
  for (int k = 0; k < 30; ++k) {
    const double r = 0.9 + 0.2 * u(), x = r + (W - 2 * r) * u(), y = r + (W - 2 * r) * u();
    const auto a = netdem::packing::drop_sphere(bp, x, y, r, Lateral::Walls);
    const auto b = netdem::packing::drop_sphere(bm, W - x, y, r, Lateral::Walls);
    EXPECT_NEAR(a[0], W - b[0], 1e-9);
    EXPECT_NEAR(a[1], b[1], 1e-9);
    EXPECT_NEAR(a[2], b[2], 1e-9);
    n += std::hypot(a[0] - x, a[1] - y) > 0.1;
  }
  EXPECT_GT(n, 10);  // most drops moved sideways (the check is not trivial)
}

namespace {

/// Means and standard deviations over seeds 1..10 of one case (docs/packing.md table).
struct TenSeeds {
  double n, n_sd, d, d_sd, z, z_sd, bd, bd_sd, bz, bz_sd;
};
TenSeeds ten_seeds(double w, Lateral lat, bool mono, double a, double b, double margin) {
  const bool per = lat == Lateral::Periodic;
  std::vector<double> D, Db, Zb, Z, N;
  for (std::uint64_t s = 1; s <= 10; ++s) {
    const Packing p = netdem::packing::ballistic_deposition_3d(opts(w, s, lat, mono ? 1.0 : 0.9, mono ? 1.0 : 1.1));
    const auto st = netdem::packing::contact_stats(p, 1e-9, per);
    const Bulk bk = bulk(p, per, a, b, margin);
    N.push_back(static_cast<double>(p.size()));
    D.push_back(st.density);
    Z.push_back(st.coordination);
    Db.push_back(bk.density);
    Zb.push_back(bk.coordination);
  }
  auto ms = [](const std::vector<double>& v) {
    double m = 0, q = 0;
    for (double x : v) m += x;
    m /= static_cast<double>(v.size());
    for (double x : v) q += (x - m) * (x - m);
    return std::pair{m, std::sqrt(q / static_cast<double>(v.size() - 1))};
  };
  TenSeeds t{};
  std::tie(t.n, t.n_sd) = ms(N);
  std::tie(t.d, t.d_sd) = ms(D);
  std::tie(t.z, t.z_sd) = ms(Z);
  std::tie(t.bd, t.bd_sd) = ms(Db);
  std::tie(t.bz, t.bz_sd) = ms(Zb);
  std::printf("  W %g %-8s %-10s N %.1f +- %.1f | D (box) %.4f +- %.4f | Z (all) %.3f +- %.3f | bulk D %.4f +- %.4f | "
              "bulk Z %.3f +- %.3f\n",
              w, per ? "periodic" : "walls", mono ? "monosized" : "R[0.9,1.1]", t.n, t.n_sd, t.d, t.d_sd, t.z, t.z_sd, t.bd,
              t.bd_sd, t.bz, t.bz_sd);
  return t;
}

}  // namespace

TEST(Ballistic3d, DensityAndCoordinationOverTenSeeds) {
  // W = 10 R, H = 10 R, r = R[0.9, 1.1]. Bulk: the slab z in [3, 6] R (away from the floor and the
  // loose top layer), whole x-y period; bulk coordination over the spheres with centres in it
  // (walls: at least 2 R from every wall).
  std::printf("  3D ballistic deposition, W = H = 10 R, seeds 1..10\n");
  const TenSeeds per = ten_seeds(10, Lateral::Periodic, false, 3.0, 6.0, 2.0);
  const TenSeeds wal = ten_seeds(10, Lateral::Walls, false, 3.0, 6.0, 2.0);
  // Physics bands: random loose to random close packing brackets the bulk density of a deposit
  // (0.5 .. 0.65); with walls the slab includes the loose layers at the four side walls, so it is
  // no bulk density, only lower. Three supports from below and, in the bulk, as many from above:
  // the mean coordination is 6 up to the few rests on two supports or walls and the finite slab.
  EXPECT_GT(per.bd, 0.50);
  EXPECT_LT(per.bd, 0.65);
  EXPECT_LT(wal.bd, per.bd);
  for (const TenSeeds& t : {per, wal}) {
    EXPECT_GT(t.bz, 5.6);
    EXPECT_LT(t.bz, 6.4);
    EXPECT_LT(t.d, t.bd);  // the box density includes the loose top layer under the lid
  }
}

// The W = 20 rows of the docs/packing.md table (about 1 s Release; run with
// --gtest_also_run_disabled_tests): slab z in [4, 14] R, wall margin 3 R.
TEST(Ballistic3d, DISABLED_DensityAndCoordinationW20) {
  for (bool mono : {false, true})
    for (Lateral lat : {Lateral::Periodic, Lateral::Walls}) {
      const TenSeeds t = ten_seeds(20, lat, mono, 4.0, 14.0, 3.0);
      EXPECT_GT(t.bz, 5.6);
      EXPECT_LT(t.bz, 6.4);
    }
}

TEST(Ballistic3d, TimingAtWidth20) {
  const auto t0 = std::chrono::steady_clock::now();
  const Packing p = netdem::packing::ballistic_deposition_3d(opts(20, 1, Lateral::Periodic));
  const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("  W = 20 R periodic: %zu spheres in %.3f s\n", p.size(), dt);
  EXPECT_GT(p.size(), 900u);
  EXPECT_NO_THROW(netdem::packing::validate(p));
}

TEST(Ballistic3d, OptionsValidation) {
  auto bad = [](Deposition3dOptions o, const std::string& needle) {
    try {
      o.validate();
      ADD_FAILURE() << "accepted; expected " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  auto o = opts(10, 1, Lateral::Walls);
  auto t = o;
  t.width = 1.5;
  bad(t, "width 1.5 is smaller");
  t = o;
  t.lateral = Lateral::Periodic;
  t.width = 4.0;
  bad(t, "periodic width 4");
  t = o;
  t.r_min = 1.2;
  bad(t, "r_min = 1.2 exceeds");
  t = o;
  t.max_rejections = 0;
  bad(t, "max_rejections");
  t = o;
  t.width = std::nan("");
  bad(t, "width must be finite");
  Packing two;
  two.box = {0, 0, 10, 10};
  EXPECT_THROW((void)netdem::packing::drop_sphere(two, 5, 5, 1, Lateral::Walls), std::invalid_argument);
}

TEST(Queries3d, TouchingPairsEqualAllPairsAndValidate) {
  for (bool periodic : {false, true}) {
    const Packing p = netdem::packing::ballistic_deposition_3d(opts(8, 31, periodic ? Lateral::Periodic : Lateral::Walls));
    // (tol = 0 only without images: the minimum-image difference rounds differently from the shifted query)
    for (double tol : periodic ? std::vector<double>{1e-9, 0.05, 0.3} : std::vector<double>{0.0, 1e-9, 0.05, 0.3}) {
      std::vector<std::pair<int, int>> brute;
      for (std::size_t i = 0; i < p.size(); ++i)
        for (std::size_t j = i + 1; j < p.size(); ++j) {
          const V d = separation(p, i, j, periodic);
          const double s = (p.r[i] + p.r[j]) * (1 + tol);
          if (dot(d, d) <= s * s) brute.emplace_back(static_cast<int>(i), static_cast<int>(j));
        }
      const auto got = periodic ? netdem::packing::touching_pairs_periodic_xy(p, tol) : netdem::packing::touching_pairs(p, tol);
      EXPECT_EQ(got, brute) << "tol " << tol << (periodic ? " periodic" : "");
    }
  }
  // periodic contacts across the boundary exist and are counted once
  const Packing q = netdem::packing::ballistic_deposition_3d(opts(8, 31, Lateral::Periodic));
  EXPECT_GT(netdem::packing::touching_pairs_periodic_xy(q, 1e-9).size(), netdem::packing::touching_pairs(q, 1e-9).size());
  EXPECT_THROW((void)netdem::packing::peripheral_layer(q), std::invalid_argument);
  // wall contacts: floor and the four side walls; periodic: the floor only
  Packing w = base_box(5, 5);
  add(w, 1, 1, 1, 1);    // floor, x_min, y_min
  add(w, 4, 2, 2.5, 1);  // x_max
  const auto sw = netdem::packing::contact_stats(w, 1e-9), sp = netdem::packing::contact_stats(w, 1e-9, true);
  EXPECT_EQ(sw.wall_contacts, 4u);
  EXPECT_EQ(sp.wall_contacts, 1u);
  EXPECT_EQ(sw.disk_contacts, 0u);
  EXPECT_EQ(sp.disk_contacts, 0u);  // nearest image: |d|^2 = 2^2 + 1 + 1.5^2 > 2^2
  // density by volume
  Packing one = base_box(2, 2);
  add(one, 1, 1, 1, 1);
  EXPECT_DOUBLE_EQ(one.density(), 4.0 / 3.0 * std::numbers::pi / 8.0);
  // validate: 3D problems named
  auto msg = [](const Packing& p) {
    try {
      netdem::packing::validate(p);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("valid");
  };
  Packing a = base_box(4, 4);
  add(a, 1, 1, 1, 1);
  add(a, 1.5, 1, 1, 1);
  EXPECT_NE(msg(a).find("spheres 0 and 1 are too close"), std::string::npos) << msg(a);
  Packing c = base_box(4, 4);
  add(c, 1, 1, 5, 1);
  EXPECT_NE(msg(c).find("sphere 0 is outside the box"), std::string::npos) << msg(c);
  Packing d = base_box(4, 4);
  add(d, 1, 1, 1, 1);
  d.z.clear();
  EXPECT_NE(msg(d).find("different sizes"), std::string::npos) << msg(d);
  Packing e = base_box(4, 4);
  add(e, 1, 1, 1, 1);
  e.box.z_max = 0;
  EXPECT_NE(msg(e).find("non-positive size"), std::string::npos) << msg(e);
  Packing f;  // 2D with z values
  f.box = {0, 0, 4, 4};
  f.x = {1}, f.y = {1}, f.r = {1}, f.z = {1};
  EXPECT_NE(msg(f).find("2D packing has 1 z"), std::string::npos) << msg(f);
  // two spheres apart in z only (the same x, y) are not a 2D duplicate
  Packing g = base_box(4, 4);
  add(g, 1, 1, 1, 1);
  add(g, 1, 1, 3, 1);
  EXPECT_EQ(msg(g), "valid");
}

TEST(PackingIO3d, RoundTripIsBitwiseAndFormatIsDocumented) {
  Packing p = netdem::packing::ballistic_deposition_3d(opts(8, 41, Lateral::Periodic));
  p.comments.push_back("lateral periodic (x, y)");
  const auto path = std::filesystem::temp_directory_path() / ("netdem_p3d_" + std::to_string(::getpid()) + ".csv");
  netdem::packing::write_packing_csv(p, path);
  const Packing q = netdem::packing::read_packing_csv(path);
  EXPECT_EQ(q.dim, 3);
  EXPECT_EQ(q.x, p.x);
  EXPECT_EQ(q.y, p.y);
  EXPECT_EQ(q.z, p.z);
  EXPECT_EQ(q.r, p.r);
  EXPECT_EQ(q.seed, p.seed);
  EXPECT_EQ(q.comments, p.comments);
  EXPECT_EQ(q.box.z_max, p.box.z_max);
  EXPECT_EQ(q.box.x_max, p.box.x_max);
  std::ifstream in(path);
  std::string l1, l2, l3, l4, l5;
  std::getline(in, l1), std::getline(in, l2), std::getline(in, l3), std::getline(in, l4), std::getline(in, l5);
  EXPECT_EQ(l1, "# box 0 0 0 8 8 8");
  EXPECT_EQ(l2, "# dim 3");
  EXPECT_EQ(l3, "# seed 41");
  EXPECT_EQ(l4, "# lateral periodic (x, y)");
  EXPECT_EQ(l5, "id,x,y,z,r");
  std::filesystem::remove(path);
  // a comment starting with the reserved word dim is refused
  Packing bad = p;
  bad.comments = {"dim 2"};
  EXPECT_THROW(netdem::packing::write_packing_csv(bad, path), std::invalid_argument);
}

TEST(PackingIO3d, MismatchedDimsAreOneLineErrorsNamingTheLine) {
  auto err = [](const std::string& text) {
    std::istringstream in(text);
    try {
      (void)netdem::packing::read_packing_csv(in, "t.csv");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  auto has = [&](const std::string& text, const std::string& needle) {
    const std::string m = err(text);
    EXPECT_NE(m.find(needle), std::string::npos) << "message: " << m;
    EXPECT_EQ(m.find('\n'), std::string::npos);
  };
  // valid 3D file, with the dim line after the box and comments anywhere
  std::istringstream ok("# box 0 0 0 4 4 4\n# dim 3\nid,x,y,z,r\n0,1,1,1,1\n1,3,3,1,1\n");
  const Packing p = netdem::packing::read_packing_csv(ok, "ok.csv");
  EXPECT_EQ(p.dim, 3);
  EXPECT_EQ(p.z, (std::vector<double>{1, 1}));
  has("# box 0 0 4 4\n# dim 3\nid,x,y,z,r\n0,1,1,1,1\n", "t.csv:1: box line has 4 numbers (a 2D box), but line 2 says '# dim 3'");
  has("# box 0 0 0 4 4 4\nid,x,y,r\n0,1,1,1\n", "t.csv:1: box line has 6 numbers (a 3D box), but there is no '# dim 3' line");
  has("# box 0 0 0 4 4 4\n# dim 3\nid,x,y,r\n0,1,1,1\n", "t.csv:3: header 'id,x,y,r' is 2D, but line 2 says '# dim 3'");
  has("# box 0 0 4 4\nid,x,y,z,r\n0,1,1,1,1\n", "t.csv:2: header 'id,x,y,z,r' is 3D, but there is no '# dim 3' line");
  has("# box 0 0 0 4 4 4\nid,x,y,z,r\n# dim 3\n0,1,1,1,1\n", "t.csv:2: header 'id,x,y,z,r' is 3D");
  has("# box 0 0 4 4\nid,x,y,r\n# dim 3\n0,1,1,1\n", "t.csv:3: dim line after the header (line 2)");
  has("# box 0 0 0 4 4 4\n# dim 4\nid,x,y,z,r\n", "t.csv:2: dim line must be '# dim 2' or '# dim 3'");
  has("# box 0 0 0 4 4 4\n# dim 3\n# dim 3\nid,x,y,z,r\n", "t.csv:3: second dim line");
  has("# box 0 0 0 4 4 4\n# dim 3\nid,x,y,z,r\n0,1,1,1\n", "t.csv:4: expected 5 fields (id,x,y,z,r), got 4");
  has("# box 0 0 0 4 4 4\n# dim 3\nid,x,y,z,r\n0,1,1,9,1\n", "t.csv:4: sphere id 0 is outside the box");
  has("# box 0 0 0 4 4 4\n# dim 3\nid,x,y,z,r\n0,1,1,nan,1\n", "t.csv:4: z is nan");
  has("# box 0 0 0 4 4 0\n# dim 3\nid,x,y,z,r\n0,1,1,1,1\n", "t.csv:1: box line: box has non-positive size");
  has("# box 0 0 0 4 4 4\n# dim 3\nid,x,y,z,r\n0,1,1,1,1\n1,1,1,1.5,1\n", "too close");
  has("# box 0 0 4\n", "t.csv:1: box line must be");
}

TEST(PackingIO3d, TwoDimensionalFilesAreWrittenAsBefore) {
  // the 2D writer's bytes are the format of docs/packing.md (no dim line, four-number box,
  // id,x,y,r), and a 2D file reads back as dim 2 with no z
  Packing p;
  p.box = {0, 0, 10, 5};
  p.seed = 3;
  p.x = {1, 4.25}, p.y = {2, 2.5}, p.r = {0.5, 1};
  p.comments = {"note"};
  const auto path = std::filesystem::temp_directory_path() / ("netdem_p2d_" + std::to_string(::getpid()) + ".csv");
  netdem::packing::write_packing_csv(p, path);
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "# box 0 0 10 5\n# seed 3\n# note\nid,x,y,r\n0,1,2,0.5\n1,4.25,2.5,1\n");
  const Packing q = netdem::packing::read_packing_csv(path);
  EXPECT_EQ(q.dim, 2);
  EXPECT_TRUE(q.z.empty());
  EXPECT_EQ(q.box.z_min, 0.0);
  EXPECT_EQ(q.box.z_max, 0.0);
  EXPECT_DOUBLE_EQ(q.density(), std::numbers::pi * (0.25 + 1.0) / 50.0);
  std::filesystem::remove(path);
}

TEST(Queries3d, FindClosePairEqualsAllPairs) {
  // CellGrid3 behind find_close_pair(): the first pair by the documented rule (disks i in order,
  // partners j no larger, ties j < i, the smallest j) with centre distance below r_i, against a
  // brute-force scan, on random polydisperse 3D sets (radius ratios 1 to 20, with and without pairs)
  std::mt19937_64 rng(9);
  auto u = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  int found = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double ratio = 1.0 + 19.0 * u(), L = 5.0 + 20.0 * u();
    const std::size_t n = 2 + static_cast<std::size_t>(200 * u());
    Packing p = base_box(L, L);
    for (std::size_t i = 0; i < n; ++i) add(p, L * u(), L * u(), L * u(), 0.05 * (1.0 + (ratio - 1.0) * u()));
    std::size_t bi = n, bj = n;
    for (std::size_t i = 0; i < n && bi == n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i || p.r[j] > p.r[i] || (p.r[j] == p.r[i] && j > i)) continue;
        const V d = separation(p, i, j, false);
        if (dot(d, d) < p.r[i] * p.r[i]) {
          bi = i, bj = j;
          break;
        }
      }
    const auto c = netdem::packing::find_close_pair(p);
    if (bi == n) {
      EXPECT_FALSE(c.has_value()) << "trial " << trial;
    } else {
      ASSERT_TRUE(c.has_value()) << "trial " << trial;
      EXPECT_EQ(c->i, bi) << "trial " << trial;
      EXPECT_EQ(c->j, bj) << "trial " << trial;
      ++found;
    }
  }
  EXPECT_GT(found, 10);
  EXPECT_LT(found, 60);
}
