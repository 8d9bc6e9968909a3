// netsolve sinter-pair: one two-particle sintering contact against time (issue #14). The model is a
// documented reconstruction (docs/sintering_pair.md), not the authors' model;
// docs/sintering_pair.md describes it, its files and this command.
//
//   netsolve sinter-pair [--material cu|ti|FILE] [--set KEY=VALUE]... [--radius R | --radii RA,RB]
//                        [--temperature T | --profile FILE] [--time T_END] [--integrator dp45|rk4|cvode|arkode]
//                        [--rtol RTOL] [--rk4-c C] [--x0 X0_OVER_R] [--x-max X_OVER_R] [--force F] [--paths LIST]
//                        [--per-decade N] [--t-first T] [--allow-long] [--out DIR]
//
// SI units everywhere (m, s, K, N). Writes command.txt, pair.csv (one row per output time: a log
// grid from --t-first, 20 per decade, plus 60, 600, 3600, 14400, 57600 s, the profile breakpoints and t_end when in
// range) and summary.json (last); apps/scripts/plot_sinter_pair.py DIR draws pair.png (x/R and
// Delta L/L0 against t, log-log). A contact that
// leaves the validity limits (note section 4.6) stops there; summary.json says why ("status":
// "incomplete", exit 0: the rows up to the limit are valid). A non-finite state or a failed step:
// "unstable", exit 3. Bad input: one line on stderr, exit 2, no output folder; exit 1 for an
// error during the run (README.md "Exit status").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/contact/sintering_pair_sundials.hpp"
#include "output.hpp"
#include "sinter_material.hpp"
#include "parse.hpp"
#include "scene_file.hpp"
#include "status.hpp"
#include "run_status.hpp"

int run_sinter_pair_command(int argc, char** argv);

namespace {

namespace fs = std::filesystem;
namespace sp = netdem::contact::sinter;
using nlohmann::json;

struct Args {
  std::string material = "cu", profile, integrator = "dp45", out = "results/sinter-pair", paths = "all";
  std::vector<std::string> set;
  std::vector<double> radii;  ///< --radii RA,RB (empty: --radius for both)
  double radius = 50e-6, temperature = 1273.15, t_end = 57600.0, rtol = 1e-8, rk4_c = 0.02, x0 = 0.01, x_max = 0.6,
         force = 0.0, t_first = 1.0;
  int per_decade = 20;
  bool quiet = false, overwrite = false, allow_unconverged = false, allow_long = false;
};

struct Row {
  double t, T, x_over_R, shrinkage, volume, energy, F_s, eta, eta_BM;
  sp::FullState y;
};

std::vector<double> output_times(double t_end, double t_first_in, const sp::TemperatureProfile& prof, int per_decade) {
  std::vector<double> t = {0.0};
  const double t_first = std::min(t_first_in, t_end);
  for (int k = 0;; ++k) {
    const double v = t_first * std::pow(10.0, static_cast<double>(k) / per_decade);
    if (v >= t_end) break;
    t.push_back(v);
  }
  for (double v : {60.0, 600.0, 3600.0, 14400.0, 57600.0})
    if (v <= t_end) t.push_back(v);
  for (double v : prof.times())
    if (v > 0.0 && v < t_end) t.push_back(v);
  t.push_back(t_end);
  std::sort(t.begin(), t.end());
  std::vector<double> u;
  for (double v : t)
    if (u.empty() || v > u.back() * (1.0 + 1e-12)) u.push_back(v);
  return u;
}

// --paths: "all" or a comma list of I, II, III, IV, V (the path types of note section 3)
sp::PathSwitches parse_paths(const std::string& s) {
  if (s == "all") return {};
  if (s.empty())  // no transport at all: a run that cannot change anything (issue 27)
    throw std::invalid_argument("--paths '' names no transport path: give 'all' or a comma list of I, II, III, IV, V");
  sp::PathSwitches p{0, 0, 0, 0, 0};
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item == "I") p.I = 1;
    else if (item == "II") p.II = 1;
    else if (item == "III") p.III = 1;
    else if (item == "IV") p.IV = 1;
    else if (item == "V") p.V = 1;
    else throw std::invalid_argument(fmt::format("--paths '{}': '{}' is not one of I, II, III, IV, V (or 'all')", s, item));
  }
  return p;
}

