// Tests for netdem::packing: ballistic deposition (Redanz & Fleck 2001, section 2.2), packing
// queries (section 2.4 peripheral layer) and CSV I/O.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"

namespace {

using netdem::packing::Box;
using netdem::packing::DepositionOptions;
using netdem::packing::Packing;
namespace fs = std::filesystem;

DepositionOptions options(double width, double r_min, double r_max, std::uint64_t seed, double height = -1.0) {
  DepositionOptions o;
  o.width = width;
  o.height = height;
  o.r_min = r_min;
  o.r_max = r_max;
  o.seed = seed;
  return o;
}

Packing deposit(double width, double r_min, double r_max, std::uint64_t seed, double height = -1.0) {
  return netdem::packing::ballistic_deposition(options(width, r_min, r_max, seed, height));
}

/// Independent check that every disk i rests, given the disks deposited before it (ids < i), the
/// side walls and the floor: contacts within `rel` relative gap; statically admissible under
/// gravity without friction, i.e. a floor contact, or two contact normals n_a, n_b with
/// (0,1) = a n_a + b n_b, a, b >= 0 (for supports below the centre: the centre's x lies between
/// the two support points; for a wall and a disk: the disk on the far side). Returns "" or the
/// first failure.
std::string check_every_disk_rests(const Packing& p, double rel = 1e-9) {
  struct N2 {
    double x, y;
  };
  std::vector<N2> n;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double xi = p.x[i], yi = p.y[i], ri = p.r[i];
    if (yi - ri - p.box.y_min <= rel * ri) continue;  // on the floor
    n.clear();
    for (std::size_t j = 0; j < i; ++j) {
      const double dx = xi - p.x[j], dy = yi - p.y[j], d = std::hypot(dx, dy);
      if (d <= (ri + p.r[j]) * (1 + rel)) n.push_back({dx / d, dy / d});
    }
    if (xi - ri - p.box.x_min <= rel * ri) n.push_back({1, 0});
    if (p.box.x_max - xi - ri <= rel * ri) n.push_back({-1, 0});
    bool ok = false;
    for (std::size_t a = 0; a < n.size() && !ok; ++a)
      for (std::size_t b = a + 1; b < n.size() && !ok; ++b) {
        const double det = n[a].x * n[b].y - n[a].y * n[b].x;
        if (std::fabs(det) < 1e-12) continue;
        const double ca = -n[b].x / det, cb = n[a].x / det;
        ok = ca >= -1e-9 && cb >= -1e-9;
      }
    if (!ok) {
      std::ostringstream s;
      s << "disk " << i << " at (" << xi << ", " << yi << ") r " << ri << " has " << n.size()
        << " contacts with earlier disks/walls and is not held against gravity";
      return s.str();
    }
  }
  return {};
}

double max_overlap_all_pairs(const Packing& p) {
  double worst = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j)
      worst = std::max(worst, p.r[i] + p.r[j] - std::hypot(p.x[i] - p.x[j], p.y[i] - p.y[j]));
  return worst;
}

std::string first_disk_outside(const Packing& p, double eps) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i];
    if (p.x[i] - r < p.box.x_min - eps || p.x[i] + r > p.box.x_max + eps || p.y[i] - r < p.box.y_min - eps ||
        p.y[i] + r > p.box.y_max + eps)
      return "disk " + std::to_string(i) + " is not inside the box";
  }
  return {};
}

/// Checks every deposition invariant on one packing.
void expect_valid_deposit(const Packing& p, double reference_radius, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_GT(p.size(), 0u);
  EXPECT_NO_THROW(netdem::packing::validate(p));
  EXPECT_EQ(first_disk_outside(p, 1e-12 * reference_radius), "");
  EXPECT_LE(max_overlap_all_pairs(p), 1e-9 * reference_radius);
  EXPECT_EQ(check_every_disk_rests(p), "");
}

Packing square_lattice(int nx, int ny, double r, Box box) {
  Packing p;
  p.box = box;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      p.x.push_back(box.x_min + r * (2 * i + 1));
      p.y.push_back(box.y_min + r * (2 * j + 1));
      p.r.push_back(r);
    }
  return p;
}

void add_disk(Packing& p, double x, double y, double r) {
  p.x.push_back(x);
  p.y.push_back(y);
  p.r.push_back(r);
}

/// EXPECT that f() throws E whose message contains `needle`.
template <class E, class F>
void expect_throw_with(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one containing '" << needle << "'";
  } catch (const E& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(needle), std::string::npos) << "message: " << msg << "\nexpected to contain: " << needle;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type, message: " << e.what();
  }
}

struct MeanStd {
  double mean = 0, std = 0;
};
MeanStd mean_std(const std::vector<double>& v) {
  MeanStd m;
  for (double a : v) m.mean += a;
  m.mean /= static_cast<double>(v.size());
  for (double a : v) m.std += (a - m.mean) * (a - m.mean);
  m.std = v.size() > 1 ? std::sqrt(m.std / static_cast<double>(v.size() - 1)) : 0.0;
  return m;
}

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("netdem_packing_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path f = path_ / name;
    std::ofstream(f, std::ios::binary) << text;
    return f;
  }

 private:
  fs::path path_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Deposition
// ---------------------------------------------------------------------------------------------

