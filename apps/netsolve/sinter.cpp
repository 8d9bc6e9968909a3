// netsolve sinter: the staggered quasi-static sintering scheme of Ivannikov et al. in 3D (issue 17
// item 4; the library: netdem/quasistatic/staggered.hpp; docs/staggered.md "netsolve sinter").
//
//   netsolve sinter [--packing FILE | --generate cu [--green-density 0.58] [--seed S]] [--material cu|ti|FILE] [--set KEY=VALUE]...
//                   [--temperature T | --profile FILE] [--time T_END] [--strategy 1|2] [--dt-max S] [--dt-initial S]
//                   [--eps-lim E] [--alpha A] [--new-contacts on|off] [--x0 X0_OVER_R] [--x-max X_OVER_R] [--E PA] [--nu NU]
//                   [--planes box|spheres] [--snapshots N] [--restart STATE] [--checkpoints T1,T2,...] [--max-steps N] [--out DIR] [--quiet] [--overwrite] [--allow-unconverged]
//
// SI units everywhere (m, s, K, N, Pa). Defaults: the Cu benchmark (the green-body packing of 805
// spheres made in-process, Cu, 1293 K, 5000 s, strategy 2, dt_max = 10 s, new contacts on).
// Writes command.txt, history.csv (one row per accepted step and one at the start), steps.csv (the
// solver's record of every step), dL_bar.csv (Eq 44 per contact at the end), particles_K.vtp and
// bonds_K.vtp snapshots with snapshots.pvd (at the first step end at or after each of N equally
// spaced times, and the last: snapshots do not change the steps), state.txt (the restart state;
// state_K.txt at each --checkpoints time, where the steps end), history.svg, report.md and
// summary.json (last); with --generate also packing.csv and laminar.csv. Bad input: one line
// on stderr, exit 2, no output folder; exit 1 for an error during the run; a run that could not
// reach --time ("unstable": a step failed or gave non-finite values; "incomplete": --max-steps, or
// a green-body packing that missed its target) exits 3 (README.md "Exit status").
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/dynamic/green_body.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/laminar.hpp"
#include "netdem/quasistatic/staggered.hpp"
#include "output.hpp"
#include "sinter_material.hpp"
#include "sinter_files.hpp"
#include "sinter_plot.hpp"
#include "parse.hpp"
#include "setup.hpp"
#include "status.hpp"

int run_sinter_command(int argc, char** argv);