sp::SinterMaterial load_material(const Args& a, std::string& source) {
  return netdem::app::netsolve::load_sinter_material(a.material, a.set, source);
}

/// The rows of pair.csv at the output times, and how the integration ended.
struct Integration {
  std::vector<Row> rows;
  double max_drift = 0.0;
  bool dropped_row = false;
  std::string failure;  ///< a SUNDIALS error: the step failed (the contact says StepFailure)
};

/// One row of the contact's current state; false if it cannot be evaluated or is not finite.
bool make_row(const sp::PairContact& c, const sp::PairProblem& p, Row& r) {
  const sp::SinterMaterial& mat = *p.material;
  const double T = (*p.temperature)(c.t);
  const auto d = sp::diffusivities(mat, T);
  r = {c.t, T, c.x_over_R(), sp::shrinkage(c.q, c.q0), sp::pair_volume(c.q), sp::pair_energy(c.q, mat), 0.0, 0.0, 0.0, sp::full_state(c.q)};
  try {
    const auto law = sp::effective_law(c.q, d, mat, p.paths);
    r.F_s = law.F_s;
    r.eta = law.eta;
    r.eta_BM = d.deltaD_gb > 0.0 ? sp::bouvard_mcmeeking_viscosity(c.q[sp::kX], d, mat) : 0.0;
  } catch (const std::domain_error&) {
    return false;
  }
  bool finite = std::isfinite(r.T) && std::isfinite(r.x_over_R) && std::isfinite(r.shrinkage) && std::isfinite(r.volume) &&
                std::isfinite(r.energy) && std::isfinite(r.F_s);  // eta may be +inf (no densifying path)
  for (double v : r.y) finite = finite && std::isfinite(v);
  return finite;
}

/// Integrates the contact through the output times, stopping where it stops (c.status).
Integration integrate(sp::PairContact& c, const sp::IntegratorOptions& io, const sp::PairProblem& problem,
                      const std::vector<double>& times, const Args& a) {
  Integration out;
  sp::PairIntegrator integ(io);
  const double V0 = sp::pair_volume(c.q);
  netdem::app::Progress progress("sinter-pair", std::log10(1.0 + a.t_end), a.quiet);
  for (double t : times) {
    if (t > 0.0) {
      try {
        integ.advance(c, problem, t);
      } catch (const sp::SundialsError& e) {
        out.failure = e.what();
        c.status = sp::PairStatus::StepFailure;
      }
    }
    Row r;
    if (make_row(c, problem, r)) {
      out.rows.push_back(r);
      out.max_drift = std::max(out.max_drift, std::fabs(r.volume / V0 - 1.0));
    } else if (!sp::validity_limit(c.status)) {  // the state past a validity limit has no row
      out.dropped_row = true;
    }
    progress.update(std::log10(1.0 + c.t));
    if (c.status != sp::PairStatus::Ok) break;
  }
  progress.finish();
  return out;
}

