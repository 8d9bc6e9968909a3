// The staggered sintering scheme (netdem/quasistatic/staggered.hpp; issue 17, docs/staggered.md):
// a free pair in the network follows the two-particle model, its shrinkage is counted once, a chain
// and a lattice shrink like the pair, E drops out bit for bit, the shrinkage correction is exact,
// and a restart is bit-identical.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/quasistatic/staggered.hpp"
#include "staggered_test_util.hpp"

namespace {

namespace cs = netdem::contact::sinter;
namespace st = netdem::qs::staggered;
using Eigen::Vector3d;

using netdem::test::cu;
using netdem::test::cubic;
using netdem::test::expect_same;
using netdem::test::jittered;
using netdem::test::kT;
using netdem::test::same_bits;

double centre_distance(const st::Staggered& s, int a, int b) {
  return (s.particles().position(b) - s.particles().position(a)).norm();
}

// ----------------------------------------------------------------------------------------------

TEST(StaggeredSplit, SumIsTheNewDistanceAndTheSignApproaches) {
  const double RA = 24e-6, RB = 27e-6;
  // the free model moved y4 by 3 and y7 by 1 (units of 1e-9 m); the network let the centres
  // approach by 2: y4 takes 3/4 of it, y7 1/4, both decrease
  const double y4p = 23.9e-6, y7p = 26.8e-6, d_prev = y4p + y7p;
  const double y4f = y4p - 3e-9, y7f = y7p - 1e-9;
  const double d_new = d_prev - 2e-9;
  const auto [y4, y7] = st::corrected_split(y4p, y7p, y4f, y7f, d_new, RA, RB);
  EXPECT_NEAR(y4 + y7, d_new, 1e-12 * d_new);
  EXPECT_LT(y4, y4p);
  EXPECT_LT(y7, y7p);
  EXPECT_NEAR((y4p - y4) / (y7p - y7), 3.0, 1e-6);
  // a free pair (the network moved the centres by the free shrinkage): Eq 44 gives 0
  const auto [z4, z7] = st::corrected_split(y4p, y7p, y4f, y7f, d_prev - 4e-9, RA, RB);
  EXPECT_NEAR(z4, y4f, 1e-12 * y4f);
  EXPECT_NEAR(z7, y7f, 1e-12 * y7f);
  // no free shrinkage: the change is split by the radii
  const auto [w4, w7] = st::corrected_split(y4p, y7p, y4p, y7p, d_prev - 5.1e-9, RA, RB);
  EXPECT_NEAR((y4p - w4) / 5.1e-9, RA / (RA + RB), 1e-6);
  EXPECT_NEAR(w4 + w7, d_prev - 5.1e-9, 1e-12 * d_prev);
}

// Two particles, A fixed in full: the network must give the two-particle model's Delta L / L0 to
// 1e-10, step by step, with the model integrated alone over the same steps (advance_free). The
// load of a step is that step's Delta(y4 + y7); if it were the total since t0 (Eq 13) the
// shrinkage would grow with the number of steps.
void two_particles(int strategy, const Vector3d& axis, double RA, double RB) {
  st::StaggeredOptions o;
  o.strategy = strategy;
  o.boundary_planes = false;
  o.dt_initial = 1e-2;
  o.dt_max = 10.0;
  const Vector3d e = axis.normalized();
  const Vector3d xA(3e-5, -2e-5, 1e-5);
  st::Particles p;
  p.push_back(xA, RA);
  p.push_back(xA + (RA + RB) * e, RB);
  st::Staggered s(p, cu(), cs::TemperatureProfile::constant(kT), o);
  ASSERT_EQ(s.contacts().size(), 1u);
  for (int k = 0; k < 6; ++k) s.fix(0, k);
  EXPECT_EQ(s.fixed_dofs(), 6);
  cs::PairContact ref;
  ref.q = ref.q0 = s.contacts()[0].pair.q;
  const double L0 = RA + RB;
  double worst = 0.0, worst_bar = 0.0, worst_sum = 0.0;
  int steps = 0;
  while (s.time() < 600.0) {
    const st::StepRecord rec = s.step(600.0);
    ++steps;
    if (strategy == 2) {
      ASSERT_TRUE(st::advance_free(ref, cu(), s.temperature(), rec.t, o));
    }
    const auto& c = s.contacts()[0];
    const double d = centre_distance(s, 0, 1);
    EXPECT_TRUE(same_bits(s.particles().coord(0, 0), xA[0]));
    worst_sum = std::max(worst_sum, std::fabs(c.pair.q[cs::kHA] + c.pair.q[cs::kHB] - d) / d);
    worst_bar = std::max(worst_bar, std::fabs(c.dL_bar) / L0);
    if (strategy == 2) {
      const double shrink_ref = 1.0 - (ref.q[cs::kHA] + ref.q[cs::kHB]) / L0;
      worst = std::max(worst, std::fabs((1.0 - d / L0) - shrink_ref));
      EXPECT_NEAR(c.pair.q[cs::kX], ref.q[cs::kX], 1e-10 * ref.q[cs::kX]);
    }
  }
  EXPECT_GT(steps, 20);
  const double shrink = 1.0 - centre_distance(s, 0, 1) / L0;
  EXPECT_GT(shrink, 1e-3);  // it did sinter
  EXPECT_LT(worst_sum, 1e-12) << "y4 + y7 against the centre distance";
  EXPECT_LT(worst_bar, 1e-12) << "Eq 44 for a free pair";
  if (strategy == 2) {
    EXPECT_LT(worst, 1e-10) << "network against the two-particle model, " << steps << " steps";
  }
  // against an independent integration of the model (DP45 at rtol 1e-10): the RK4 step-doubling
  // error of eps_lim = 1e-6 per step is what remains
  cs::PairContact dp = cs::make_contact(RA, RB, 0.01);
  dp.q = dp.q0 = s.contacts()[0].pair.q0;
  cs::IntegratorOptions io;
  io.rtol = 1e-10;
  const cs::TemperatureProfile T = cs::TemperatureProfile::constant(kT);
  cs::PairProblem prob{&cu(), &T, {}, 0.0};
  ASSERT_EQ(cs::advance(dp, prob, 600.0, io), cs::PairStatus::Ok);
  const double shrink_dp = 1.0 - (dp.q[cs::kHA] + dp.q[cs::kHB]) / L0;
  EXPECT_NEAR(shrink, shrink_dp, 1e-4 * shrink_dp) << "strategy " << strategy;
  char vs[32] = "(strategy 2 only)";
  if (strategy == 2) std::snprintf(vs, sizeof vs, "%.2e", worst);
  std::printf("strategy %d: %d steps, shrinkage %.9e (DP45 %.9e, rel. diff %.2e), network vs model %s, "
              "|sum - d|/d %.2e\n",
              strategy, steps, shrink, shrink_dp, std::fabs(shrink / shrink_dp - 1.0),
              vs, worst_sum);
}

TEST(Staggered, TwoParticlesFollowThePairModelStrategy2) {
  two_particles(2, Vector3d(0, 0, 1), 25e-6, 25e-6);
  two_particles(2, Vector3d(1.0, -0.7, 0.4), 24e-6, 27e-6);
}

TEST(Staggered, TwoParticlesStrategy1) { two_particles(1, Vector3d(0.3, 1.0, -0.2), 24e-6, 27e-6); }

// A straight chain of equal spheres (A anchored) shrinks, bond by bond and as a whole, like the pair.
TEST(Staggered, ChainShrinksLikeThePair) {
  const double r = 25e-6;
  const int n = 6;
  st::Particles p;
  for (int i = 0; i < n; ++i) p.push_back(Vector3d(2.0 * r * i, 0.0, 0.0), r);
  st::StaggeredOptions o;
  o.boundary_planes = false;
  st::Staggered s(p, cu(), cs::TemperatureProfile::constant(kT), o);
  ASSERT_EQ(s.contacts().size(), static_cast<std::size_t>(n - 1));
  cs::PairContact ref;
  ref.q = ref.q0 = s.contacts()[0].pair.q;
  double worst = 0.0;
  while (s.time() < 300.0) {
    const auto rec = s.step(300.0);
    ASSERT_TRUE(st::advance_free(ref, cu(), s.temperature(), rec.t, o));
    const double shrink_ref = 1.0 - (ref.q[cs::kHA] + ref.q[cs::kHB]) / (2.0 * r);
    for (int i = 0; i + 1 < n; ++i)
      worst = std::max(worst, std::fabs(1.0 - centre_distance(s, i, i + 1) / (2.0 * r) - shrink_ref));
    worst = std::max(worst, std::fabs(-s.homogeneous_strain()(0, 0) - shrink_ref));
    EXPECT_NEAR(s.homogeneous_strain()(1, 1), 0.0, 1e-14);
  }
  EXPECT_LT(worst, 1e-10);
}

// A simple cubic lattice of equal spheres with the boundary planes of section 3.3: every bond
// shrinks freely, so the sample shrinks homogeneously by the pair's Delta L / L0 along x, y, z.
TEST(Staggered, LatticeShrinksLikeThePair) {
  const double r = 25e-6;
  const auto p = cubic(4, r, 0.0, 1);
  st::StaggeredOptions o;
  st::Staggered s(p, cu(), cs::TemperatureProfile::constant(kT), o);
  ASSERT_EQ(s.contacts().size(), 3u * 3u * 16u);
  // the planes hold the 3 lower faces: 16 particles each, one normal DOF
  EXPECT_EQ(s.fixed_dofs(), 3 * 16);
  cs::PairContact ref;
  ref.q = ref.q0 = s.contacts()[0].pair.q;
  double worst = 0.0, worst_bar = 0.0;
  while (s.time() < 300.0) {
    const auto rec = s.step(300.0);
    ASSERT_TRUE(st::advance_free(ref, cu(), s.temperature(), rec.t, o));
    const double shrink_ref = 1.0 - (ref.q[cs::kHA] + ref.q[cs::kHB]) / (2.0 * r);
    const Eigen::Matrix3d F = s.homogeneous_strain();
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::fabs(-F(k, k) - shrink_ref));
    for (const auto& c : s.contacts()) worst_bar = std::max(worst_bar, std::fabs(c.dL_bar) / (2.0 * r));
    EXPECT_EQ(rec.new_contacts, 0);
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_LT(worst_bar, 1e-12);
  EXPECT_GT(-s.homogeneous_strain()(0, 0), 1e-3);
}

TEST(Staggered, YoungsModulusDropsOutBitForBit) {
  st::Staggered a = jittered(120e9), b = jittered(8.0 * 120e9);
  int newc = 0;
  double bar = 0.0;
  while (a.time() < 400.0) {
    const auto ra = a.step(400.0);
    const auto rb = b.step(400.0);
    newc += ra.new_contacts;
    EXPECT_EQ(ra.gmres_iterations, rb.gmres_iterations);
    expect_same(a, b);
  }
  for (const auto& c : a.contacts()) bar = std::max(bar, std::fabs(c.dL_bar));
  EXPECT_GT(bar, 1e-12) << "the sample must load its bonds against each other";
  std::printf("E x 8: %ld steps, %zu contacts (%d new), max |dL_bar| %.3e m\n", a.steps(), a.contacts().size(), newc,
              bar);
}

TEST(Staggered, RestartIsBitIdentical) {
  for (int strategy : {1, 2}) {
    st::Staggered a = jittered(120e9, strategy);
    std::string saved;
    int refactors_after = 0;
    while (a.time() < 400.0) {
      const auto rec = a.step(400.0);
      if (saved.empty() && a.time() >= 40.0) saved = a.save();
      else if (!saved.empty() && rec.refactorised) ++refactors_after;
    }
    ASSERT_FALSE(saved.empty());
    st::Staggered b = st::Staggered::load(saved, "saved");
    while (b.time() < 400.0) b.step(400.0);
    expect_same(a, b);
    EXPECT_EQ(a.steps(), b.steps());
    EXPECT_EQ(a.save().substr(0, 200), b.save().substr(0, 200));
    std::printf("strategy %d: restart from t = 40 s, %ld steps to 400 s, %d refactorisations after it\n", strategy,
                a.steps(), refactors_after);
  }
}

// A rigid translation of the input and a renumbering of the particles change nothing but rounding.
TEST(Staggered, InvariantUnderTranslationAndNumbering) {
  const auto p = cubic(3, 25e-6, 0.01, 11);
  st::StaggeredOptions o;
  auto run = [&](const st::Particles& q) {
    st::Staggered s(q, cu(), cs::TemperatureProfile::constant(kT), o);
    while (s.time() < 300.0) s.step(300.0);
    return s;
  };
  const st::Staggered a = run(p);
  const Vector3d shift(1.3e-3, -2.1e-3, 0.7e-3);
  st::Particles moved = p;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) moved.pos[3 * i + static_cast<std::size_t>(k)] += shift[k];
  std::vector<int> perm(p.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(3));
  std::vector<int> inverse(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) inverse[static_cast<std::size_t>(perm[i])] = static_cast<int>(i);
  st::Particles shuffled;
  for (int i : inverse) shuffled.push_back(p.position(static_cast<std::size_t>(i)), p.r[static_cast<std::size_t>(i)]);
  const st::Staggered b = run(moved), c = run(shuffled);
  const Eigen::Matrix3d Fa = a.homogeneous_strain(), Fb = b.homogeneous_strain(), Fc = c.homogeneous_strain();
  ASSERT_GT(-Fa(0, 0), 1e-4);
  EXPECT_LT((Fa - Fb).norm(), 1e-9 * Fa.norm());
  EXPECT_LT((Fa - Fc).norm(), 1e-9 * Fa.norm());
  EXPECT_EQ(a.contacts().size(), c.contacts().size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_LT((a.particles().position(i) + shift - b.particles().position(i)).norm(), 1e-9 * 25e-6);
    EXPECT_LT((a.particles().position(i) - c.particles().position(static_cast<std::size_t>(perm[i]))).norm(), 1e-9 * 25e-6);
  }
}

