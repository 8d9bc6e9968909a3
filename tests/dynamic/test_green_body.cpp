// The green-body route of Ivannikov et al. with DynamicSolver3 (make_green_body, green_body.hpp;
// docs/packing.md "The green-body route"). Small samples with a soft spring (kappa = 1e3) so that
// each run takes about a second; the Cu default (805 spheres) is measured in the docs, not here.
#include <gtest/gtest.h>

#include "test_scale.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "netdem/dynamic/green_body.hpp"
#include "netdem/packing/laminar.hpp"

using namespace netdem::dem;
namespace pk = netdem::packing;

namespace {

GreenBodyOptions small(std::size_t n, double target) {
  GreenBodyOptions o;
  o.n = n;
  o.target_density = target;
  o.stiffness_number = 1e3;
  o.wall_speed = 0.05;
  o.max_mean_overlap = 0.01;  // the gravity level at kappa = 1e3 is about 4e-3 r (measured)
  return o;
}

}  // namespace

// A reachable target: the walls stop at the target box (density to rounding), the sample is at
// rest in the settle and rest phases, the lid sat on the uppermost sphere, the overlaps stay at the
// gravity level, and the packing is valid (centres inside, no pair closer than max(r_i, r_j)).
// The Eq 48 profiles are flat in the interior (one diameter from the walls): within 0.12 of their
// mean (measured max deviation printed), and the bulk is denser than the box (the wall layers).
TEST(GreenBody, ReachesTargetAtRest) {
  const std::size_t n = netdem::test::small_scale() ? 150 : 300;
  const double target = 0.53;
  const GreenBodyResult r = make_green_body(small(n, target));
  std::printf("  n = %zu: settled %.4f, final %.4f, mean overlap %.3e r (max %.3e), status %s %s\n", n, r.settled_density,
              r.packing.density(), r.overlaps.pair_mean, r.overlaps.pair_max, r.status.c_str(), r.reason.c_str());
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.packing.size(), n);
  EXPECT_NEAR(r.packing.density(), target, 1e-9);
  ASSERT_EQ(r.phases.size(), 4u);
  EXPECT_EQ(r.phases[0].name, "settle");
  EXPECT_TRUE(r.phases[0].at_rest);
  EXPECT_EQ(r.phases[3].name, "rest");
  EXPECT_TRUE(r.phases[3].at_rest);
  EXPECT_LT(r.phases[3].kinetic, 1e-6);
  EXPECT_LT(r.settled_density, target);
  EXPECT_GT(r.settled_density, 0.3);
  EXPECT_LT(r.overlaps.pair_mean, 0.01);
  EXPECT_LT(r.overlaps.pair_max, 0.1);
  {  // the work estimate at the door is a lower bound of the steps taken, and not a loose one
    double steps = 0.0;
    for (const auto& ph : r.phases) steps += static_cast<double>(ph.steps);
    const double lower = netdem::dem::green_body_min_steps(small(n, target));
    std::printf("  steps taken %.0f, lower bound %.0f\n", steps, lower);
    EXPECT_LE(lower, steps);
    EXPECT_GT(lower, 0.1 * steps);
  }
  if (r.exact_aspect) {
    EXPECT_NEAR(r.packing.box.depth() / r.packing.box.width(), 0.8, 1e-9);
  }
  pk::validate(r.packing);
  const double d = 2.0 * 25e-6;
  double worst = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const pk::LaminarProfile prof = pk::laminar_density(r.packing, axis, 25e-6);
    const double lo = axis == 0 ? r.packing.box.x_min : axis == 1 ? r.packing.box.y_min : r.packing.box.z_min;
    const double hi = axis == 0 ? r.packing.box.x_max : axis == 1 ? r.packing.box.y_max : r.packing.box.z_max;
    const auto in = prof.interior(lo, hi, d);
    ASSERT_GT(in.count, 1u);
    worst = std::max({worst, in.max - in.mean, in.mean - in.min});
    EXPECT_GT(in.mean, r.packing.density()) << "axis " << axis;  // the wall layers are looser
  }
  std::printf("  Eq 48 interior: max deviation from the mean %.4f\n", worst);
  EXPECT_LT(worst, 0.12);
}

// Deterministic for a seed (bit for bit), different for another seed.
TEST(GreenBody, DeterministicForSeed) {
  const GreenBodyOptions o = small(60, 0.45);
  const GreenBodyResult a = make_green_body(o), b = make_green_body(o);
  EXPECT_EQ(a.packing.x, b.packing.x);
  EXPECT_EQ(a.packing.z, b.packing.z);
  EXPECT_EQ(a.phases.back().steps, b.phases.back().steps);
  GreenBodyOptions o2 = o;
  o2.seed = 2;
  EXPECT_NE(make_green_body(o2).packing.x, a.packing.x);
}

// A target the springs alone can hold is refused: status unreachable, the packing still returned,
// the reason names the overlap and the limit.
TEST(GreenBody, UnreachableTargetIsReported) {
  GreenBodyOptions o = small(60, 0.62);
  o.max_mean_overlap = 0.005;
  const GreenBodyResult r = make_green_body(o);
  std::printf("  target 0.62 of 60 spheres: %s (%s)\n", r.status.c_str(), r.reason.c_str());
  EXPECT_EQ(r.status, "unreachable");
  EXPECT_NE(r.reason.find("mean overlap"), std::string::npos);
  EXPECT_EQ(r.packing.size(), 60u);
  EXPECT_GT(r.overlaps.pair_mean, o.max_mean_overlap);
}

TEST(GreenBody, RefusesBadOptions) {
  auto msg = [](GreenBodyOptions o) {
    try {
      make_green_body(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  GreenBodyOptions o;
  o.target_density = 0.8;
  EXPECT_NE(msg(o).find("target density must be in (0, 0.74]"), std::string::npos);
  o = {};
  o.restitution = 0.0;
  EXPECT_NE(msg(o).find("restitution"), std::string::npos);
  o = {};
  o.steps_per_contact = 5;
  EXPECT_NE(msg(o).find("steps per contact"), std::string::npos);
  o = {};
  o.mu_compress = -1;
  EXPECT_NE(msg(o).find("compression friction"), std::string::npos);
  o = {};
  o.cloud_fraction = 0.5;
  EXPECT_NE(msg(o).find("cloud fraction"), std::string::npos);
}