int run(const Args& a, const std::string& command) {
  // ---- everything is checked before the output folder exists
  {
    netdem::app::RunDirOptions rdo;
    rdo.overwrite = a.overwrite;
    netdem::app::check_run_dir(a.out, rdo);  // a refused folder: exit 2 before any work
  }
  if (!a.profile.empty() && fs::is_directory(a.profile))
    throw netdem::app::UsageError(fmt::format("--profile '{}' is a folder, not a CSV file", a.profile.substr(0, 80)));
  std::string mat_source;
  const sp::SinterMaterial mat = load_material(a, mat_source);
  double RA = a.radius, RB = a.radius;
  if (!a.radii.empty()) {
    if (a.radii.size() != 2)
      throw std::invalid_argument(fmt::format("--radii: {} values given, not RA,RB in metres", a.radii.size()));
    RA = a.radii[0];
    RB = a.radii[1];
  }
  for (double r : {RA, RB})
    if (!(std::isfinite(r) && r >= 1e-9 && r <= 0.1))
      throw std::invalid_argument(fmt::format("radius {} m is outside [1e-9, 0.1] m (radii are in metres: 50 um is 50e-6)", r));
  if (!(std::isfinite(a.t_end) && a.t_end > 0.0)) throw std::invalid_argument(fmt::format("--time must be positive [s], got {}", a.t_end));
  if (!(std::isfinite(a.temperature) && a.temperature > 0.0 && a.temperature < 1e4))
    throw std::invalid_argument(fmt::format("--temperature must be in (0, 1e4) K, got {}", a.temperature));
  if (a.per_decade < 1 || a.per_decade > 1000) throw std::invalid_argument("--per-decade must be in [1, 1000]");
  if (!std::isfinite(a.force)) throw std::invalid_argument("--force must be finite");
  const sp::TemperatureProfile prof =
      a.profile.empty() ? sp::TemperatureProfile::constant(a.temperature) : sp::TemperatureProfile::read_csv(a.profile);
  netdem::app::netsolve::check_profile_work(prof, 0.0, a.t_end, a.allow_long,
                                            fmt::format("--profile '{}'", netdem::packing::quote_input(a.profile)));
  sp::IntegratorOptions io;
  io.kind = sp::parse_integrator(a.integrator);
  io.rtol = a.rtol;
  io.rk4_c = a.rk4_c;
  io.x_over_R_max = a.x_max;
  io.validate();
  sp::PairContact c = sp::make_contact(RA, RB, a.x0);
  c.status = sp::check_state(c.q, c.R_min0(), io.x_over_R_max);  // a start outside the limits ends there, at t = 0
  if (!(std::isfinite(a.t_first) && a.t_first > 0.0)) throw std::invalid_argument("--t-first must be positive [s]");
  const auto times = output_times(a.t_end, a.t_first, prof, a.per_decade);
  const sp::PathSwitches paths = parse_paths(a.paths);

  const fs::path out(a.out);
  netdem::app::RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  if (!a.profile.empty()) rdo.inputs.emplace_back(a.profile);
  if (a.material != "cu" && a.material != "ti") rdo.inputs.emplace_back(a.material);
  netdem::app::open_run_dir(out, command, rdo);

  const sp::PairProblem problem{&mat, &prof, paths, a.force};
  const auto w0 = std::chrono::steady_clock::now();
  const Integration result = integrate(c, io, problem, times, a);
  const std::vector<Row>& rows = result.rows;
  const double max_drift = result.max_drift;
  const bool dropped_row = result.dropped_row;
  const std::string& failure = result.failure;
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };  // inf viscosity -> null
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();

  std::string csv = "t,T,x_over_R,shrinkage,volume,free_energy,sintering_force,y1,y2,y3,y4,y5,y6,y7\n";
  for (const auto& r : rows) {
    csv += fmt::format("{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g}", r.t, r.T, r.x_over_R, r.shrinkage, r.volume,
                       r.energy, r.F_s);
    for (double v : r.y) csv += fmt::format(",{:.12g}", v);
    csv += "\n";
  }
  netdem::app::write_file_atomic(out / "pair.csv", csv);

  json j;
  j["command"] = command;
  j["model"] = "two-particle cap-cone sintering model: a documented reconstruction of "
               "the model note described in docs/sintering_pair.md, not the model of Thomsen et al. / Ivannikov et al.";
  j["material"] = {{"name", mat.name},         {"source", mat_source},         {"Omega", mat.omega},
                   {"gamma_s", mat.gamma_s},   {"gamma_gb", mat.gamma_gb},     {"D_vol0", mat.D_vol0},
                   {"Q_vol", mat.Q_vol},       {"deltaD_gb0", mat.deltaD_gb0}, {"Q_gb", mat.Q_gb},
                   {"deltaD_s0", mat.deltaD_s0}, {"Q_s", mat.Q_s},             {"c_III", mat.c_III},
                   {"c_IV", mat.c_IV},         {"E", mat.youngs_modulus}};
  j["radii_m"] = {RA, RB};
  j["x0_over_R"] = a.x0;
  if (a.profile.empty())
    j["temperature"] = {{"constant_K", a.temperature}};
  else
    j["temperature"] = {{"profile", a.profile}, {"breakpoints", prof.times().size()}};
  j["t_end_s"] = a.t_end;
  j["force_N"] = a.force;
  j["paths"] = {{"I", paths.I}, {"II", paths.II}, {"III", paths.III}, {"IV", paths.IV}, {"V", paths.V}};
  j["integrator"] = {{"name", sp::to_string(io.kind)}, {"rtol", io.rtol}, {"atol_scale", io.atol_scale}, {"rk4_c", io.rk4_c}};
  // the run status of every netsolve command: a validity limit is a documented, expected end
  // (incomplete, exit 0); a non-finite state, a failed step or a dropped row is unstable (exit 3)
  netdem::app::netsolve::RunStatus status;
  switch (c.status) {
    case sp::PairStatus::Ok: break;
    case sp::PairStatus::NeckLimit:
    case sp::PairStatus::ConeDegenerate:
    case sp::PairStatus::NeckVanished:
      status.add("incomplete", fmt::format("stopped at t = {:.6g} s at a validity limit: {}", c.t, sp::describe(c.status, io.x_over_R_max)));
      break;
    case sp::PairStatus::NonFinite:
    case sp::PairStatus::StepFailure:
      status.add("unstable", fmt::format("stopped at t = {:.6g} s: {}{}", c.t, sp::describe(c.status, io.x_over_R_max),
                                         failure.empty() ? "" : " (" + failure + ")"));
      break;
  }
  if (dropped_row) status.add("unstable", "rows with non-finite values were dropped from pair.csv");
  status.write(j);
  j["stop"] = sp::to_string(c.status);
  j["reason"] = sp::describe(c.status, io.x_over_R_max);
  j["completed"] = c.status == sp::PairStatus::Ok && c.t >= a.t_end;
  j["t_stop_s"] = c.t;
  j["x_over_R_max"] = io.x_over_R_max;
  j["rows"] = rows.size();
  j["rows_dropped_non_finite"] = dropped_row;
  j["max_volume_drift"] = max_drift;
  json at = json::object();
  for (const auto& r : rows)
    for (double v : {60.0, 600.0, 3600.0, 14400.0, 57600.0})
      if (r.t == v)
        at[fmt::format("{:g}", v)] = {{"x_over_R", r.x_over_R}, {"shrinkage", r.shrinkage}, {"sintering_force", r.F_s},
                                      {"viscosity", num(r.eta)}, {"viscosity_bouvard_mcmeeking", num(r.eta_BM)}};
  j["at"] = at;
  if (!rows.empty()) {
    const Row& r = rows.back();
    j["final"] = {{"t", r.t},
                  {"x_over_R", r.x_over_R},
                  {"shrinkage", r.shrinkage},
                  {"R_A_over_R_A0", r.y[1] / RA},
                  {"R_B_over_R_B0", r.y[4] / RB},
                  {"sintering_force", r.F_s},
                  {"viscosity", num(r.eta)},
                  {"viscosity_bouvard_mcmeeking", num(r.eta_BM)}};
    if (mat.youngs_modulus > 0.0)
      j["final"]["equivalent_bar_force"] = sp::equivalent_bar_force(mat.youngs_modulus, c.q0, c.q);  // Eq 17
  }
  j["stats"] = {{"steps", c.steps}, {"rejected", c.rejected}, {"rhs_evals", c.rhs_evals}, {"restarts", c.restarts}};
  j["wall_s"] = wall;
  j["files"] = {{"csv", "pair.csv"}};  // plotted by apps/scripts/plot_sinter_pair.py
  netdem::app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  netdem::app::close_run_dir(out);
  const Row* last = rows.empty() ? nullptr : &rows.back();
  if (c.status != sp::PairStatus::Ok)
    std::fprintf(stderr, "netsolve sinter-pair: stopped at t = %.6g s: %s\n", c.t, sp::describe(c.status, io.x_over_R_max).c_str());
  if (last != nullptr)
    netdem::app::summary_printf("t = %.6g s: x/R = %.6f, shrinkage = %.5e, %ld steps, %.3g s -> %s\n", last->t, last->x_over_R, last->shrinkage,
                c.steps, wall, out.c_str());
  return status.exit_code(a.allow_unconverged);
}

}  // namespace

