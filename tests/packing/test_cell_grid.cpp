// Tests for netdem/packing/cell_grid.hpp: the neighbours found through the grids equal all pairs
// (brute force) on random polydisperse sets, radius ratios up to 100, with and without skin;
// storage reuse, NaN/inf coordinates, the cell cap and the visiting order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <utility>
#include <vector>

#include "netdem/packing/cell_grid.hpp"

// Counts the allocations of this test program (the storage-reuse test below).
namespace {
std::size_t g_allocations = 0;
}  // namespace
void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
// GCC's -Wmismatched-new-delete cannot see that the replaced new above allocates with malloc
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace {

using netdem::packing::CellGrid;
using netdem::packing::GridLayout;
using netdem::packing::GrowingCellGrid;
using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

struct Disks {
  std::vector<double> x, y, r;
  double rmax = 0;
};

/// n disks in a square of side L = sqrt(pi sum r^2 / density); radii log-uniform in [1, ratio]
/// (so that the small ones dominate in number), a few at exactly 1 and ratio.
Disks random_disks(std::size_t n, double ratio, double density, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Disks d;
  double area = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double r = std::exp(std::log(ratio) * u(rng));
    if (i == 0) r = ratio;
    if (i == 1) r = 1.0;
    d.r.push_back(r);
    d.rmax = std::max(d.rmax, r);
    area += 3.14159 * r * r;
  }
  const double L = std::sqrt(area / density);
  for (std::size_t i = 0; i < n; ++i) {
    d.x.push_back(-0.3 * L + L * u(rng));  // origin away from 0
    d.y.push_back(5.0 + L * u(rng));
  }
  return d;
}

Pairs brute_force(const Disks& d, double skin) {
  Pairs p;
  for (std::uint32_t i = 0; i < d.x.size(); ++i)
    for (std::uint32_t j = i + 1; j < d.x.size(); ++j) {
      const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i], s = d.r[i] + d.r[j] + skin;
      if (dx * dx + dy * dy < s * s) p.emplace_back(i, j);
    }
  return p;
}

/// Pairs through a grid, with the query reach r_i + r_max + skin of the file comment.
template <class Grid>
Pairs through_grid(const Grid& g, const Disks& d, double skin) {
  Pairs p;
  for (std::uint32_t i = 0; i < d.x.size(); ++i)
    g.for_each_near(d.x[i], d.y[i], d.r[i] + d.rmax + skin, [&](std::uint32_t j) {
      if (j <= i) return;
      const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i], s = d.r[i] + d.r[j] + skin;
      if (dx * dx + dy * dy < s * s) p.emplace_back(i, j);
    });
  std::sort(p.begin(), p.end());
  return p;
}

TEST(CellGrid, NeighboursEqualAllPairsOnPolydisperseSets) {
  std::size_t checked = 0;
  for (double ratio : {1.0, 1.2, 10.0, 100.0})
    for (std::size_t n : {2u, 17u, 300u, 1500u})
      for (double skin_factor : {0.0, 0.3})
        for (std::uint64_t seed : {1u, 2u, 3u}) {
          const Disks d = random_disks(n, ratio, 0.7, seed + 10 * n);
          const double skin = skin_factor;  // radii >= 1
          const Pairs want = brute_force(d, skin);
          // several cell sizes: the documented 2 r_max + skin, smaller than a disk, huge
          for (double cell : {2.0 * d.rmax + skin, 0.5, 1e9}) {
            const CellGrid g(d.x, d.y, cell);
            EXPECT_EQ(through_grid(g, d, skin), want) << "ratio " << ratio << " n " << n << " seed " << seed;
            EXPECT_LE(g.layout().cells(), 4 * static_cast<long>(n) + 64);
          }
          checked += want.size();
        }
  EXPECT_GT(checked, 10000u);  // the sets are dense enough to have many pairs
}