TEST(Ballistic, DeterministicForSeedAndSensitiveToIt) {
  for (double r_min : {1.0, 0.9}) {
    const double r_max = r_min == 1.0 ? 1.0 : 1.1;
    const Packing a = deposit(40, r_min, r_max, 7), b = deposit(40, r_min, r_max, 7);
    const Packing c = deposit(40, r_min, r_max, 8);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_TRUE(a.x == b.x && a.y == b.y && a.r == b.r) << "same seed must give a bitwise identical packing";
    EXPECT_EQ(a.seed, 7u);
    EXPECT_FALSE(a.size() == c.size() && a.x == c.x && a.y == c.y && a.r == c.r) << "seeds 7 and 8 gave the same packing";
  }
}

TEST(Ballistic, DocumentedDrawOrder) {
  // The first disk falls straight to the floor, so it exposes the draws: radius, then abscissa,
  // u -> (u >> 11) 2^-53 from std::mt19937_64 (whose output sequence is fixed by the standard).
  auto u01 = [](std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; };
  {
    const Packing p = deposit(80, 1.0, 1.0, 42);  // monosized: no radius draw
    std::mt19937_64 g(42);
    EXPECT_EQ(p.x[0], 1.0 + 78.0 * u01(g));
    EXPECT_EQ(p.y[0], 1.0);
  }
  {
    DepositionOptions o = options(80, 0.9, 1.1, 42);
    o.radius = 2.0;  // box [0, 160] x [0, 160], radii in [1.8, 2.2]
    const Packing p = netdem::packing::ballistic_deposition(o);
    std::mt19937_64 g(42);
    const double r = 2.0 * (0.9 + (1.1 - 0.9) * u01(g));
    EXPECT_EQ(p.r[0], r);
    EXPECT_EQ(p.x[0], r + (160.0 - 2 * r) * u01(g));
    EXPECT_EQ(p.y[0], r);
    EXPECT_EQ(p.box.x_max, 160.0);
    EXPECT_EQ(p.box.y_max, 160.0);
  }
}

TEST(Ballistic, EveryDiskRestsNoOverlapInsideBox) {
  // the paper's box, both size distributions, a few seeds
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    expect_valid_deposit(deposit(80, 1.0, 1.0, seed), 1.0, "monosized W=80 seed " + std::to_string(seed));
    expect_valid_deposit(deposit(80, 0.9, 1.1, seed), 1.0, "r=[0.9,1.1] W=80 seed " + std::to_string(seed));
  }
  // narrow boxes (walls everywhere), wide size ratios (large rolls, small disks under big ones),
  // a non-unit reference radius and a non-square box
  for (double w : {2.0, 2.5, 3.0, 4.0, 5.0, 7.3})
    expect_valid_deposit(deposit(w, 1.0, 1.0, 5, 30), 1.0, "monosized W=" + std::to_string(w));
  for (double w : {2.3, 3.0, 4.4, 6.0})
    expect_valid_deposit(deposit(w, 0.9, 1.1, 5, 30), 1.0, "r=[0.9,1.1] W=" + std::to_string(w));
  for (std::uint64_t seed : {1u, 2u}) {
    expect_valid_deposit(deposit(30, 0.5, 1.5, seed), 1.0, "r=[0.5,1.5] seed " + std::to_string(seed));
    expect_valid_deposit(deposit(30, 0.2, 1.0, seed), 1.0, "r=[0.2,1.0] seed " + std::to_string(seed));
  }
  DepositionOptions o = options(20, 0.9, 1.1, 3, 50);
  o.radius = 0.37;
  expect_valid_deposit(netdem::packing::ballistic_deposition(o), 0.37, "R=0.37, 20 x 50");
}

TEST(Ballistic, SingleColumnInBoxOfOneDiameter) {
  // W = 2R: every disk falls onto the previous one; exactly on top of it, pinned by both walls.
  DepositionOptions o = options(2, 1.0, 1.0, 3, 21);
  o.radius = 2.5;
  const Packing p = netdem::packing::ballistic_deposition(o);
  ASSERT_EQ(p.size(), 10u);  // floor(21 / 2)
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(p.x[i], 2.5);
    EXPECT_NEAR(p.y[i], 2.5 * static_cast<double>(2 * i + 1), 1e-12);
  }
}

TEST(Ballistic, ZigzagColumnInBoxOfThreeRadii) {
  // W = 3R, monosized: from the third disk on, each disk lands on the previous one (which touches
  // a wall), rolls to the opposite wall and rests on (disk, wall) exactly sqrt(3) R higher, since
  // the centres are R apart horizontally and 2R apart.
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const double R = 1.7;
    DepositionOptions o = options(3, 1.0, 1.0, seed, 60);
    o.radius = R;
    const Packing p = netdem::packing::ballistic_deposition(o);
    ASSERT_GE(p.size(), 20u);
    EXPECT_NEAR(p.y[0], R, 1e-15);
    for (std::size_t i = 1; i < p.size(); ++i) {
      const bool left = std::fabs(p.x[i] - R) < 1e-12 * R, right = std::fabs(p.x[i] - 2 * R) < 1e-12 * R;
      EXPECT_TRUE(left || right) << "disk " << i << " x = " << p.x[i];
      EXPECT_NEAR(std::hypot(p.x[i] - p.x[i - 1], p.y[i] - p.y[i - 1]), 2 * R, 1e-12 * R);
      if (i >= 2) {
        EXPECT_NEAR(std::fabs(p.x[i] - p.x[i - 1]), R, 1e-12 * R) << "disk " << i;
        EXPECT_NEAR(p.y[i] - p.y[i - 1], std::sqrt(3.0) * R, 1e-12 * R) << "disk " << i;
      }
    }
    // full: the next zigzag disk would poke through the lid
    EXPECT_GT(p.y.back() + std::sqrt(3.0) * R + R, 60 * R);
  }
}