int run_sinter_pair_command(int argc, char** argv) {
  std::string command;
  for (int k = 0; k < argc; ++k) command += (k ? " " : "") + std::string(argv[k]);
  Args a;
  CLI::App app{"netsolve sinter-pair: one two-particle sintering contact against time (a documented reconstruction of "
               "the model note described in docs/sintering_pair.md). SI units."};
  app.add_option("--material", a.material, "cu | ti (built in) | FILE (docs/sintering_pair.md format)")->capture_default_str();
  app.add_option("--set", a.set, "override a material key, KEY=VALUE (repeatable), e.g. --set D_vol0=1.9e-7");
  auto* o_r = app.add_option("--radius", a.radius, "radius of both particles [m]")->capture_default_str();
  auto* o_rr = netdem::app::netsolve::add_list_option(app, "--radii", a.radii, "RA,RB radii of the two particles [m]");
  o_r->excludes(o_rr);
  auto* o_T = app.add_option("--temperature", a.temperature, "constant temperature [K]")->capture_default_str();
  auto* o_p = app.add_option("--profile", a.profile, "temperature profile: CSV with header time,T [s, K], linear between rows")
                  ->check(netdem::app::netsolve::non_empty_file("a temperature profile CSV file"));
  o_T->excludes(o_p);
  app.add_option("--time", a.t_end, "end time [s]")->capture_default_str();
  app.add_option("--integrator", a.integrator, "dp45 (default) | rk4 (dt = c x/|dx/dt|) | cvode (BDF) | arkode (ERKStep DP5(4))")
      ->capture_default_str();
  app.add_option("--rtol", a.rtol, "relative tolerance (dp45, cvode, arkode)")->capture_default_str();
  app.add_option("--rk4-c", a.rk4_c, "rk4 step factor c in dt = c x / |dx/dt|")->capture_default_str();
  app.add_option("--x0", a.x0, "initial neck x0 / min(RA, RB) (tangent-cone fillet)")->capture_default_str();
  app.add_option("--x-max", a.x_max, "stop when x / min(RA0, RB0) exceeds this (useful range, note section 4.6)")->capture_default_str();
  app.add_option("--force", a.force, "compressive normal force on the contact [N] (0: free sintering)")->capture_default_str();
  app.add_option("--per-decade", a.per_decade, "output rows per decade of time")->capture_default_str();
  app.add_option("--t-first", a.t_first, "first time of the logarithmic output grid [s]")->capture_default_str();
  app.add_option("--paths", a.paths, "transport paths on: all, or a list of I (GB), II (surface), III, IV, V (lattice); note section 3")
      ->capture_default_str();
  app.add_flag("--allow-long", a.allow_long, "run a temperature profile of more than 1e4 breakpoints within the run (each ends a step)");
  app.add_flag("--quiet", a.quiet, "no progress on stderr");
  app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
  app.add_flag("--allow-unconverged", a.allow_unconverged, "exit 0 for a run that summary.json marks 'unstable' (the status is kept)");
  app.add_option("--out", a.out, "output folder")->capture_default_str();
  netdem::app::add_scene_config(app, "netsolve", "sinter-pair", netdem::app::kNetsolveSections);
  try {
    app.parse(argc - 1, argv + 1);
    netdem::app::set_scene(app, "netsolve", "sinter-pair");
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    netdem::app::print_error_line(fmt::format("netsolve sinter-pair: error: {} (see --help)", e.what()));
    return 2;
  }
  return netdem::app::netsolve::guarded("netsolve sinter-pair", [&]() { return run(a, command); });
}
