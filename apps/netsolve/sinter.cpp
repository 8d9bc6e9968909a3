// netsolve sinter: the staggered quasi-static sintering scheme of Ivannikov et al. in 3D (issue 17
// item 4; docs/staggered.md "netsolve sinter"). The command line and the files only: the scheme is
// netdem/quasistatic/staggered.hpp, its run loop (stopping rules, snapshots, checkpoints, the
// summary) and the options' checks netdem/quasistatic/staggered_run.hpp.
//
//   netsolve sinter [--packing FILE | --generate cu [--green-density 0.58] [--seed S]] [--material cu|ti|FILE] [--set KEY=VALUE]...
//                   [--temperature T | --profile FILE] [--time T_END] [--strategy 1|2] [--dt-max S] [--dt-initial S]
//                   [--eps-lim E] [--alpha A] [--new-contacts on|off] [--x0 X0_OVER_R] [--x-max X_OVER_R] [--E PA] [--nu NU]
//                   [--planes box|spheres] [--snapshots N] [--restart STATE] [--checkpoints T1,T2,...] [--max-steps N] [--allow-long] [--out DIR] [--quiet] [--overwrite] [--allow-unconverged]
//
// SI units everywhere (m, s, K, N, Pa). Defaults: the Cu benchmark (the green-body packing of 805
// spheres made in-process, Cu, 1293 K, 5000 s, strategy 2, dt_max = 10 s, new contacts on).
// Writes command.txt, history.csv (one row per accepted step and one at the start), steps.csv (the
// solver's record of every step), dL_bar.csv (Eq 44 per contact at the end), particles_K.vtp and
// bonds_K.vtp snapshots with snapshots.pvd (at the first step end at or after each of N equally
// spaced times, and the last: snapshots do not change the steps), state.txt (the restart state;
// state_K.txt at each --checkpoints time, where the steps end), report.md (which names
// apps/scripts/plot_sinter.py, the plot of history.csv) and
// summary.json (last); with --generate also packing.csv and laminar.csv. Bad input: one line
// on stderr, exit 2, no output folder; exit 1 for an error during the run; a run that could not
// reach --time ("unstable": a step failed or gave non-finite values; "incomplete": --max-steps, or
// a green-body packing that missed its target) exits 3 (README.md "Exit status").
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/dynamic/green_body.hpp"
#include "netdem/field_error.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/laminar.hpp"
#include "netdem/quasistatic/staggered.hpp"
#include "netdem/quasistatic/staggered_run.hpp"
#include "output.hpp"
#include "sinter_material.hpp"
#include "sinter_files.hpp"
#include "parse.hpp"
#include "scene_file.hpp"
#include "setup.hpp"
#include "status.hpp"
#include "run_status.hpp"

int run_sinter_command(int argc, char** argv);

