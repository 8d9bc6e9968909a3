// The jammed state both solvers share (netdem/system/jammed_state.hpp, issue 28 item 6): the same
// jammed packing is the same state in the network solver and in the DEM, histories included.
//  * a network compaction between walls (sticking friction), written and read, gives the DEM the
//    same contact forces, pair by pair and wall contact by wall contact, to 1e-12 of the normal
//    force; and the reverse: a DEM compaction between walls, at rest, gives the network solver
//    the forces of the DEM's springs;
//  * file -> solver -> file is byte-identical for each solver (disks), and a state that went once
//    through the other solver is a fixed point of it; spheres through the DEM to 1e-14;
//  * bad files (a negative radius, a missing entry, a non-number, a tangential spring on a pair
//    that does not touch, a wall contact without walls) are refused with one line naming the
//    field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "netdem/dynamic/jammed.hpp"
#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/ballistic3d.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/jammed_state.hpp"

using namespace netdem;
using Jammed = sys::JammedStateT<2>;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// netsolve's deposition of width W, its box enlarged to enclose every disk (as --boundary walls).
packing::Packing walls_packing(double width) {
  packing::DepositionOptions d;
  d.width = width;
  d.seed = 3;
  d.lid = packing::Lid::Centre;
  packing::Packing pk = packing::ballistic_deposition(d);
  for (std::size_t i = 0; i < pk.size(); ++i) {
    pk.box.x_min = std::min(pk.box.x_min, pk.x[i] - pk.r[i]);
    pk.box.x_max = std::max(pk.box.x_max, pk.x[i] + pk.r[i]);
    pk.box.y_min = std::min(pk.box.y_min, pk.y[i] - pk.r[i]);
    pk.box.y_max = std::max(pk.box.y_max, pk.y[i] + pk.r[i]);
  }
  return pk;
}

contact::PlasticIndentationParams law(double mu, bool reversible = true) {
  contact::PlasticIndentationParams p;
  p.mu = mu;
  p.reversible = reversible;  // true: netsolve compact's default normal law; false: u_max matters
  return p;
}

qs::SolverOptions walls_options(double mu, bool reversible = true) {
  qs::SolverOptions so;
  so.mode = qs::BoundaryMode::Walls;
  so.law = law(mu, reversible);
  return so;
}

dem::DynamicOptions dem_options(double mu, bool reversible = true) {
  dem::DynamicOptions o;
  o.model = dem::ContactModel::PlasticIndentation;
  o.plastic = law(mu, reversible);
  o.plastic.damping_n = o.plastic.damping_t = 0.3;  // the DEM's own dashpots (not part of the state)
  o.plastic_wall_mu = 0.0;
  return o;
}

dem::Box affine_walls() {
  dem::Box b;
  b.right.mode = b.top.mode = dem::WallMode::Affine;
  return b;
}

/// A network compaction between walls: 12 hydrostatic increments of 0.4 %.
qs::NetworkSolver compacted_network(double mu, bool reversible = true) {
  qs::NetworkSolver s(walls_packing(16), walls_options(mu, reversible));
  for (int k = 0; k < 12; ++k) s.increment(Eigen::Matrix2d::Identity() * -0.004);
  return s;
}

/// A DEM compaction between walls (affine walls, strain rate 0.01 per t*) by 4 %.
dem::DynamicSolver compacted_dem(double mu) {
  const packing::Packing pk = walls_packing(16);
  dem::Box box = affine_walls();
  static_cast<packing::Box&>(box) = pk.box;
  dem::DynamicSolver s(dem::particles_from(pk, 1.0), law(mu), box, dem_options(mu));
  s.set_strain_rate(-0.01, -0.01);
  s.set_affine_velocities();
  while (s.time() < 2.0) s.step();
  return s;
}

struct Forces {
  std::map<std::pair<int, int>, std::pair<double, double>> pairs;  ///< (i, j) -> (f_n, f_t) of loaded contacts
  std::map<std::pair<int, int>, double> walls;                     ///< (particle, wall) -> f_n
};

Forces dem_forces(const dem::DynamicSolver& s) {
  std::vector<dem::ContactInfo> cs;
  s.contacts(cs);
  Forces f;
  for (const auto& c : cs) {
    if (!(c.f_spring > 0.0)) continue;
    if (c.wall < 0) f.pairs[{static_cast<int>(c.i), static_cast<int>(c.j)}] = {c.f_spring, c.f_t};
    else f.walls[{static_cast<int>(c.i), c.wall}] = c.f_spring;
  }
  return f;
}

