// netsolve compact (compact.hpp): the door (every option and the packing or state checked before
// the folder opens), the run through qs::run_compaction (a hydrostatic precompaction first with
// --precompact-density), history.csv, the snapshots, the run status and summary.json.
#include "compact.hpp"
#include "compact_common.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include <Eigen/LU>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/jammed_state.hpp"
#include "output.hpp"
#include "parse.hpp"
#include "status.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;

namespace netdem::app::netsolve {

namespace {

/// particles_TAG.vtp, contacts_TAG.vtp and (periodic) cell_TAG.vtp, listed in `series` at the
/// density D of the state.
void write_snapshot(const netdem::qs::NetworkSolver& s, SnapshotSeries& series, const std::string& tag, double density) {
  const fs::path out = series.dir();
  std::vector<double> x = s.x(), y = s.y();
  const auto cell = s.periodic_cell();
  if (cell) {  // a periodic cell: the centres wrapped into it, contacts drawn to j's image, the cell's outline
    for (std::size_t p = 0; p < x.size(); ++p) {
      const Eigen::Vector2d w = cell->wrap(Eigen::Vector2d(x[p], y[p]));
      x[p] = w.x();
      y[p] = w.y();
    }
    const Eigen::Vector2d o = cell->origin, a = cell->h.col(0), b = cell->h.col(1);
    const Eigen::Vector2d c[4] = {o, o + a, o + a + b, o + b};
    netdem::app::write_file_atomic(out / fmt::format("cell_{}.vtp", tag),
                                   netdem::app::vtp_network({c[0].x(), c[1].x(), c[2].x(), c[3].x()},
                                                            {c[0].y(), c[1].y(), c[2].y(), c[3].y()}, {0, 1, 2, 3},
                                                            {1, 2, 3, 0}, {}));
  }
  std::vector<double> rad = s.radius(), th = s.theta(), per(s.peripheral().begin(), s.peripheral().end());
  netdem::app::write_file_atomic(out / fmt::format("particles_{}.vtp", tag),
                                 netdem::app::vtp_particles(x, y, {{"radius", 1, rad}, {"theta", 1, th}, {"peripheral", 1, per}}));
  const auto cs = s.contacts();
  std::vector<int> ci, cj;
  Field fn{"normal_force", 1, {}}, ft{"tangential_force", 1, {}}, ov{"overlap", 1, {}}, sl{"sliding", 1, {}};
  std::vector<double> nx = x, ny = y;  // the network's points: the centres, then the images a contact reaches
  for (const auto& c : cs) {
    ci.push_back(c.i);
    int j = c.j;
    if (cell) {  // j's image as i meets it: a new point where it is not j's wrapped centre
      const double ex = x[c.i] + c.l[0], ey = y[c.i] + c.l[1];
      if (std::hypot(ex - x[c.j], ey - y[c.j]) > 1e-9 * (std::fabs(ex) + std::fabs(ey) + 1.0)) {
        j = static_cast<int>(nx.size());
        nx.push_back(ex);
        ny.push_back(ey);
      }
    }
    cj.push_back(j);
    fn.values.push_back(c.f_n);
    ft.values.push_back(c.f_t);
    ov.values.push_back(c.overlap);
    sl.values.push_back(c.sliding ? 1.0 : 0.0);
  }
  netdem::app::write_file_atomic(out / fmt::format("contacts_{}.vtp", tag), netdem::app::vtp_network(nx, ny, ci, cj, {fn, ft, ov, sl}));
  series.add(density, tag);
}

/// snapshots.pvd: ParaView's time is the density D (the quantity --snapshots names).
SnapshotSeries snapshot_series(const fs::path& out, bool periodic) {
  std::vector<std::string> kinds = {"particles", "contacts"};
  if (periodic) kinds.emplace_back("cell");
  return SnapshotSeries(out / "snapshots.pvd", kinds);
}

/// The solver and compaction options of `compact`, checked (before the output folder exists).
void compact_options(const CompactArgs& a, netdem::qs::SolverOptions& so, netdem::qs::CompactionOptions& co) {
  so = compact_solver_options(a);
  co = compact_compaction_options<2>(a, so);
}

/// Disk centres outside the initial box: die mode prescribes only the peripheral layer, and a
/// (frictionless) packing can squeeze disks out of the box between peripheral disks
/// (docs/quasistatic.md).
int centres_outside(const netdem::qs::NetworkSolver& solver, const netdem::packing::Box& box) {
  int outside = 0;
  const Eigen::Matrix2d Finv = solver.box_deformation().inverse();
  for (std::size_t p = 0; p < solver.size(); ++p) {
    const Eigen::Vector2d q = Finv * solver.particles().position(p);  // in the initial box
    outside += q.x() < box.x_min || q.x() > box.x_max || q.y() < box.y_min || q.y() > box.y_max;
  }
  return outside;
}
/// The last row of a leg (increment 0 counts as the precompaction's first row).
struct LegEnd {
  bool reached = false;
  int increment = 0;
  netdem::qs::StateMeasures state;
};

/// What a `compact` run measured, for its summary.json.
struct CompactRecord {
  std::string source;
  int done = 0, outside = 0;
  double wall = 0.0;
  netdem::qs::StateMeasures last;
  std::string stopped;
  const IncrementTally& tally;
  std::array<LegEnd, 2> legs;  ///< the last row of each leg (a run that precompacts)
};


/// summary.json "legs" of a run that precompacts: each leg's target, increments and last row; the
/// path's equivalent strain |E| = sqrt(dE11^2 + dE22^2 + 2 dE12^2) from the end of the precompaction.
nlohmann::json legs_summary(const qs::CompactionOptions& co, const std::array<LegEnd, 2>& legs, double sy) {
  nlohmann::json out = nlohmann::json::array();
  for (int k = 0; k < 2; ++k) {
    const LegEnd& e = legs[static_cast<std::size_t>(k)];
    nlohmann::json j;
    j["leg"] = k;
    j["name"] = k == 0 ? "precompaction" : "path";
    j["path"] = k == 0 ? "hydrostatic" : co.path.name;
    j["increments"] = k == 0 ? co.precompact_increments : co.increments;
    if (k == 0 || co.target_strain == 0.0) {
      j["to_density"] = k == 0 ? co.precompact_density : co.target_density;
    } else {
      j["to_strain"] = co.target_strain;
    }
    if (!e.reached) {
      j["end"] = nullptr;
    } else {
      const auto& m = e.state;
      j["end"] = {{"increment", e.increment}, {"D", m.density},   {"S11", m.S11 / sy}, {"S22", m.S22 / sy},
                  {"S12", m.S12 / sy},        {"Z", m.Z},         {"E11", m.E11},      {"E22", m.E22},
                  {"E12", m.E12}};
      if (k == 1) {
        const auto& s = legs[0].state;
        const double d11 = m.E11 - s.E11, d22 = m.E22 - s.E22, d12 = m.E12 - s.E12;
        j["end"]["strain"] = std::sqrt(d11 * d11 + d22 * d22 + 2 * d12 * d12);
      }
    }
    out.push_back(j);
  }
  return out;
}

/// summary.json of a `compact` run (docs/quasistatic.md).
nlohmann::json compact_summary(const std::string& command, const CompactArgs& a, const RunArgs& ra, const netdem::qs::SolverOptions& so,
                               const netdem::qs::CompactionOptions& co, const netdem::packing::Packing& pk,
                               const netdem::qs::NetworkSolver& solver, const netdem::app::RunStatus& status, const CompactRecord& r) {
  namespace qs = netdem::qs;
  const double sy = so.law.sigma_y;
  const auto& tm = solver.timings();
  const auto& [source, done, outside, wall, last, stopped, tally, legs] = r;
  nlohmann::json j;
  j["command"] = command;
  status.write(j);
  j["allow_unconverged"] = ra.allow_unconverged;
  j["increments_done"] = done;
  j["centres_outside_box"] = outside;
  j["packing"] = source;
  j["seed"] = pk.seed;
  j["particles"] = pk.size();
  j["initial_density"] = solver.initial_density();
  j["sigma_y"] = sy;
  j["friction"] = a.law.friction;
  j["mode"] = a.affine ? (so.affine_centres ? "affine (periodic cell)" : "affine") : so.mode == qs::BoundaryMode::Walls ? "walls" : so.mode == qs::BoundaryMode::Periodic ? "periodic" : "die";
  if (so.mode == qs::BoundaryMode::Periodic)  // no prescribed boundary: Eq 13 has no reactions to sum
    j["stress_measure"] = "contact stress (periodic cell: S = S_contacts, eq13_vs_contacts 0 by construction)";
  j["rotations"] = !a.no_rotation;
  j["path"] = {{"name", co.path.name}, {"E11", co.path.E11}, {"E22", co.path.E22}, {"E12", co.path.E12}};
  j["increments"] = co.increments;
  if (co.target_strain > 0.0) j["to_strain"] = co.target_strain;
  if (co.precompacts()) j["legs"] = legs_summary(co, legs, sy);
  j["k_t"] = so.law.k_t;
  j["first_touch"] = so.law.first_touch;
  j["normal_unloading"] = a.law.normal_unloading;
  j["final"] = {{"D", last.density},       {"S11", last.S11 / sy},        {"S22", last.S22 / sy},
                {"S12", last.S12 / sy},     {"S_asym", last.S_asym / sy},  {"Z", last.Z},
                {"contacts", last.contacts}, {"sliding", last.sliding},   {"E11", last.E11},
                {"E22", last.E22},          {"E12", last.E12},
                {"rattlers", last.rattlers}, {"Z_backbone", last.Z_backbone},
                {"fabric11", last.fabric11}, {"fabric22", last.fabric22}, {"fabric12", last.fabric12}};
  j["solver"] = solver_summary(so, tm, solver.free_dofs(), tally, 2);
  const bool saved = a.save_state && stopped.empty();
  j["state"] = saved ? nlohmann::json("state.txt") : nlohmann::json(nullptr);
  if (a.save_state || !a.state_file.empty())  // a periodic cell is not a jammed state's box (yet)
    j["jammed_state"] = {{"from", a.state_file},
                         {"saved", saved && so.mode != qs::BoundaryMode::Periodic ? "jammed.json" : ""}};
  add_run_records(j, tm, wall);
  return j;
}

/// The rows of a run: history.csv (with the column `leg` when it precompacts), the records of the
/// run status, the snapshots at the --snapshots densities, the progress and each leg's last row.
struct CompactRows {
  CompactRows(const qs::NetworkSolver& s, SnapshotSeries& snapshot_series, std::vector<double> snapshots, const qs::SolverOptions& so,
              const qs::CompactionOptions& co, bool quiet)
      : solver(s), series(snapshot_series), snaps(std::move(snapshots)), sy(so.law.sigma_y), legs(co.precompacts()),
        total(co.increments + (legs ? co.precompact_increments : 0)), progress("compact", total, quiet), tally(so) {
    csv = legs ? "increment,leg," : "increment,";
    csv += "E11,E22,E12,D,S11,S22,S12,S_asym,S11_contacts,S22_contacts,Z,contacts,sliding,mean_fn,"
           "dev_un_mean_ratio,dev_un_ratio_of_means,dev_ut_centres,dev_ut_rotations,affine_ut,residual,residual_rms,newton_residual,newton,"
           "linear_iterations,converged,net_force_ratio,eq13_vs_contacts,substeps,instability,drag_work_fraction,"
           "unconverged_substeps,rattlers,Z_backbone,fabric11,fabric22,fabric12\n";
    growth.tol = so.residual_tol;
  }