namespace {

namespace fs = std::filesystem;
namespace sp = netdem::contact::sinter;
namespace st = netdem::qs::staggered;
using netdem::app::UsageError;
using netdem::app::write_file_atomic;
using nlohmann::json;

struct Args {
  std::string packing, generate = "cu", material = "cu", profile, new_contacts = "on", planes = "box", restart, out = "results/sinter";
  std::vector<double> checkpoints;  ///< in the order given: the library refuses times that do not increase
  std::vector<std::string> set;
  double green_density = 0.58, temperature = 1293.0, t_end = 5000.0, dt_max = 10.0, dt_initial = st::StaggeredOptions{}.dt_initial,
         eps_lim = st::StaggeredOptions{}.eps_lim, alpha = st::StaggeredOptions{}.alpha, x0 = st::StaggeredOptions{}.x0_over_R,
         x_max = 0.0, E = 0.0, nu = -1.0;
  int strategy = 2, snapshots = 5;
  long max_steps = 10'000'000;
  std::uint64_t seed = 1;
  bool quiet = false, overwrite = false, allow_unconverged = false, allow_long = false;
};

constexpr const char* kHistoryHeader = "t,T,dt,shrink_x,shrink_y,shrink_z,density,neck_mean,neck_std,contacts,newton,substeps";
constexpr const char* kStepsHeader =
    "step,t,dt,rejected,contacts_substepped,new_contacts,newly_frozen,gmres_iterations,refactorised,max_error,max_shrink_error";
constexpr const char* kDLbarHeader = "a,b,L0,dL_bar,dL_bar_over_L0,neck,t_created";

// One row of history.csv. t and dt with 17 digits: a t read back from history.csv is the same
// double (--time t1 of a restart test stops exactly at a step of the uninterrupted run)
std::string row_csv(const st::StaggeredMeasures& r) {
  return fmt::format("{:.17g},{:.10g},{:.17g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{},{},{}\n", r.t, r.T, r.dt,
                     r.shrink_x, r.shrink_y, r.shrink_z, r.density, r.neck_mean, r.neck_std, r.contacts, r.solves, r.substeps);
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

// ---- inputs
std::string read_text(const fs::path& p, const char* what) {
  if (!fs::is_regular_file(p))
    throw UsageError(fmt::format("{} '{}' is not a readable file", what, netdem::packing::quote_input(p.string())));
  std::ifstream in(p, std::ios::binary);
  if (!in) throw UsageError(fmt::format("{} '{}' cannot be opened", what, netdem::packing::quote_input(p.string())));
  std::ostringstream o;
  o << in.rdbuf();
  return o.str();
}

using netdem::app::netsolve::laminar_csv;
using netdem::app::netsolve::write_snapshot;
using netdem::app::netsolve::pvd;
using netdem::app::netsolve::options_json;
using netdem::app::netsolve::material_json;

/// Work (spheres x the least number of global steps) above which a run is refused unless
/// --allow-long: at the 15-90 us per sphere-step of the validation runs (805 Cu spheres: 12 ms a
/// step; the Ti packing: 125-180 ms) 1e8 is 0.4-2.5 h of one core, and the steps are a lower bound.
constexpr double kMaxSphereSteps = 1e8;

/// The options that a restart state fixes: given with --restart they are refused.
const char* const kFixedByState[] = {"--packing", "--generate", "--green-density", "--seed", "--material", "--set",
                                     "--temperature", "--profile", "--strategy", "--dt-max", "--dt-initial", "--eps-lim",
                                     "--alpha", "--new-contacts", "--x0", "--x-max", "--E", "--nu", "--planes"};

/// The library checks the options (StaggeredOptions, StaggeredRunOptions) and names a bad one by
/// its field (netdem::FieldError), which the error handler reports as --field-with-dashes; the
/// fields whose option is named otherwise are renamed here.
template <class F>
void as_options(F&& check) {
  try {
    check();
  } catch (const netdem::FieldError& e) {
    static const std::map<std::string, std::string> kOption{{"x0_over_R", "x0"}, {"x_max_over_R", "x_max"}, {"t_end", "time"}};
    const auto it = kOption.find(e.field());
    if (it == kOption.end()) throw;
    throw netdem::FieldError(it->second, e.what());
  }
}

/// Everything a run starts from, checked before the output folder exists.
struct Setup {
  bool restart = false, generate = false;
  std::optional<st::Staggered> sim;  ///< a restart, or a packing file (--generate: after the green body)
  std::optional<sp::SinterMaterial> mat;
  netdem::packing::Packing pk;
  netdem::dem::GreenBodyOptions gb;
  st::StaggeredOptions so;
  st::StaggeredRunOptions ro;
  sp::TemperatureProfile prof = sp::TemperatureProfile::constant(1.0);
  std::string mat_source, packing_source;
  json restart_json;
  std::uint64_t seed = 0;
  bool seed_known = true;
  std::array<int, 3> box_fixed{-1, -1, -1};  ///< particles fixed on the box planes (-1: --planes spheres, or a restart)
};

/// The record of origin of a restart state (its run's packing and seed), checked against the state:
/// a field of the wrong type, or a particle count that is not the state's, is refused. false: no
/// seed recorded.
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

void setup_restart(const Args& a, Setup& u) {
  const std::string text = read_text(a.restart, "--restart");
  try {
    u.sim.emplace(st::Staggered::load(text, a.restart));
  } catch (const std::exception& e) {
    throw UsageError(e.what());
  }
  as_options([&] { u.ro.validate(u.sim->time(), u.sim->options().dt_max); });
  u.mat = u.sim->material();
  u.mat_source = fmt::format("restart state {}", a.restart);
  u.packing_source = fmt::format("restart state {}", a.restart);
  u.restart_json = {{"state", a.restart}, {"t_start", u.sim->time()}, {"steps_before", u.sim->steps()}};
  // the seed and the packing of the run that made the sample: the state's record of origin
  u.seed_known = read_origin(a.restart, u.sim->origin_record(), u.sim->particles().size(), u.seed, u.restart_json);
}

void read_packing(const Args& a, Setup& u) {
  if (fs::is_directory(a.packing))
    throw UsageError(fmt::format("--packing '{}' is a folder, not a packing CSV file (netsolve pack writes DIR/packing.csv)",
                                 netdem::packing::quote_input(a.packing)));
  if (!fs::is_regular_file(a.packing))
    throw UsageError(fmt::format("--packing '{}' is not a readable file", netdem::packing::quote_input(a.packing)));
  u.pk = netdem::packing::read_packing_csv(a.packing);
  if (u.pk.dim != 3)
    throw UsageError(fmt::format("--packing {} is a 2D packing; netsolve sinter needs spheres (id,x,y,z,r, SI metres)",
                                 netdem::packing::quote_input(a.packing, 200)));
  if (u.pk.periodic)
    throw UsageError(fmt::format("--packing {} is periodic ('# periodic'): netsolve sinter has no periodic cell (its boundary "
                                 "planes are the box's)", netdem::packing::quote_input(a.packing, 200)));
  if (u.pk.size() < 2) throw UsageError(fmt::format("--packing {} holds fewer than two spheres", netdem::packing::quote_input(a.packing, 200)));
  for (double r : u.pk.r)
    if (!(r <= 1e-2))
      throw UsageError(fmt::format("--packing {}: radius {} m: the packing is in SI metres (25 um is 25e-6); above 1 cm is refused",
                                   netdem::packing::quote_input(a.packing, 200), r));
  u.packing_source = a.packing;
  u.seed = u.pk.seed;
}

// The network of a packing (a file, or the green body): the boundary planes at its box (--planes box).
void make_network(const Args& a, Setup& u) {
  if (a.planes == "box") u.so.plane_origin = {u.pk.box.x_min, u.pk.box.y_min, u.pk.box.z_min};
  u.sim.emplace(st::Particles::from_packing(u.pk), *u.mat, u.prof, u.so);
  if (a.planes == "box") u.box_fixed = u.sim->plane_particles();
}

void setup_new(const Args& a, Setup& u) {
  if (!a.profile.empty() && fs::is_directory(a.profile))
    throw UsageError(fmt::format("--profile '{}' is a folder, not a CSV file", netdem::packing::quote_input(a.profile)));
  u.mat = netdem::app::netsolve::load_sinter_material(a.material, a.set, u.mat_source);
  st::StaggeredOptions& so = u.so;
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
  as_options([&] { so.validate(*u.mat); });  // the options' ranges, and the bonds' E and nu
  as_options([&] { u.ro.validate(0.0, so.dt_max); });
  if (a.profile.empty()) {
    try {
      u.prof = sp::TemperatureProfile::constant(a.temperature);
    } catch (const std::invalid_argument& e) {
      throw UsageError(fmt::format("--temperature: {}", e.what()));
    }
  } else {
    u.prof = sp::TemperatureProfile::read_csv(a.profile);
  }
  u.seed = a.seed;
  if (u.generate) {
    u.gb.seed = a.seed;
    u.gb.target_density = a.green_density;
    try {
      u.gb.validate();
    } catch (const std::invalid_argument& e) {
      throw UsageError(fmt::format("--green-density / --seed: {}", e.what()));
    }
    u.packing_source = fmt::format("generated: green-body route (Ivannikov et al. section 3.2), {} spheres, mean diameter {:g} m +- {:g} %, "
                                   "target density {:g}, seed {}",
                                   u.gb.n, 2.0 * u.gb.mean_radius, 100.0 * u.gb.dispersion, u.gb.target_density, a.seed);
    return;
  }
  read_packing(a, u);
  try {
    make_network(a, u);  // bad particles: exit 2, nothing written
  } catch (const std::invalid_argument& e) {
    throw UsageError(fmt::format("--packing {}: {}", netdem::packing::quote_input(a.packing, 200), e.what()));
  }
}

Setup setup(const Args& a, const CLI::App& app) {
  Setup u;
  u.restart = !a.restart.empty();
  u.generate = !u.restart && a.packing.empty();
  if (u.restart)
    for (const char* name : kFixedByState)
      if (app.count(name) > 0)
        throw UsageError(fmt::format("{} cannot be combined with --restart: the state fixes the particles, material, temperature "
                                     "and solver options (only --time, --snapshots, --checkpoints, --max-steps and the output options apply)",
                                     name));
  u.ro.t_end = a.t_end;
  u.ro.max_steps = a.max_steps;
  u.ro.snapshots = a.snapshots;
  u.ro.checkpoints = a.checkpoints;
  if (u.restart)
    setup_restart(a, u);
  else
    setup_new(a, u);
  // the work estimate with the temperature profile's breakpoints (each ends a global step): the
  // steps against --max-steps, and the breakpoints against kMaxProfileBreakpoints (--allow-long)
  const double t0 = u.sim ? u.sim->time() : 0.0;
  const sp::TemperatureProfile& T = u.sim ? u.sim->temperature() : u.prof;
  const double dt_max = u.sim ? u.sim->options().dt_max : u.so.dt_max;
  as_options([&] { u.ro.validate(t0, dt_max, T); });
  const double n = static_cast<double>(u.sim ? u.sim->particles().size() : u.generate ? u.gb.n : u.pk.size());
  const double steps = std::max(std::ceil((a.t_end - t0) / dt_max),
                                1.0 + static_cast<double>(netdem::app::netsolve::profile_breakpoints_within(T, t0, a.t_end)));
  if (!a.allow_long && !(n * steps <= kMaxSphereSteps))
    throw UsageError(fmt::format("--time {:g}: the run needs at least {:.3g} sphere-steps ({:g} spheres x {:.3g} global steps of at "
                                 "most {:g} s), more than {:.3g}, hours of one core: pass --allow-long to run it",
                                 a.t_end, n * steps, n, steps, dt_max, kMaxSphereSteps));
  netdem::app::netsolve::check_profile_work(
      T, t0, a.t_end, a.allow_long,
      fmt::format("{} '{}'", u.restart ? "--restart" : "--profile", netdem::packing::quote_input(u.restart ? a.restart : a.profile)));
  return u;
}

// The green-body route (--generate): packing.csv and laminar.csv, then the network; its record
// for summary.json. A packing that missed its target is not sintered ("incomplete").
json make_green_body(const Args& a, const fs::path& out, Setup& u, netdem::app::RunStatus& status, double& wall) {
  namespace na = netdem::app;
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
  const netdem::dem::GreenBodyResult res = netdem::dem::make_green_body(u.gb, observer);
  if (printed) std::fprintf(stderr, "\n");
  wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - g0).count();
  u.pk = res.packing;
  u.pk.comments.emplace_back("green-body route (Ivannikov et al. section 3.2): lengths in metres");
  u.pk.comments.emplace_back(fmt::format("target density {} status {}", u.gb.target_density, res.status));
  netdem::packing::write_packing_csv(u.pk, out / "packing.csv");
  write_file_atomic(out / "laminar.csv", laminar_csv(u.pk, 25e-6));  // q_s = 0.025 mm: the paper's Fig 10, pack's default
  const auto& b = u.pk.box;
  const auto bb = netdem::packing::bounding_box(u.pk);
  json green = {{"status", res.status},
                {"status_reason", res.ok() ? std::string("every criterion met") : res.reason},
                {"target_density", u.gb.target_density},
                {"density_box", u.pk.solid_volume() / b.volume()},
                {"density_bounding_box", u.pk.solid_volume() / bb.volume()},
                {"box_mm", {1e3 * b.width(), 1e3 * b.height(), 1e3 * b.depth()}},
                {"overlap_pair_mean", res.overlaps.pair_mean},
                {"overlap_pair_max", res.overlaps.pair_max},
                {"coordination", res.overlaps.coordination},
                {"wall_s", wall}};
  if (!res.ok()) {
    status.add("incomplete", fmt::format("the green-body packing is {}: {}; not sintered (packing.csv is kept)", res.status, res.reason));
  } else {
    na::activity() = "setting up the network";
    make_network(a, u);
  }
  return green;
}

/// The run's files as it goes (the library's observation points): history.csv's rows, steps.csv,
/// the snapshots, the checkpoints' states, the progress on stderr.
class Recorder final : public st::StaggeredObserver {
 public:
  Recorder(fs::path out, bool quiet, double t_end) : out_(std::move(out)), quiet_(quiet), t_end_(t_end) {}
  void start(const st::Staggered& s, const st::StaggeredMeasures& m) override {
    rows.push_back(m);
    t_start_ = s.time();
    progress_.emplace("sinter", t_end_ - t_start_, quiet_);
  }
  void step(const st::Staggered& s, long k, const st::StepRecord& rec, const st::StaggeredMeasures& m) override {
    rows.push_back(m);
    steps_csv += fmt::format("{},{:.17g},{:.17g},{},{},{},{},{},{},{:.6g},{:.6g}\n", k, rec.t, rec.dt, rec.rejected,
                             rec.contacts_substepped, rec.new_contacts, rec.newly_frozen, rec.gmres_iterations,
                             rec.refactorised ? 1 : 0, rec.max_error, rec.max_shrink_error);
    progress_->update(s.time() - t_start_);
  }
  void snapshot(const st::Staggered& s, int index) override {
    write_snapshot(out_, index, s);
    snaps.emplace_back(index, s.time());
    write_file_atomic(out_ / "snapshots.pvd", pvd(snaps));  // rewritten with each: a killed run keeps a valid one
  }
  void checkpoint(const st::Staggered& s, int index, long k) override {
    const std::string file = fmt::format("state_{}.txt", index);
    write_file_atomic(out_ / file, s.save());
    checkpoint_json.push_back({{"file", file}, {"t", s.time()}, {"step", k}});
  }
  void finish() {
    if (progress_) progress_->finish();
  }

