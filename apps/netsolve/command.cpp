// netsolve: quasi-static implicit network solver for powder compaction (Redanz & Fleck 2001).
//
//   netsolve pack     [--width 80] [--r-min 0.9] [--r-max 1.1] [--seed 1] [--dim 2|3] [--lateral walls|periodic] [--out DIR]
//   netsolve compact  [--affine | --boundary layer|walls|periodic] [--path hydrostatic|closed-die|E11,E22,E12] [--friction MU|inf]
//                     [--no-rotation] [--to-density 0.85 | --to-strain S] [--packing FILE] [--increments N]
//                     [--precompact-density D1 [--precompact-increments 20]] [--out DIR]   (compact.cpp)
//
// Every subcommand reads its options from a scene file too, --config scene.toml (the command line
// overrides it; apps/common/scene_file.hpp), and every run writes its own as scene.toml.
// Every run writes into its own folder: .incomplete (first, removed last), command.txt, the packing,
// history.csv, summary.json and VTK PolyData snapshots; a folder that holds another run is refused
// unless --overwrite. Errors are one line on stderr. Exit status: 0 ok, 1 run error, 2 command-line
// error (nothing written), 3 finished but untrustworthy (summary.json "status"; README.md).
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/linear_solver.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/jammed_state.hpp"
#include "command.hpp"
#include "compact.hpp"
#include "output.hpp"
#include "pack_green.hpp"
#include "pack_periodic.hpp"
#include "parse.hpp"
#include "scene_file.hpp"
#include "setup.hpp"
#include "status.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using netdem::app::Field;
int run_yield_command(int argc, char** argv);  // apps/netsolve/yield.cpp: netsolve yield | yield-merge
int run_sinter_pair_command(int argc, char** argv);  // apps/netsolve/sinter_pair.cpp: netsolve sinter-pair
int run_sinter_command(int argc, char** argv);       // apps/netsolve/sinter.cpp: netsolve sinter