  void add(const qs::CompactionRow& row) {
    const auto& m = row.state;
    csv += fmt::format("{}", row.increment);
    if (legs) csv += fmt::format(",{}", row.leg);
    csv += fmt::format(",{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{:.9g},"
                       "{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.3e},{:.3e},{:.3e},{},{},{},{:.3e},{:.3e},{},{},{:.3e},{},{},{:.6g},"
                       "{:.9g},{:.9g},{:.9g}\n",
                       m.E11, m.E22, m.E12, m.density, m.S11 / sy, m.S22 / sy, m.S12 / sy, m.S_asym / sy,
                       m.S11_contacts / sy, m.S22_contacts / sy, m.Z, m.contacts, m.sliding, m.mean_normal_force,
                       m.dev_normal_mean_ratio, m.dev_normal_ratio_of_means, m.dev_tangential_centres,
                       m.dev_tangential_rotations, m.affine_tangential, row.report.residual, row.report.residual_rms, row.report.newton_residual,
                       row.report.newton_iterations, row.report.linear_iterations, row.report.converged ? 1 : 0,
                       m.net_force_ratio, m.eq13_vs_contacts, row.report.substeps, row.report.instability ? 1 : 0,
                       qs::drag_work_fraction(row.report), row.report.unconverged_substeps, m.rattlers,
                       m.Z_backbone, m.fabric11, m.fabric22, m.fabric12);
    if (row.increment > 0) tally.add(row.increment, row.report, m.eq13_vs_contacts, m.net_force_ratio);
    done = row.increment;
    leg_end[row.leg == 0 ? 0 : 1] = {true, row.increment, m};
    while (next_snap < snaps.size() && m.density >= snaps[next_snap] - 1e-9) {
      write_snapshot(solver, series, fmt::format("D{:.3f}", snaps[next_snap]), m.density);
      ++next_snap;
    }
    last = m;
    end_compact_row(row.increment, row.report.newton_residual, total, csv, series, progress, growth);
  }