  std::vector<st::StaggeredMeasures> rows;
  std::string steps_csv = std::string(kStepsHeader) + "\n";
  std::vector<std::pair<int, double>> snaps;
  json checkpoint_json = json::array();

 private:
  fs::path out_;
  bool quiet_;
  double t_end_, t_start_ = 0.0;
  std::optional<netdem::app::Progress> progress_;
};

/// What a run made, for summary.json and report.md.
struct Outcome {
  const Args* a = nullptr;
  const Setup* u = nullptr;
  std::string command;
  json green = nullptr;
  double green_wall = 0.0, wall = 0.0;
  std::optional<st::StaggeredRunSummary> sum;  ///< none: nothing was sintered
  const Recorder* rec = nullptr;
  netdem::app::RunStatus judged;
};

// summary.json's sections of the sintering run (with a network) and dL_bar.csv's statistics
void sintering_json(json& j, const Outcome& o, const std::vector<double>& dl, const std::vector<double>& dlr) {
  const Args& a = *o.a;
  const Setup& u = *o.u;
  const st::Staggered& s = *u.sim;
  const st::StaggeredRunSummary& r = *o.sum;
  const st::StaggeredMeasures& f = r.last;
  j["completed"] = r.completed();
  j["t_stop_s"] = s.time();
  j["x_max_over_R_in_use"] = s.x_max_over_R();
  j["fixed_dofs"] = s.fixed_dofs();
  j["boundary_planes"] = u.restart ? json("as in the restart state")
                         : a.planes == "box"
                             ? json({{"planes", "lower faces of the packing's box"},
                                     {"box_lower_corner", {u.pk.box.x_min, u.pk.box.y_min, u.pk.box.z_min}},
                                     {"particles_on_x_y_z_planes", {u.box_fixed[0], u.box_fixed[1], u.box_fixed[2]}}})
                             : json({{"planes", "lower faces of the spheres' bounding box (the library's own)"}});
  j["final"] = {{"t", f.t},
                {"T", f.T},
                {"shrink_x", f.shrink_x},
                {"shrink_y", f.shrink_y},
                {"shrink_z", f.shrink_z},
                {"shrink_mean", (f.shrink_x + f.shrink_y + f.shrink_z) / 3.0},
                {"density", f.density},
                {"density_start", r.start.density},
                {"neck_mean", f.neck_mean},
                {"neck_std", f.neck_std},
                {"contacts", f.contacts},
                {"contacts_start", r.start.contacts},
                {"frozen_contacts", r.frozen_contacts}};
  j["dL_bar"] = {{"what", "Eq 44 of the last step per contact (dL_bar.csv): corrected minus free y4 + y7 [m]; over L0 = the centre "
                           "distance at the contact's creation; population moments"},
                 {"dL_bar", moments(dl)},
                 {"dL_bar_over_L0", moments(dlr)}};
  j["steps"] = {{"accepted", r.accepted},        {"total_in_state", s.steps()},       {"rejected", r.rejected},
                {"substeps", r.substeps},        {"linear_solves", r.linear_solves},  {"gmres_iterations", r.gmres_iterations},
                {"refactorisations", r.refactorisations}, {"new_contacts", r.new_contacts}, {"newly_frozen", r.newly_frozen},
                {"max_error_over_eps_lim", r.max_error},  {"max_shrink_error", r.max_shrink_error}};
  const st::Timers& tm = s.timers();
  const double parts = tm.detect + tm.integrate + tm.assemble + tm.factorise + tm.solve + tm.correct;
  j["timers_s"] = {{"detect", tm.detect},       {"integrate", tm.integrate}, {"assemble", tm.assemble},
                   {"factorise", tm.factorise}, {"solve", tm.solve},         {"correct", tm.correct},
                   {"sum", parts},              {"sinter_loop_wall", r.wall_s},
                   {"note", u.restart ? "the library's timers are cumulative over the restarted run (what the state carries)"
                                      : "cumulative over this run"}};
  json sn = json::array();
  for (const auto& [k, t] : o.rec->snaps)
    sn.push_back({{"index", k}, {"t", t}, {"particles", fmt::format("particles_{:03d}.vtp", k)}, {"bonds", fmt::format("bonds_{:03d}.vtp", k)}});
  j["snapshots"] = sn;
  j["checkpoints"] = o.rec->checkpoint_json;
}

// summary.json (and dL_bar.csv, whose statistics it holds)
json summary_json(const Outcome& o, const fs::path& out) {
  const Args& a = *o.a;
  const Setup& u = *o.u;
  const double t_start = o.sum ? o.sum->t_start : 0.0;
  json j;
  j["command"] = o.command;
  j["units"] = "SI: m, s, K, N, Pa";
  j["model"] = "staggered quasi-static sintering scheme of Ivannikov et al. (Fig 6) with the two-particle model of "
               "docs/sintering_pair.md (a documented reconstruction) and the Potyondy-Cundall bond (docs/staggered.md)";
  j["seed"] = u.seed_known ? json(u.seed) : json(nullptr);
  j["packing"] = {{"source", u.packing_source}, {"particles", u.sim ? u.sim->particles().size() : u.pk.size()}};
  if (!o.green.is_null()) j["green_body"] = o.green;
  if (u.restart) j["restart"] = u.restart_json;
  if (u.mat) j["material"] = material_json(u.sim ? u.sim->material() : *u.mat, u.mat_source);
  if (u.restart || !a.profile.empty()) {
    const auto& tp = u.sim ? u.sim->temperature() : u.prof;
    j["temperature"] = {{"profile", u.restart ? a.restart : a.profile}, {"breakpoints", tp.times().size()}, {"T_start_K", tp(t_start)}};
  } else {
    j["temperature"] = {{"constant_K", a.temperature}};
  }
  j["options"] = options_json(u.sim ? u.sim->options() : u.so);
  j["t_start_s"] = t_start;
  j["t_end_s"] = a.t_end;
  j["snapshots_requested"] = a.snapshots;
  if (o.sum) {
    std::vector<double> dl, dlr;
    std::string dcsv = std::string(kDLbarHeader) + "\n";
    for (const auto& c : u.sim->contacts()) {
      const double L0 = c.L_created;
      dl.push_back(c.dL_bar);
      dlr.push_back(L0 > 0.0 ? c.dL_bar / L0 : 0.0);
      dcsv += fmt::format("{},{},{:.17g},{:.17g},{:.17g},{:.10g},{:.17g}\n", c.a, c.b, L0, c.dL_bar, dlr.back(), c.pair.x_over_R(),
                          c.t_created);
    }
    write_file_atomic(out / "dL_bar.csv", dcsv);
    sintering_json(j, o, dl, dlr);
  }
  j["wall_s"] = o.wall;
  j["green_body_wall_s"] = o.green_wall;
  j["files"] = {{"history", "history.csv"}, {"steps", "steps.csv"},   {"dL_bar", "dL_bar.csv"},
                {"state", o.sum && o.sum->failed() ? "state_stopped.txt" : "state.txt"},
                {"snapshots", "snapshots.pvd"}, {"report", "report.md"}};
  o.judged.write(j);
  return j;
}

std::string report_md(const Outcome& o, const std::string& title, const json& j) {
  const Args& a = *o.a;
  std::string md = fmt::format("# {}\n\n`{}`\n\nStatus: **{}** ({})\n\n", title, o.command, o.judged.status, o.judged.reason());
  if (o.sum) {
    const st::StaggeredRunSummary& r = *o.sum;
    const st::StaggeredMeasures& f = r.last;
    const json& dj = j["dL_bar"]["dL_bar_over_L0"];
    auto num = [](const json& v) { return v.is_null() ? std::string("-") : fmt::format("{:.4g}", v.get<double>()); };
    md += "| quantity | value |\n|---|---|\n";
    md += fmt::format("| time | {:.6g} s (from {:.6g} s, to {:.6g} s requested) |\n", f.t, r.t_start, a.t_end);
    md += fmt::format("| shrinkage x, y, z (-F_ii) | {:.5g}, {:.5g}, {:.5g} |\n", f.shrink_x, f.shrink_y, f.shrink_z);
    md += fmt::format("| density (bounding box) | {:.5f} -> {:.5f} |\n", r.start.density, f.density);
    md += fmt::format("| neck x/R_min mean (std) | {:.5f} ({:.5f}) |\n", f.neck_mean, f.neck_std);
    md += fmt::format("| contacts (start, new, frozen) | {} ({}, {}, {}) |\n", f.contacts, r.start.contacts, r.new_contacts,
                      r.frozen_contacts);
    md += fmt::format("| steps (rejected), sub-steps, linear solves | {} ({}), {}, {} |\n", r.accepted, r.rejected, r.substeps,
                      r.linear_solves);
    md += fmt::format("| refactorisations, GMRES iterations | {}, {} |\n", r.refactorisations, r.gmres_iterations);
    md += fmt::format("| dL_bar/L0 of the last step: mean, std, skewness, excess kurtosis (Eq 44) | {}, {}, {}, {} |\n", num(dj["mean"]),
                      num(dj["std"]), num(dj["skewness"]), num(dj["excess_kurtosis"]));
    md += fmt::format("| max shrinkage-correction error | {:.3g} |\n\n", r.max_shrink_error);
    const st::Timers& tm = o.u->sim->timers();
    md += "## Timing\n\n| part | s | % of the sintering loop |\n|---|---|---|\n";
    const double base = r.wall_s > 0.0 ? r.wall_s : 1.0;
    for (const auto& [name, v] : std::vector<std::pair<const char*, double>>{{"detect", tm.detect},
                                                                             {"integrate (per-contact model)", tm.integrate},
                                                                             {"assemble", tm.assemble},
                                                                             {"factorise", tm.factorise},
                                                                             {"solve", tm.solve},
                                                                             {"correct", tm.correct}})
      md += fmt::format("| {} | {:.3f} | {:.1f} |\n", name, v, 100.0 * v / base);
    md += fmt::format("| sintering loop (wall, with output) | {:.3f} | 100 |\n", r.wall_s);
    if (o.u->generate) md += fmt::format("| green-body packing | {:.3f} | |\n", o.green_wall);
    md += fmt::format("| whole run | {:.3f} | |\n\n", o.wall);
  }
  md += "Plot: `/usr/bin/python3 apps/scripts/plot_sinter.py DIR` (DIR: this run folder) writes history.png: left, the shrinkage "
        "per axis (least-squares homogeneous strain of the centres); right, the mean neck x / R_min.\n";
  return md;
}

int run(const Args& a, const CLI::App& app, const std::string& command) {
  namespace na = netdem::app;
  const auto w0 = std::chrono::steady_clock::now();
  // ---- everything is checked before the output folder exists
  na::RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  na::check_run_dir(a.out, rdo);
  Setup u = setup(a, app);

  const fs::path out(a.out);
  if (!a.packing.empty()) rdo.inputs.emplace_back(a.packing);
  if (!a.profile.empty()) rdo.inputs.emplace_back(a.profile);
  if (!a.restart.empty()) rdo.inputs.emplace_back(a.restart);
  if (!u.restart && a.material != "cu" && a.material != "ti") rdo.inputs.emplace_back(a.material);
  na::activity() = "opening the output folder";
  na::open_run_dir(out, command, rdo);
  if (!a.quiet && u.seed_known) std::fprintf(stderr, "netsolve sinter: seed %llu\n", static_cast<unsigned long long>(u.seed));

  Outcome o;
  o.a = &a;
  o.u = &u;
  o.command = command;
  if (u.generate) o.green = make_green_body(a, out, u, o.judged, o.green_wall);
  if (!u.restart && u.sim)  // the record of origin travels with every state this run writes
    u.sim->set_origin_record(json{{"seed", u.seed_known ? json(u.seed) : json(nullptr)},
                                  {"packing", {{"source", u.packing_source}, {"particles", u.sim->particles().size()}}}}
                                 .dump());
  // ---- the run: the library's loop, the files from its observation points
  Recorder rec(out, a.quiet, a.t_end);
  o.rec = &rec;
  if (u.sim) {
    na::activity() = "sintering";
    o.sum = st::run(*u.sim, u.ro, &rec);
    rec.finish();
    for (const auto& reason : o.sum->reasons) o.judged.add(st::to_string(o.sum->status), reason);
    na::activity() = "writing the results";
    write_file_atomic(out / "snapshots.pvd", pvd(rec.snaps));
    write_file_atomic(out / (o.sum->failed() ? "state_stopped.txt" : "state.txt"), u.sim->save());
  }
  std::string hist = std::string(kHistoryHeader) + "\n";
  for (const auto& r : rec.rows) hist += row_csv(r);
  if (o.sum && o.sum->failed()) hist += "# stopped: " + o.sum->stop_message + "\n";
  write_file_atomic(out / "history.csv", hist);
  write_file_atomic(out / "steps.csv", rec.steps_csv);

  o.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  const json j = summary_json(o, out);
  // ---- the report (apps/scripts/plot_sinter.py draws the plot)
  const std::string title = fmt::format("netsolve sinter: {}, {}, {} particles", u.mat ? u.mat->name : std::string("?"),
                                        u.restart ? std::string("restart") : a.profile.empty() ? fmt::format("T = {:g} K", a.temperature) : "T(t) profile",
                                        u.sim ? u.sim->particles().size() : u.pk.size());
  write_file_atomic(out / "report.md", report_md(o, title, j));
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  na::close_run_dir(out);

  if (o.sum) {
    const st::StaggeredMeasures& f = o.sum->last;
    netdem::app::summary_printf("t = %.6g s: shrinkage %.5g %.5g %.5g, density %.5f, neck %.5f, %zu contacts, %zu steps, %.3g s -> %s\n", f.t, f.shrink_x,
                f.shrink_y, f.shrink_z, f.density, f.neck_mean, f.contacts, rec.rows.size() - 1, o.wall, out.c_str());
    if (o.sum->failed()) {
      std::fprintf(stderr, "netsolve sinter: error: unstable: %s (history.csv keeps the steps before)\n", o.sum->stop_message.c_str());
      return na::exit_code::untrustworthy;
    }
  }
  if (!o.judged.ok()) {
    // a run that did not reach --time exits 3 whatever --allow-unconverged says
    const bool forgiven = a.allow_unconverged && o.sum && o.sum->completed();
    std::fprintf(stderr, "netsolve sinter: %s: %s: %s\n", forgiven ? "warning (--allow-unconverged)" : "error", o.judged.status.c_str(),
                 o.judged.reason().c_str());
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
  auto* o_pk = app.add_option("--packing", a.packing, "3D packing CSV (id,x,y,z,r in metres, as netsolve pack --dim 3 --route green-body writes)")
                   ->check(netdem::app::netsolve::non_empty_file("a packing CSV file"));
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
  auto* o_p = app.add_option("--profile", a.profile, "temperature profile: CSV with header time,T [s, K], linear between rows")
                  ->check(netdem::app::netsolve::non_empty_file("a temperature profile CSV file"));
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
  app.add_option("--restart", a.restart, "continue from a state.txt of an earlier run to --time, into a new --out folder")
      ->check(netdem::app::netsolve::non_empty_file("a state.txt of an earlier run"));
  netdem::app::netsolve::add_list_option(app, "--checkpoints", a.checkpoints,
                                         "comma list of increasing times [s] at which the steps end and state_K.txt is written (K = 1, 2, ...)");
  app.add_option("--max-steps", a.max_steps, "stop (incomplete, exit 3) after this many steps")->capture_default_str();
  app.add_flag("--allow-long", a.allow_long, "run above 1e8 sphere-steps (spheres x --time / --dt-max, hours of one core) or a "
                                            "temperature profile of more than 1e4 breakpoints within the run (each ends a step)");
  app.add_flag("--quiet", a.quiet, "no progress on stderr");
  app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
  app.add_flag("--allow-unconverged", a.allow_unconverged, "exit 0 for a run that reached --time but summary.json marks untrustworthy");
  app.add_option("--out", a.out, "output folder")->capture_default_str();
  netdem::app::add_scene_config(app, "netsolve", "sinter", netdem::app::kNetsolveSections);
  try {
    app.parse(argc - 1, argv + 1);
    netdem::app::set_scene(app, "netsolve", "sinter");
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    netdem::app::print_error_line(fmt::format("netsolve sinter: error: {} (see --help)", e.what()));
    return 2;
  }
  return netdem::app::netsolve::guarded("netsolve sinter", [&]() { return run(a, app, command); });
}
