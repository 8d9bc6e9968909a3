// The packing parts of the green-body route (docs/packing.md "The green-body route"): the random
// cloud of spheres (random_fill_3d) and the homogeneity measures (laminar.hpp: Eq 48 of Ivannikov
// et al., the sampled bulk density, the overlap statistics), against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/packing/laminar.hpp"
#include "netdem/packing/random_fill.hpp"

using namespace netdem::packing;

namespace {

constexpr double kPi = std::numbers::pi;

Packing one_sphere(double x, double y, double z, double r, const Box& b) {
  Packing p;
  p.dim = 3;
  p.x = {x};
  p.y = {y};
  p.z = {z};
  p.r = {r};
  p.box = b;
  return p;
}

/// n^3 spheres of radius a/2 on the simple cubic lattice of pitch a in the box [0, n a]^3.
Packing cubic_lattice(int n, double a) {
  Packing p;
  p.dim = 3;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        p.x.push_back((i + 0.5) * a);
        p.y.push_back((j + 0.5) * a);
        p.z.push_back((k + 0.5) * a);
        p.r.push_back(0.5 * a);
      }
  p.box = Box{0, 0, n * a, n * a, 0, n * a};
  return p;
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// The cloud: no two spheres overlap (all pairs), every sphere lies inside the box, radii in the
// band, the documented draw of the radii, deterministic for a seed and different for another.
TEST(RandomFill3d, NonOverlappingInsideDeterministic) {
  RandomFill3dOptions o;
  o.n = 400;
  o.mean_radius = 25e-6;
  o.dispersion = 0.1;
  o.box = Box{0, 0, 4e-4, 4e-4, 0, 1e-3};
  o.seed = 7;
  const Packing p = random_fill_3d(o);
  ASSERT_EQ(p.size(), o.n);
  EXPECT_EQ(p.dim, 3);
  EXPECT_EQ(p.seed, 7u);
  double worst = 1.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_GE(p.r[i], 0.9 * o.mean_radius * (1 - 1e-12));
    EXPECT_LE(p.r[i], 1.1 * o.mean_radius * (1 + 1e-12));
    EXPECT_GE(p.x[i] - p.r[i], 0.0);
    EXPECT_LE(p.x[i] + p.r[i], 4e-4);
    EXPECT_GE(p.y[i] - p.r[i], 0.0);
    EXPECT_LE(p.y[i] + p.r[i], 4e-4);
    EXPECT_GE(p.z[i] - p.r[i], 0.0);
    EXPECT_LE(p.z[i] + p.r[i], 1e-3);
    for (std::size_t j = 0; j < i; ++j) {
      const double d = std::sqrt((p.x[i] - p.x[j]) * (p.x[i] - p.x[j]) + (p.y[i] - p.y[j]) * (p.y[i] - p.y[j]) +
                                 (p.z[i] - p.z[j]) * (p.z[i] - p.z[j]));
      worst = std::min(worst, d / (p.r[i] + p.r[j]));
    }
  }
  EXPECT_GE(worst, 1.0);
  validate(p);
  // the radii are drawn first: r_0 from the first draw of the generator
  std::mt19937_64 rng(7);
  EXPECT_EQ(p.r[0], o.mean_radius * (1.0 + o.dispersion * (2.0 * uniform01(rng) - 1.0)));
  const Packing q = random_fill_3d(o);
  EXPECT_EQ(p.x, q.x);
  EXPECT_EQ(p.z, q.z);
  EXPECT_EQ(p.r, q.r);
  o.seed = 8;
  EXPECT_NE(random_fill_3d(o).x, p.x);
}

TEST(RandomFill3d, RefusesWithOneLine) {
  RandomFill3dOptions o;
  o.n = 805;
  o.box = Box{0, 0, 5e-4, 5e-4, 0, 4e-4};  // the paper's box: 0.53 full, no cloud fits
  const std::string full = error_of([&] { random_fill_3d(o); });
  EXPECT_NE(full.find("above the 0.3 a random cloud can hold"), std::string::npos) << full;
  EXPECT_EQ(full.find('\n'), std::string::npos);
  o.box = Box{0, 0, 4e-5, 1e-2, 0, 1e-2};
  EXPECT_NE(error_of([&] { random_fill_3d(o); }).find("does not fit"), std::string::npos);
  o.box = Box{0, 0, 1e-3, 1e-3, 0, 1e-3};
  o.dispersion = 1.0;
  EXPECT_NE(error_of([&] { random_fill_3d(o); }).find("dispersion must be in [0, 1)"), std::string::npos);
  o.dispersion = 0.1;
  o.n = 0;
  EXPECT_NE(error_of([&] { random_fill_3d(o); }).find("number of spheres"), std::string::npos);
  o.n = 805;
  o.box = Box{0, 0, 1e-3, 1e-3, 0, 0.0};
  EXPECT_NE(error_of([&] { random_fill_3d(o); }).find("positive extents"), std::string::npos);
  // a cloud just below the limit with a single attempt per sphere cannot be placed
  o.box = Box{0, 0, 1e-3, 1e-3, 0, 1.9e-4};  // fraction 0.28
  o.max_attempts = 1;
  const std::string stuck = error_of([&] { random_fill_3d(o); });
  EXPECT_NE(stuck.find("could not place sphere"), std::string::npos) << stuck;
}