TEST(Ballistic, DropDiskAnalyticCases) {
  using netdem::packing::drop_disk;
  const double s3 = std::sqrt(3.0);
  auto expect_at = [](std::pair<double, double> got, double x, double y, const char* what, double tol = 1e-13) {
    EXPECT_NEAR(got.first, x, tol) << what;
    EXPECT_NEAR(got.second, y, tol) << what;
  };
  {  // onto two touching disks: the pocket, sqrt(3) R above them, wherever it lands
    Packing p = square_lattice(1, 1, 1.0, {0, 0, 30, 30});
    p.x[0] = 10;
    add_disk(p, 12, 1, 1);
    for (double x0 : {10.0 + 1e-9, 10.3, 11.7, 12.0 - 1e-9}) expect_at(drop_disk(p, x0, 1.0), 11, 1 + s3, "pocket");
    // landing 1e-12 off the pocket centre: both contacts are within the contact tolerance at
    // first touch, so it rests there, 1e-12 off (contacts exact to ~1e-12)
    expect_at(drop_disk(p, 11.0 - 1e-12, 1.0), 11, 1 + s3, "pocket centre", 2e-12);
    // a smaller disk: centre 1.5 from both, i.e. sqrt(1.5^2 - 1) above
    expect_at(drop_disk(p, 10.4, 0.5), 11, 1 + std::sqrt(1.25), "small disk in the pocket");
  }
  {  // falls off a single disk at its equator, then rests on the floor beside it
    Packing p = square_lattice(1, 1, 1.0, {0, 0, 30, 30});
    p.x[0] = 10;
    expect_at(drop_disk(p, 10.5, 1.0), 12, 1, "off to the right");
    expect_at(drop_disk(p, 9.99, 1.0), 8, 1, "off to the left");
    expect_at(drop_disk(p, 10.0, 1.0), 12, 1, "exactly on top, no wall: rolls to +x");
    // a large disk over a small one on the floor reaches the floor before the equator
    Packing q = square_lattice(1, 1, 0.5, {0, 0, 30, 30});
    q.x[0] = 10;
    expect_at(drop_disk(q, 10.2, 1.5), 10 + std::sqrt(4.0 - 1.0), 1.5, "big over small");
  }
  {  // rolls into the right wall: rests on (disk, wall)
    Packing p = square_lattice(1, 1, 1.0, {0, 0, 10, 30});
    p.x[0] = 8.5;
    expect_at(drop_disk(p, 8.8, 1.0), 9, 1 + std::sqrt(3.75), "disk + wall");
  }
  {  // exactly on top of a disk touching the right wall: unstable, rolls off away from the wall
    Packing p = square_lattice(1, 1, 1.0, {0, 0, 10, 30});
    p.x[0] = 9;
    expect_at(drop_disk(p, 9.0, 1.0), 7, 1, "top of a wall disk");
  }
  {  // rolls off a disk exactly at the wall, slides down the wall onto another disk
    Packing p = square_lattice(1, 1, 1.0, {0, 0, 10, 30});
    p.x[0] = 8.2;
    add_disk(p, 7, 6, 1);  // a fixed obstacle (need not be stable itself)
    expect_at(drop_disk(p, 7.5, 1.0), 9, 1 + std::sqrt(4 - 0.64), "slide down the wall");
  }
  {  // rolls over one disk onto the next and down into the floor pocket between them and a third
    Packing p = square_lattice(1, 1, 1.0, {0, 0, 30, 30});
    p.x[0] = 10;
    add_disk(p, 11, 1 + s3, 1);  // on the pocket of (10, 1) and (12, 1)
    add_disk(p, 12, 1, 1);
    add_disk(p, 16.5, 1, 1);
    // over the top disk to the right until it touches (12, 1): its centre is then right of both
    // supports, so it rolls on over (12, 1), falls off its equator at (14, 1): the floor.
    expect_at(drop_disk(p, 11.2, 1.0), 14, 1, "roll over two disks");
  }
  {  // boxes not at the origin behave the same
    Packing p = square_lattice(2, 1, 1.0, {-50, 7, -20, 40});
    expect_at(drop_disk(p, -48.5, 1.0), -48, 8 + s3, "shifted box");
  }
  Packing p = square_lattice(1, 1, 1.0, {0, 0, 10, 10});
  expect_throw_with<std::invalid_argument>([&] { (void)drop_disk(p, 0.5, 1.0); }, "x0 = 0.5 is not in");
  expect_throw_with<std::invalid_argument>([&] { (void)drop_disk(p, 5, -1.0); }, "radius must be > 0");
}

TEST(Ballistic, MonosizedLatticeContactsStayExact) {
  // Monosized disks meet gaps of exactly one diameter (exact up to rounding). If such a disk
  // "bridged" the gap at ~1e-8 R above the equators instead of falling through, rounding would be
  // amplified through the crystal and lattice contacts would open by 1e-8..1e-7 (45 pairs on seed
  // 1 before this was handled). Contacts must be exact (<= 1e-12) or clearly open; on these seeds
  // no genuine gap falls in between (genuine near-misses do exist on other seeds, e.g. 5e-6 R).
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Packing p = deposit(80, 1.0, 1.0, seed);
    std::size_t exact = 0, in_window = 0;
    for (auto [i, j] : netdem::packing::touching_pairs(p, 1e-6)) {
      const auto a = static_cast<std::size_t>(i), b = static_cast<std::size_t>(j);
      const double rel = std::hypot(p.x[a] - p.x[b], p.y[a] - p.y[b]) / (p.r[a] + p.r[b]) - 1;
      if (std::fabs(rel) <= 1e-12) ++exact;
      else ++in_window;
    }
    EXPECT_EQ(in_window, 0u) << "seed " << seed;
    EXPECT_GT(exact, 3000u) << "seed " << seed;
  }
}

