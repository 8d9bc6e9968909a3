// Periodic packings (issue 29, item 1): the DEM route's packing is valid and periodic, at the
// reported density, jammed (the backbone's coordination near the isostatic 2D = 4 of frictionless
// disks), with negligible overlaps, at rest, and the same for the same seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "netdem/dynamic/periodic_packing.hpp"
#include "netdem/field_error.hpp"
#include "netdem/packing/packing.hpp"

using namespace netdem::dem;
namespace packing = netdem::packing;

namespace {
PeriodicPackOptions small(std::uint64_t seed) {
  PeriodicPackOptions o;
  o.n = 100;
  o.pressure = 1e-3;
  o.seed = seed;
  return o;
}

// The largest overlap over all pairs through the nearest image of a rectangular cell, brute force.
double max_overlap(const packing::Packing& p) {
  const double W = p.box.width(), H = p.box.height();
  double m = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      double dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i];
      dx -= W * std::round(dx / W);
      dy -= H * std::round(dy / H);
      m = std::max(m, p.r[i] + p.r[j] - std::hypot(dx, dy));
    }
  return m;
}
}  // namespace

TEST(PeriodicPacking, ValidJammedAtRestAndDeterministic) {
  PeriodicPackSummary m;
  const packing::Packing pk = make_periodic_packing(2, small(4), m);
  EXPECT_EQ(m.status, "ok") << m.reason;
  EXPECT_TRUE(pk.periodic);
  EXPECT_EQ(pk.seed, 4u);
  EXPECT_EQ(pk.size(), 100u);
  EXPECT_NO_THROW(packing::validate(pk));
  EXPECT_NEAR(pk.density(), m.density, 1e-12) << "the file's density is the reported one";
  // the radii of the distribution
  for (double r : pk.r) EXPECT_TRUE(r >= 0.9 && r <= 1.1);
  // overlaps: the reported largest one is the brute force's, and below 1e-2 R (docs/packing.md)
  double r_mean = 0.0;
  for (double r : pk.r) r_mean += r / static_cast<double>(pk.size());
  EXPECT_NEAR(max_overlap(pk) / r_mean, m.max_overlap, 1e-9);
  EXPECT_LT(m.max_overlap, 1e-2);
  EXPECT_GT(m.mean_overlap, 0.0);
  EXPECT_LT(m.mean_overlap, 3e-3);
  // jammed and at rest: the target pressure, the force balance, a rigid backbone near isostatic
  EXPECT_NEAR(m.pressure, 1e-3, 0.02 * 1e-3 + 1e-12);
  EXPECT_LT(m.unbalanced, 3e-3);
  EXPECT_GT(m.Z_backbone, 3.95);
  EXPECT_LT(m.Z_backbone, 4.4);
  EXPECT_LT(m.rattler_fraction, 0.15);
  EXPECT_GT(m.density, 0.80);
  EXPECT_LT(m.density, 0.88);
  EXPECT_GE(m.psi6_local, m.psi6_global);
  // the same seed, the same packing to the bit; another seed, another packing
  PeriodicPackSummary m2, m3;
  const packing::Packing again = make_periodic_packing(2, small(4), m2);
  EXPECT_EQ(again.x, pk.x);
  EXPECT_EQ(again.y, pk.y);
  EXPECT_EQ(again.r, pk.r);
  EXPECT_EQ(m2.steps, m.steps);
  const packing::Packing other = make_periodic_packing(2, small(5), m3);
  EXPECT_NE(other.x, pk.x);
}

TEST(PeriodicPacking, Spheres) {
  PeriodicPackOptions o = small(2);
  o.n = 64;
  PeriodicPackSummary m;
  const packing::Packing pk = make_periodic_packing(3, o, m);
  EXPECT_EQ(m.status, "ok") << m.reason;
  EXPECT_EQ(pk.dim, 3);
  EXPECT_NO_THROW(packing::validate(pk));
  EXPECT_NEAR(pk.density(), m.density, 1e-12);
  EXPECT_GT(m.density, 0.58);  // frictionless spheres jam near 0.64 (random close packing)
  EXPECT_LT(m.density, 0.70);
  EXPECT_GT(m.Z_backbone, 5.9);  // isostatic: 2D = 6
  EXPECT_LT(m.max_overlap, 1e-2);
}

TEST(PeriodicPacking, Refusals) {
  PeriodicPackSummary m;
  PeriodicPackOptions o;
  o.n = 3;
  EXPECT_THROW(make_periodic_packing(2, o, m), netdem::FieldError);
  o = PeriodicPackOptions{};
  o.pressure = 1.0;
  EXPECT_THROW(make_periodic_packing(2, o, m), netdem::FieldError);
  o = PeriodicPackOptions{};
  o.r_min = 1.2;
  EXPECT_THROW(make_periodic_packing(2, o, m), netdem::FieldError);
  o = PeriodicPackOptions{};
  o.friction = -1.0;
  EXPECT_THROW(make_periodic_packing(2, o, m), netdem::FieldError);
  EXPECT_THROW(make_periodic_packing(4, PeriodicPackOptions{}, m), netdem::FieldError);
}
