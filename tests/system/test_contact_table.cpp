// Tests for the system layer's particles and contact table (netdem/system/particle_set.hpp,
// contact_table.hpp), in 2D and 3D: the rows are exactly the pairs with a gap below the skin
// (brute force), the pair set does not depend on the numbering of the particles, the history of
// a pair within the skin survives a rebuild and is dropped beyond it, a law whose history ends at
// separation gets a fresh one for a pair found apart, the adjacency lists every row of a
// particle, and needs_rebuild() follows the motion relative to the box.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/system/contact_table.hpp"
#include "netdem/system/particle_set.hpp"

namespace {

using netdem::sys::ContactTable;
using netdem::sys::ParticleSet;
namespace ct = netdem::contact;

template <int D>
ParticleSet<D> random_set(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ParticleSet<D> s;
  const double side = D == 2 ? std::sqrt(n) * 1.6 : std::cbrt(n) * 1.6;
  for (int p = 0; p < n; ++p) {
    for (int a = 0; a < D; ++a) s.pos.push_back(side * u(rng));
    s.r.push_back(0.5 + 0.4 * u(rng));
  }
  s.rot.assign(static_cast<std::size_t>(ParticleSet<D>::kRotDofs * n), 0.0);
  return s;
}

template <int D>
std::set<std::pair<int, int>> brute_force(const ParticleSet<D>& s, double skin) {
  std::set<std::pair<int, int>> out;
  const int n = static_cast<int>(s.size());
  for (int p = 0; p < n; ++p)
    for (int q = p + 1; q < n; ++q)
      if ((s.position(q) - s.position(p)).norm() - s.r[p] - s.r[q] < skin) out.emplace(p, q);
  return out;
}

template <int D>
using PlasticTable = ContactTable<ct::PlasticIndentationHistoryT<D>, D>;

template <int D>
void check_rows_and_renumbering() {
  const ct::PlasticIndentationLawT<D> law{ct::PlasticIndentationParams{}};
  const double skin = 0.3;
  const ParticleSet<D> s = random_set<D>(300, 7 + D);
  PlasticTable<D> t;
  t.rebuild(law, s, skin, 0.9, PlasticTable<D>::Mat::Identity());
  const auto expect = brute_force(s, skin);
  ASSERT_GT(expect.size(), 100u);
  std::set<std::pair<int, int>> got;
  for (std::size_t k = 0; k < t.pairs(); ++k) {
    ASSERT_LT(t.pi[k], t.pj[k]);
    if (k > 0) {
      ASSERT_LT(std::make_pair(t.pi[k - 1], t.pj[k - 1]), std::make_pair(t.pi[k], t.pj[k]));
    }
    got.emplace(t.pi[k], t.pj[k]);
  }
  EXPECT_EQ(got, expect);
  // adjacency: every row of a particle, in increasing row order
  for (int p = 0; p < static_cast<int>(s.size()); ++p) {
    std::vector<int> rows;
    for (std::size_t k = 0; k < t.pairs(); ++k)
      if (t.pi[k] == p || t.pj[k] == p) rows.push_back(static_cast<int>(k));
    const std::vector<int> adj(t.adj_pair.begin() + t.adj_start[p], t.adj_pair.begin() + t.adj_start[p + 1]);
    ASSERT_EQ(adj, rows) << "particle " << p;
  }
  // renumbering: the same pairs of the same particles
  std::vector<int> perm(s.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(3));
  ParticleSet<D> sp = s;
  for (std::size_t p = 0; p < s.size(); ++p) {
    const auto q = static_cast<std::size_t>(perm[p]);  // old p is new q
    for (int a = 0; a < D; ++a) sp.pos[D * q + static_cast<std::size_t>(a)] = s.coord(p, a);
    sp.r[q] = s.r[p];
  }
  PlasticTable<D> tp;
  tp.rebuild(law, sp, skin, 0.9, PlasticTable<D>::Mat::Identity());
  std::vector<int> inverse(s.size());
  for (std::size_t p = 0; p < s.size(); ++p) inverse[static_cast<std::size_t>(perm[p])] = static_cast<int>(p);
  std::set<std::pair<int, int>> back;
  for (std::size_t k = 0; k < tp.pairs(); ++k) {
    const int a = inverse[static_cast<std::size_t>(tp.pi[k])], b = inverse[static_cast<std::size_t>(tp.pj[k])];
    back.emplace(std::min(a, b), std::max(a, b));
  }
  EXPECT_EQ(back, expect);
}

TEST(ContactTable, RowsAreThePairsWithinTheSkinAndIndependentOfNumbering2D) { check_rows_and_renumbering<2>(); }
TEST(ContactTable, RowsAreThePairsWithinTheSkinAndIndependentOfNumbering3D) { check_rows_and_renumbering<3>(); }

// Three particles on the x axis: 0-1 touching, 1-2 apart within the skin. Histories are set, then
// particle 2 moves: within the skin the history stays, beyond it the row (and history) goes, and a
// pair that comes back is fresh.
template <int D>
void check_history_lifecycle() {
  const ct::PlasticIndentationLawT<D> law{ct::PlasticIndentationParams{}};
  ParticleSet<D> s;
  s.pos.assign(3 * D, 0.0);
  s.pos[D * 1] = 1.9;   // r = 1: overlap 0.1 with 0
  s.pos[D * 2] = 4.0;   // gap 0.1 with 1
  s.r = {1.0, 1.0, 1.0};
  s.rot.assign(3 * ParticleSet<D>::kRotDofs, 0.0);
  const double skin = 0.5;
  const auto I = PlasticTable<D>::Mat::Identity();
  PlasticTable<D> t;
  t.rebuild(law, s, skin, 1.0, I);
  ASSERT_EQ(t.pairs(), 2u);
  EXPECT_EQ(t.with_history(law), 0u);
  t.hist[0].u_max = 0.1;
  t.hist[1].u_max = 0.05;  // touched before, apart now: the plastic flattening outlives separation
  std::vector<double> extra = {10.0, 20.0};
  s.pos[D * 2] = 4.3;  // gap 0.4 < skin
  t.rebuild(law, s, skin, 1.0, I);
  t.carry(extra, -1.0);
  ASSERT_EQ(t.pairs(), 2u);
  EXPECT_EQ(t.hist[0].u_max, 0.1);
  EXPECT_EQ(t.hist[1].u_max, 0.05);
  EXPECT_EQ(extra, (std::vector<double>{10.0, 20.0}));
  EXPECT_EQ(t.with_history(law), 2u);
  s.pos[D * 2] = 4.6;  // gap 0.7 > skin: dropped
  t.rebuild(law, s, skin, 1.0, I);
  t.carry(extra, -1.0);
  ASSERT_EQ(t.pairs(), 1u);
  EXPECT_EQ(t.hist[0].u_max, 0.1);
  EXPECT_EQ(extra, (std::vector<double>{10.0}));
  s.pos[D * 2] = 4.0;  // back within the skin: a new row with a fresh history
  t.rebuild(law, s, skin, 1.0, I);
  t.carry(extra, -1.0);
  ASSERT_EQ(t.pairs(), 2u);
  EXPECT_EQ(t.hist[0].u_max, 0.1);
  EXPECT_EQ(t.hist[1].u_max, 0.0);
  EXPECT_EQ(extra, (std::vector<double>{10.0, -1.0}));
  EXPECT_EQ(t.carried_from(), (std::vector<int>{0, -1}));

  // a law whose history ends at separation: the apart pair within the skin starts fresh
  const ct::LudingParams lp;
  const ct::LudingLaw<ct::kLudingFull, D> luding(lp, lp.k1());
  ContactTable<typename ct::LudingLaw<ct::kLudingFull, D>::History, D> tl;
  tl.rebuild(luding, s, skin, 1.0, I);
  ASSERT_EQ(tl.pairs(), 2u);
  tl.hist[0].delta_max = 0.1;
  tl.hist[1].delta_max = 0.05;
  tl.rebuild(luding, s, skin, 1.0, I);
  EXPECT_EQ(tl.hist[0].delta_max, 0.1);  // touching: kept
  EXPECT_EQ(tl.hist[1].delta_max, 0.0);  // apart: fresh
  EXPECT_EQ(tl.with_history(luding), 1u);
}

TEST(ContactTable, HistoryLifecycle2D) { check_history_lifecycle<2>(); }
TEST(ContactTable, HistoryLifecycle3D) { check_history_lifecycle<3>(); }

template <int D>
void check_needs_rebuild() {
  const ct::PlasticIndentationLawT<D> law{ct::PlasticIndentationParams{}};
  ParticleSet<D> s = random_set<D>(50, 11);
  PlasticTable<D> t;
  using Mat = typename PlasticTable<D>::Mat;
  t.rebuild(law, s, 0.2, 0.9, Mat::Identity());
  EXPECT_FALSE(t.needs_rebuild(s, Mat::Identity(), 0.2, 0.9));
  // an affine motion with the box: only the affine relative motion counts
  Mat F = Mat::Identity();
  F(0, 0) = 1.0 - 1e-4;
  ParticleSet<D> moved = s;
  for (std::size_t p = 0; p < s.size(); ++p) moved.pos[D * p] *= F(0, 0);
  EXPECT_FALSE(t.needs_rebuild(moved, F, 0.2, 0.9));
  // one particle moved by 0.11 relative to the box: 2 x 0.11 > skin
  moved.pos[D * 7 + 1] += 0.11;
  EXPECT_TRUE(t.needs_rebuild(moved, F, 0.2, 0.9));
}

TEST(ContactTable, NeedsRebuild2D) { check_needs_rebuild<2>(); }
TEST(ContactTable, NeedsRebuild3D) { check_needs_rebuild<3>(); }

TEST(ParticleSet, FromPacking) {
  netdem::packing::Packing pk;
  pk.x = {0.0, 1.0};
  pk.y = {2.0, 3.0};
  pk.r = {0.5, 0.25};
  const auto s = ParticleSet<2>::from_packing(pk);
  EXPECT_EQ(s.pos, (std::vector<double>{0.0, 2.0, 1.0, 3.0}));
  EXPECT_EQ(s.rot, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(s.axis(1), pk.y);
  EXPECT_THROW(ParticleSet<3>::from_packing(pk), std::invalid_argument);
  pk.dim = 3;
  pk.z = {4.0, 5.0};
  const auto s3 = ParticleSet<3>::from_packing(pk);
  EXPECT_EQ(s3.pos, (std::vector<double>{0.0, 2.0, 4.0, 1.0, 3.0, 5.0}));
  EXPECT_EQ(s3.rot.size(), 6u);
  EXPECT_EQ(s3.position(1), Eigen::Vector3d(1.0, 3.0, 5.0));
}

}  // namespace