Forces network_forces(const qs::NetworkSolver& s) {
  Forces f;
  for (const auto& c : s.contacts()) f.pairs[{c.i, c.j}] = {c.f_n, c.f_t};
  const auto st = s.state();
  for (std::size_t k = 0; k < st.wall_f_n.size(); ++k)
    if (st.wall_f_n[k] > 0.0) f.walls[{static_cast<int>(k / 4), static_cast<int>(k % 4)}] = st.wall_f_n[k];
  return f;
}

/// Every loaded contact of `a` is one of `b` with the same forces to `tol` of its normal force.
double max_difference(const Forces& a, const Forces& b, int& sliding_checked) {
  EXPECT_EQ(a.pairs.size(), b.pairs.size());
  EXPECT_EQ(a.walls.size(), b.walls.size());
  double worst = 0.0;
  for (const auto& [key, f] : a.pairs) {
    const auto it = b.pairs.find(key);
    if (it == b.pairs.end()) {
      ADD_FAILURE() << "pair " << key.first << "-" << key.second << " is loaded in one solver only";
      continue;
    }
    worst = std::max(worst, std::fabs(f.first - it->second.first) / f.first);
    worst = std::max(worst, std::fabs(f.second - it->second.second) / f.first);
    sliding_checked += f.second != 0.0;
  }
  for (const auto& [key, fn] : a.walls) {
    const auto it = b.walls.find(key);
    if (it == b.walls.end()) {
      ADD_FAILURE() << "wall contact " << key.first << "/" << key.second << " is loaded in one solver only";
      continue;
    }
    worst = std::max(worst, std::fabs(fn - it->second) / fn);
  }
  return worst;
}

TEST(JammedState, NetworkWallsStateGivesTheDemTheSameForces) {
  // the last case with the elastic unloading branch: the forces of unloaded contacts depend on u_max
  for (const auto& [mu, rev] : {std::pair{kInf, true}, {0.1, true}, {0.0, true}, {0.0, false}}) {
    const qs::NetworkSolver net = compacted_network(mu, rev);
    const std::string text = sys::format_jammed_state(net.jammed_state());
    const Jammed j = sys::parse_jammed_state<2>(text, "net.json");
    EXPECT_TRUE(j.walls);
    EXPECT_FALSE(j.wall_particle.empty());
    const dem::DynamicSolver dem = dem::solver_from_jammed(j, 1.0, affine_walls(), dem_options(mu, rev));
    const Forces a = network_forces(net), b = dem_forces(dem);
    ASSERT_GT(a.pairs.size(), 100u);
    ASSERT_GT(a.walls.size(), 10u);
    int tangential = 0;
    const double worst = max_difference(a, b, tangential);
    std::printf("network -> DEM, mu %g%s: %zu pairs (%d with f_t), %zu wall contacts, max relative difference %.3g\n", mu,
                rev ? "" : " (elastic unloading)", a.pairs.size(), tangential, a.walls.size(), worst);
    EXPECT_LE(worst, 1e-12) << "mu " << mu;
    if (mu > 0.0) {
      EXPECT_GT(tangential, 50) << "the tangential springs must be part of the comparison";
    }
  }
}

TEST(JammedState, DemWallsStateGivesTheNetworkTheSameForces) {
  for (double mu : {kInf, 0.0}) {
    const dem::DynamicSolver run = compacted_dem(mu);
    Eigen::Matrix2d E = Eigen::Matrix2d::Identity() * (-0.01 * run.time());
    const std::string text = sys::format_jammed_state(dem::jammed_state(run, E, 3));
    const Jammed j = sys::parse_jammed_state<2>(text, "dem.json");
    EXPECT_EQ(j.strain, E);
    const qs::NetworkSolver net(j, walls_options(mu));
    const dem::DynamicSolver rest = dem::solver_from_jammed(j, 1.0, affine_walls(), dem_options(mu));
    const Forces a = network_forces(net), b = dem_forces(rest);
    ASSERT_GT(a.pairs.size(), 60u);
    int tangential = 0;
    const double worst_rest = max_difference(a, b, tangential);
    std::printf("DEM -> network, mu %g: %zu pairs (%d with f_t), %zu wall contacts, max relative difference %.3g\n", mu,
                a.pairs.size(), tangential, a.walls.size(), worst_rest);
    EXPECT_LE(worst_rest, 1e-12) << "mu " << mu;
    if (mu > 0.0) {
      EXPECT_GT(tangential, 30);
    }
    // and the normal springs of the running DEM itself (its positions are the state's)
    const Forces c = dem_forces(run);
    double worst = 0.0;
    for (const auto& [key, f] : a.pairs) {
      const auto it = c.pairs.find(key);
      ASSERT_NE(it, c.pairs.end());
      worst = std::max(worst, std::fabs(f.first - it->second.first) / f.first);
    }
    EXPECT_LE(worst, 1e-12) << "mu " << mu;
  }
}