// The spherical-cap integral: the segments of one sphere over adjacent slabs sum to its volume, a
// cut through the centre leaves 2/3 pi r^3 on each side, a cap of height h is pi h^2 (3r - h) / 3.
TEST(Laminar, SphereSegmentsClosedForms) {
  const double r = 1.3, c = 0.4;
  EXPECT_NEAR(sphere_slab_volume(c, r, c - 2 * r, c), 2.0 / 3.0 * kPi * r * r * r, 1e-14);
  EXPECT_NEAR(sphere_slab_volume(c, r, c, c + 5 * r), 2.0 / 3.0 * kPi * r * r * r, 1e-14);
  for (double h : {0.01, 0.3, 1.0, 2.0})
    EXPECT_NEAR(sphere_slab_volume(c, r, c + r - h, c + r), kPi * h * h * (3 * r - h) / 3.0, 1e-13);
  double sum = 0.0;
  for (double a = -3.0; a < 3.0; a += 0.137) sum += sphere_slab_volume(c, r, a, a + 0.137);
  EXPECT_NEAR(sum, 4.0 / 3.0 * kPi * r * r * r, 1e-13);
  EXPECT_EQ(sphere_slab_volume(c, r, 5.0, 6.0), 0.0);
}

// Eq 48 on one sphere: sum of density x lamina volume = the sphere's volume along each axis;
// centred in a box cut into two laminae, each holds 2/3 pi r^3.
TEST(Laminar, SingleSphereSumsToItsVolume) {
  const Box b{0, 0, 3.0, 2.0, 0, 2.5};
  const Packing p = one_sphere(1.1, 0.9, 1.3, 0.7, b);
  const double v = 4.0 / 3.0 * kPi * 0.7 * 0.7 * 0.7;
  for (int axis = 0; axis < 3; ++axis) {
    const LaminarProfile prof = laminar_density(p, axis, 0.23);
    const double L = axis == 0 ? 3.0 : axis == 1 ? 2.0 : 2.5;
    EXPECT_NEAR(prof.width, L / std::round(L / 0.23), 1e-15);
    double s = 0.0;
    for (std::size_t k = 0; k < prof.density.size(); ++k)
      s += prof.density[k] * (prof.hi[k] - prof.lo[k]) * b.volume() / L;
    EXPECT_NEAR(s, v, 1e-13) << "axis " << axis;
  }
  const Packing q = one_sphere(1.0, 1.0, 1.0, 0.7, Box{0, 0, 2.0, 2.0, 0, 2.0});
  const LaminarProfile halves = laminar_density(q, 2, 1.0);
  ASSERT_EQ(halves.density.size(), 2u);
  for (double d : halves.density) EXPECT_NEAR(d * 4.0, 2.0 / 3.0 * kPi * 0.343, 1e-14);  // lamina volume 4
}

// A simple cubic lattice of touching spheres: every lamina of one pitch or of half a pitch
// (aligned with the box) holds pi/6, the lattice's density.
TEST(Laminar, CubicLatticeHoldsPiOverSix) {
  const Packing p = cubic_lattice(5, 2.0);
  for (int axis = 0; axis < 3; ++axis)
    for (double q : {2.0, 1.0}) {
      const LaminarProfile prof = laminar_density(p, axis, q);
      for (double d : prof.density) EXPECT_NEAR(d, kPi / 6.0, 1e-13) << "axis " << axis << " q " << q;
    }
}

// Mirror x -> x_min + x_max - x reverses the profile along x and keeps y and z; a translation of
// the packing with its box changes nothing.
TEST(Laminar, MirrorAndTranslationInvariant) {
  RandomFill3dOptions o;
  o.n = 150;
  o.mean_radius = 1.0;
  o.box = Box{0, 0, 14, 12, 0, 16};
  o.seed = 3;
  const Packing p = random_fill_3d(o);
  Packing m = p, t = p;
  for (std::size_t i = 0; i < p.size(); ++i) {
    m.x[i] = 14.0 - p.x[i];
    t.x[i] += 3.25;
    t.y[i] -= 7.5;
    t.z[i] += 0.125;
  }
  t.box = Box{3.25, -7.5, 17.25, 4.5, 0.125, 16.125};
  for (int axis = 0; axis < 3; ++axis) {
    const LaminarProfile a = laminar_density(p, axis, 1.0), b = laminar_density(m, axis, 1.0),
                         c = laminar_density(t, axis, 1.0);
    ASSERT_EQ(a.density.size(), b.density.size());
    const std::size_t n = a.density.size();
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_NEAR(a.density[k], axis == 0 ? b.density[n - 1 - k] : b.density[k], 1e-12);
      EXPECT_NEAR(a.density[k], c.density[k], 1e-12);
    }
  }
  // the interior range: laminae at least the margin from both faces
  const LaminarProfile a = laminar_density(p, 2, 1.0);
  const auto in = a.interior(0.0, 16.0, 2.0);
  EXPECT_EQ(in.count, 12u);
  EXPECT_LE(in.min, in.mean);
  EXPECT_LE(in.mean, in.max);
}

