// demsolve: explicit 2D DEM with Luding's sintering contact law (Luding, Manetsberger & Muellers 2005).
//
//   demsolve prepare [--n 300] [--pressure 100] [--seed 1] [--time 0.2] [--out DIR] [--quiet]
//
// Preparation (section 4.1): disks with radii uniform in a0[1 - w0, 1 + w0] placed at random
// (no overlap) in a square box at density 0.35 with random velocities, compressed by the
// stress-controlled right and top walls (Eq 1) at isotropic pressure p, frictionless, 80 deg C,
// no gravity. Writes command.txt, timeseries.csv, summary.json, particles_{initial,final}.vtp and
// state.txt. Errors are one line on stderr and a non-zero exit.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/dynamic/solver.hpp"
#include "output.hpp"

namespace fs = std::filesystem;
using netdem::app::Field;

namespace {

std::string g_command;

struct PrepareArgs {
  int n = 300;
  double pressure = 100.0, time = 0.2, initial_density = 0.35;
  std::uint64_t seed = 1;
  bool quiet = false;
};

/// Uniform in [0, 1) from the 64-bit output (platform independent, unlike std::uniform_real_distribution).
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

void validate(const PrepareArgs& a) {
  if (a.n < 1 || a.n > 1000000) throw std::invalid_argument(fmt::format("--n must be in [1, 1e6], got {}", a.n));
  if (!(std::isfinite(a.pressure) && a.pressure > 0.0))
    throw std::invalid_argument(fmt::format("--pressure must be a positive number of N/m, got {}", a.pressure));
  if (!(std::isfinite(a.time) && a.time > 0.0))
    throw std::invalid_argument(fmt::format("--time must be a positive number of seconds, got {}", a.time));
}

/// Random non-overlapping placement in a square box of the given solid fraction; random velocities
/// with components uniform in [-v0, v0], v0 = a0 / (100 t_c-ish) chosen as 0.01 m/s.
netdem::dem::Particles place(const PrepareArgs& a, const netdem::dem::LudingParams& lp, netdem::dem::Box& box) {
  std::mt19937_64 rng(a.seed);
  std::vector<double> r(a.n);
  double area = 0.0;
  for (int i = 0; i < a.n; ++i) {  // draw order: all radii first, then positions, then velocities
    r[i] = lp.a0 * (1.0 - lp.w0 + 2.0 * lp.w0 * uniform01(rng));
    area += std::numbers::pi * r[i] * r[i];
  }
  const double L = std::sqrt(area / a.initial_density);
  box.x_min = box.y_min = 0.0;
  box.x_max = box.y_max = L;
  netdem::dem::Particles P;
  std::vector<double> xs, ys;
  for (int i = 0; i < a.n; ++i) {
    bool placed = false;
    for (int attempt = 0; attempt < 100000 && !placed; ++attempt) {
      const double x = r[i] + (L - 2 * r[i]) * uniform01(rng), y = r[i] + (L - 2 * r[i]) * uniform01(rng);
      placed = true;
      for (std::size_t k = 0; k < xs.size() && placed; ++k)
        placed = std::hypot(x - xs[k], y - ys[k]) >= r[i] + P.radius[k];
      if (placed) {
        xs.push_back(x);
        ys.push_back(y);
        P.add(x, y, r[i], lp);
      }
    }
    if (!placed) throw std::runtime_error(fmt::format("could not place disk {} without overlap at density {}", i, a.initial_density));
  }
  const double v0 = 0.01;  // [m/s]
  for (int i = 0; i < a.n; ++i) {
    P.vx[i] = v0 * (2.0 * uniform01(rng) - 1.0);
    P.vy[i] = v0 * (2.0 * uniform01(rng) - 1.0);
  }
  return P;
}

std::string vtp(const netdem::dem::Particles& P) {
  Field rad{"radius", 1, P.radius}, vel{"velocity", 3, {}}, om{"omega", 1, P.omega};
  for (std::size_t i = 0; i < P.size(); ++i) vel.values.insert(vel.values.end(), {P.vx[i], P.vy[i], 0.0});
  return netdem::app::vtp_particles(P.x, P.y, {rad, vel, om});
}

int run_prepare(const PrepareArgs& a, const fs::path& out) {
  using namespace netdem::dem;
  validate(a);
  LudingParams lp;
  lp.mu = 0.0;  // section 4.1: frictionless preparation
  lp.validate();
  Box box;
  auto P = place(a, lp, box);
  box.right.mode = WallMode::Stress;
  box.top.mode = WallMode::Stress;
  box.right.pressure = box.top.pressure = a.pressure;
  DynamicOptions opt;
  opt.temperature = 80.0;
  DynamicSolver s(std::move(P), lp, box, opt);
  netdem::app::make_output_dir(out);
  netdem::app::write_file_atomic(out / "command.txt", g_command + "\n");
  netdem::app::write_file_atomic(out / "particles_initial.vtp", vtp(s.particles()));

  const auto steps = static_cast<std::size_t>(std::ceil(a.time / s.dt()));
  const std::size_t every = std::max<std::size_t>(1, steps / 1500);
  std::string csv = "t,nu,C,sxx,szz,sxx_contacts,szz_contacts,Ekin,box_width,box_height\n";
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  auto row = [&] {
    s.touching_pairs(pairs);
    const auto ws = s.wall_stress();
    const auto cs = s.contact_stress();
    csv += fmt::format("{:.9g},{:.9g},{:.6g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", s.time(), s.density(),
                       2.0 * static_cast<double>(pairs.size()) / static_cast<double>(s.particles().size()), ws.xx, ws.yy,
                       cs.xx, cs.yy, s.energies().kinetic, s.box().x_max - s.box().x_min, s.box().y_max - s.box().y_min);
  };
  const auto t0 = std::chrono::steady_clock::now();
  netdem::app::Progress progress("prepare", static_cast<double>(steps), a.quiet);
  row();
  for (std::size_t k = 1; k <= steps; ++k) {
    s.step();
    if (k % every == 0 || k == steps) {
      row();
      progress.update(static_cast<double>(k));
    }
  }
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  netdem::app::write_file_atomic(out / "timeseries.csv", csv);
  netdem::app::write_file_atomic(out / "particles_final.vtp", vtp(s.particles()));
  // state.txt: the particle and wall state at the end (documented in docs/dynamic.md); the
  // contact history is not stored yet, so a restart from it starts with fresh contacts.
  const auto& Pf = s.particles();
  std::string st = fmt::format("# demsolve state v1\n# time {:.17g}\n# box {:.17g} {:.17g} {:.17g} {:.17g}\n", s.time(),
                               s.box().x_min, s.box().y_min, s.box().x_max, s.box().y_max);
  st += "id,x,y,vx,vy,omega,theta,radius,mass\n";
  for (std::size_t i = 0; i < Pf.size(); ++i)
    st += fmt::format("{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", i, Pf.x[i], Pf.y[i], Pf.vx[i],
                      Pf.vy[i], Pf.omega[i], Pf.theta[i], Pf.radius[i], Pf.mass[i]);
  netdem::app::write_file_atomic(out / "state.txt", st);
  s.touching_pairs(pairs);
  const auto ws = s.wall_stress();
  nlohmann::json j;
  j["command"] = g_command;
  j["seed"] = a.seed;
  j["particles"] = a.n;
  j["pressure_N_per_m"] = a.pressure;
  j["time_s"] = s.time();
  j["dt_s"] = s.dt();
  j["steps"] = steps;
  j["steps_per_contact_lightest_pair"] = s.time_step().steps_per_contact_lightest;
  j["final"] = {{"nu", s.density()},
                {"C_without_walls", 2.0 * static_cast<double>(pairs.size()) / static_cast<double>(Pf.size())},
                {"sxx_over_p", ws.xx / a.pressure},
                {"szz_over_p", ws.yy / a.pressure},
                {"Ekin_J", s.energies().kinetic}};
  j["wall_time_s"] = wall;
  j["particle_steps_per_s"] = static_cast<double>(steps) * a.n / std::max(wall, 1e-9);
  netdem::app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  std::printf("t = %.4f s: nu = %.4f, C = %.3f (walls excluded), sxx/p = %.4f, szz/p = %.4f, Ekin = %.3e J, %.1f s -> %s\n",
              s.time(), s.density(), 2.0 * static_cast<double>(pairs.size()) / static_cast<double>(Pf.size()), ws.xx / a.pressure,
              ws.yy / a.pressure, s.energies().kinetic, wall, out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int k = 0; k < argc; ++k) g_command += (k ? " " : "") + std::string(argv[k]);
  CLI::App app{"demsolve: explicit 2D DEM with Luding's sintering contact law (Luding et al. 2005)"};
  app.require_subcommand(1);
  PrepareArgs pa;
  std::string out;
  auto* prep = app.add_subcommand("prepare", "random disks compressed by stress-controlled walls, frictionless, 80 deg C (section 4.1)");
  prep->add_option("--n", pa.n, "number of disks")->capture_default_str();
  prep->add_option("--pressure", pa.pressure, "wall pressure p [N/m] (Eq 1)")->capture_default_str();
  prep->add_option("--seed", pa.seed, "random seed of placement and velocities")->capture_default_str();
  prep->add_option("--time", pa.time, "simulated preparation time [s] (the paper's t_heat = 0.2)")->capture_default_str();
  prep->add_flag("--quiet", pa.quiet, "no progress on stderr");
  prep->add_option("--out", out, "output folder")->default_val("results/prepare");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "demsolve: error: %s (see --help)\n", e.what());
    return 2;
  }
  try {
    return run_prepare(pa, out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "demsolve: error: %s\n", e.what());
    return 1;
  }
}
