// The packing reader's valid ranges and the geometry checks of validate() (issue 13, item 1;
// docs/packing.md "Valid ranges"): every limit is rejected with one line naming the file line and
// the quantity, valid polydisperse packings up to r_max / r_min = 100 pass, a 10^5-disk
// near-duplicate set is rejected quickly (cell grid), and the packing-side fixes of the fuzz
// findings (subnormal radius in peripheral_layer) hold for packings built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/random_fill.hpp"

namespace {

using netdem::packing::Box;
using netdem::packing::Packing;

Packing read_text(const std::string& text) {
  std::istringstream in(text);
  return netdem::packing::read_packing_csv(in, "t.csv");
}

/// The reader must throw std::runtime_error whose one-line message contains every needle.
void expect_read_error(const std::string& text, const std::vector<std::string>& needles) {
  try {
    (void)read_text(text);
    ADD_FAILURE() << "no exception; expected: " << needles.front();
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    for (const std::string& n : needles) EXPECT_NE(msg.find(n), std::string::npos) << "message: " << msg << "\nneedle: " << n;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  }
}

const std::string kHead = "# box 0 0 10 10\nid,x,y,r\n";

}  // namespace

TEST(PackingLimits, EachFieldRangeNamesTheLineAndTheQuantity) {
  expect_read_error(kHead + "0,5,5,1\n1,2,2,1e-300\n", {"t.csv:4:", "r = 1e-300", "disk id 1", "[1e-06, 1e+06]"});
  expect_read_error(kHead + "0,5,5,4.9e-324\n", {"t.csv:3:", "r = 5e-324", "[1e-06, 1e+06]"});
  expect_read_error(kHead + "0,5,5,9e-7\n", {"t.csv:3:", "r = 9e-07"});
  expect_read_error("# box 0 0 4e6 4e6\nid,x,y,r\n0,5,5,2e6\n", {"t.csv:1:", "box x_max = 4000000", "[-1e+06, 1e+06]"});
  expect_read_error("# box 0 0 1e6 1e6\nid,x,y,r\n0,5,5,1.5e6\n", {"t.csv:3:", "r = 1500000"});
  expect_read_error("# box 0 0 2e300 2e300\nid,x,y,r\n0,1e299,1e299,1\n", {"t.csv:1:", "box x_max = 2e+300"});
  expect_read_error("# box -2e6 0 10 10\nid,x,y,r\n0,5,5,1\n", {"t.csv:1:", "box x_min = -2000000"});
  expect_read_error(kHead + "0,5,5,1\n1,-3e6,5,1\n", {"t.csv:4:", "x = -3000000"});
  expect_read_error(kHead + "0,5,5,1\n1,5,1e7,1\n", {"t.csv:4:", "y = 10000000"});
  expect_read_error("# box 0 0 1e-7 10\nid,x,y,r\n0,0,5,1\n", {"t.csv:1:", "width 1e-07", "below 1e-06"});
  expect_read_error("# box 0 0 10 10\nid,x,y,r\n0,5,5,1\n1,8,8,0.5\n2,2,2,0.0099\n",
                    {"t.csv:3:", "r_max / r_min", "exceeds 100", "r_min on line 5"});
  expect_read_error(kHead + "0,5,5,1\n1,5.9,5,0.5\n", {"t.csv:3:", "disk id 0 and disk id 1 (line 4) are too close",
                                                        "centre distance 0.9", "max(r_i, r_j) = 1"});
  expect_read_error(kHead + "7,5,5,1\n3,5,5.5,2\n", {"t.csv:4:", "disk id 3 and disk id 7 (line 3)", "max(r_i, r_j) = 2"});
  // exact duplicates keep validate()'s wording, with both lines
  expect_read_error(kHead + "0,1,1,1\n1,1,1,1\n", {"t.csv: invalid packing: disk 1 duplicates disk 0", "lines 4 and 3"});
  // outside the box (unchanged criterion: the centre)
  expect_read_error(kHead + "0,1,1,1\n1,10.5,3,1\n", {"t.csv:4:", "disk id 1 is outside the box"});
}

