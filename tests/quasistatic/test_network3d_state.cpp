// The 3D network's state file (kind "network3d", issue 30): a solver restored from it continues
// bit-identically to the uninterrupted run, in the die, between walls and in a periodic cell, with
// friction and rotations, through loading and the elastic unloading (where the contact histories
// decide the forces); the round trip keeps every value; bad files give one-line errors that name
// the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/network_solver.hpp"

namespace {

namespace qs = netdem::qs;
using netdem::packing::Packing;
using M3 = Eigen::Matrix3d;
using V3 = Eigen::Vector3d;

/// m^3 spheres on a jittered simple cubic lattice (spacing 2), radii 1 + overlap u (u uniform in
/// [0, 1)): a prestressed network. periodic: the box [-m, m]^3 is the cell; else the box touches
/// the outer spheres.
Packing jittered(int m, double jitter, double overlap, unsigned seed, bool periodic) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing pk;
  pk.dim = 3;
  const double c = m - 1.0;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        pk.x.push_back(2 * i - c + jitter * (2 * u(rng) - 1));
        pk.y.push_back(2 * j - c + jitter * (2 * u(rng) - 1));
        pk.z.push_back(2 * k - c + jitter * (2 * u(rng) - 1));
        pk.r.push_back(1.0 + overlap * u(rng));
      }
  const double h = periodic ? m : m + 0.02;
  pk.box = {-h, -h, h, h, -h, h};
  pk.periodic = periodic;
  if (!periodic)
    for (std::size_t p = 0; p < pk.size(); ++p) {  // walls: the outer spheres touch them
      const double lim = h - pk.r[p];
      pk.x[p] = std::clamp(pk.x[p], -lim, lim);
      pk.y[p] = std::clamp(pk.y[p], -lim, lim);
      pk.z[p] = std::clamp(pk.z[p], -lim, lim);
    }
  return pk;
}

/// The state file's text without its timings (wall-clock times differ between two runs).
nlohmann::json without_timings(const qs::NetworkState3& s, const std::string& file) {
  qs::save_state(s, file);
  std::ifstream in(file);
  nlohmann::json j = nlohmann::json::parse(in);
  j.erase("timings");
  return j;
}

TEST(Network3DState, RestartThroughTheFileIsBitIdentical) {
  struct Scene {
    const char* name;
    qs::BoundaryMode mode;
    double mu;
  };
  for (const Scene sc : {Scene{"die", qs::BoundaryMode::Die, 0.3}, Scene{"walls", qs::BoundaryMode::Walls, 0.3},
                         Scene{"periodic", qs::BoundaryMode::Periodic, std::numeric_limits<double>::infinity()}}) {
    SCOPED_TRACE(sc.name);
    qs::SolverOptions o = qs::SolverOptions::compact();
    o.mode = sc.mode;
    o.iteration = sc.mode == qs::BoundaryMode::Die ? qs::Iteration::LegacyDrag : qs::Iteration::PseudoTransient;
    o.law.mu = sc.mu;
    const Packing pk = jittered(4, 0.05, 0.04, 21, sc.mode == qs::BoundaryMode::Periodic);
    const M3 dE = M3(V3(-0.002, -0.001, -0.0015).asDiagonal());
    // the restart falls on the section 3.4 elastic unloading, where the histories (u_max of every
    // pair and wall contact, the tangential springs) decide the forces; then reloading past it
    qs::SolverOptions elastic = o;
    elastic.law.reversible = false;
    auto load_and_start_unloading = [&](qs::NetworkSolver3& s) {
      for (int k = 0; k < 4; ++k) s.increment(dE);
      s.set_reversible_normal(false);
      s.increment(-0.001 * dE);
    };
    auto continue_run = [&](qs::NetworkSolver3& s) {
      s.increment(-0.001 * dE);
      for (int k = 0; k < 2; ++k) s.increment(0.3 * dE);
    };
    qs::NetworkSolver3 ref(pk, o), first(pk, o);
    load_and_start_unloading(ref);
    continue_run(ref);
    load_and_start_unloading(first);
    const std::string file = testing::TempDir() + "/netdem_state3_" + sc.name + ".txt";
    qs::save_state(first.state(), file);
    qs::NetworkSolver3 restored(qs::load_state3(file), elastic);
    continue_run(restored);
    const auto a = ref.state(), b = restored.state();
    ASSERT_GT(a.pair_i.size(), 100u);
    EXPECT_EQ(a.periodic, sc.mode == qs::BoundaryMode::Periodic);
    EXPECT_EQ(!a.wall_history.empty(), sc.mode == qs::BoundaryMode::Walls);
    EXPECT_EQ(a.particles.pos, b.particles.pos);
    EXPECT_EQ(a.particles.rot, b.particles.rot);
    EXPECT_EQ(a.f_contact, b.f_contact);
    EXPECT_EQ(a.f_n, b.f_n);
    EXPECT_NE(*std::max_element(a.particles.rot.begin(), a.particles.rot.end()), 0.0);  // the spheres rotated
    const std::string fa = file + ".a", fb = file + ".b";
    EXPECT_EQ(without_timings(a, fa), without_timings(b, fb));  // every other field, exactly
    EXPECT_EQ(ref.stress().eq13, restored.stress().eq13);
    for (const std::string& f : {file, fa, fb}) std::remove(f.c_str());
  }
}