/// The same text; else the first difference with its context (the states are long lines).
void expect_same_text(const std::string& a, const std::string& b, const char* what) {
  if (a == b) return;
  std::size_t k = 0;
  while (k < a.size() && k < b.size() && a[k] == b[k]) ++k;
  const std::size_t from = k > 80 ? k - 80 : 0;
  ADD_FAILURE() << what << ": the texts differ at byte " << k << " of " << a.size() << " / " << b.size() << ":\n  "
                << a.substr(from, 160) << "\n  " << b.substr(from, 160);
}

TEST(JammedState, RoundTripsAreByteIdentical) {
  const double mu = kInf;
  // network: file -> solver -> file
  const std::string net_text = sys::format_jammed_state(compacted_network(mu).jammed_state());
  const qs::NetworkSolver net(sys::parse_jammed_state<2>(net_text, "a"), walls_options(mu));
  expect_same_text(sys::format_jammed_state(net.jammed_state()), net_text, "network");
  // the DEM: file -> solver -> file
  const dem::DynamicSolver run = compacted_dem(mu);
  const std::string dem_text = sys::format_jammed_state(dem::jammed_state(run, Eigen::Matrix2d(Eigen::Matrix2d::Zero()), 3));
  const dem::DynamicSolver rest = dem::solver_from_jammed(sys::parse_jammed_state<2>(dem_text, "b"), 1.0,
                                                          affine_walls(), dem_options(mu));
  expect_same_text(sys::format_jammed_state(dem::jammed_state(rest, Eigen::Matrix2d(Eigen::Matrix2d::Zero()), 3)), dem_text, "DEM");
  // across: the DEM's state through the network solver once is a fixed point of it, and back
  const qs::NetworkSolver n1(sys::parse_jammed_state<2>(dem_text, "c"), walls_options(mu));
  const std::string once = sys::format_jammed_state(n1.jammed_state());
  const qs::NetworkSolver n2(sys::parse_jammed_state<2>(once, "d"), walls_options(mu));
  expect_same_text(sys::format_jammed_state(n2.jammed_state()), once, "DEM -> network");
  expect_same_text(once, dem_text, "DEM -> network, against the DEM's own");
  const dem::DynamicSolver d1 =
      dem::solver_from_jammed(sys::parse_jammed_state<2>(net_text, "e"), 1.0, affine_walls(), dem_options(mu));
  const std::string back = sys::format_jammed_state(dem::jammed_state(d1, net.jammed_state().strain, 3));
  const dem::DynamicSolver d2 = dem::solver_from_jammed(sys::parse_jammed_state<2>(back, "f"), 1.0, affine_walls(),
                                                        dem_options(mu));
  expect_same_text(sys::format_jammed_state(dem::jammed_state(d2, net.jammed_state().strain, 3)), back, "network -> DEM");
}

// Spheres: a DEM compaction between six walls, saved at rest and read again, keeps its pairs,
// u_max and sliding flags exactly and its tangential springs (vectors) to 1e-14.
TEST(JammedState, SpheresRoundTripThroughTheDem) {
  packing::Deposition3dOptions d;
  d.width = 6.0;
  d.seed = 2;
  packing::Packing pk = packing::ballistic_deposition_3d(d);
  for (std::size_t i = 0; i < pk.size(); ++i) pk.box.z_max = std::max(pk.box.z_max, pk.z[i] + pk.r[i]);
  dem::Box box;
  static_cast<packing::Box&>(box) = pk.box;
  box.right.mode = box.back.mode = box.top.mode = dem::WallMode::Affine;
  dem::DynamicSolver3 run(dem::spheres_from(pk, 1.0), law(kInf), box, dem_options(kInf));
  run.set_strain_rate3(-0.02, -0.02, -0.02, 0.0, 0.0, 0.0);
  run.set_affine_velocities();
  while (run.time() < 3.0) run.step();
  const Eigen::Matrix3d E = Eigen::Matrix3d::Identity() * (-0.02 * run.time());
  const std::string text = sys::format_jammed_state(dem::jammed_state(run, E, 2));
  const auto j = sys::parse_jammed_state<3>(text, "spheres.json");
  ASSERT_GT(j.pair_i.size(), 20u);
  int springs = 0;
  for (const auto& h : j.pair_history) springs += h.f_t.norm() > 0.0;
  EXPECT_GT(springs, 10);
  const dem::DynamicSolver3 rest = dem::solver_from_jammed(j, 1.0, box, dem_options(kInf));
  // not to the bit in 3D: each evaluation projects the spring on the tangent plane (the DEM's
  // transport), which moves a component by rounding; the rest is exact
  const auto back = sys::parse_jammed_state<3>(sys::format_jammed_state(dem::jammed_state(rest, E, 2)), "again");
  ASSERT_EQ(back.pair_i, j.pair_i);
  ASSERT_EQ(back.pair_j, j.pair_j);
  EXPECT_EQ(back.particles.pos, j.particles.pos);
  EXPECT_EQ(back.wall_particle, j.wall_particle);
  double worst = 0.0;
  for (std::size_t k = 0; k < j.pair_history.size(); ++k) {
    EXPECT_EQ(back.pair_history[k].u_max, j.pair_history[k].u_max);
    EXPECT_EQ(back.pair_history[k].sliding, j.pair_history[k].sliding) << "pair " << k;
    const double ft = j.pair_history[k].f_t.norm();
    if (ft > 0.0) worst = std::max(worst, (back.pair_history[k].f_t - j.pair_history[k].f_t).norm() / ft);
  }
  std::printf("spheres: %zu pairs (%d springs), file -> DEM -> file: largest spring change %.3g (relative)\n",
              j.pair_i.size(), springs, worst);
  EXPECT_LE(worst, 1e-14);
  EXPECT_THROW(sys::parse_jammed_state<2>(text, "spheres.json"), std::invalid_argument);
}

