// Tests of the sintering protocol's library part (netdem/dynamic/protocol.hpp): the packing round
// trip (netsolve's packing writer -> demsolve's sample -> the solver's state -> back), the unit
// rule, bad packings, the random fill sample and the phase stepping's observer calls.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/dynamic/material_tests.hpp"
#include "netdem/dynamic/protocol.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"

using namespace netdem::dem;
namespace fs = std::filesystem;
namespace pk = netdem::packing;

namespace {

fs::path temp_file(const std::string& name) {
  return fs::temp_directory_path() / ("netdem_test_protocol_" + std::to_string(::getpid()) + "_" + name);
}

double mean(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()); }

/// A ballistic deposit (netsolve pack) in a box not at the origin, written by the packing writer.
pk::Packing deposit(double width, std::uint64_t seed) {
  pk::DepositionOptions o;
  o.width = width;
  o.seed = seed;
  o.r_min = 0.7;
  o.r_max = 1.3;
  o.lid = pk::Lid::Centre;  // netsolve's default: the top layer sticks out through the lid
  pk::Packing p = pk::ballistic_deposition(o);
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.x[i] += 3.0;
    p.y[i] -= 2.0;
  }
  p.box = {3.0, -2.0, p.box.x_max + 3.0, p.box.y_max - 2.0};
  return p;
}

TEST(Protocol, PackingRoundTripThroughDemsolveSample) {
  const LudingParams lp;
  for (std::uint64_t seed : {1u, 2u}) {
    const pk::Packing file = deposit(16.0, seed);
    const fs::path f = temp_file("round_trip.csv");
    pk::write_packing_csv(file, f);
    for (double unit : {0.0, 2.5e-4}) {
      SampleSpec spec;
      spec.packing_file = f.string();
      spec.length_unit = unit;
      Box box;
      double used = -1.0;
      Particles P = make_sample(spec, lp, box, &used);
      const double s = unit > 0.0 ? unit : lp.a0 / mean(file.r);
      EXPECT_EQ(used, s);
      if (unit == 0.0) {
        EXPECT_NEAR(mean(P.r), lp.a0, 1e-15);  // the mean radius is a0
      }
      ASSERT_EQ(P.size(), file.size());
      double top = 0.0;
      for (std::size_t i = 0; i < P.size(); ++i) {
        EXPECT_EQ(P.pos[2 * i], s * file.x[i]);
        EXPECT_EQ(P.pos[2 * i + 1], s * file.y[i]);
        EXPECT_EQ(P.r[i], s * file.r[i]);
        EXPECT_EQ(P.vel[2 * i], 0.0);
        EXPECT_EQ(P.vel[2 * i + 1], 0.0);
        top = std::max(top, P.pos[2 * i + 1] + P.r[i]);
      }
      EXPECT_EQ(box.x_min, s * file.box.x_min);
      EXPECT_EQ(box.y_min, s * file.box.y_min);
      EXPECT_EQ(box.x_max, s * file.box.x_max);
      EXPECT_GT(top, s * file.box.y_max);  // Lid::Centre: the top wall is raised to the highest disk
      EXPECT_EQ(box.y_max, top);
      // the solver's state holds the same geometry (radii at T_radius_ref)
      DynamicOptions o;
      o.temperature = lp.T_radius_ref;
      const DynamicSolver solver(P, lp, box, o);
      const SolverState st = solver.state();
      EXPECT_EQ(st.radius_ref, P.r);
      EXPECT_EQ(st.particles_of<2>().pos, P.pos);
      EXPECT_EQ(st.box.x_max, box.x_max);
      // and back to a packing in file units, equal to round-off
      const pk::Packing back = to_packing(st.particles_of<2>(), st.box);
      for (std::size_t i = 0; i < back.size(); ++i) {
        EXPECT_NEAR(back.x[i] / s, file.x[i], 1e-13 * std::fabs(file.x[i]) + 1e-300);
        EXPECT_NEAR(back.y[i] / s, file.y[i], 1e-13 * (std::fabs(file.y[i]) + 1.0));
        EXPECT_NEAR(back.r[i] / s, file.r[i], 1e-13 * file.r[i]);
      }
      EXPECT_NEAR(back.box.x_min / s, file.box.x_min, 1e-13);
      EXPECT_NEAR(back.box.x_max / s, file.box.x_max, 1e-13 * file.box.x_max);
    }
    fs::remove(f);
  }
}