  const qs::NetworkSolver& solver;
  SnapshotSeries& series;
  std::vector<double> snaps;
  double sy;
  bool legs;
  int total;
  Progress progress;
  std::string csv;
  std::size_t next_snap = 0;
  IncrementTally tally;
  int done = 0;
  qs::StateMeasures last;
  ResidualGrowth growth;
  std::array<LegEnd, 2> leg_end;
};

int run_compact(const PackArgs& pa, const CompactArgs& a, const RunArgs& ra, const std::string& command, const fs::path& out) {
  qs::SolverOptions so;
  qs::CompactionOptions co;
  compact_options(a, so, co);
  std::vector<double> snaps = a.snapshots;  // a set of densities (the file names carry each): any order
  std::sort(snaps.begin(), snaps.end());

  const std::string input = a.state_file.empty() ? a.packing_file : a.state_file;
  check_run_dir(out, run_dir_options(ra, input));
  std::string source;
  const auto jammed = jammed_input(a.state_file, a.packing_file, so, "netsolve compact", "--boundary walls");
  if (input.empty()) check_deposition_size(pa, true);
  activity() = input.empty() ? "building the ballistic deposition" : "reading " + input;
  const bool periodic = so.mode == qs::BoundaryMode::Periodic;
  packing::Packing pk = jammed ? jammed->packing()
                               : input_packing(a.packing_file, pa, source, "netsolve compact",
                                               periodic ? PeriodicInput::Require : PeriodicInput::Refuse);
  if (jammed) source = "jammed state " + a.state_file;
  // the walls enclose every disk at the start (as demsolve compact --boundary walls); a state has its box
  if (so.mode == qs::BoundaryMode::Walls && !jammed) pk.box = walls_box(pk);
  co.validate(pk.density());
  activity() = "setting up the network solver";
  open_run_dir(out, command, run_dir_options(ra, input));
  packing::write_packing_csv(pk, out / "packing.csv");
  if (!a.quiet) std::fprintf(stderr, "netsolve: %zu particles, D0 = %.4f, seed %llu (%s)\n", pk.size(), pk.density(),
                             static_cast<unsigned long long>(pk.seed), source.c_str());

  const auto t0 = std::chrono::steady_clock::now();
  qs::NetworkSolver solver = jammed ? qs::NetworkSolver(*jammed, so) : qs::NetworkSolver(pk, so);
  SnapshotSeries series = snapshot_series(out, periodic);
  write_snapshot(solver, series, "initial", solver.measures().density);
  CompactRows rows(solver, series, snaps, so, co, a.quiet);
  std::string stopped;  // why the run stopped before the target, or ""
  activity() = "compacting";
  try {
    qs::run_compaction(solver, co, [&](const qs::CompactionRow& row) { rows.add(row); });
  } catch (const StopRun& s) {
    stopped = s.reason;
  } catch (const qs::DivergedError& e) {
    stopped = fmt::format("increment {}: {}", rows.done + 1, e.what());
  }
  rows.progress.finish();
  if (!stopped.empty()) rows.csv += "# stopped: " + stopped + "\n";  // history readers skip '#' lines
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_file_atomic(out / "history.csv", rows.csv);
  if (stopped.empty()) {  // a stopped run keeps what it wrote up to its last good increment
    write_snapshot(solver, series, "final", rows.last.density);
    if (a.save_state) qs::save_state(solver.state(), (out / "state.txt").string());
    if (a.save_state && !periodic) sys::write_jammed_state(solver.jammed_state(), (out / "jammed.json").string());
  }
  // die mode prescribes only the peripheral layer: a (frictionless) packing can squeeze disks out
  // of the box between peripheral disks; count them and say so (docs/quasistatic.md)
  const int outside = periodic ? 0 : centres_outside(solver, pk.box);  // a periodic cell has no outside
  if (outside > 0)
    std::fprintf(stderr, "netsolve: warning: %d disk centres left the box between the peripheral disks (die mode)\n",
                 outside);
  RunStatus status;
  if (!stopped.empty()) status.add("unstable", "stopped: " + stopped);
  rows.tally.conv.judge(status, "");
  if (stopped.empty()) rows.tally.equilibrium.judge(status);
  if (so.mode == qs::BoundaryMode::Walls && a.state_file.empty() && rows.tally.unconverged > 0 && !status.ok())
    status.add("unconverged", "a loose packing between walls is a mechanism until the walls jam it: start from a "
                              "jammed state (--state, e.g. demsolve compact --boundary walls --save-state)");
  if (outside > 0) status.add("unstable", fmt::format("{} disk centres left the box between the peripheral disks", outside));
  const qs::StateMeasures& last = rows.last;
  if (last.Z < 2.0) status.add("unstable", fmt::format("final Z = {:.3g} < 2: the network is a mechanism", last.Z));
  const nlohmann::json j =
      compact_summary(command, a, ra, so, co, pk, solver, status,
                      {source, rows.done, outside, wall, last, stopped, rows.tally, rows.leg_end});
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  const double sy = so.law.sigma_y;
  netdem::app::summary_printf("D = %.4f: S11/sy = %.4f, S22/sy = %.4f, Z = %.3f, %d unconverged increments (max residual %.2e), %.2f s -> %s\n",
              last.density, last.S11 / sy, last.S22 / sy, last.Z, rows.tally.unconverged, rows.tally.max_residual, wall, out.c_str());
  return finish_compact_run(stopped, rows.done, status, ra);
}

}  // namespace

template <int D>
std::optional<sys::JammedStateT<D>> jammed_input(const std::string& state_file, const std::string& packing_file,
                                                 const qs::SolverOptions& so, const char* command,
                                                 const char* walls_option) {
  if (state_file.empty()) return std::nullopt;
  if (!packing_file.empty()) throw netdem::app::UsageError("--state and --packing exclude each other");
  const std::string text = sys::read_text_file(state_file, "jammed state file");
  if (const int dim = sys::jammed_state_dim(text, state_file); dim != D)
    throw netdem::app::UsageError(fmt::format("--state {} is a {}D state; {} is {}D",
                                              netdem::packing::quote_input(state_file), dim, command, D));
  sys::JammedStateT<D> j = sys::parse_jammed_state<D>(text, state_file);
  const bool walls = so.mode == netdem::qs::BoundaryMode::Walls;
  if (j.walls != walls)
    throw netdem::app::UsageError(fmt::format("--state {} holds a box {} contact walls: run it {} {}",
                                              netdem::packing::quote_input(state_file), j.walls ? "with" : "without",
                                              j.walls ? "with" : "without", walls_option));
  if (const std::string d = sys::law_difference(j.law, so.law); !d.empty())
    throw netdem::app::UsageError(fmt::format("--state {}: its contact law is not the command line's ({}; state vs command "
                                              "line): give the state's --friction, --k-t, --first-touch and --normal-unloading",
                                              netdem::packing::quote_input(state_file), d));
  return j;
}

template std::optional<sys::JammedStateT<2>> jammed_input<2>(const std::string&, const std::string&,
                                                              const qs::SolverOptions&, const char*, const char*);
template std::optional<sys::JammedStateT<3>> jammed_input<3>(const std::string&, const std::string&,
                                                              const qs::SolverOptions&, const char*, const char*);

CompactCli add_compact_options(CLI::App* comp, CompactArgs& ca, RunArgs& ra, std::string& out) {
  CompactCli cli;
  cli.packing = comp->add_option("--packing", ca.packing_file, "packing CSV (id,x,y,r with '# box' line) instead of a new deposition");
  comp->add_flag("--affine", ca.affine,
                 "affine motion of every particle centre (default: die, peripheral layer only); with --boundary periodic: "
                 "every centre follows the periodic cell");
  comp->add_option("--boundary", ca.boundary,
                   "layer: the peripheral layer follows the strain (die mode, section 2.4); walls: nothing prescribed, four "
                   "rigid frictionless walls at the box faces move with the box (E12 = 0; Eq 13 from the wall forces); periodic: a "
                   "periodic packing (--packing with '# periodic') in a cell that follows the strain, the contact stress")
      ->check(CLI::IsMember({"layer", "walls", "periodic"}))
      ->capture_default_str();
  comp->add_option("--path", ca.path, "hydrostatic | closed-die | E11,E22,E12 strain-rate direction (--dim 3: "
                                      "E11,E22,E33[,E23,E13,E12], closed die along z)")->capture_default_str();
  comp->add_flag("--no-rotation", ca.no_rotation, "forbid all particle rotations");
  cli.density = comp->add_option("--to-density", ca.to_density, "target relative density D")->capture_default_str();
  cli.strain = comp->add_option("--to-strain", ca.to_strain,
                                    "run to this equivalent strain |E| = sqrt(E11^2 + E22^2 + 2 E12^2) along --path instead "
                                    "of to a density, in [1e-9, 1]; any direction, e.g. pure shear --path 1,-1,0 at constant volume");
  cli.strain->excludes(cli.density);
  comp->add_option("--increments", ca.increments, "number of strain increments to the target density or strain (with "
                   "--precompact-density: of the path after the precompaction)")->capture_default_str();
  cli.precompact_density = comp->add_option(
      "--precompact-density", ca.precompact_density,
      "first compact hydrostatically from the start density to this density (leg 0), then run --path to --to-density "
      "or --to-strain from there (leg 1); history.csv gets the column 'leg'");
  cli.precompact_increments =
      comp->add_option("--precompact-increments", ca.precompact_increments,
                       "number of increments of the precompaction (with --precompact-density)")->capture_default_str();
  add_list_option(*comp, "--snapshots", ca.snapshots,
                                         "densities at which VTK snapshots are written, a comma list in any order (\"\": none)");
  comp->add_option("--slide-fraction", ca.solver.slide_stiffness_fraction, "tangential stiffness kept by sliding contacts in the iteration matrix")->capture_default_str();
  comp->add_option("--linear-tol", ca.solver.linear_tolerance, "GMRES tolerance relative to the Newton residual")->capture_default_str();
  comp->add_option("--max-step", ca.solver.max_step, "cap on a Newton step's translation of one particle [R]")->capture_default_str();
  comp->add_option("--max-rotation-step", ca.solver.max_rotation_step, "cap on a Newton step's rotation of one particle [rad]")->capture_default_str();
  comp->add_option("--freeze-after", ca.solver.freeze_after, "contacts that flipped stick/slip this often in an increment keep their stick stiffness in the iteration matrix")->capture_default_str();
  comp->add_option("--factor-reuse", ca.factor_reuse, "kept factor: fresh tangents in a row solved by GMRES preconditioned with the last factorisation instead of a new one (0: off; the answer is judged on the same residual); default 20 with --dim 3, 0 in 2D")->check(CLI::Range(0, 1000000));
  comp->add_option("--preconditioner", ca.preconditioner, "the linear solver's preconditioner: full (the factor of the whole iteration matrix), translations (the factor of the translations' block and each particle's rotation block inverted; every solve is then GMRES on the whole matrix), auto (translations with --dim 3 where rotations are unknowns, else full)")->check(CLI::IsMember({"auto", "full", "translations"}))->capture_default_str();
  comp->add_option("--chord-steps", ca.solver.chord_steps, "modified Newton: iterations that reuse the last tangent and its factorisation after each fresh one (0: off)")->capture_default_str();
  comp->add_option("--backtracks", ca.solver.backtracks, "residual line search: step lengths tried (1, 1/2, 1/4, ...)")->capture_default_str();
  comp->add_option("--threads", ca.solver.threads, "threads for the force evaluations (line search, chord steps); the linear algebra stays serial; results are identical for any number")->capture_default_str();
  comp->add_option("--local-sweeps", ca.solver.local_sweeps, "nonlinear Gauss-Seidel sweeps over the worst particles after each Newton step (0: off)")->capture_default_str();
  comp->add_option("--local-iterations", ca.solver.local_iterations, "damped Newton iterations per particle in a local sweep")->capture_default_str();
  comp->add_option("--local-threshold", ca.solver.local_threshold, "local sweeps treat particles whose residual exceeds this multiple of the RMS residual")->capture_default_str();
  comp->add_option("--viscosity-strain", ca.solver.viscosity_strain, "drag per unit strain: an increment dE gets the drag --viscosity x mean stiffness x this / |dE|, i.e. --viscosity at |dE| = this (default: the increment of the 100-increment default run); 0: --viscosity in every increment whatever its size")->capture_default_str();
  add_law_options(*comp, ca.law,
                  "normal law on unloading: 'reversible' retraces Eq 2 (the paper's compaction, sections 2-3.3), "
                  "'elastic' follows the 10^3 stiffer unloading line of section 3.4");
  comp->add_flag("--save-state", ca.save_state, "write the final state: jammed.json (the jammed state netsolve and demsolve compact --state start from) "
                 "and state.txt (exact; netsolve yield --from-state continues from it)");
  comp->add_option("--state", ca.state_file, "a jammed state (jammed.json of netsolve or demsolve compact --save-state) instead of "
                   "a packing: its disks, box, walls and contact histories")
      ->check(non_empty_file("a jammed state file"));
  comp->add_flag("--verbose", ca.verbose, "print every Newton iteration");
  comp->add_flag("--quiet", ca.quiet, "no progress on stderr");
  comp->add_flag("--allow-unconverged", ra.allow_unconverged,
                 "exit 0 for a finished run that summary.json marks 'unconverged' or 'unstable' (the status is kept; a run "
                 "stopped by a growing residual still exits 3)");
  comp->add_option("--out", out, "output folder")->default_val("results/compact");
  return cli;
}

int run_compact_cli(const CompactCli& cli, const PackArgs& pa, const CompactArgs& ca, const RunArgs& ra,
                    const std::string& command, const fs::path& out) {
  if (cli.packing->count() > 0 && ca.packing_file.empty())
    throw UsageError("--packing is empty: give a packing CSV file, or leave --packing out for a new deposition");
  using CO = qs::CompactionOptions;
  if (cli.strain->count() > 0 && !(ca.to_strain >= CO::kMinTargetStrain && ca.to_strain <= CO::kMaxTargetStrain))
    throw UsageError(fmt::format("--to-strain must be in [{:g}, {:g}], got {}", CO::kMinTargetStrain,
                                 CO::kMaxTargetStrain, ca.to_strain));
  if (cli.precompact_increments->count() > 0 && cli.precompact_density->count() == 0)
    throw UsageError("--precompact-increments is an option of --precompact-density");
  if (cli.precompact_density->count() > 0 && cli.density->count() == 0 && cli.strain->count() == 0)
    throw UsageError("--precompact-density: give the path's target after it, --to-density or --to-strain");
  if (cli.precompact_density->count() > 0 && !(ca.precompact_density > 0.0 && ca.precompact_density < 1.0))
    throw UsageError(fmt::format("--precompact-density must be in (0, 1) (a relative density), got {}",
                                 ca.precompact_density));
  if (pa.dim == 3) return run_compact_3d(pa, ca, ra, command, out);
  return run_compact(pa, ca, ra, command, out);
}

}  // namespace netdem::app::netsolve