namespace {

namespace fs = std::filesystem;
namespace sp = netdem::contact::sinter;
namespace st = netdem::qs::staggered;
using netdem::app::Field;
using netdem::app::UsageError;
using netdem::app::write_file_atomic;
using nlohmann::json;

struct Args {
  std::string packing, generate = "cu", material = "cu", profile, new_contacts = "on", planes = "box", restart, checkpoints, out = "results/sinter";
  std::vector<std::string> set;
  double green_density = 0.58, temperature = 1293.0, t_end = 5000.0, dt_max = 10.0, dt_initial = st::StaggeredOptions{}.dt_initial,
         eps_lim = st::StaggeredOptions{}.eps_lim, alpha = st::StaggeredOptions{}.alpha, x0 = st::StaggeredOptions{}.x0_over_R,
         x_max = 0.0, E = 0.0, nu = -1.0;
  int strategy = 2, snapshots = 5;
  long max_steps = 10'000'000;
  std::uint64_t seed = 1;
  bool quiet = false, overwrite = false, allow_unconverged = false;
};

/// One row of history.csv.
struct Row {
  double t = 0, T = 0, dt = 0, sx = 0, sy = 0, sz = 0, density = 0, neck_mean = 0, neck_std = 0;
  std::size_t contacts = 0;
  int newton = 0;
  long substeps = 0;
  bool finite() const {
    for (double v : {t, T, dt, sx, sy, sz, density, neck_mean, neck_std})
      if (!std::isfinite(v)) return false;
    return true;
  }
};

constexpr const char* kHistoryHeader = "t,T,dt,shrink_x,shrink_y,shrink_z,density,neck_mean,neck_std,contacts,newton,substeps";
constexpr const char* kStepsHeader =
    "step,t,dt,rejected,contacts_substepped,new_contacts,newly_frozen,gmres_iterations,refactorised,max_error,max_shrink_error";
constexpr const char* kDLbarHeader = "a,b,L0,dL_bar,dL_bar_over_L0,neck,t_created";

// t and dt with 17 digits: a t read back from history.csv is the same double (--time t1 of a
// restart test stops exactly at a step of the uninterrupted run)
std::string row_csv(const Row& r) {
  return fmt::format("{:.17g},{:.10g},{:.17g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{},{},{}\n", r.t, r.T, r.dt, r.sx, r.sy,
                     r.sz, r.density, r.neck_mean, r.neck_std, r.contacts, r.newton, r.substeps);
}

/// Mean and population standard deviation of the contacts' necks x / R_min0.
void neck_stats(const std::vector<st::Contact>& cs, double& mean, double& sd) {
  mean = sd = 0.0;
  if (cs.empty()) return;
  for (const auto& c : cs) mean += c.pair.x_over_R();
  mean /= static_cast<double>(cs.size());
  for (const auto& c : cs) sd += (c.pair.x_over_R() - mean) * (c.pair.x_over_R() - mean);
  sd = std::sqrt(sd / static_cast<double>(cs.size()));
}

Row make_row(const st::Staggered& s, const st::StepRecord* rec) {
  Row r;
  r.t = s.time();
  r.T = rec ? rec->T : s.temperature()(s.time());
  r.dt = rec ? rec->dt : 0.0;
  const Eigen::Matrix3d F = s.homogeneous_strain();
  r.sx = 0.0 - F(0, 0);  // not -F: no "-0" in the file
  r.sy = 0.0 - F(1, 1);
  r.sz = 0.0 - F(2, 2);
  r.density = s.density();
  neck_stats(s.contacts(), r.neck_mean, r.neck_std);
  r.contacts = s.contacts().size();
  r.newton = rec ? rec->solves : 0;
  r.substeps = rec ? rec->substeps : 0;
  return r;
}

/// Population moments of a sample: mean, standard deviation, skewness g1 and excess kurtosis g2
/// (null when the standard deviation is below 1e-10 of the mean: all equal up to rounding).
json moments(const std::vector<double>& v) {
  const double n = static_cast<double>(v.size());
  if (v.empty()) return {{"count", 0}, {"mean", nullptr}, {"std", nullptr}, {"skewness", nullptr}, {"excess_kurtosis", nullptr}};
  double m = 0;
  for (double x : v) m += x;
  m /= n;
  double m2 = 0, m3 = 0, m4 = 0;
  for (double x : v) {
    const double d = x - m;
    m2 += d * d;
    m3 += d * d * d;
    m4 += d * d * d * d;
  }
  m2 /= n;
  m3 /= n;
  m4 /= n;
  // the shape of a spread at the rounding level of the mean is noise: no skewness, no kurtosis
  const bool spread = std::isfinite(m2) && std::sqrt(m2) > 1e-10 * std::fabs(m);
  return {{"count", v.size()},
          {"mean", m},
          {"std", std::sqrt(m2)},
          {"skewness", spread ? json(m3 / std::pow(m2, 1.5)) : json(nullptr)},
          {"excess_kurtosis", spread ? json(m4 / (m2 * m2) - 3.0) : json(nullptr)}};
}

std::string plot_svg(const std::vector<Row>& rows, const std::string& title) {
  std::vector<double> t, sx, sy, sz, neck;
  for (const auto& r : rows) {
    t.push_back(r.t);
    sx.push_back(r.sx);
    sy.push_back(r.sy);
    sz.push_back(r.sz);
    neck.push_back(r.neck_mean);
  }
  return netdem::app::netsolve::history_svg(t, sx, sy, sz, neck, title);
}

// ---- inputs
sp::SinterMaterial load_material(const Args& a, std::string& source) {
  return netdem::app::netsolve::load_sinter_material(a.material, a.set, source);
}

std::string read_text(const fs::path& p, const char* what) {
  if (!fs::is_regular_file(p))
    throw UsageError(fmt::format("{} '{}' is not a readable file", what, netdem::packing::quote_input(p.string())));
  std::ifstream in(p, std::ios::binary);
  if (!in) throw UsageError(fmt::format("{} '{}' cannot be opened", what, netdem::packing::quote_input(p.string())));
  std::ostringstream o;
  o << in.rdbuf();
  return o.str();
}

// The work estimate at the door: a run of `span` seconds takes at least span / dt_max steps; more
// than --max-steps would end "incomplete" after hours, so it is refused now (issue 27).
void check_step_budget(double span, double dt_max, long max_steps) {
  const double min_steps = span / dt_max;
  if (!(min_steps <= static_cast<double>(max_steps)))
    throw UsageError(fmt::format("the run of {:.6g} s needs at least {:.3g} steps of at most {:.6g} s (--dt-max), more than "
                                 "--max-steps {}: shorten --time or raise --max-steps",
                                 span, min_steps, dt_max, max_steps));
}

using netdem::app::netsolve::laminar_csv;
using netdem::app::netsolve::particles_of;
using netdem::app::netsolve::box_plane_counts;
using netdem::app::netsolve::write_snapshot;
using netdem::app::netsolve::pvd;
using netdem::app::netsolve::options_json;
using netdem::app::netsolve::material_json;

/// The options that a restart state fixes: given with --restart they are refused.
const char* const kFixedByState[] = {"--packing", "--generate", "--green-density", "--seed", "--material", "--set",
                                     "--temperature", "--profile", "--strategy", "--dt-max", "--dt-initial", "--eps-lim",
                                     "--alpha", "--new-contacts", "--x0", "--x-max", "--E", "--nu", "--planes"};

// The door checks of a new (not restarted) run's options.
void check_new_run(const Args& a) {
  if (!a.profile.empty() && fs::is_directory(a.profile))
    throw UsageError(fmt::format("--profile '{}' is a folder, not a CSV file", netdem::packing::quote_input(a.profile)));
  if (!(std::isfinite(a.temperature) && a.temperature > 0.0 && a.temperature < 1e4))
    throw UsageError(fmt::format("--temperature must be in (0, 1e4) K, got {}", a.temperature));
  if (a.strategy != 1 && a.strategy != 2) throw UsageError(fmt::format("--strategy must be 1 or 2, got {}", a.strategy));
  if (!(std::isfinite(a.dt_max) && a.dt_max > 0.0)) throw UsageError(fmt::format("--dt-max must be a positive time in seconds, got {}", a.dt_max));
  if (!(std::isfinite(a.dt_initial) && a.dt_initial > 0.0))
    throw UsageError(fmt::format("--dt-initial must be a positive time in seconds, got {}", a.dt_initial));
  if (!(std::isfinite(a.eps_lim) && a.eps_lim > 0.0 && a.eps_lim < 1.0))
    throw UsageError(fmt::format("--eps-lim must be in (0, 1), got {}", a.eps_lim));
  if (!(std::isfinite(a.alpha) && a.alpha > 1.0)) throw UsageError(fmt::format("--alpha must be a finite number above 1, got {}", a.alpha));
  if (!(std::isfinite(a.x0) && a.x0 > 0.0 && a.x0 < 1.0)) throw UsageError(fmt::format("--x0 must be in (0, 1) (x0 / R_min), got {}", a.x0));
  if (!(std::isfinite(a.x_max) && a.x_max >= 0.0 && a.x_max < 1.0))
    throw UsageError(fmt::format("--x-max must be in [0, 1) (x / R_min; 0: the dihedral limit), got {}", a.x_max));
  if (a.x_max > 0.0 && a.x_max <= a.x0) throw UsageError(fmt::format("--x-max {} must be above --x0 {}", a.x_max, a.x0));
  if (!(std::isfinite(a.E) && a.E >= 0.0)) throw UsageError(fmt::format("--E must be a Young's modulus in Pa (> 0), got {}", a.E));
  if (!(std::isfinite(a.nu) && a.nu < 0.5) || (a.nu < 0.0 && a.nu != -1.0))
    throw UsageError(fmt::format("--nu must be a Poisson's ratio in [0, 0.5), got {}", a.nu));
}

/// The record of origin of a restart state: the seed (false if it has none) and the packing into
/// restart_json. Checked: a seed that is not a whole number in [0, 2^64), a packing that is not an
/// object, whose source is not a string or whose particles are not the state's count is refused
/// (the campaign of issue 27: a seed of -1 or 1e300 became "seed": null, a 27-sphere state claimed 100).
bool read_origin(const std::string& state, const std::string& record, std::size_t n, std::uint64_t& seed,
                 json& restart_json) {
  const json origin = json::parse(record);
  if (!origin.is_object()) return false;
  const auto bad = [&](const std::string& what) {
    return UsageError(fmt::format("restart state '{}': /origin/{}", netdem::packing::quote_input(state), what));
  };
  if (origin.contains("packing")) {
    const json& pk = origin["packing"];
    if (!pk.is_object()) throw bad("packing: expected an object");
    if (pk.contains("source") && !pk["source"].is_string()) throw bad("packing/source: expected a string");
    if (pk.contains("particles") && !(pk["particles"].is_number_unsigned() && pk["particles"].get<std::uint64_t>() == n))
      throw bad(fmt::format("packing/particles: expected {}, the number of particles of the state", n));
    restart_json["packing"] = pk;
  }
  if (!origin.contains("seed")) return false;
  if (!origin["seed"].is_number_unsigned()) throw bad("seed: expected a whole number in [0, 2^64)");
  seed = origin["seed"].get<std::uint64_t>();
  return true;
}

int run(const Args& a, const CLI::App& app, const std::string& command) {
  namespace na = netdem::app;
  const auto w0 = std::chrono::steady_clock::now();
  // ---- everything is checked before the output folder exists
  na::RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  na::check_run_dir(a.out, rdo);
  const bool restart = !a.restart.empty();
  if (restart)
    for (const char* name : kFixedByState)
      if (app.count(name) > 0)
        throw UsageError(fmt::format("{} cannot be combined with --restart: the state fixes the particles, material, temperature "
                                     "and solver options (only --time, --snapshots, --checkpoints, --max-steps and the output options apply)",
                                     name));
  if (!(std::isfinite(a.t_end) && a.t_end > 0.0)) throw UsageError(fmt::format("--time must be a positive time in seconds, got {}", a.t_end));
  if (a.snapshots < 0 || a.snapshots > 10000) throw UsageError(fmt::format("--snapshots must be in [0, 10000], got {}", a.snapshots));
  if (a.max_steps < 1) throw UsageError(fmt::format("--max-steps must be at least 1, got {}", a.max_steps));
  const std::vector<double> checkpoints = netdem::app::netsolve::parse_number_list(a.checkpoints, "--checkpoints");

  std::string mat_source, packing_source;
  std::optional<st::Staggered> sim;
  std::optional<sp::SinterMaterial> mat;
  netdem::packing::Packing pk;
  netdem::dem::GreenBodyOptions gb;
  const bool generate = !restart && a.packing.empty();
  json restart_json;
  std::uint64_t seed = a.seed;
  bool seed_known = true;
  if (restart) {
    const std::string text = read_text(a.restart, "--restart");
    try {
      sim.emplace(st::Staggered::load(text, a.restart));
    } catch (const std::exception& e) {
      throw UsageError(e.what());
    }
    if (!(a.t_end > sim->time()))
      throw UsageError(fmt::format("--time {} s is not after the time of the restart state {} ({:.17g} s)", a.t_end,
                                   netdem::packing::quote_input(a.restart), sim->time()));
    check_step_budget(a.t_end - sim->time(), sim->options().dt_max, a.max_steps);
    mat = sim->material();
    mat_source = fmt::format("restart state {}", a.restart);
    packing_source = fmt::format("restart state {}", a.restart);
    restart_json = {{"state", a.restart}, {"t_start", sim->time()}, {"steps_before", sim->steps()}};
    // the seed and the packing of the run that made the sample: the state's record of origin
    seed_known = read_origin(a.restart, sim->origin_record(), sim->particles().size(), seed, restart_json);
  } else {
    check_new_run(a);
    mat = load_material(a, mat_source);
    const double E = a.E > 0.0 ? a.E : mat->youngs_modulus;
    const double nu = a.nu >= 0.0 ? a.nu : mat->poisson_ratio;
    if (!(E > 0.0))
      throw UsageError(fmt::format("material {} has no Young's modulus: add 'E = ...' to it, --set E=PA or --E PA", mat->name));
    if (nu < 0.0)
      throw UsageError(fmt::format("material {} has no Poisson's ratio: add 'nu = ...' to it, --set nu=NU or --nu NU", mat->name));
    if (!(nu < 0.5)) throw UsageError(fmt::format("material {}: Poisson's ratio nu = {} is outside [0, 0.5)", mat->name, nu));
    check_step_budget(a.t_end, a.dt_max, a.max_steps);
    if (generate) {
      gb.seed = a.seed;
      gb.target_density = a.green_density;
      try {
        gb.validate();
      } catch (const std::invalid_argument& e) {
        throw UsageError(fmt::format("--green-density / --seed: {}", e.what()));
      }
      packing_source = fmt::format("generated: green-body route (Ivannikov et al. section 3.2), {} spheres, mean diameter {:g} m +- {:g} %, "
                                   "target density {:g}, seed {}",
                                   gb.n, 2.0 * gb.mean_radius, 100.0 * gb.dispersion, gb.target_density, a.seed);
    } else {
      if (fs::is_directory(a.packing))
        throw UsageError(fmt::format("--packing '{}' is a folder, not a packing CSV file (netsolve pack writes DIR/packing.csv)",
                                     netdem::packing::quote_input(a.packing)));
      if (!fs::is_regular_file(a.packing))
        throw UsageError(fmt::format("--packing '{}' is not a readable file", netdem::packing::quote_input(a.packing)));
      pk = netdem::packing::read_packing_csv(a.packing);
      if (pk.dim != 3)
        throw UsageError(fmt::format("--packing {} is a 2D packing; netsolve sinter needs spheres (id,x,y,z,r, SI metres)",
                                     netdem::packing::quote_input(a.packing, 200)));
      if (pk.size() < 2) throw UsageError(fmt::format("--packing {} holds fewer than two spheres", netdem::packing::quote_input(a.packing, 200)));
      for (double r : pk.r)
        if (!(r <= 1e-2))
          throw UsageError(fmt::format("--packing {}: radius {} m: the packing is in SI metres (25 um is 25e-6); above 1 cm is refused",
                                       netdem::packing::quote_input(a.packing, 200), r));
      packing_source = a.packing;
      seed = pk.seed;
    }
  }
  {
    const double t0 = restart ? sim->time() : 0.0;
    for (double c : checkpoints)
      if (!(c > t0 && c < a.t_end))
        throw UsageError(fmt::format("--checkpoints: {} s is not between the start ({} s) and --time ({} s)", c, t0, a.t_end));
  }
  st::StaggeredOptions so;
  std::array<int, 3> box_fixed{-1, -1, -1};  // particles fixed on the box planes (-1: --planes spheres, or a restart)
  sp::TemperatureProfile prof = sp::TemperatureProfile::constant(restart ? 1.0 : a.temperature);
  if (!restart) {
    so.strategy = a.strategy;
    so.dt_initial = a.dt_initial;
    so.dt_max = a.dt_max;
    so.eps_lim = a.eps_lim;
    so.alpha = a.alpha;
    so.new_contacts = a.new_contacts == "on";
    so.x0_over_R = a.x0;
    so.x_max_over_R = a.x_max;
    so.E = a.E;
    so.nu = a.nu;
    try {
      so.validate();
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
    if (!a.profile.empty()) prof = sp::TemperatureProfile::read_csv(a.profile);
    if (!generate) {
      try {
        if (a.planes == "box") {
          so.plane_origin = {pk.box.x_min, pk.box.y_min, pk.box.z_min};
          box_fixed = box_plane_counts(particles_of(pk), pk.box, so.boundary_factor);
        }
        sim.emplace(particles_of(pk), *mat, prof, so);  // bad particles or options: exit 2, nothing written
      } catch (const std::invalid_argument& e) {
        throw UsageError(fmt::format("--packing {}: {}", netdem::packing::quote_input(a.packing, 200), e.what()));
      }
    }
  }

  // ---- the run
  const fs::path out(a.out);
  if (!a.packing.empty()) rdo.inputs.emplace_back(a.packing);
  if (!a.profile.empty()) rdo.inputs.emplace_back(a.profile);
  if (!a.restart.empty()) rdo.inputs.emplace_back(a.restart);
  if (!restart && a.material != "cu" && a.material != "ti") rdo.inputs.emplace_back(a.material);
  na::activity() = "opening the output folder";
  na::open_run_dir(out, command, rdo);
  if (!a.quiet && seed_known) std::fprintf(stderr, "netsolve sinter: seed %llu\n", static_cast<unsigned long long>(seed));

  na::RunStatus status;
  json green = nullptr;
  double green_wall = 0.0;
  bool green_ok = true;
  if (generate) {
    na::activity() = "running the green-body route";
    const auto g0 = std::chrono::steady_clock::now();
    auto last = g0;
    bool printed = false;
    const auto observer = [&](const netdem::dem::GreenBodyProgress& p) {
      if (a.quiet) return;
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last).count() < 0.5) return;
      last = now;
      printed = true;
      const std::string done = p.fraction >= 0.0 ? fmt::format(" {:5.1f} %", 100.0 * p.fraction) : "";
      std::fprintf(stderr, "\rgreen body: %-8s%s step %8lld  density %.4f   ", p.phase, done.c_str(), static_cast<long long>(p.steps),
                   p.density);
    };
    const netdem::dem::GreenBodyResult res = netdem::dem::make_green_body(gb, observer);
    if (printed) std::fprintf(stderr, "\n");
    green_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - g0).count();
    pk = res.packing;
    pk.comments.emplace_back("green-body route (Ivannikov et al. section 3.2): lengths in metres");
    pk.comments.emplace_back(fmt::format("target density {} status {}", gb.target_density, res.status));
    netdem::packing::write_packing_csv(pk, out / "packing.csv");
    write_file_atomic(out / "laminar.csv", laminar_csv(pk, 25e-6));  // q_s = 0.025 mm: the paper's Fig 10, pack's default
    const auto& b = pk.box;
    const auto bb = netdem::packing::bounding_box(pk);
    green = {{"status", res.status},
             {"status_reason", res.ok() ? std::string("every criterion met") : res.reason},
             {"target_density", gb.target_density},
             {"density_box", pk.solid_volume() / b.volume()},
             {"density_bounding_box", pk.solid_volume() / bb.volume()},
             {"box_mm", {1e3 * b.width(), 1e3 * b.height(), 1e3 * b.depth()}},
             {"overlap_pair_mean", res.overlaps.pair_mean},
             {"overlap_pair_max", res.overlaps.pair_max},
             {"coordination", res.overlaps.coordination},
             {"wall_s", green_wall}};
    green_ok = res.ok();
    if (!green_ok) {
      status.add("incomplete", fmt::format("the green-body packing is {}: {}; not sintered (packing.csv is kept)", res.status, res.reason));
    } else {
      na::activity() = "setting up the network";
      if (a.planes == "box") {
        so.plane_origin = {pk.box.x_min, pk.box.y_min, pk.box.z_min};
        box_fixed = box_plane_counts(particles_of(pk), pk.box, so.boundary_factor);
      }
      sim.emplace(particles_of(pk), *mat, prof, so);
    }
  }
  if (!restart && sim)  // the record of origin travels with every state this run writes
    sim->set_origin_record(json{{"seed", seed_known ? json(seed) : json(nullptr)},
                                {"packing", {{"source", packing_source}, {"particles", sim->particles().size()}}}}
                               .dump());

  std::vector<Row> rows;
  std::string steps_csv = std::string(kStepsHeader) + "\n";
  std::vector<std::pair<int, double>> snaps;
  json checkpoint_json = json::array();
  std::string stopped;
  bool completed = false;
  long rejected = 0, substeps = 0, new_contacts = 0, newly_frozen = 0, gmres = 0, refactorisations = 0, solves = 0;
  double max_error = 0.0, max_shrink_error = 0.0, t_start = 0.0, density0 = 0.0;
  std::size_t contacts0 = 0;
  double sinter_wall = 0.0;
  if (sim) {
    na::activity() = "sintering";
    st::Staggered& s = *sim;
    t_start = s.time();
    const long steps0 = s.steps();
    rows.push_back(make_row(s, nullptr));
    density0 = rows.back().density;
    contacts0 = rows.back().contacts;
    const int N = a.snapshots;
    auto snap_time = [&](int k) { return t_start + (a.t_end - t_start) * static_cast<double>(k) / static_cast<double>(N); };
    int next = 0;
    auto take_snapshots = [&]() {
      while (next < N && s.time() >= snap_time(next)) {
        write_snapshot(out, next, s);
        snaps.emplace_back(next, s.time());
        ++next;
      }
    };
    take_snapshots();
    std::size_t next_checkpoint = 0;
    const auto s0 = std::chrono::steady_clock::now();
    na::Progress progress("sinter", a.t_end - t_start, a.quiet);
    while (s.time() < a.t_end) {
      if (s.steps() - steps0 >= a.max_steps) {
        status.add("incomplete", fmt::format("--max-steps {} reached at t = {:.6g} s", a.max_steps, s.time()));
        break;
      }
      st::StepRecord rec;
      try {
        // a checkpoint is a step boundary: the steps end on it, as those of a run that stops there
        rec = s.step(next_checkpoint < checkpoints.size() ? checkpoints[next_checkpoint] : a.t_end);
      } catch (const std::bad_alloc&) {
        throw;
      } catch (const std::exception& e) {
        stopped = fmt::format("step {} from t = {:.6g} s failed: {}", s.steps() - steps0 + 1, s.time(), e.what());
        break;
      }
      const Row r = make_row(s, &rec);
      rows.push_back(r);
      rejected += rec.rejected;
      substeps += rec.substeps;
      new_contacts += rec.new_contacts;
      newly_frozen += rec.newly_frozen;
      gmres += rec.gmres_iterations;
      refactorisations += rec.refactorised ? 1 : 0;
      solves += rec.solves;
      max_error = std::max(max_error, rec.max_error);
      if (!(rec.max_shrink_error <= max_shrink_error)) max_shrink_error = rec.max_shrink_error;  // also a NaN
      steps_csv += fmt::format("{},{:.17g},{:.17g},{},{},{},{},{},{},{:.6g},{:.6g}\n", s.steps() - steps0, rec.t, rec.dt, rec.rejected,
                               rec.contacts_substepped, rec.new_contacts, rec.newly_frozen, rec.gmres_iterations,
                               rec.refactorised ? 1 : 0, rec.max_error, rec.max_shrink_error);
      if (!r.finite()) {
        stopped = fmt::format("non-finite values at step {} (t = {:.6g} s)", s.steps() - steps0, s.time());
        break;
      }
      take_snapshots();
      if (next_checkpoint < checkpoints.size() && s.time() >= checkpoints[next_checkpoint]) {
        const std::string file = fmt::format("state_{}.txt", next_checkpoint + 1);
        write_file_atomic(out / file, s.save());
        checkpoint_json.push_back({{"file", file}, {"t", s.time()}, {"step", s.steps() - steps0}});
        ++next_checkpoint;
      }
      progress.update(s.time() - t_start);
    }
    progress.finish();
    sinter_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - s0).count();
    completed = stopped.empty() && s.time() >= a.t_end;
    if (!stopped.empty()) status.add("unstable", "stopped: " + stopped);

    na::activity() = "writing the results";
    // the last snapshot, the restart state (state_stopped.txt when a step failed), the Eq 44 distribution
    write_snapshot(out, N, s);
    snaps.emplace_back(N, s.time());
    write_file_atomic(out / "snapshots.pvd", pvd(snaps));
    write_file_atomic(out / (stopped.empty() ? "state.txt" : "state_stopped.txt"), s.save());
  }

  std::string hist = std::string(kHistoryHeader) + "\n";
  for (const auto& r : rows) hist += row_csv(r);
  if (!stopped.empty()) hist += "# stopped: " + stopped + "\n";
  write_file_atomic(out / "history.csv", hist);
  write_file_atomic(out / "steps.csv", steps_csv);

  json j;
  j["command"] = command;
  j["units"] = "SI: m, s, K, N, Pa";
  j["model"] = "staggered quasi-static sintering scheme of Ivannikov et al. (Fig 6) with the two-particle model of "
               "docs/sintering_pair.md (a documented reconstruction) and the Potyondy-Cundall bond (docs/staggered.md)";
  j["seed"] = seed_known ? json(seed) : json(nullptr);
  j["packing"] = {{"source", packing_source}, {"particles", sim ? sim->particles().size() : pk.size()}};
  if (!green.is_null()) j["green_body"] = green;
  if (restart) j["restart"] = restart_json;
  if (mat) j["material"] = material_json(sim ? sim->material() : *mat, mat_source);
  if (restart || !a.profile.empty()) {
    const auto& tp = sim ? sim->temperature() : prof;
    j["temperature"] = {{"profile", restart ? a.restart : a.profile}, {"breakpoints", tp.times().size()}, {"T_start_K", tp(t_start)}};
  } else {
    j["temperature"] = {{"constant_K", a.temperature}};
  }
  j["options"] = options_json(sim ? sim->options() : so);
  j["t_start_s"] = t_start;
  j["t_end_s"] = a.t_end;
  j["snapshots_requested"] = a.snapshots;
  na::RunStatus judged = status;
  if (sim) {
    const st::Staggered& s = *sim;
    // the shrinkage correction leaves y4 + y7 = |x_B - x_A| to rounding: more is not trusted
    constexpr double kMaxShrinkError = 1e-9;
    if (!(max_shrink_error <= kMaxShrinkError))
      judged.add("unconverged", fmt::format("shrinkage correction error {:.3g} above {:g} (y4 + y7 against the centre distance)",
                                            max_shrink_error, kMaxShrinkError));
    const Row& f = rows.back();
    std::size_t frozen = 0;
    std::vector<double> dl, dlr;
    std::string dcsv = std::string(kDLbarHeader) + "\n";
    for (const auto& c : s.contacts()) {
      frozen += c.frozen ? 1 : 0;
      const double L0 = c.L_created;
      dl.push_back(c.dL_bar);
      dlr.push_back(L0 > 0.0 ? c.dL_bar / L0 : 0.0);
      dcsv += fmt::format("{},{},{:.17g},{:.17g},{:.17g},{:.10g},{:.17g}\n", c.a, c.b, L0, c.dL_bar, dlr.back(), c.pair.x_over_R(),
                          c.t_created);
    }
    write_file_atomic(out / "dL_bar.csv", dcsv);
    j["completed"] = completed;
    j["t_stop_s"] = s.time();
    j["x_max_over_R_in_use"] = s.x_max_over_R();
    j["fixed_dofs"] = s.fixed_dofs();
    j["boundary_planes"] = restart ? json("as in the restart state")
                           : a.planes == "box"
                               ? json({{"planes", "lower faces of the packing's box"},
                                       {"box_lower_corner", {pk.box.x_min, pk.box.y_min, pk.box.z_min}},
                                       {"particles_on_x_y_z_planes", {box_fixed[0], box_fixed[1], box_fixed[2]}}})
                               : json({{"planes", "lower faces of the spheres' bounding box (the library's own)"}});
    j["final"] = {{"t", f.t},
                  {"T", f.T},
                  {"shrink_x", f.sx},
                  {"shrink_y", f.sy},
                  {"shrink_z", f.sz},
                  {"shrink_mean", (f.sx + f.sy + f.sz) / 3.0},
                  {"density", f.density},
                  {"density_start", density0},
                  {"neck_mean", f.neck_mean},
                  {"neck_std", f.neck_std},
                  {"contacts", f.contacts},
                  {"contacts_start", contacts0},
                  {"frozen_contacts", frozen}};
    j["dL_bar"] = {{"what", "Eq 44 of the last step per contact (dL_bar.csv): corrected minus free y4 + y7 [m]; over L0 = the centre "
                             "distance at the contact's creation; population moments"},
                   {"dL_bar", moments(dl)},
                   {"dL_bar_over_L0", moments(dlr)}};
    j["steps"] = {{"accepted", rows.size() - 1}, {"total_in_state", s.steps()}, {"rejected", rejected},
                  {"substeps", substeps},        {"linear_solves", solves},     {"gmres_iterations", gmres},
                  {"refactorisations", refactorisations}, {"new_contacts", new_contacts}, {"newly_frozen", newly_frozen},
                  {"max_error_over_eps_lim", max_error},  {"max_shrink_error", max_shrink_error}};
    const st::Timers& tm = s.timers();
    const double parts = tm.detect + tm.integrate + tm.assemble + tm.factorise + tm.solve + tm.correct;
    j["timers_s"] = {{"detect", tm.detect},     {"integrate", tm.integrate}, {"assemble", tm.assemble},
                     {"factorise", tm.factorise}, {"solve", tm.solve},       {"correct", tm.correct},
                     {"sum", parts},             {"sinter_loop_wall", sinter_wall},
                     {"note", restart ? "the library's timers are cumulative over the restarted run (what the state carries)"
                                      : "cumulative over this run"}};
    json sn = json::array();
    for (const auto& [k, t] : snaps) sn.push_back({{"index", k}, {"t", t}, {"particles", fmt::format("particles_{:03d}.vtp", k)},
                                                   {"bonds", fmt::format("bonds_{:03d}.vtp", k)}});
    j["snapshots"] = sn;
    j["checkpoints"] = checkpoint_json;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  j["wall_s"] = wall;
  j["green_body_wall_s"] = green_wall;
  j["files"] = {{"history", "history.csv"}, {"steps", "steps.csv"},   {"dL_bar", "dL_bar.csv"}, {"state", stopped.empty() ? "state.txt" : "state_stopped.txt"},
                {"snapshots", "snapshots.pvd"}, {"plot", "history.svg"}, {"report", "report.md"}};

  // ---- plot and report
  const std::string title = fmt::format("netsolve sinter: {}, {}, {} particles", mat ? mat->name : std::string("?"),
                                        restart ? std::string("restart") : a.profile.empty() ? fmt::format("T = {:g} K", a.temperature) : "T(t) profile",
                                        sim ? sim->particles().size() : pk.size());
  write_file_atomic(out / "history.svg", plot_svg(rows, title));
  std::string md = fmt::format("# {}\n\n`{}`\n\nStatus: **{}** ({})\n\n", title, command, judged.status, judged.reason());
  if (sim) {
    const Row& f = rows.back();
    const auto& fj = j["final"];
    const auto& dj = j["dL_bar"]["dL_bar_over_L0"];
    auto num = [](const json& v) { return v.is_null() ? std::string("-") : fmt::format("{:.4g}", v.get<double>()); };
    md += "| quantity | value |\n|---|---|\n";
    md += fmt::format("| time | {:.6g} s (from {:.6g} s, to {:.6g} s requested) |\n", f.t, t_start, a.t_end);
    md += fmt::format("| shrinkage x, y, z (-F_ii) | {:.5g}, {:.5g}, {:.5g} |\n", f.sx, f.sy, f.sz);
    md += fmt::format("| density (bounding box) | {:.5f} -> {:.5f} |\n", density0, f.density);
    md += fmt::format("| neck x/R_min mean (std) | {:.5f} ({:.5f}) |\n", f.neck_mean, f.neck_std);
    md += fmt::format("| contacts (start, new, frozen) | {} ({}, {}, {}) |\n", f.contacts, contacts0, new_contacts,
                      fj["frozen_contacts"].get<std::size_t>());
    md += fmt::format("| steps (rejected), sub-steps, linear solves | {} ({}), {}, {} |\n", rows.size() - 1, rejected, substeps, solves);
    md += fmt::format("| refactorisations, GMRES iterations | {}, {} |\n", refactorisations, gmres);
    md += fmt::format("| dL_bar/L0 of the last step: mean, std, skewness, excess kurtosis (Eq 44) | {}, {}, {}, {} |\n", num(dj["mean"]),
                      num(dj["std"]), num(dj["skewness"]), num(dj["excess_kurtosis"]));
    md += fmt::format("| max shrinkage-correction error | {:.3g} |\n\n", max_shrink_error);
    const st::Timers& tm = sim->timers();
    md += "## Timing\n\n| part | s | % of the sintering loop |\n|---|---|---|\n";
    const double base = sinter_wall > 0.0 ? sinter_wall : 1.0;
    for (const auto& [name, v] : std::vector<std::pair<const char*, double>>{{"detect", tm.detect},
                                                                             {"integrate (per-contact model)", tm.integrate},
                                                                             {"assemble", tm.assemble},
                                                                             {"factorise", tm.factorise},
                                                                             {"solve", tm.solve},
                                                                             {"correct", tm.correct}})
      md += fmt::format("| {} | {:.3f} | {:.1f} |\n", name, v, 100.0 * v / base);
    md += fmt::format("| sintering loop (wall, with output) | {:.3f} | 100 |\n", sinter_wall);
    if (generate) md += fmt::format("| green-body packing | {:.3f} | |\n", green_wall);
    md += fmt::format("| whole run | {:.3f} | |\n\n", wall);
  }
  md += "![history](history.svg)\n\n*Left: shrinkage per axis (least-squares homogeneous strain of the centres); right: the mean neck "
        "x / R_min.*\n";
  write_file_atomic(out / "report.md", md);
  judged.write(j);
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  na::close_run_dir(out);

  if (sim) {
    const Row& f = rows.back();
    std::printf("t = %.6g s: shrinkage %.5g %.5g %.5g, density %.5f, neck %.5f, %zu contacts, %zu steps, %.3g s -> %s\n", f.t, f.sx, f.sy,
                f.sz, f.density, f.neck_mean, f.contacts, rows.size() - 1, wall, out.c_str());
  }
  if (!stopped.empty()) {
    std::fprintf(stderr, "netsolve sinter: error: unstable: %s (history.csv keeps the steps before)\n", stopped.c_str());
    return na::exit_code::untrustworthy;
  }
  if (!judged.ok()) {
    // a run that did not reach --time exits 3 whatever --allow-unconverged says
    const bool forgiven = a.allow_unconverged && completed;
    std::fprintf(stderr, "netsolve sinter: %s: %s: %s\n", forgiven ? "warning (--allow-unconverged)" : "error", judged.status.c_str(),
                 judged.reason().c_str());
    return forgiven ? na::exit_code::ok : na::exit_code::untrustworthy;
  }
  return na::exit_code::ok;
}

}  // namespace