TEST(Ballistic, OptionsValidation) {
  using netdem::packing::ballistic_deposition;
  auto bad = [](auto mutate, const std::string& needle) {
    DepositionOptions o;
    mutate(o);
    expect_throw_with<std::invalid_argument>([&] { o.validate(); }, needle);
    expect_throw_with<std::invalid_argument>([&] { (void)ballistic_deposition(o); }, needle);
  };
  bad([](DepositionOptions& o) { o.radius = -1; }, "reference radius must be > 0");
  bad([](DepositionOptions& o) { o.r_min = -0.5; }, "r_min must be > 0");
  bad([](DepositionOptions& o) { o.r_min = 1.2; }, "r_min = 1.2 exceeds r_max = 1.1");
  bad([](DepositionOptions& o) { o.width = 2.1; }, "width 2.1 is smaller than the largest diameter");
  bad([](DepositionOptions& o) { o.height = 1.0; }, "height 1 is smaller than the largest diameter");
  bad([](DepositionOptions& o) { o.width = std::nan(""); }, "width must be finite");
  bad([](DepositionOptions& o) { o.r_max = std::numeric_limits<double>::infinity(); }, "r_max must be finite");
  bad([](DepositionOptions& o) { o.max_rejections = 0; }, "max_rejections must be >= 1");
  EXPECT_NO_THROW(DepositionOptions{}.validate());
}

TEST(Ballistic, StatisticsOverTenSeedsVersusPaperFig3) {
  // Paper, section 2.2 / Fig 3, square box W = 80R: monosized 1683 nodes, 3279 elements,
  // D0 = 0.823; r = R[0.9, 1.1] 1644 nodes, 3183 elements, D0 = 0.814.
  //
  // Two conventions are measured on the same deposition process (see docs/packing.md):
  //  * "ours" (the library default): disks entirely inside [0,80]^2, D = sum(pi r^2) / 80^2;
  //  * "paper": deposit into a taller box and count every disk that reaches into [0,80]^2
  //    (y - r < 80), D = their total area / 80^2 -- this reproduces the paper's N and D0.
  struct Case {
    const char* name;
    double r_min, r_max, n, elements, d0;
  };
  const Case cases[] = {{"monosized r = R", 1.0, 1.0, 1683, 3279, 0.823},
                        {"r = R[0.9, 1.1]", 0.9, 1.1, 1644, 3183, 0.814}};
  std::printf("\n10 seeds (1..10), W = H = 80R; mean +- std (sample)\n");
  std::printf("%-16s %-6s %16s %16s %14s %16s %16s\n", "case", "conv.", "N", "disk contacts", "wall contacts",
              "D0", "Z (walls excl.)");
  for (const Case& c : cases) {
    std::vector<double> n, dc, wc, d, z, pn, pdc, pd, pz;
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      const Packing p = deposit(80, c.r_min, c.r_max, seed);
      const auto s = netdem::packing::contact_stats(p, 1e-9);
      n.push_back(static_cast<double>(s.particles));
      dc.push_back(static_cast<double>(s.disk_contacts));
      wc.push_back(static_cast<double>(s.wall_contacts));
      d.push_back(s.density);
      z.push_back(s.coordination);
      // The process is causal (later disks never move earlier ones), so the disks reaching below
      // y = 80 in a 90R-tall deposit are those of an unbounded one.
      const Packing tall = deposit(80, c.r_min, c.r_max, seed, 90);
      Packing q;
      q.box = {0, 0, 80, 80};
      for (std::size_t i = 0; i < tall.size(); ++i)
        if (tall.y[i] - tall.r[i] < 80) add_disk(q, tall.x[i], tall.y[i], tall.r[i]);
      const auto qs = netdem::packing::contact_stats(q, 1e-9);
      pn.push_back(static_cast<double>(qs.particles));
      pdc.push_back(static_cast<double>(qs.disk_contacts));
      pd.push_back(qs.density);
      pz.push_back(qs.coordination);
    }
    const auto row = [&](const char* conv, const std::vector<double>& vn, const std::vector<double>& vdc,
                         const std::vector<double>* vwc, const std::vector<double>& vd, const std::vector<double>& vz) {
      const MeanStd a = mean_std(vn), b = mean_std(vdc), e = mean_std(vd), f = mean_std(vz);
      char walls[32] = "-";
      if (vwc) std::snprintf(walls, sizeof walls, "%.1f +- %.1f", mean_std(*vwc).mean, mean_std(*vwc).std);
      std::printf("%-16s %-6s %8.1f +- %5.1f %8.1f +- %5.1f %14s %8.4f +- %.4f %7.3f +- %.3f\n", c.name, conv, a.mean,
                  a.std, b.mean, b.std, walls, e.mean, e.std, f.mean, f.std);
    };
    row("ours", n, dc, &wc, d, z);
    row("paper", pn, pdc, nullptr, pd, pz);
    std::printf("%-16s %-6s %8.0f %8s %8.0f %8s %14s %8.3f %9s %7.3f\n", c.name, "Fig3", c.n, "", c.elements, "", "-",
                c.d0, "", 2 * c.elements / c.n);

    SCOPED_TRACE(c.name);
    // ours: N within 5 %, Z in the expected band; D0 is lower than the paper's by the loose
    // layer under the lid (documented): asserted within 0.03, and below the paper convention.
    EXPECT_NEAR(mean_std(n).mean, c.n, 0.05 * c.n);
    EXPECT_GE(mean_std(z).mean, 3.8);
    EXPECT_LE(mean_std(z).mean, 4.05);
    EXPECT_NEAR(mean_std(d).mean, c.d0, 0.03);
    EXPECT_LT(mean_std(d).mean, mean_std(pd).mean - 0.005);
    // paper convention: N within 5 %, D0 within 0.015, Z in the band
    EXPECT_NEAR(mean_std(pn).mean, c.n, 0.05 * c.n);
    EXPECT_NEAR(mean_std(pd).mean, c.d0, 0.015);
    EXPECT_GE(mean_std(pz).mean, 3.8);
    EXPECT_LE(mean_std(pz).mean, 4.05);
    // per seed as well: monosized packings crystallise in patches (6 exact contacts per disk
    // there), so their Z scatters ~30x more than the dispersed one's (std 0.14 vs 0.004)
    const double z_lo = c.r_min == c.r_max ? 3.6 : 3.82, z_hi = c.r_min == c.r_max ? 4.5 : 3.95;
    for (std::size_t i = 0; i < n.size(); ++i) {
      EXPECT_GE(z[i], z_lo) << "seed " << i + 1;
      EXPECT_LE(z[i], z_hi) << "seed " << i + 1;
    }
  }
}