namespace {

using netdem::app::netsolve::parse_double;
using netdem::app::netsolve::parse_friction;
using netdem::app::netsolve::parse_int;
using netdem::app::netsolve::PackArgs;
using netdem::app::netsolve::activity;

std::string g_command;

using netdem::app::netsolve::CompactArgs;
using netdem::app::netsolve::RunArgs;
using netdem::app::netsolve::run_dir_options;

/// netsolve pack --dim 3: the 3D ballistic deposition (ballistic3d.hpp), packing.csv in the 3D
/// format, particles.vtp (x, y, z with radius and z as point data) and summary.json.
int run_pack_3d(const PackArgs& a, const RunArgs& ra, const fs::path& out) {
  netdem::app::check_run_dir(out, run_dir_options(ra));
  netdem::app::netsolve::check_deposition_size(a);
  if (a.lateral != "walls" && a.lateral != "periodic")
    throw netdem::app::UsageError(fmt::format("--lateral '{}' is not 'walls' or 'periodic'", netdem::packing::quote_input(a.lateral)));
  activity() = fmt::format("building the 3D ballistic deposition of width {} R", a.width);
  const auto t0 = std::chrono::steady_clock::now();
  const auto pk = netdem::app::netsolve::make_packing_3d(a);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  activity() = "writing the packing";
  netdem::app::open_run_dir(out, g_command, run_dir_options(ra));
  netdem::packing::write_packing_csv(pk, out / "packing.csv");
  const bool periodic = a.lateral == "periodic";
  const auto st = netdem::packing::contact_stats(pk, 1e-6, periodic);
  netdem::app::write_file_atomic(out / "particles.vtp",
                                 netdem::app::vtp_particles_3d(pk.x, pk.y, &pk.z, {{"radius", 1, pk.r}, {"z", 1, pk.z}}));
  nlohmann::json j;
  j["command"] = g_command;
  j["dim"] = 3;
  j["lateral"] = a.lateral;
  j["seed"] = a.seed;
  j["width"] = a.width;
  j["particles"] = st.particles;
  j["sphere_contacts"] = st.disk_contacts;
  j["wall_contacts"] = st.wall_contacts;
  j["density"] = st.density;
  j["coordination"] = st.coordination;
  j["timing_s"] = {{"deposition", wall}};
  j["status"] = "ok";
  j["status_reason"] = "a packing has no convergence criteria";
  netdem::app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  netdem::app::close_run_dir(out);
  netdem::app::summary_printf("seed %llu (3D, %s): %zu spheres, %zu contacts (+%zu wall), D0 = %.4f, Z = %.3f -> %s\n",
              static_cast<unsigned long long>(a.seed), a.lateral.c_str(), st.particles, st.disk_contacts, st.wall_contacts,
              st.density, st.coordination, (out / "packing.csv").c_str());
  return 0;
}

int run_pack(const PackArgs& a, const RunArgs& ra, const fs::path& out) {
  if (a.dim == 3) return run_pack_3d(a, ra, out);
  netdem::app::check_run_dir(out, run_dir_options(ra));
  netdem::app::netsolve::check_deposition_size(a);
  activity() = fmt::format("building the ballistic deposition of width {} R", a.width);
  const auto pk = netdem::app::netsolve::make_packing(a);
  activity() = "writing the packing";
  netdem::app::open_run_dir(out, g_command, run_dir_options(ra));
  netdem::packing::write_packing_csv(pk, out / "packing.csv");
  const auto st = netdem::packing::contact_stats(pk);
  nlohmann::json j;
  j["command"] = g_command;
  j["seed"] = a.seed;
  j["particles"] = st.particles;
  j["disk_contacts"] = st.disk_contacts;
  j["wall_contacts"] = st.wall_contacts;
  j["density"] = st.density;
  j["coordination"] = st.coordination;
  j["status"] = "ok";
  j["status_reason"] = "a packing has no convergence criteria";
  netdem::app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  netdem::app::close_run_dir(out);
  netdem::app::summary_printf("seed %llu: %zu particles, %zu contacts (+%zu wall), D0 = %.4f, Z = %.3f -> %s\n",
              static_cast<unsigned long long>(a.seed), st.particles, st.disk_contacts, st.wall_contacts, st.density,
              st.coordination, (out / "packing.csv").c_str());
  return 0;
}

}  // namespace