TEST(Protocol, BadPackingsGiveOneLineErrors) {
  const LudingParams lp;
  auto message = [&](const pk::Packing& p, double unit) -> std::string {
    Box box;
    try {
      particles_from_packing(p, lp, unit, box);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  pk::Packing p;
  p.box = {0.0, 0.0, 10.0, 10.0};
  p.x = {2.0, 5.0};
  p.y = {2.0, 5.0};
  p.r = {1.0, 1.5};
  EXPECT_EQ(message(p, 0.0), "");
  EXPECT_NE(message(p, 1.0).find("outside [a0 / 100, 100 a0]"), std::string::npos);  // 1 m disks
  EXPECT_NE(message(p, 1e-9).find("check the length unit"), std::string::npos);
  EXPECT_NE(message(p, -1.0).find("length unit"), std::string::npos);
  EXPECT_NE(message(p, std::nan("")).find("length unit"), std::string::npos);
  pk::Packing q = p;
  q.x[1] = 9.0;  // through the right wall
  EXPECT_NE(message(q, 0.0).find("disk 1"), std::string::npos);
  EXPECT_NE(message(q, 0.0).find("side wall or the floor"), std::string::npos);
  q = p;
  q.y[0] = 0.5;  // through the floor
  EXPECT_NE(message(q, 0.0).find("disk 0"), std::string::npos);
  q = p;
  q.y[1] = 9.5;  // through the open lid: allowed, the top wall is raised
  EXPECT_EQ(message(q, 0.0), "");
  q = p;
  q.x[0] = 20.0;  // centre outside the box: packing::validate
  EXPECT_NE(message(q, 0.0).find("outside the box"), std::string::npos);
  for (const std::string& m : {message(p, 1.0), message(q, 0.0)}) EXPECT_EQ(m.find('\n'), std::string::npos);
  SampleSpec spec;
  spec.packing_file = temp_file("does_not_exist.csv").string();
  Box box;
  EXPECT_THROW(make_sample(spec, lp, box), std::runtime_error);
}

TEST(Protocol, RandomSampleIsInsideWithoutOverlapAndDeterministic) {
  const LudingParams lp;
  SampleSpec spec;
  spec.n = 200;
  spec.seed = 5;
  Box box, box2;
  const Particles P = make_sample(spec, lp, box), Q = place_sample(spec, lp, box2);
  EXPECT_EQ(P.pos, Q.pos);
  EXPECT_EQ(P.vel, Q.vel);
  ASSERT_EQ(P.size(), 200u);
  double area = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const double r = P.r[i];
    EXPECT_GE(r, lp.a0 * (1 - lp.w0));
    EXPECT_LE(r, lp.a0 * (1 + lp.w0));
    EXPECT_GE(P.pos[2 * i] - r, box.x_min);
    EXPECT_LE(P.pos[2 * i] + r, box.x_max);
    EXPECT_GE(P.pos[2 * i + 1] - r, box.y_min);
    EXPECT_LE(P.pos[2 * i + 1] + r, box.y_max);
    EXPECT_LE(std::fabs(P.vel[2 * i]), 0.01);
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE(std::hypot(P.coord(i, 0) - P.coord(j, 0), P.coord(i, 1) - P.coord(j, 1)), r + P.r[j]);
    area += std::numbers::pi * r * r;
  }
  EXPECT_NEAR(area / ((box.x_max - box.x_min) * (box.y_max - box.y_min)), spec.initial_density, 1e-12);
  spec.seed = 6;
  EXPECT_NE(place_sample(spec, lp, box2).pos, P.pos);
}

struct Recorder final : PhaseObserver {
  std::vector<std::int64_t> samples;
  std::vector<std::size_t> sample_phase, ends;
  std::vector<double> end_time, end_mu;
  void sample(const DynamicSolver&, std::size_t phase, std::int64_t steps) override {
    samples.push_back(steps);
    sample_phase.push_back(phase);
  }
  void phase_end(const DynamicSolver& s, std::size_t phase) override {
    ends.push_back(phase);
    end_time.push_back(s.time());
    end_mu.push_back(s.params().mu);
  }
};

TEST(Protocol, RunPhasesSamplesAndEndsEveryPhase) {
  LudingParams lp;
  SampleSpec spec;
  spec.n = 20;
  Box box;
  Particles P = make_sample(spec, lp, box);
  set_stress_walls(box, 100.0, lp);
  EXPECT_EQ(box.top.mode, WallMode::Stress);
  EXPECT_EQ(box.right.pressure, 100.0);
  EXPECT_EQ(box.right.mass, lp.m_wall);
  DynamicOptions o;
  DynamicSolver s(std::move(P), lp, box, o);
  SinterProtocol prot;
  prot.t_heat = 40 * s.dt();
  prot.heat = 10 * s.dt();
  prot.sinter = 10 * s.dt();
  prot.cool = 0.0;  // a zero-length phase still ends
  prot.relax = 6.5 * s.dt();
  const auto phases = prot.phases();
  Recorder rec;
  const PhaseRun run = run_phases(s, phases, {0.4, 0.0}, 10, rec);
  EXPECT_EQ(run.steps, 67);
  EXPECT_EQ(run.sample_every, 6);
  EXPECT_EQ(rec.samples.front(), 0);
  EXPECT_EQ(rec.samples.back(), 67);  // after the last step, not a multiple of 6
  EXPECT_EQ(rec.samples.size(), 1u + 11u + 1u);
  EXPECT_EQ(rec.ends, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(rec.end_mu.front(), 0.0);  // frictionless preparation
  EXPECT_EQ(rec.end_mu.back(), 0.4);   // mu on after t_heat
  EXPECT_EQ(rec.sample_phase.back(), 4u);
  EXPECT_NEAR(rec.end_time.front(), prot.t_heat, 0.5 * s.dt());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> buf;
  const ContactCounts c = count_contacts(s, buf);
  EXPECT_EQ(c.pairs, buf.size());
  EXPECT_EQ(c.walls, s.wall_contacts());
  EXPECT_DOUBLE_EQ(c.coordination(20), (2.0 * c.pairs + c.walls) / 20.0);
}

TEST(MaterialTests, CompressionFiguresAndClusters) {
  CompressionRun run;
  for (int k = 0; k <= 20; ++k) {
    run.eps.push_back(0.0005 * k);
    run.szz.push_back(k <= 12 ? 3.0 + 2000.0 * 0.0005 * k : 15.0 - k);  // peak at sample 12
  }
  CompressionFigures f = compression_figures(run, 0.005);
  EXPECT_EQ(f.peak, 12u);
  EXPECT_NEAR(f.stiffness, 2000.0, 1e-9);
  run.eps = {0.0, 0.1, 0.2};
  f = compression_figures(run, 0.005);  // one sample in the window
  EXPECT_TRUE(std::isnan(f.stiffness));

  // clusters: 0-1-2 overlapping in a chain, 3 alone, 4-5 a pair
  LudingParams lp;
  const double a = lp.a0;
  Particles P;
  for (double x : {0.0, 1.9, 3.8}) P.add(x * a, 0.0, a, lp);
  P.add(20 * a, 0.0, a, lp);
  P.add(40 * a, 0.0, a, lp);
  P.add(41.9 * a, 0.0, a, lp);
  Box box;
  box.enabled = false;
  const DynamicSolver s(P, lp, box, DynamicOptions{});
  Clusters c;
  c.update(s);
  EXPECT_EQ(c.largest(), 3u);
  EXPECT_EQ(c.single_grains(), 1u);
  EXPECT_EQ(c.sizes(), (std::vector<std::uint32_t>{3, 2, 1}));
  EXPECT_EQ(c.rank(), (std::vector<double>{0, 0, 0, 2, 1, 1}));
  EXPECT_EQ(c.label()[0], c.label()[2]);
  EXPECT_NE(c.label()[0], c.label()[4]);
}

TEST(MaterialTests, OpenBoxAndBadTests) {
  SolverState st;
  st.box.x_min = 0.0;
  st.box.x_max = 0.02;
  st.box.y_max = 0.03;
  st.box.right.mode = WallMode::Stress;
  st.box.top.mode = WallMode::Strain;
  st.wall_velocity[1] = -0.5;
  open_box_for_vibration(st);
  EXPECT_EQ(st.box.x_min, -1.0);
  EXPECT_EQ(st.box.x_max, 1.02);
  EXPECT_EQ(st.box.y_min, 0.0);  // the floor stays
  EXPECT_EQ(st.box.y_max, 1.03);
  EXPECT_EQ(st.box.right.mode, WallMode::Fixed);
  EXPECT_EQ(st.box.top.mode, WallMode::Fixed);
  EXPECT_EQ(st.wall_velocity[1], 0.0);
  CompressionTest c;
  c.max_strain = 0.95;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = {};
  c.strain_rate = 0.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  VibrationTest v;
  v.frequency = -1.0;
  EXPECT_THROW(v.validate(), std::invalid_argument);
  v = {};
  EXPECT_NO_THROW(v.validate());
}

}  // namespace