TEST(Ballistic, StopRuleFillsTheBox) {
  // Stopping at the first misfit leaves the top under-filled; the default (1000 consecutive
  // misfits) fills it: more disks, and more misfits change nothing measurable.
  DepositionOptions o = options(80, 0.9, 1.1, 4);
  o.max_rejections = 1;
  const auto first = netdem::packing::ballistic_deposition(o).size();
  o.max_rejections = 1000;
  const Packing full = netdem::packing::ballistic_deposition(o);
  o.max_rejections = 20000;
  const auto fuller = netdem::packing::ballistic_deposition(o).size();
  EXPECT_LT(first, full.size());
  EXPECT_LE(fuller - full.size(), 3u);
  // the first misfit-free prefix is shared: deposition is sequential
  const Packing prefix = [&] {
    DepositionOptions q = o;
    q.max_rejections = 1;
    return netdem::packing::ballistic_deposition(q);
  }();
  for (std::size_t i = 0; i < prefix.size(); ++i) ASSERT_EQ(prefix.x[i], full.x[i]);
}

TEST(Ballistic, CentreLidKeepsCentresInsideAndRaisesTheDensity) {
  // Lid::Centre: a disk is kept when its centre is below the lid, so the top layer may stick out
  // by less than a radius; the packing still validates and its density lies between the
  // whole-disk rule and the paper's convention (docs/packing.md).
  DepositionOptions o = options(80, 0.9, 1.1, 2);
  const Packing inside = netdem::packing::ballistic_deposition(o);
  o.lid = netdem::packing::Lid::Centre;
  const Packing centre = netdem::packing::ballistic_deposition(o);
  EXPECT_NO_THROW(netdem::packing::validate(centre));
  double top = 0.0;
  for (std::size_t i = 0; i < centre.size(); ++i) {
    ASSERT_LE(centre.y[i], centre.box.y_max);
    top = std::max(top, centre.y[i] + centre.r[i]);
  }
  EXPECT_GT(top, centre.box.y_max);  // some disk sticks out above the lid
  EXPECT_GT(centre.size(), inside.size());
  EXPECT_GT(centre.density(), inside.density() + 0.004);
  EXPECT_LT(centre.density(), 0.814 + 0.005);
}

TEST(Ballistic, LargeBoxIsFastAndValid) {
  const auto t0 = std::chrono::steady_clock::now();
  const Packing p = deposit(640, 0.9, 1.1, 1);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("W = 640R: %zu disks in %.3f s, D = %.4f\n", p.size(), s, p.density());
  EXPECT_GT(p.size(), 100000u);
  EXPECT_EQ(first_disk_outside(p, 1e-12), "");
  // overlaps via the cell list (all pairs is too slow here): no pair closer than (r_i + r_j)(1 - 1e-9)
  std::size_t overlapping = 0;
  for (auto [i, j] : netdem::packing::touching_pairs(p, 0.0)) {
    const auto a = static_cast<std::size_t>(i), b = static_cast<std::size_t>(j);
    if (std::hypot(p.x[a] - p.x[b], p.y[a] - p.y[b]) < (p.r[a] + p.r[b]) * (1 - 1e-9)) ++overlapping;
  }
  EXPECT_EQ(overlapping, 0u);
  const auto st = netdem::packing::contact_stats(p, 1e-9);
  EXPECT_GT(st.coordination, 3.9);
  EXPECT_LT(st.coordination, 4.05);
}

// ---------------------------------------------------------------------------------------------
// Queries
// ---------------------------------------------------------------------------------------------