TEST(Laminar, RefusesBadInput) {
  const Packing p = one_sphere(1, 1, 1, 0.5, Box{0, 0, 2, 2, 0, 2});
  EXPECT_NE(error_of([&] { laminar_density(p, 3, 1.0); }).find("axis must be 0, 1 or 2"), std::string::npos);
  EXPECT_NE(error_of([&] { laminar_density(p, 0, 0.0); }).find("q_s must be positive"), std::string::npos);
  EXPECT_NE(error_of([&] { laminar_density(p, 0, 1e-9); }).find("more than 1e6 laminae"), std::string::npos);
  Packing q = p;
  q.dim = 2;
  q.z.clear();
  EXPECT_NE(error_of([&] { laminar_density(q, 0, 1.0); }).find("needs a 3D packing"), std::string::npos);
  EXPECT_NE(error_of([&] { sampled_density(p, Box{0, 0, 2, 2, 0, 2}, 0.0); }).find("spacing"), std::string::npos);
}

// The sampled density: one sphere in a box within the lattice error (asserted (h / r)^2; a centre
// on a symmetry point of the lattice errs most: 0.46 % at h = r / 25), the cubic lattice pi/6, and overlapping spheres counted once
// (the union: two equal spheres at distance d hold 2 V - lens).
TEST(Sampled, ClosedForms) {
  const double r = 1.0;
  const Box b{-1.5, -1.5, 1.5, 1.5, -1.5, 1.5};
  const Packing p = one_sphere(0.0123, -0.031, 0.047, r, b);
  const double exact = 4.0 / 3.0 * kPi / 27.0;
  for (double h : {0.2, 0.1, 0.05}) {
    const double s = sampled_density(p, b, h * r);
    EXPECT_NEAR(s / exact, 1.0, h * h) << "h " << h;
  }
  const Packing lat = cubic_lattice(4, 2.0);
  // three lattice periods per axis, the lattice of points shifted off the centres (aligned: 0.528)
  EXPECT_NEAR(sampled_density(lat, Box{1.0371, 1.0213, 7.0371, 7.0213, 1.0111, 7.0111}, 0.1), kPi / 6.0, 2e-3);
  // (centres off the lattice's symmetry points: a centre on one resonates, up to 0.46 % at h = r / 25)
  Packing two = one_sphere(0.0123, -0.031, 0.047, r, Box{-2, -2, 3, 2, -2, 2});
  two.x.push_back(1.0123);
  two.y.push_back(-0.031);
  two.z.push_back(0.047);
  two.r.push_back(r);
  const double d = 1.0, lens = kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
  const double uni = 2 * 4.0 / 3.0 * kPi - lens;
  EXPECT_NEAR(sampled_density(two, two.box, 0.04) * two.box.volume() / uni, 1.0, 2e-3);
  const OverlapStats ov = overlap_stats(two);
  EXPECT_EQ(ov.pairs, 1u);
  EXPECT_NEAR(ov.pair_mean, 1.0, 1e-15);  // overlap 1 over the pair's mean radius 1
  EXPECT_NEAR(ov.lens_volume, lens, 1e-13);
  EXPECT_NEAR(ov.coordination, 1.0, 1e-15);
}

// Overlaps with the box faces and the bounding box.
TEST(Sampled, WallOverlapsAndBoundingBox) {
  Packing p = one_sphere(0.9, 1.0, 1.0, 1.0, Box{0, 0, 3, 2, 0, 2});  // pokes 0.1 through x_min, touches y_min/y_max/z
  const OverlapStats ov = overlap_stats(p);
  EXPECT_EQ(ov.pairs, 0u);
  EXPECT_EQ(ov.wall_contacts, 1u);  // exact touches (d = 0) do not count
  EXPECT_NEAR(ov.wall_max, 0.1, 1e-15);
  const Box bb = bounding_box(p);
  EXPECT_NEAR(bb.x_min, -0.1, 1e-15);
  EXPECT_NEAR(bb.x_max, 1.9, 1e-15);
  EXPECT_NEAR(bb.z_max, 2.0, 1e-15);
}