TEST(Network3DState, RoundTripAndBadFiles) {
  qs::SolverOptions o = qs::SolverOptions::compact();
  o.mode = qs::BoundaryMode::Periodic;
  o.iteration = qs::Iteration::PseudoTransient;
  qs::NetworkSolver3 s(jittered(3, 0.05, 0.04, 5, true), o);
  for (int k = 0; k < 2; ++k) s.increment(-1e-3 * M3::Identity());
  const auto st = s.state();
  const std::string file = testing::TempDir() + "/netdem_state3_rt.txt";
  qs::save_state(st, file);
  const auto back = qs::load_state3(file);
  EXPECT_EQ(back.particles.pos, st.particles.pos);
  EXPECT_EQ(back.du_prev, st.du_prev);
  EXPECT_EQ(back.strain, st.strain);
  EXPECT_EQ(back.shift, st.shift);
  EXPECT_EQ(back.pinned, st.pinned);
  ASSERT_EQ(back.f_t.size(), st.f_t.size());
  for (std::size_t k = 0; k < st.f_t.size(); ++k) EXPECT_EQ(back.f_t[k], st.f_t[k]);
  std::ifstream in(file);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto expect_error = [&](const std::string& text, const std::string& what) {
    const std::string bad = testing::TempDir() + "/netdem_state3_bad.txt";
    {
      std::ofstream f(bad);
      f << text;
    }
    try {
      (void)qs::load_state3(bad);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(bad), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_NE(m.find(what), std::string::npos) << m;
    }
    std::remove(bad.c_str());
  };
  auto set = [&](const std::string& pointer, const nlohmann::json& v) {
    nlohmann::json j = nlohmann::json::parse(good);
    j[nlohmann::json::json_pointer(pointer)] = v;
    return j.dump();
  };
  expect_error(good.substr(0, good.size() / 2), ": /: not a JSON state archive (syntax error at byte");  // truncated
  expect_error(set("/kind", "network"), ": /kind:");  // a 2D state is not a 3D one
  expect_error(set("/particles/r/2", -1.0), ": /particles/r/2: -1.0 is below 0");
  expect_error(set("/particles/r/2", 0.0), ": /particles/r/2: a radius must be positive");
  expect_error(set("/particles/pos", nlohmann::json::array({1.0, 2.0})), ": /particles/pos: expected");
  expect_error(set("/pairs/f_t/0", nlohmann::json::array({1.0, 2.0})), ": /pairs/f_t/0: expected");
  expect_error(set("/pairs/E_form/0", "x"), ": /pairs/E_form/0: expected an array of 9");
  expect_error(set("/pairs/history/0/u_max", -1.0), ": /pairs/history/0/u_max: -1.0 is below 0");
  expect_error(set("/periodic/shift/0", nlohmann::json::array({0, 1})), ": /periodic/shift/0: expected");
  expect_error(set("/periodic/pinned", -3), ": /periodic/pinned:");
  expect_error(set("/box0/max/2", -100.0), ": /box0: the initial box must have positive size");
  expect_error(set("/zz", 1), ": /zz: unknown member");
  EXPECT_THROW((void)qs::load_state3(testing::TempDir() + "/does_not_exist3.txt"), std::invalid_argument);
  std::remove(file.c_str());
}

}  // namespace