TEST(Queries, TouchingPairsEqualsAllPairs) {
  const Packing p = deposit(40, 0.9, 1.1, 11);
  for (double tol : {0.0, 1e-9, 1e-6, 0.05, 0.5}) {
    std::vector<std::pair<int, int>> brute;
    for (std::size_t i = 0; i < p.size(); ++i)
      for (std::size_t j = i + 1; j < p.size(); ++j) {
        const double dx = p.x[i] - p.x[j], dy = p.y[i] - p.y[j], reach = (p.r[i] + p.r[j]) * (1 + tol);
        if (dx * dx + dy * dy <= reach * reach) brute.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    EXPECT_EQ(netdem::packing::touching_pairs(p, tol), brute) << "tol " << tol;
    if (tol == 1e-6) {
      EXPECT_GT(brute.size(), p.size());  // a real test: ~2 contacts per disk
    }
  }
  // a sparse set far from the origin, and degenerate sizes
  Packing s;
  s.box = {1e6, 1e6, 1e6 + 1e4, 1e6 + 1e4};
  add_disk(s, 1e6 + 10, 1e6 + 10, 1);
  add_disk(s, 1e6 + 12, 1e6 + 10, 1);
  add_disk(s, 1e6 + 9000, 1e6 + 9000, 1);
  EXPECT_EQ(netdem::packing::touching_pairs(s), (std::vector<std::pair<int, int>>{{0, 1}}));
  EXPECT_TRUE(netdem::packing::touching_pairs(Packing{}).empty());
}

TEST(Queries, ContactStatsOnSquareLattice) {
  // 6 x 4 touching disks filling [0,12] x [0,8]: 5*4 + 6*3 = 38 disk contacts; the left, right and
  // bottom walls touch 4 + 4 + 6 = 14 disks (the lid is not a wall contact).
  const Packing p = square_lattice(6, 4, 1.0, {0, 0, 12, 8});
  const auto s = netdem::packing::contact_stats(p);
  EXPECT_EQ(s.particles, 24u);
  EXPECT_EQ(s.disk_contacts, 38u);
  EXPECT_EQ(s.wall_contacts, 14u);
  EXPECT_DOUBLE_EQ(s.density, std::numbers::pi / 4);
  EXPECT_DOUBLE_EQ(s.coordination, 76.0 / 24.0);
  EXPECT_DOUBLE_EQ(p.solid_area(), 24 * std::numbers::pi);
  // default tolerance 1e-6 relative to r_i + r_j = 2: a gap of 1e-6 touches, 2.1e-5 does not
  Packing q = square_lattice(2, 1, 1.0, {0, 0, 10, 10});
  q.x[1] += 1e-6;
  EXPECT_EQ(netdem::packing::contact_stats(q).disk_contacts, 1u);
  q.x[1] += 2e-5;
  EXPECT_EQ(netdem::packing::contact_stats(q).disk_contacts, 0u);
}

TEST(Queries, PeripheralLayerOnHandMadeLattice) {
  // 8 x 5 square lattice (r = 1) in a box [0,16] x [0,20] (lid far above), plus two cap disks
  // resting in the top-row pockets at x = 4 and x = 6: they bury the top-row disk at x = 5.
  Packing p = square_lattice(8, 5, 1.0, {0, 0, 16, 20});
  const double cap_y = 9 + std::sqrt(3.0);
  add_disk(p, 4, cap_y, 1);
  add_disk(p, 6, cap_y, 1);
  const auto flag = netdem::packing::peripheral_layer(p);
  ASSERT_EQ(flag.size(), p.size());
  for (std::size_t k = 0; k < 40; ++k) {
    const int i = static_cast<int>(k % 8), j = static_cast<int>(k / 8);
    const bool wall = i == 0 || i == 7 || j == 0;
    const bool skyline = j == 4 && i != 2;  // x = 2i + 1; the disk at x = 5 is buried
    EXPECT_EQ(flag[k] != 0, wall || skyline) << "lattice disk (" << i << ", " << j << ")";
  }
  EXPECT_EQ(flag[40], 1);
  EXPECT_EQ(flag[41], 1);
  // a lid touching the top row flags it even under caps
  Packing q = square_lattice(8, 5, 1.0, {0, 0, 16, 10});
  const auto f2 = netdem::packing::peripheral_layer(q);
  for (std::size_t k = 32; k < 40; ++k) EXPECT_EQ(f2[k], 1);
  for (std::size_t k = 9; k < 15; ++k) EXPECT_EQ(f2[k], 0);
}

TEST(Queries, PeripheralLayerOnDepositMatchesSampledSkyline) {
  const Packing p = deposit(40, 0.9, 1.1, 21);
  const auto flag = netdem::packing::peripheral_layer(p);
  const double tol = 1e-6;
  // walls
  for (std::size_t i = 0; i < p.size(); ++i) {
    const bool wall = p.x[i] - p.r[i] <= tol * p.r[i] || 40 - p.x[i] - p.r[i] <= tol * p.r[i] ||
                      p.y[i] - p.r[i] <= tol * p.r[i] || 40 - p.y[i] - p.r[i] <= tol * p.r[i];
    if (wall) {
      EXPECT_EQ(flag[i], 1) << "wall disk " << i;
    }
  }
  // brute-force skyline on a fine sampling: the owner of every sample is flagged
  std::vector<std::uint8_t> sampled(p.size(), 0);
  double lowest_skyline = std::numeric_limits<double>::infinity();
  for (int s = 0; s < 40000; ++s) {
    const double x = (s + 0.5) * 40.0 / 40000;
    double best = -1;
    std::size_t owner = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double dx = std::fabs(x - p.x[i]);
      if (dx >= p.r[i]) continue;
      const double h = p.y[i] + std::sqrt(p.r[i] * p.r[i] - dx * dx);
      if (h > best) {
        best = h;
        owner = i;
      }
    }
    sampled[owner] = 1;
    lowest_skyline = std::min(lowest_skyline, best);
  }
  std::size_t top = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (sampled[i]) {
      ++top;
      EXPECT_EQ(flag[i], 1) << "skyline disk " << i;
    }
    // deep interior: not flagged
    const bool near_wall = p.x[i] < 3 || p.x[i] > 37 || p.y[i] < 3;
    if (!near_wall && p.y[i] + p.r[i] < lowest_skyline - 2.5) {
      EXPECT_EQ(flag[i], 0) << "interior disk " << i;
    }
  }
  EXPECT_GT(top, 15u);
  // and nothing else: every flagged disk is a wall/lid disk or owns part of the exact skyline
  // (the sampled one may miss slivers thinner than the sampling step, so compare counts loosely)
  std::size_t flagged_non_wall = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const bool wall = p.x[i] - p.r[i] <= tol * p.r[i] || 40 - p.x[i] - p.r[i] <= tol * p.r[i] ||
                      p.y[i] - p.r[i] <= tol * p.r[i] || 40 - p.y[i] - p.r[i] <= tol * p.r[i];
    if (flag[i] && !wall) {
      ++flagged_non_wall;
      EXPECT_TRUE(sampled[i] || p.y[i] + p.r[i] > lowest_skyline - 1e-3) << "flagged disk " << i << " is buried";
    }
  }
  EXPECT_GT(flagged_non_wall, 0u);
}