TEST(Staggered, RefusesBadInput) {
  const auto T = cs::TemperatureProfile::constant(kT);
  st::StaggeredOptions o;
  st::Particles p;
  p.push_back(Vector3d::Zero(), 25e-6);
  p.push_back(Vector3d(50e-6, 0, 0), -1.0);
  EXPECT_THROW(st::Staggered(p, cu(), T, o), std::invalid_argument);
  p.r[1] = 25e-6;
  p.pos[3] = std::nan("");
  EXPECT_THROW(st::Staggered(p, cu(), T, o), std::invalid_argument);
  p.pos[3] = 50e-6;
  st::Particles torn = p;  // arrays of different lengths: one line, not a read past the end
  torn.pos.pop_back();
  EXPECT_THROW(st::Staggered(torn, cu(), T, o), std::invalid_argument);
  st::StaggeredOptions bad = o;
  bad.strategy = 3;
  EXPECT_THROW(st::Staggered(p, cu(), T, bad), std::invalid_argument);
  bad = o;
  bad.dt_max = -1.0;
  EXPECT_THROW(st::Staggered(p, cu(), T, bad), std::invalid_argument);
  cs::SinterMaterial m = cu();
  m.poisson_ratio = -1.0;
  EXPECT_THROW(st::Staggered(p, m, T, o), std::invalid_argument);
  EXPECT_THROW(st::Staggered::load("netdem-staggered-state 1\noptions 2 nonsense", "x"), std::invalid_argument);
}