/// Three disks in a box with walls: 0 and 1 touch, 2 is apart; disk 0 touches the left wall.
Jammed tiny() {
  Jammed j;
  j.particles.pos = {1.0, 2.0, 2.9, 2.0, 6.0, 2.0};
  j.particles.rot = {0.0, 0.0, 0.0};
  j.particles.r = {1.0, 1.0, 1.0};
  j.box = {0.01, 0.0, 8.0, 4.0};
  j.walls = true;
  j.law = law(kInf);
  j.pair_i = {0};
  j.pair_j = {1};
  contact::PlasticIndentationHistory h;
  h.u_max = 0.1;
  h.f_t = 0.05;
  j.pair_history = {h};
  j.wall_particle = {0};
  j.wall_side = {0};
  contact::PlasticIndentationHistory w;
  w.u_max = 0.01;
  j.wall_history = {w};
  return j;
}

/// The reader's one-line message for the tiny state edited by `edit`.
std::string refusal(const std::function<void(sys::Json&)>& edit) {
  sys::Json doc = sys::Json::parse(sys::format_jammed_state(tiny()));
  edit(doc);
  try {
    sys::parse_jammed_state<2>(doc.dump(), "bad.json");
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_EQ(m.rfind("bad.json: ", 0), 0u) << m;
    return m;
  }
  ADD_FAILURE() << "accepted: " << doc.dump();
  return {};
}

TEST(JammedState, BadFilesAreRefusedWithOneLine) {
  EXPECT_NO_THROW(sys::parse_jammed_state<2>(sys::format_jammed_state(tiny()), "good.json"));
  EXPECT_NE(refusal([](sys::Json& d) { d["particles"]["r"][1] = -1.0; }).find("/particles/r/1"), std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["particles"]["y"].erase(2); }).find("/particles/y"), std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["particles"]["x"][0] = "nan"; }).find("/particles/x/0"), std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["pairs"]["j"][0] = 3; }).find("/pairs/j/0"), std::string::npos);
  // a tangential spring on a pair that does not touch: the law clears it when a contact opens
  EXPECT_NE(refusal([](sys::Json& d) { d["pairs"]["j"][0] = 2; }).find("carries no normal force"), std::string::npos);
  // u_max below the current overlap (0.1 here)
  EXPECT_NE(refusal([](sys::Json& d) { d["pairs"]["history"][0]["u_max"] = 0.05; }).find("below the current overlap"),
            std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["box"]["walls"] = false; }).find("without contact walls"), std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["wall_contacts"]["wall"][0] = 4; }).find("/wall_contacts/wall/0"),
            std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["dim"] = 3; }).find("/dim"), std::string::npos);
  EXPECT_NE(refusal([](sys::Json& d) { d["kind"] = "network"; }).find("/kind"), std::string::npos);
  // the text NaN is no JSON number: a syntax error, one line
  std::string text = sys::format_jammed_state(tiny());
  text.replace(text.find("\"x\":[1") + 5, 1, "NaN");
  EXPECT_THROW(sys::parse_jammed_state<2>(text, "nan.json"), std::invalid_argument);
  // a key twice in one object (JSON allows it, the reader would keep the last): refused, naming it
  std::string twice = sys::format_jammed_state(tiny());
  twice.insert(twice.find("\"dim\":") + 1, "dim\":3,\"");
  try {
    sys::parse_jammed_state<2>(twice, "twice.json");
    ADD_FAILURE() << "accepted a key twice: " << twice.substr(0, 120);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("\"dim\" appears twice"), std::string::npos) << e.what();
  }
  // the writer refuses what the reader would
  Jammed j = tiny();
  j.pair_j = {2};
  EXPECT_THROW(sys::format_jammed_state(j), std::invalid_argument);
}

}  // namespace