TEST(Queries, ValidateNamesTheFirstProblem) {
  using netdem::packing::validate;
  const Packing good = square_lattice(3, 2, 1.0, {0, 0, 6, 4});
  EXPECT_NO_THROW(validate(good));
  auto bad = [&](auto mutate, const std::string& needle) {
    Packing p = good;
    mutate(p);
    expect_throw_with<std::invalid_argument>([&] { validate(p); }, needle);
  };
  bad([](Packing& p) { p.x.clear(), p.y.clear(), p.r.clear(); }, "packing is empty");
  bad([](Packing& p) { p.r.pop_back(); }, "x, y, r have different sizes (6, 6, 5)");
  bad([](Packing& p) { p.box.x_max = -1; }, "box has non-positive size");
  bad([](Packing& p) { p.box.y_max = std::nan(""); }, "box has a non-finite bound");
  bad([](Packing& p) { p.x[4] = std::nan(""); }, "disk 4 has a non-finite coordinate");
  bad([](Packing& p) { p.y[2] = std::numeric_limits<double>::infinity(); }, "disk 2 has a non-finite coordinate");
  bad([](Packing& p) { p.r[3] = std::nan(""); }, "disk 3 has a non-finite radius");
  bad([](Packing& p) { p.r[1] = 0; }, "disk 1 has r <= 0");
  bad([](Packing& p) { p.r[5] = -1; }, "disk 5 has r <= 0");
  bad([](Packing& p) { p.x[3] = 6.5; }, "disk 3 is outside the box");
  bad([](Packing& p) { p.x[1] = p.x[4], p.y[1] = p.y[4]; }, "disk 4 duplicates disk 1");
  bad([](Packing& p) { p.r[1] = 0, p.x[0] = -5; }, "disk 0 is outside the box");  // first id wins
  // allowed: overlaps and a disk poking through a wall (compacted states)
  Packing ok = good;
  ok.x[1] -= 0.3;
  ok.x[0] -= 0.5;
  EXPECT_NO_THROW(validate(ok));
}

// ---------------------------------------------------------------------------------------------
// I/O
// ---------------------------------------------------------------------------------------------

TEST(PackingIO, RoundTripIsExact) {
  TempDir dir;
  Packing p = deposit(30, 0.9, 1.1, 99);
  p.comments = {"generated by test_packing", "second comment, with commas, and # signs", ""};
  p.x[0] = 0.1 + 0.2;  // not representable in few digits
  const fs::path f = dir.path() / "p.csv";
  netdem::packing::write_packing_csv(p, f);
  const Packing q = netdem::packing::read_packing_csv(f);
  EXPECT_EQ(q.x, p.x);
  EXPECT_EQ(q.y, p.y);
  EXPECT_EQ(q.r, p.r);
  EXPECT_EQ(q.seed, 99u);
  EXPECT_EQ(q.comments, p.comments);
  EXPECT_EQ(q.box.x_min, p.box.x_min);
  EXPECT_EQ(q.box.y_max, p.box.y_max);
  // overwrite in place; no temporary left behind
  p.seed = 0;
  p.comments.clear();
  netdem::packing::write_packing_csv(p, f);
  const Packing r = netdem::packing::read_packing_csv(f);
  EXPECT_EQ(r.seed, 0u);
  EXPECT_TRUE(r.comments.empty());
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1u);
  // the header lines as documented
  std::ifstream in(f);
  std::string l1, l2;
  std::getline(in, l1);
  std::getline(in, l2);
  EXPECT_EQ(l1, "# box 0 0 30 30");
  EXPECT_EQ(l2, "id,x,y,r");
}

TEST(PackingIO, WriteRefusesWhatCannotBeReadBack) {
  TempDir dir;
  Packing p = square_lattice(2, 2, 1.0, {0, 0, 4, 4});
  p.comments = {"line\nbreak"};
  expect_throw_with<std::invalid_argument>([&] { netdem::packing::write_packing_csv(p, dir.path() / "a.csv"); },
                                           "line break");
  p.comments = {"box 1 2 3 4"};
  expect_throw_with<std::invalid_argument>([&] { netdem::packing::write_packing_csv(p, dir.path() / "a.csv"); },
                                           "reserved word");
  p.comments.clear();
  p.r[0] = -1;
  expect_throw_with<std::invalid_argument>([&] { netdem::packing::write_packing_csv(p, dir.path() / "a.csv"); },
                                           "disk 0 has r <= 0");
  p.r[0] = 1;
  expect_throw_with<std::runtime_error>(
      [&] { netdem::packing::write_packing_csv(p, dir.path() / "no_such_dir" / "a.csv"); }, "cannot create");
  EXPECT_FALSE(fs::exists(dir.path() / "a.csv"));
}

