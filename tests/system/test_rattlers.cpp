// Rattler pruning (sys::prune_rattlers, issue 28 item 4) on small contact graphs whose backbone is
// known by hand: a particle with fewer than `need` contacts is removed, its neighbours lose one,
// and so on until every particle left has `need` contacts among the others (walls included).
#include <gtest/gtest.h>

#include <vector>

#include "netdem/system/rattlers.hpp"

using netdem::sys::prune_rattlers;

namespace {
// the complete graph on particles 0-3 (each with 3 contacts) plus the given extra contacts
void k4(std::vector<int>& pi, std::vector<int>& pj) {
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) pi.push_back(a), pj.push_back(b);
}
}  // namespace

TEST(Rattlers, ChainIsAllRattlersWithoutFriction) {
  const auto b = prune_rattlers(3, {0, 1}, {1, 2}, {}, 3);
  EXPECT_EQ(b.rattlers, 3u);
  EXPECT_EQ(b.contacts, 0u);
  EXPECT_EQ(b.Z, 0.0);
  // with need = D = 2 (friction) the ends go first, then the middle particle
  EXPECT_EQ(prune_rattlers(3, {0, 1}, {1, 2}, {}, 2).rattlers, 3u);
}

TEST(Rattlers, PendantParticleAndIsolatedOneLeaveTheBackbone) {
  std::vector<int> pi, pj;
  k4(pi, pj);
  pi.push_back(3), pj.push_back(4);  // particle 4 hangs on particle 3; particle 5 touches nothing
  const auto b = prune_rattlers(6, pi, pj, {}, 3);
  EXPECT_EQ(b.rattlers, 2u);
  EXPECT_EQ(b.rattler, (std::vector<std::uint8_t>{0, 0, 0, 0, 1, 1}));
  EXPECT_EQ(b.contacts, 6u);
  EXPECT_DOUBLE_EQ(b.Z, 3.0);  // 2 x 6 / 4
}

TEST(Rattlers, RemovalCascades) {
  // particle 4 touches 0 and 1 of the K4 and particle 5; 5 touches only 4: with need 3, 5 goes,
  // then 4 (left with 2), and the K4 stays; with 4 also touching 2, it keeps 3 after 5 goes
  std::vector<int> pi, pj;
  k4(pi, pj);
  for (int a : {0, 1}) pi.push_back(a), pj.push_back(4);
  pi.push_back(4), pj.push_back(5);
  EXPECT_EQ(prune_rattlers(6, pi, pj, {}, 3).rattlers, 2u);
  pi.push_back(2), pj.push_back(4);
  const auto b = prune_rattlers(6, pi, pj, {}, 3);
  EXPECT_EQ(b.rattlers, 1u);
  EXPECT_EQ(b.rattler[5], 1);
  EXPECT_DOUBLE_EQ(b.Z, 2.0 * 9 / 5);
}

TEST(Rattlers, WallContactsCountAndNeverLeave) {
  // a disk in a corner: one contact with a neighbour and two walls holds it (need 3); the
  // neighbour, with that one contact and one wall, is a rattler, and then so is the corner disk
  const std::vector<int> pi{0}, pj{1};
  EXPECT_EQ(prune_rattlers(2, pi, pj, {2, 2}, 3).rattlers, 0u);
  const auto b = prune_rattlers(2, pi, pj, {2, 1}, 3);
  EXPECT_EQ(b.rattlers, 2u);
}

TEST(Rattlers, NumberingDoesNotMatter) {
  // the pendant case with the particles renumbered by p -> 5 - p
  std::vector<int> pi, pj;
  k4(pi, pj);
  pi.push_back(3), pj.push_back(4);
  for (auto& v : pi) v = 5 - v;
  for (auto& v : pj) v = 5 - v;
  const auto b = prune_rattlers(6, pi, pj, {}, 3);
  EXPECT_EQ(b.rattler, (std::vector<std::uint8_t>{1, 1, 0, 0, 0, 0}));
  EXPECT_DOUBLE_EQ(b.Z, 3.0);
}