int run_sinter_command(int argc, char** argv) {
  std::string command;
  for (int k = 0; k < argc; ++k) command += (k ? " " : "") + std::string(argv[k]);
  Args a;
  CLI::App app{"netsolve sinter: the staggered quasi-static sintering scheme of Ivannikov et al. in 3D (docs/staggered.md). SI units; "
               "defaults: the Cu benchmark."};
  auto* o_pk = app.add_option("--packing", a.packing, "3D packing CSV (id,x,y,z,r in metres, as netsolve pack --dim 3 --route green-body writes)");
  auto* o_gen = app.add_option("--generate", a.generate, "make the packing in-process: cu = the green-body route with 805 spheres, "
                                                         "mean diameter 50e-6 m +- 10 % (the default when --packing is not given)")
                    ->check(CLI::IsMember({"cu"}))
                    ->capture_default_str();
  o_pk->excludes(o_gen);
  app.add_option("--green-density", a.green_density, "--generate: target density of the green body (0.60 is refused as unreachable, docs/packing.md)")
      ->capture_default_str();
  app.add_option("--seed", a.seed, "--generate: seed of the packing, a whole number in [0, 2^64)")
      ->check(netdem::app::netsolve::seed_validator())
      ->capture_default_str();
  app.add_option("--material", a.material, "cu | ti (built in) | FILE (docs/sintering_pair.md format; needs E and nu)")->capture_default_str();
  app.add_option("--set", a.set, "override a material key, KEY=VALUE (repeatable), e.g. --set D_vol0=1.9e-7");
  auto* o_T = app.add_option("--temperature", a.temperature, "constant temperature [K]")->capture_default_str();
  auto* o_p = app.add_option("--profile", a.profile, "temperature profile: CSV with header time,T [s, K], linear between rows");
  o_T->excludes(o_p);
  app.add_option("--time", a.t_end, "end time [s]")->capture_default_str();
  app.add_option("--strategy", a.strategy, "time marching: 1 (one global dt, steps rejected) | 2 (global dt, per-contact sub-steps)")
      ->capture_default_str();
  app.add_option("--dt-max", a.dt_max, "largest global step [s]")->capture_default_str();
  app.add_option("--dt-initial", a.dt_initial, "first global step [s]")->capture_default_str();
  app.add_option("--eps-lim", a.eps_lim, "relative error limit of x and y4 + y7 per (sub-)step")->capture_default_str();
  app.add_option("--alpha", a.alpha, "step factor of Eqs 45 and 47 (> 1)")->capture_default_str();
  app.add_option("--new-contacts", a.new_contacts, "detect new contacts at every step (off: the paper's Fig 11c)")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_option("--x0", a.x0, "neck of a new or initial contact, x0 / R_min")->capture_default_str();
  app.add_option("--x-max", a.x_max, "a contact freezes at x / R_min = this (0: the dihedral limit sin(psi/2))")->capture_default_str();
  app.add_option("--E", a.E, "Young's modulus of the bonds [Pa] (0: the material's E)")->capture_default_str();
  app.add_option("--nu", a.nu, "Poisson's ratio of the bonds (-1: the material's nu)")->capture_default_str();
  app.add_option("--planes", a.planes, "boundary planes (section 3.3): box = the lower faces of the packing's box (the "
                                      "walls), spheres = those of the spheres' bounding box only")
      ->check(CLI::IsMember({"box", "spheres"}))
      ->capture_default_str();
  app.add_option("--snapshots", a.snapshots, "particles_K.vtp / bonds_K.vtp at N equally spaced times, plus the last")->capture_default_str();
  app.add_option("--restart", a.restart, "continue from a state.txt of an earlier run to --time, into a new --out folder");
  app.add_option("--checkpoints", a.checkpoints, "comma list of times [s] at which the steps end and state_K.txt is written (K = 1, 2, ...)");
  app.add_option("--max-steps", a.max_steps, "stop (incomplete, exit 3) after this many steps")->capture_default_str();
  app.add_flag("--quiet", a.quiet, "no progress on stderr");
  app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
  app.add_flag("--allow-unconverged", a.allow_unconverged, "exit 0 for a run that reached --time but summary.json marks untrustworthy");
  app.add_option("--out", a.out, "output folder")->capture_default_str();
  try {
    app.parse(argc - 1, argv + 1);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "netsolve sinter: error: %s (see --help)\n", e.what());
    return 2;
  }
  return netdem::app::netsolve::guarded("netsolve sinter", [&]() { return run(a, app, command); });
}