TEST(CellGrid, GrowingGridEqualsAllPairs) {
  for (double ratio : {1.0, 100.0})
    for (std::uint64_t seed : {4u, 5u}) {
      const Disks d = random_disks(800, ratio, 0.6, seed);
      const auto [xlo, xhi] = std::minmax_element(d.x.begin(), d.x.end());
      const auto [ylo, yhi] = std::minmax_element(d.y.begin(), d.y.end());
      // a layout smaller than the points' extent: outside points go to the edge cells
      const GridLayout layout = GridLayout::fit({*xlo + 10, *ylo + 10}, {*xhi - 10, *yhi - 10}, 2.0 * d.rmax, 1e9);
      GrowingCellGrid g(layout);
      for (std::uint32_t i = 0; i < d.x.size(); ++i) g.insert(i, d.x[i], d.y[i]);
      EXPECT_EQ(g.size(), d.x.size());
      for (double skin : {0.0, 0.3}) EXPECT_EQ(through_grid(g, d, skin), brute_force(d, skin));
    }
}

TEST(CellGrid, GrowingGridAnswersAsItGrows) {
  // incremental use (placement): after each insert, the overlap test equals brute force
  const Disks d = random_disks(400, 10.0, 0.5, 7);
  GrowingCellGrid g(GridLayout::fit({-200, -200}, {400, 400}, 2.0 * d.rmax, 1e9));
  for (std::uint32_t i = 0; i < d.x.size(); ++i) {
    auto overlaps = [&](std::uint32_t k) { return std::hypot(d.x[i] - d.x[k], d.y[i] - d.y[k]) < d.r[i] + d.r[k]; };
    bool brute = false;
    for (std::uint32_t k = 0; k < i; ++k) brute = brute || overlaps(k);
    EXPECT_EQ(g.any_near(d.x[i], d.y[i], d.r[i] + d.rmax, overlaps), brute) << i;
    g.insert(i, d.x[i], d.y[i]);
  }
}

TEST(CellGrid, RebuildReusesStorageAndFollowsMovingPoints) {
  Disks d = random_disks(1000, 2.0, 0.7, 9);
  CellGrid g;
  g.rebuild(d.x, d.y, 2.0 * d.rmax + 0.3);
  EXPECT_EQ(through_grid(g, d, 0.3), brute_force(d, 0.3));
  std::mt19937_64 rng(3);
  std::normal_distribution<double> step(0.0, 0.2);
  for (int rebuild = 0; rebuild < 5; ++rebuild) {
    for (std::size_t i = 0; i < d.x.size(); ++i) {
      d.x[i] += step(rng);
      d.y[i] += step(rng);
    }
    g.rebuild(d.x, d.y, 2.0 * d.rmax + 0.3);
    EXPECT_EQ(through_grid(g, d, 0.3), brute_force(d, 0.3)) << rebuild;
  }
  // a smaller set after a larger one
  d.x.resize(10);
  d.y.resize(10);
  d.r.resize(10);
  g.rebuild(d.x, d.y, 2.0 * d.rmax);
  EXPECT_EQ(g.size(), 10u);
  EXPECT_EQ(through_grid(g, d, 0.0), brute_force(d, 0.0));
  g.rebuild({}, {}, 1.0);
  int visited = 0;
  g.for_each_near(0, 0, 1e9, [&](std::uint32_t) { ++visited; });
  EXPECT_EQ(visited, 0);
}

TEST(CellGrid, WarmRebuildAllocatesNothing) {
  Disks d = random_disks(2000, 3.0, 0.7, 11);
  CellGrid g;
  g.rebuild(d.x, d.y, 2.0 * d.rmax + 0.3);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> step(-0.2, 0.2);
  for (std::size_t i = 0; i < d.x.size(); ++i) {  // the points move
    d.x[i] += step(rng);
    d.y[i] += step(rng);
  }
  g.rebuild(d.x, d.y, 2.0 * d.rmax + 0.3);  // warm at the moved extent (the cell count may grow once)
  const std::size_t before = g_allocations;
  for (int k = 0; k < 5; ++k) g.rebuild(d.x, d.y, 2.0 * d.rmax + 0.3);
  EXPECT_EQ(g_allocations, before);  // the DEM rebuilds its Verlet table's grid this way
  std::size_t visited = 0;
  g.for_each_near(d.x[7], d.y[7], 10.0, [&](std::uint32_t) { ++visited; });
  EXPECT_EQ(g_allocations, before);
  EXPECT_GT(visited, 0u);
}