// The restart state in the state archive: the record of origin travels with it, and every field is
// checked at the door, one line naming the field (a negative initial radius, the 8th value of an old
// particle row, was accepted before issue 26).
TEST(Staggered, StateFieldsAreCheckedAtTheDoor) {
  st::Staggered a = jittered(120e9, 2);
  while (a.time() < 40.0) a.step(40.0);
  a.set_origin_record(R"({"seed":7,"packing":{"source":"lattice.csv"}})");
  const std::string good = a.save();
  const st::Staggered b = st::Staggered::load(good, "s");
  EXPECT_EQ(b.origin_record(), R"({"packing":{"source":"lattice.csv"},"seed":7})");
  EXPECT_EQ(b.save(), good) << "state -> file -> state is not the identity";
  EXPECT_THROW(a.set_origin_record("[1, 2]"), std::invalid_argument);
  ASSERT_GT(a.contacts().size(), 2u);
  auto refuse = [&](const char* pointer, const nlohmann::json& v, const std::string& needle) {
    nlohmann::json j = nlohmann::json::parse(good);
    j[nlohmann::json::json_pointer(pointer)] = v;
    try {
      (void)st::Staggered::load(j.dump(), "s");
      ADD_FAILURE() << pointer << ": accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("s: " + needle), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  };
  refuse("/particles/r0/3", -25e-6, "/particles/r0/3: an initial radius must be positive");
  refuse("/particles/r/1", 0.0, "/particles/r/1: a radius must be positive");
  refuse("/particles/x/2", "nan", "/particles/x/2: expected a number, found string \"nan\"");
  refuse("/particles/fixed_user/0", 64, "/particles/fixed_user/0: 64 is outside [0, 63]");
  refuse("/contacts/status/1", 9, "/contacts/status/1: 9 is outside [0, 5]");
  refuse("/contacts/b/0", 1000, "/contacts/b/0: 1000 is outside");
  refuse("/contacts/q/0", nlohmann::json::array({1.0, 2.0}), "/contacts/q/0: expected 5 elements, found 2");
  refuse("/contacts/h/0", -1.0, "/contacts/h/0: -1.0 is below 0");
  refuse("/options/dt_max", -1.0, "/options/dt_max: the largest global step");
  refuse("/options/strategy", 3, "/options/strategy: 3 is outside [1, 2]");
  refuse("/material/gamma_s", "x", "/material/gamma_s: expected a number");
  refuse("/clock/dt", "inf", "/clock/dt: must be a finite number");
  refuse("/clock/dt", 0.0, "/clock/dt: must be > 0");  // the restart hung (campaign of issue 27)
  refuse("/contacts/L_created/0", 1e-300, "/contacts/L_created/0: 1e-300 is outside");  // dL_bar/L0 overflowed to null
  refuse("/factor/fixed", nlohmann::json::array({0}), "/factor/fixed: expected 0 or");
  refuse("/origin", 5, "/origin: expected an object or null");
  refuse("/kind", "dem", "/kind: a dem state, expected a staggered state");
  // the regressions of fuzz_staggered_state: every refuse_* file refused on one line naming a field
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(NETDEM_STAGGERED_REGRESSIONS)) {
    std::ifstream in(e.path(), std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ++files;
    try {
      (void)st::Staggered::load(text, "input");
      ADD_FAILURE() << e.path() << ": accepted";
    } catch (const std::invalid_argument& err) {
      const std::string m = err.what();
      EXPECT_EQ(m.rfind("input: /", 0), 0u) << e.path() << ": " << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      std::printf("  %s: %s\n", e.path().filename().c_str(), m.c_str());
    }
  }
  EXPECT_GE(files, 7);
  try {
    (void)st::Staggered::load("netdem-staggered-state 1\noptions 2\n", "old");
    ADD_FAILURE() << "an old text state was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("convert it with apps/scripts/convert_state.py"), std::string::npos) << e.what();
  }
}

}  // namespace

namespace {
// The planes of section 3.3 at the packing box (plane_origin) or at the spheres' bounding box: a
// sphere pressed 0.7 % r into the x wall moves the bounding-box face and leaves the others off it.
TEST(Staggered, BoundaryPlanesAtTheBoxOrTheBoundingBox) {
  const double r = 25e-6;
  auto p = cubic(4, r, 0.0, 1);
  p.pos[0] -= 0.007 * r;
  st::StaggeredOptions o;
  const auto T = cs::TemperatureProfile::constant(kT);
  const st::Staggered bbox(p, cu(), T, o);
  o.plane_origin = {0.0, 0.0, 0.0};
  const st::Staggered box(p, cu(), T, o);
  // the pressed sphere loses its 3 bonds (2.007 r and more) and is fixed in full (6). Bounding box:
  // the x plane holds no other sphere, so the 63-sphere cluster keeps its x translation and is
  // held at one DOF (1); y and z hold 15 others each: 6 + 1 + 30 = 37. The box: 15 others on each
  // of the three planes: 6 + 45 = 51.
  EXPECT_EQ(bbox.fixed_dofs(), 37);
  EXPECT_EQ(box.fixed_dofs(), 51);
  EXPECT_EQ(bbox.plane_particles(), (std::array<int, 3>{1, 16, 16}));  // the spheres on each plane
  EXPECT_EQ(box.plane_particles(), (std::array<int, 3>{16, 16, 16}));
  o.plane_origin = {0.0, std::nan(""), 0.0};  // per axis: y from the bounding box (the same here)
  EXPECT_EQ(st::Staggered(p, cu(), T, o).fixed_dofs(), 51);
  o.plane_origin = {std::numeric_limits<double>::infinity(), 0.0, 0.0};
  EXPECT_THROW(st::Staggered(p, cu(), T, o), std::invalid_argument);
}
}  // namespace