TEST(PackingIO, ReadsHandMadeFiles) {
  TempDir dir;
  // ids in any order, padding, CRLF, blank lines, '+' signs, exponents, comments anywhere
  const fs::path f = dir.write("hand.csv",
                               "# a hand-made 2 x 2 lattice\r\n"
                               "#box   0 0   4 4  \r\n"
                               "\r\n"
                               "  id , x , y , r \r\n"
                               "3, 3, 3, 1\r\n"
                               "#   seed 17\r\n"
                               "1,3.0e0,+1,1.0\r\n"
                               " 0 ,\t1 , 1 , 1\r\n"
                               "\r\n"
                               "2,1,3,1");
  const Packing p = netdem::packing::read_packing_csv(f);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p.x, (std::vector<double>{1, 3, 1, 3}));
  EXPECT_EQ(p.y, (std::vector<double>{1, 1, 3, 3}));
  EXPECT_EQ(p.r, (std::vector<double>{1, 1, 1, 1}));
  EXPECT_EQ(p.seed, 17u);
  EXPECT_EQ(p.comments, (std::vector<std::string>{"a hand-made 2 x 2 lattice"}));
  EXPECT_EQ(p.box.x_max, 4.0);
  EXPECT_EQ(netdem::packing::contact_stats(p).disk_contacts, 4u);
}

TEST(PackingIO, MalformedFilesGiveSpecificErrors) {
  TempDir dir;
  const std::string head = "# box 0 0 10 10\nid,x,y,r\n";
  auto bad = [&](const std::string& name, const std::string& text, const std::string& needle) {
    SCOPED_TRACE(name);
    const fs::path f = dir.write(name, text);
    expect_throw_with<std::runtime_error>([&] { (void)netdem::packing::read_packing_csv(f); }, needle);
  };
  const std::string d = dir.path().string() + "/";
  expect_throw_with<std::runtime_error>([&] { (void)netdem::packing::read_packing_csv(dir.path() / "missing.csv"); },
                                        d + "missing.csv: cannot open file");
  bad("nobox.csv", "id,x,y,r\n0,1,1,1\n", d + "nobox.csv:2: missing '# box x_min y_min x_max y_max' line");
  bad("shortbox.csv", "# box 0 0 10\nid,x,y,r\n0,1,1,1\n", d + "shortbox.csv:1: box line must be");
  bad("textbox.csv", "# box 0 0 ten 10\nid,x,y,r\n0,1,1,1\n", d + "textbox.csv:1: box line: non-numeric field 'ten'");
  bad("flatbox.csv", "# box 0 0 10 0\nid,x,y,r\n0,1,1,1\n", d + "flatbox.csv:1: box line: box has non-positive size");
  bad("nanbox.csv", "# box 0 0 nan 10\nid,x,y,r\n0,1,1,1\n", d + "nanbox.csv:1: box line: NaN or infinite bound");
  bad("seed.csv", "# seed -3\n" + head + "0,1,1,1\n", d + "seed.csv:1: seed line must be");
  bad("header.csv", "# box 0 0 10 10\nid,x,y,radius\n0,1,1,1\n", d + "header.csv:2: bad header 'id,x,y,radius'");
  bad("noheader.csv", "# box 0 0 10 10\n0,1,1,1\n", d + "noheader.csv:2: bad header");
  bad("fields.csv", head + "0,1,1,1\n1,3,1\n", d + "fields.csv:4: expected 4 fields (id,x,y,r), got 3");
  bad("fields5.csv", head + "0,1,1,1,7\n", d + "fields5.csv:3: expected 4 fields (id,x,y,r), got 5");
  bad("text.csv", head + "0,1,1,1\n1,3,one,1\n", d + "text.csv:4: non-numeric y 'one'");
  bad("empty_field.csv", head + "0,1,,1\n", d + "empty_field.csv:3: non-numeric y ''");
  bad("id.csv", head + "x1,1,1,1\n", d + "id.csv:3: id 'x1' is not a non-negative integer");
  bad("nan.csv", head + "0,1,1,1\n1,NaN,1,1\n", d + "nan.csv:4: x is NaN (disk id 1)");
  bad("inf.csv", head + "0,1,inf,1\n", d + "inf.csv:3: y is inf (disk id 0)");
  bad("rzero.csv", head + "0,1,1,1\n1,3,3,0\n", d + "rzero.csv:4: r <= 0 (r = 0, disk id 1)");
  bad("rneg.csv", head + "0,1,1,-1\n", d + "rneg.csv:3: r <= 0");
  bad("outside.csv", head + "0,1,1,1\n1,3,3,1\n2,12,3,1\n", d + "outside.csv:5: disk id 2 is outside the box");
  bad("dupid.csv", head + "0,1,1,1\n0,3,3,1\n", d + "dupid.csv:4: duplicate id 0 (first on line 3)");
  bad("dupdisk.csv", head + "0,1,1,1\n1,1,1,1\n", "dupdisk.csv: invalid packing: disk 1 duplicates disk 0");
  bad("nodisks.csv", head, d + "nodisks.csv:2: no disks");
}