TEST(CellGrid, SparseSetsAreCapped) {
  // two disks a million diameters apart: ~4 N cells, not 10^12
  const std::vector<double> x{0.0, 1e6, 5e5}, y{0.0, 1e6, 3.0};
  const CellGrid g(x, y, 1.0);
  EXPECT_LE(g.layout().cells(), 4 * 3 + 64);
  EXPECT_GE(g.layout().cell[0], 1.0);
  std::vector<std::uint32_t> near;
  g.for_each_near(5e5, 3.0, 1.0, [&](std::uint32_t j) { near.push_back(j); });
  EXPECT_NE(std::find(near.begin(), near.end(), 2u), near.end());
}

TEST(CellGrid, NonFiniteCoordinatesDoNotCrash) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const std::vector<double>& x : {std::vector<double>{0, nan, 1, 2}, std::vector<double>{nan, 0, 1, 2},
                                       std::vector<double>{0, inf, 1, -inf}}) {
    const std::vector<double> y{0, 0, 1, nan};
    const CellGrid g(x, y, 1.0);
    EXPECT_EQ(g.size(), 4u);
    std::vector<std::uint32_t> all;
    g.for_each_near(0.5, 0.5, inf, [&](std::uint32_t j) { all.push_back(j); });  // infinite reach: every cell
    std::sort(all.begin(), all.end());
    EXPECT_EQ(all, (std::vector<std::uint32_t>{0, 1, 2, 3}));
    // finite points still find each other
    bool found = false;
    g.for_each_near(0.0, 0.0, 2.0, [&](std::uint32_t j) { found = found || j == 2; });
    EXPECT_TRUE(found);
    g.for_each_near(nan, nan, nan, [](std::uint32_t) {});  // a NaN query visits some cell, no crash
  }
  const CellGrid bad(std::vector<double>{0, 1}, std::vector<double>{0, 1}, nan);  // NaN cell size: cell 1
  EXPECT_EQ(bad.layout().cell[0], 1.0);
}

TEST(CellGrid, VisitsRowsThenColumnsThenIndexOrder) {
  // 3 x 2 cells of side 1 from the lower corner (0.2, 0.1) of the points: row 0 holds 2, 4 | 3, 5,
  // row 1 holds 1 | - | 0
  const std::vector<double> x{2.5, 0.5, 0.2, 1.5, 0.7, 2.1}, y{1.5, 1.5, 0.5, 0.5, 0.5, 0.1};
  const CellGrid g(x, y, 1.0);
  ASSERT_EQ(g.layout().count[0], 3);
  ASSERT_EQ(g.layout().count[1], 2);
  std::vector<std::uint32_t> order;
  g.for_each_in(0, 3, 0, 2, [&](std::uint32_t j) { order.push_back(j); });
  EXPECT_EQ(order, (std::vector<std::uint32_t>{2, 4, 3, 5, 1, 0}));
  GrowingCellGrid h(g.layout());
  for (std::uint32_t i : {4u, 0u, 2u, 1u, 5u, 3u}) h.insert(i, x[i], y[i]);
  order.clear();
  h.for_each_in(0, 3, 0, 2, [&](std::uint32_t j) { order.push_back(j); });
  EXPECT_EQ(order, (std::vector<std::uint32_t>{4, 2, 5, 3, 1, 0}));  // insertion order within a cell
}

}  // namespace