TEST(PackingLimits, BoundariesOfTheRangesAreAccepted) {
  const Packing a = read_text("# box -1e6 -1e6 1e6 1e6\nid,x,y,r\n0,-1e6,1e6,1e6\n1,1e6,-1e6,1e6\n");
  EXPECT_EQ(a.size(), 2u);
  const Packing b = read_text("# box 0 0 1e-6 1e-6\nid,x,y,r\n0,5e-7,5e-7,1e-6\n");
  EXPECT_EQ(b.r[0], 1e-6);
  // centre distance exactly max(r_i, r_j) is allowed (a small disk centred on a big one's rim)
  const Packing c = read_text(kHead + "0,5,5,1\n1,6,5,0.5\n");
  EXPECT_EQ(c.size(), 2u);
}

TEST(PackingLimits, BinaryInputIsRefusedAndQuotedShortly) {
  expect_read_error(std::string("\x01\x02garbage\x7f\n", 11), {"t.csv:1:", "control character (byte 1) in column 1"});
  expect_read_error(kHead + std::string("0,5,5,1\0\n", 9), {"t.csv:3:", "control character (byte 0) in column 8"});
  // a 5 MB first line of printable junk: the message quotes at most 80 characters of it
  const std::string junk(5u << 20, 'A');
  try {
    (void)read_text(junk + "\n");
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_LT(msg.size(), 200u) << msg.substr(0, 300);
    EXPECT_NE(msg.find("t.csv:1: bad header 'AAAA"), std::string::npos) << msg;
    EXPECT_NE(msg.find("...'"), std::string::npos) << msg;
  }
  // non-printable bytes of a quoted field become '?'
  expect_read_error(kHead + "0,5,\xff\xfe,1\n", {"t.csv:3:", "non-numeric y '?" "?'"});
}

TEST(PackingLimits, DirectoryIsNamedAsSuch) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "packing_limits_dir";
  std::filesystem::create_directories(dir);
  try {
    (void)netdem::packing::read_packing_csv(dir);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory, not a packing file"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(PackingLimits, PolydispersePackingsUpToRatio100AreAccepted) {
  // random non-overlapping fills with r_max / r_min = 100 exactly, 10 and 1, round trip by file
  for (const double ratio : {1.0, 10.0, 100.0}) {
    std::mt19937_64 rng(7);
    std::vector<double> radii;
    for (int i = 0; i < 400; ++i) radii.push_back(i % 20 == 0 ? 1.0 : 1.0 / ratio);
    radii[1] = 1.0 / ratio;
    const Packing p = netdem::packing::random_fill(radii, Box{0, 0, 80, 80}, rng);
    EXPECT_NO_THROW(netdem::packing::validate(p)) << "ratio " << ratio;
    const auto file = std::filesystem::path(testing::TempDir()) / "limits_poly.csv";
    netdem::packing::write_packing_csv(p, file);
    const Packing q = netdem::packing::read_packing_csv(file);
    EXPECT_EQ(q.r, p.r);
    std::filesystem::remove(file);
  }
  // a deposited-like dense polydisperse set (radii 0.05 .. 5, touching lattice rows) passes too
  Packing d;
  d.box = {0, 0, 100, 100};
  for (int i = 0; i < 10; ++i) d.x.push_back(5 + 10 * i), d.y.push_back(5), d.r.push_back(5);
  for (int i = 0; i < 1000; ++i) d.x.push_back(0.05 + 0.1 * i), d.y.push_back(10.05), d.r.push_back(0.05);
  EXPECT_NO_THROW(netdem::packing::validate(d));
  d.r.back() = 0.0499;  // ratio 100.2
  try {
    netdem::packing::validate(d);
    ADD_FAILURE() << "ratio 100.2 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("r_max / r_min"), std::string::npos) << e.what();
  }
}