/// The options of `pack --route green-body` (pack_green.hpp); returned so that main can refuse
/// them with the ballistic route.
std::vector<CLI::Option*> add_green_body_options(CLI::App* pack, netdem::app::netsolve::GreenArgs& ga) {
  auto& gb = ga.body;
  return {
      pack->add_option("--n", gb.n, "green-body: number of spheres")->capture_default_str(),
      pack->add_option("--diameter", ga.diameter, "green-body: mean diameter [m]")->capture_default_str(),
      pack->add_option("--dispersion", gb.dispersion, "green-body: diameters uniform in mean (1 +- dispersion)")->capture_default_str(),
      pack->add_option("--target-density", gb.target_density, "green-body: sum of sphere volumes / wall-box volume at the end")
          ->capture_default_str(),
      pack->add_option("--aspect", gb.aspect, "green-body: intended final height / width (x = y)")->capture_default_str(),
      pack->add_option("--solid-density", gb.solid_density, "green-body: particle material density [kg/m^3] (Cu)")->capture_default_str(),
      pack->add_option("--friction", gb.mu_settle, "green-body: particle friction while settling and at the final rest")
          ->capture_default_str(),
      pack->add_option("--compress-friction", gb.mu_compress, "green-body: particle friction during the compression")
          ->capture_default_str(),
      pack->add_option("--wall-friction", gb.mu_wall, "green-body: sphere-wall friction")->capture_default_str(),
      pack->add_option("--gravity", gb.gravity, "green-body: gravity along -z [m/s^2] (at a fixed stiffness number it rescales time only)")
          ->capture_default_str(),
      pack->add_option("--stiffness-number", gb.stiffness_number, "green-body: kappa = k r / (m g) of the mean sphere")
          ->capture_default_str(),
      pack->add_option("--restitution", gb.restitution, "green-body: normal restitution of a mean pair")->capture_default_str(),
      pack->add_option("--steps-per-contact", gb.steps_per_contact, "green-body: time step t_c / this (mean pair)")->capture_default_str(),
      pack->add_option("--wall-speed", gb.wall_speed, "green-body: speed of the fastest compressing wall / sqrt(g r)")
          ->capture_default_str(),
      pack->add_option("--rest-energy", gb.rest_energy, "green-body: at rest when the kinetic energy per sphere < this x m g r")
          ->capture_default_str(),
      pack->add_option("--max-overlap", gb.max_mean_overlap, "green-body: refuse (unreachable, exit 3) a mean pair overlap / r above this at rest")
          ->capture_default_str(),
      pack->add_option("--cloud-fraction", gb.cloud_fraction, "green-body: solid fraction of the initial cloud's box")->capture_default_str(),
      pack->add_option("--lamina", ga.lamina, "green-body: lamina width q_s of Eq 48 [m] (laminar.csv)")->capture_default_str(),
      pack->add_option("--bulk-margin", ga.bulk_margin, "green-body: the bulk density's region keeps this many mean diameters from every wall")
          ->capture_default_str(),
      pack->add_flag("--quiet", ga.quiet, "green-body: no progress on stderr"),
      pack->add_flag("--allow-long", ga.allow_long, "green-body: run even above 5e10 particle-steps (hours of one core)")};
}

/// The options of `pack --periodic` (pack_periodic.hpp) but the flag itself, returned so that main
/// can refuse them without it.
std::vector<CLI::Option*> add_periodic_options(CLI::App* pack, netdem::app::netsolve::PeriodicPackArgs& pp) {
  pack->add_flag("--periodic", pp.periodic, "a periodic packing: a random gas in a periodic cell compressed by the DEM until "
                                            "it jams at --jam-pressure (--n particles, default 1600; r = R[--r-min, --r-max])");
  return {pack->add_option("--pack-friction", pp.pack.friction, "--periodic: Coulomb friction of the packing's linear contact law")
              ->capture_default_str(),
          pack->add_option("--jam-pressure", pp.pack.pressure,
                           "--periodic: the pressure p / k_n (3D: p R / k_n) at which the packing is held at rest (overlaps "
                           "of this order x R)")
              ->capture_default_str()};
}

/// netsolve pack --periodic: the deposition's and the green body's options it does not take are
/// refused; --n and --quiet are the green body's, --r-min, --r-max, --mono and --seed the deposition's.
int run_pack_periodic_cli(CLI::App* pack, const std::vector<CLI::Option*>& green_opts,
                          const netdem::app::netsolve::GreenArgs& ga, const PackArgs& pa,
                          netdem::app::netsolve::PeriodicPackArgs pp, const RunArgs& ra, const std::string& out) {
  if (ga.route == "green-body") throw netdem::app::UsageError("--periodic and --route green-body exclude each other");
  for (const char* name : {"--width", "--lid", "--lateral", "--route"})
    if (pack->count(name) > 0)
      throw netdem::app::UsageError(fmt::format("{} is an option of the deposition, not of --periodic (use --n)", name));
  for (std::size_t k = 1; k < green_opts.size(); ++k)  // all but --n and --quiet
    if (green_opts[k]->count() > 0 && green_opts[k]->get_name() != "--quiet")
      throw netdem::app::UsageError(fmt::format("{} is an option of --route green-body", green_opts[k]->get_name()));
  if (green_opts[0]->count() > 0) pp.pack.n = ga.body.n;
  pp.pack.r_min = pa.mono ? 1.0 : pa.r_min;
  pp.pack.r_max = pa.mono ? 1.0 : pa.r_max;
  pp.pack.seed = pa.seed;
  pp.quiet = ga.quiet;
  return netdem::app::netsolve::run_pack_periodic(pp, pa.dim, ra.overwrite, g_command, out);
}