TEST(PackingLimits, ValidateRejectsPairsCloserThanTheLargerRadius) {
  Packing p;
  p.box = {0, 0, 10, 10};
  p.x = {2, 5, 5.9};
  p.y = {2, 5, 5};
  p.r = {1, 1, 0.5};
  try {
    netdem::packing::validate(p);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("disks 1 and 2 are too close: centre distance 0.9"), std::string::npos) << e.what();
  }
  p.x[2] = 6.0;  // exactly r_1 away: allowed (overlap 0.5, as strongly compacted states may have)
  EXPECT_NO_THROW(netdem::packing::validate(p));
}

TEST(PackingLimits, FindClosePairAgreesWithAllPairs) {
  // random polydisperse sets (ratios up to 100), some with planted close pairs
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Packing p;
    p.box = {0, 0, 30, 30};
    const int n = 50 + static_cast<int>(seed) * 7;
    const double ratio = seed % 3 == 0 ? 100.0 : (seed % 3 == 1 ? 10.0 : 1.5);
    for (int i = 0; i < n; ++i) {
      p.x.push_back(30 * u(rng));
      p.y.push_back(30 * u(rng));
      p.r.push_back(0.05 * (1 + (ratio - 1) * u(rng) * u(rng)));
    }
    bool any = false;
    for (int i = 0; i < n && !any; ++i)
      for (int j = 0; j < i && !any; ++j)
        any = std::hypot(p.x[i] - p.x[j], p.y[i] - p.y[j]) < std::max(p.r[i], p.r[j]);
    const auto c = netdem::packing::find_close_pair(p);
    ASSERT_EQ(c.has_value(), any) << "seed " << seed;
    if (c) {
      EXPECT_GE(p.r[c->i], p.r[c->j]);
      EXPECT_LT(std::hypot(p.x[c->i] - p.x[c->j], p.y[c->i] - p.y[c->j]), p.r[c->i]);
    }
  }
}

TEST(PackingLimits, HundredThousandNearDuplicatesAreRejectedQuickly) {
  // 10^5 disks within 1e-10 of each other (a 317 x 316 grid of spacing 3e-13, r = 0.01): all pairs
  // would take ~5e9 distance tests; the cell grid rejects the set after two scans of its cell.
  std::string text = "# box 0 0 1 1\nid,x,y,r\n";
  text.reserve(100000 * 48);
  char buf[96];
  for (int i = 0; i < 100000; ++i) {
    std::snprintf(buf, sizeof buf, "%d,%.17g,%.17g,0.01\n", i, 0.5 + (i % 317) * 3e-13, 0.5 + (i / 317) * 3e-13);
    text += buf;
  }
  const auto t0 = std::chrono::steady_clock::now();
  expect_read_error(text, {"t.csv:4:", "disk id 1 and disk id 0 (line 3) are too close"});
  Packing p;
  p.box = {0, 0, 1, 1};
  for (int i = 0; i < 100000; ++i) {
    p.x.push_back(0.5 + (i % 317) * 3e-13);
    p.y.push_back(0.5 + (i / 317) * 3e-13);
    p.r.push_back(0.01);
  }
  EXPECT_THROW(netdem::packing::validate(p), std::invalid_argument);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(s, 5.0) << "near-duplicate rejection took " << s << " s";
}

TEST(PackingLimits, PeripheralLayerWithSubnormalRadiusTerminates) {
  // issue 13: one radius 4.9e-324 made the bin width 0.5 r_min round to 0 and the loop spin
  Packing p;
  p.box = {0, 0, 10, 10};
  p.x = {1, 3, 5, 7.5};
  p.y = {1, 1, 1, 1};
  p.r = {1, 1, 1, std::numeric_limits<double>::denorm_min()};
  const auto t0 = std::chrono::steady_clock::now();
  const auto flag = netdem::packing::peripheral_layer(p);
  EXPECT_EQ(flag.size(), 4u);
  EXPECT_EQ(flag[0], 1);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
  // and validate() refuses such a packing (ratio), so the solvers never see it
  EXPECT_THROW(netdem::packing::validate(p), std::invalid_argument);
}