int netsolve_command(int argc, char** argv) {
  netdem::app::reset_run_state();
  g_command = netdem::app::shell_command(argc, argv);
  if (argc > 1 && (std::string(argv[1]) == "yield" || std::string(argv[1]) == "yield-merge")) return run_yield_command(argc, argv);
  if (argc > 1 && std::string(argv[1]) == "sinter-pair") return run_sinter_pair_command(argc, argv);
  if (argc > 1 && std::string(argv[1]) == "sinter") return run_sinter_command(argc, argv);
  if (argc > 1 && argv[1][0] != '-' && std::string(argv[1]) != "pack" && std::string(argv[1]) != "compact") {
    std::string word;
    for (const char* c = argv[1]; *c != '\0' && word.size() < 80; ++c) word += std::isprint(static_cast<unsigned char>(*c)) ? *c : '?';
    netdem::app::print_error_line(fmt::format(
        "netsolve: error: unknown subcommand '{}': use pack, compact, yield, yield-merge, sinter-pair or sinter (see --help)", word));
    return netdem::app::exit_code::usage;
  }
  CLI::App app{"netsolve: quasi-static implicit network solver for powder compaction (Redanz & Fleck 2001)"};
  app.require_subcommand(1);
  app.add_subcommand("yield", "yield surface probes after precompaction (docs/yield.md; own --help)");
  app.add_subcommand("yield-merge", "assemble yield_points.csv from the probe files of several yield runs");
  app.add_subcommand("sinter-pair", "one two-particle sintering contact against time (docs/sintering_pair.md; own --help)");
  app.add_subcommand("sinter", "the staggered sintering scheme of Ivannikov et al. in 3D (docs/staggered.md; own --help)");
  PackArgs pa;
  CompactArgs ca;
  RunArgs ra;
  std::string out;
  auto add_pack_opts = [&](CLI::App* c) {
    c->add_option("--width", pa.width, "box width W in units of the mean radius R")->capture_default_str();
    c->add_option("--r-min", pa.r_min, "smallest radius / R")->capture_default_str();
    c->add_option("--r-max", pa.r_max, "largest radius / R")->capture_default_str();
    c->add_flag("--mono", pa.mono, "monosized disks (r = R)");
    c->add_option("--seed", pa.seed, "random seed of the deposition, a whole number in [0, 2^64)")
        ->check(netdem::app::netsolve::seed_validator())
        ->capture_default_str();
    c->add_flag("--overwrite", ra.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
    c->add_option("--lid", pa.lid, "stop rule: 'centre' keeps disks whose centre is below the lid (D0 near the paper's), 'inside' only whole disks")->capture_default_str();
  };
  auto* pack = app.add_subcommand("pack", "ballistic deposition packing (section 2.2; --dim 3: spheres, docs/packing.md)");
  add_pack_opts(pack);
  pack->add_option("--dim", pa.dim, "2: disks (the paper's packings), 3: spheres under gravity along -z (ballistic3d.hpp)")
      ->check(CLI::IsMember({2, 3}))
      ->capture_default_str();
  auto* o_lateral = pack->add_option("--lateral", pa.lateral, "3D only: side boundary 'walls' (planes x, y = 0, W) or 'periodic' in x and y")
                        ->capture_default_str();
  pack->add_option("--out", out, "output folder")->default_val("results/pack");
  // --route green-body (3D): the route of Ivannikov et al. (pack_green.hpp), lengths in SI metres
  netdem::app::netsolve::GreenArgs ga;
  pack->add_option("--route", ga.route, "3D only: 'ballistic' deposition, or 'green-body': a random cloud, gravity, a lid, "
                                        "triaxial compression to --target-density with the 3D DEM (Ivannikov et al. 3.2; SI metres)")
      ->check(CLI::IsMember({"ballistic", "green-body"}))
      ->capture_default_str();
  const std::vector<CLI::Option*> green_opts = add_green_body_options(pack, ga);
  // --periodic: the periodic route (pack_periodic.hpp); its --n and --quiet are the green body's options
  netdem::app::netsolve::PeriodicPackArgs pp;
  const std::vector<CLI::Option*> periodic_opts = add_periodic_options(pack, pp);
  auto* comp = app.add_subcommand("compact", "compaction to a target density (default: polydisperse packing, hydrostatic, sticking, D = 0.85)");
  add_pack_opts(comp);
  const netdem::app::netsolve::CompactCli ccli = netdem::app::netsolve::add_compact_options(comp, ca, ra, out);
  comp->add_option("--dim", pa.dim, "2: disks; 3: spheres (netsolve pack --dim 3's deposition, --width 20 unless given, or a 3D "
                                    "--packing; --affine, --boundary layer or periodic; --path E11,E22,E33[,E23,E13,E12], closed die along z)")
      ->check(CLI::IsMember({2, 3}))
      ->capture_default_str();
  netdem::app::add_scene_config(app, "netsolve", "", netdem::app::kNetsolveSections);
  try {
    app.parse(argc, argv);
    netdem::app::set_scene(*app.get_subcommands().front(), "netsolve", app.get_subcommands().front()->get_name());
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    netdem::app::print_error_line(fmt::format("netsolve: error: {} (see --help)", e.what()));
    return 2;
  }
  return netdem::app::netsolve::guarded("netsolve", [&]() {
    if (*pack) {
      if (pa.dim == 2 && o_lateral->count() > 0)
        throw netdem::app::UsageError("--lateral is for --dim 3 only (the 2D deposition has side walls)");
      if (pa.dim == 3 && pack->count("--lid") > 0 && pa.lid != "inside")
        throw netdem::app::UsageError(fmt::format("--lid '{}': the 3D deposition implements only --lid inside (whole spheres below the lid)",
                                                  netdem::packing::quote_input(pa.lid)));
      if (pp.periodic) return run_pack_periodic_cli(pack, green_opts, ga, pa, pp, ra, out);
      for (CLI::Option* opt : periodic_opts)
        if (opt->count() > 0) throw netdem::app::UsageError(fmt::format("{} is an option of --periodic", opt->get_name()));
      if (ga.route == "green-body") {
        if (pa.dim != 3) throw netdem::app::UsageError("--route green-body is 3D: add --dim 3");
        for (const char* name : {"--width", "--r-min", "--r-max", "--mono", "--lateral", "--lid"})
          if (pack->count(name) > 0)
            throw netdem::app::UsageError(fmt::format("{} is an option of the ballistic deposition, not of --route green-body "
                                                      "(use --n, --diameter, --dispersion)", name));
        return netdem::app::netsolve::run_pack_green_body(ga, pa.seed, ra.overwrite, g_command, out);
      }
      if (pack->count("--route") > 0 && pa.dim != 3)
        throw netdem::app::UsageError("--route is for --dim 3 only (the 2D packing is the ballistic deposition)");
      for (CLI::Option* opt : green_opts)
        if (opt->count() > 0)
          throw netdem::app::UsageError(fmt::format("{} is an option of --route green-body", opt->get_name()));
      return run_pack(pa, ra, out);
    }
    if (pa.dim == 3 && comp->count("--width") == 0) pa.width = netdem::app::netsolve::kDefaultWidth3d;  // ~1000 spheres, not ~7e4
    if (pa.dim == 3 && comp->count("--lid") > 0 && pa.lid != "inside")
      throw netdem::app::UsageError(fmt::format("--lid '{}': the 3D deposition implements only --lid inside (whole spheres below the lid)",
                                                netdem::packing::quote_input(pa.lid)));
    return netdem::app::netsolve::run_compact_cli(ccli, pa, ca, ra, g_command, out);
  });
}
