// netsolve: quasi-static implicit network solver for powder compaction (Redanz & Fleck 2001).
//
//   netsolve pack     [--width 80] [--r-min 0.9] [--r-max 1.1] [--seed 1] [--dim 2|3] [--lateral walls|periodic] [--out DIR]
//   netsolve compact  [--affine | --boundary layer|walls] [--path hydrostatic|closed-die|E11,E22,E12] [--friction MU|inf]
//                     [--no-rotation] [--to-density 0.85 | --to-strain S] [--packing FILE] [--increments N] [--out DIR]
//
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
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/linear_solver.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/jammed_state.hpp"
#include "output.hpp"
#include "pack_green.hpp"
#include "pack_periodic.hpp"
#include "parse.hpp"
#include "setup.hpp"
#include "status.hpp"

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

/// Options of every run that writes a folder.
struct RunArgs {
  bool overwrite = false, allow_unconverged = false;
};

// The defaults of `compact` are the library preset qs::SolverOptions::compact()
// (solver_options.hpp; why each value: docs/quasistatic.md "Presets").
struct CompactArgs {
  bool affine = false, no_rotation = false, quiet = false, verbose = false, save_state = false;
  std::string path = "hydrostatic", packing_file, boundary = "layer";
  std::string state_file;  ///< a jammed state to start from (netdem/system/jammed_state.hpp)
  std::vector<double> snapshots = {0.82, 0.84, 0.85};  ///< densities, a set: sorted before use
  double to_density = 0.85, to_strain = 0.0;  // to_strain > 0: run to |E| = to_strain instead
  int increments = 100;
  netdem::qs::SolverOptions solver = netdem::qs::SolverOptions::compact();  // bound directly by the command line
  netdem::app::netsolve::LawArgs law = netdem::app::netsolve::law_args(solver);
};


netdem::app::RunDirOptions run_dir_options(const RunArgs& r, const std::string& input = "") {
  netdem::app::RunDirOptions o;
  o.overwrite = r.overwrite;
  if (!input.empty()) o.inputs.emplace_back(input);
  return o;
}

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
  std::printf("seed %llu (3D, %s): %zu spheres, %zu contacts (+%zu wall), D0 = %.4f, Z = %.3f -> %s\n",
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
  std::printf("seed %llu: %zu particles, %zu contacts (+%zu wall), D0 = %.4f, Z = %.3f -> %s\n",
              static_cast<unsigned long long>(a.seed), st.particles, st.disk_contacts, st.wall_contacts, st.density,
              st.coordination, (out / "packing.csv").c_str());
  return 0;
}

void write_snapshot(const netdem::qs::NetworkSolver& s, const fs::path& out, const std::string& tag) {
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
}

/// The solver and compaction options of `compact`, checked (before the output folder exists).
void compact_options(const CompactArgs& a, netdem::qs::SolverOptions& so, netdem::qs::CompactionOptions& co) {
  namespace qs = netdem::qs;
  so = a.solver;  // the Newton knobs bound directly by the command line
  so.mode = a.affine                 ? qs::BoundaryMode::Affine
            : a.boundary == "walls"    ? qs::BoundaryMode::Walls
            : a.boundary == "periodic" ? qs::BoundaryMode::Periodic
                                       : qs::BoundaryMode::Die;
  if (a.affine && a.boundary != "layer")
    throw std::invalid_argument(fmt::format("--affine and --boundary {} exclude each other (--affine prescribes every centre)",
                                            a.boundary));
  if (so.mode == qs::BoundaryMode::Periodic && !a.state_file.empty())
    throw netdem::app::UsageError("--state: a jammed state has walls or a layer, not a periodic cell (--boundary periodic)");
  so.rotations = !a.no_rotation;
  netdem::app::netsolve::apply_law_args(a.law, so);
  so.verbose = a.verbose;
  so.validate();
  co.path = qs::StrainPath::parse(a.path);
  co.target_density = a.to_density;
  co.target_strain = a.to_strain;
  co.increments = a.increments;
  if (so.mode == qs::BoundaryMode::Walls && co.path.E12 != 0.0)
    throw std::invalid_argument(fmt::format("--boundary walls: the walls stay axis-parallel, so the path needs E12 = 0, got {}",
                                            co.path.E12));
}

/// The jammed state of --state, checked against the command line (walls, law).
std::optional<netdem::sys::JammedStateT<2>> input_state(const CompactArgs& a, const netdem::qs::SolverOptions& so) {
  namespace sys = netdem::sys;
  if (a.state_file.empty()) return std::nullopt;
  if (!a.packing_file.empty()) throw netdem::app::UsageError("--state and --packing exclude each other");
  const std::string text = sys::read_text_file(a.state_file, "jammed state file");
  if (const int dim = sys::jammed_state_dim(text, a.state_file); dim != 2)
    throw netdem::app::UsageError(fmt::format("--state {} is a {}D state; netsolve compact is 2D",
                                              netdem::packing::quote_input(a.state_file), dim));
  sys::JammedStateT<2> j = sys::parse_jammed_state<2>(text, a.state_file);
  const bool walls = so.mode == netdem::qs::BoundaryMode::Walls;
  if (j.walls != walls)
    throw netdem::app::UsageError(fmt::format("--state {} holds a box {} contact walls: run it {} --boundary walls",
                                              netdem::packing::quote_input(a.state_file), j.walls ? "with" : "without",
                                              j.walls ? "with" : "without"));
  if (const std::string d = sys::law_difference(j.law, so.law); !d.empty())
    throw netdem::app::UsageError(fmt::format("--state {}: its contact law is not the command line's ({}; state vs command "
                                              "line): give the state's --friction, --k-t, --first-touch and --normal-unloading",
                                              netdem::packing::quote_input(a.state_file), d));
  return j;
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

/// What a `compact` run measured, for its summary.json.
struct CompactRecord {
  std::string source;
  int done = 0, unconverged = 0, outside = 0;
  double max_residual = 0.0, wall = 0.0;
  netdem::qs::StateMeasures last;
  netdem::app::netsolve::ConvergenceRecord conv;
  netdem::app::netsolve::EquilibriumRecord equilibrium;
  std::string stopped;
  int instabilities = 0, cut_increments = 0;  ///< increments with an instability event, cut increments
  double drag_work = 0.0, contact_work = 0.0;  ///< summed over the increments
};

/// summary.json of a `compact` run (docs/quasistatic.md).
nlohmann::json compact_summary(const CompactArgs& a, const RunArgs& ra, const netdem::qs::SolverOptions& so,
                               const netdem::qs::CompactionOptions& co, const netdem::packing::Packing& pk,
                               const netdem::qs::NetworkSolver& solver, const netdem::app::RunStatus& status, const CompactRecord& r) {
  namespace qs = netdem::qs;
  const double sy = so.law.sigma_y;
  const auto& tm = solver.timings();
  const auto& [source, done, unconverged, outside, max_residual, wall, last, conv, equilibrium, stopped, instabilities,
               cut_increments, drag_work, contact_work] = r;
  nlohmann::json j;
  j["command"] = g_command;
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
  j["mode"] = a.affine ? "affine" : so.mode == qs::BoundaryMode::Walls ? "walls" : so.mode == qs::BoundaryMode::Periodic ? "periodic" : "die";
  if (so.mode == qs::BoundaryMode::Periodic)  // no prescribed boundary: Eq 13 has no reactions to sum
    j["stress_measure"] = "contact stress (periodic cell: S = S_contacts, eq13_vs_contacts 0 by construction)";
  j["rotations"] = !a.no_rotation;
  j["path"] = {{"name", co.path.name}, {"E11", co.path.E11}, {"E22", co.path.E22}, {"E12", co.path.E12}};
  j["increments"] = co.increments;
  if (co.target_strain > 0.0) j["to_strain"] = co.target_strain;
  j["k_t"] = so.law.k_t;
  j["first_touch"] = so.law.first_touch;
  j["normal_unloading"] = a.law.normal_unloading;
  j["final"] = {{"D", last.density},       {"S11", last.S11 / sy},        {"S22", last.S22 / sy},
                {"S12", last.S12 / sy},     {"S_asym", last.S_asym / sy},  {"Z", last.Z},
                {"contacts", last.contacts}, {"sliding", last.sliding},   {"E11", last.E11},
                {"E22", last.E22},          {"E12", last.E12}};
  j["solver"] = {{"unconverged_increments", unconverged}, {"max_residual", max_residual},
                 {"free_dofs", solver.free_dofs()},     {"newton_iterations", tm.newton_iterations},
                 {"analyses", tm.analyses},             {"factorisations", tm.factorisations},
                 {"solves", tm.solves},                 {"tol", so.residual_tol},
                 {"max_newton", so.max_newton},         {"viscosity", so.viscosity},
                 {"viscosity_strain", so.viscosity_strain}, {"linear_tol", so.linear_tolerance}};
  {
    std::string why;
    const bool inl = qs::cholmod_inline_openmp(&why);
    j["cholmod_inline_openmp"] = {{"active", inl}, {"why_not", inl ? nlohmann::json(nullptr) : nlohmann::json(why)}};
  }
  j["solver"]["iteration"] = so.iteration == qs::Iteration::PseudoTransient ? "pseudo-transient" : "legacy-drag";
  j["solver"]["regularisation_scale"] = so.regularisation_scale;
  j["solver"]["max_cuts"] = so.max_cuts;
  j["solver"]["instability_events"] = instabilities;
  j["solver"]["cut_increments"] = cut_increments;
  j["solver"]["drag_work_fraction"] = contact_work > 0.0 ? drag_work / contact_work : 0.0;
  j["solver"]["max_newton_residual"] = conv.max_newton_residual;
  j["solver"]["last_increment_converged"] = conv.last_converged;
  j["solver"]["eq13_vs_contacts"] = equilibrium.last;  // judged in the run status (origin-free Eq 13)
  j["solver"]["max_eq13_vs_contacts"] = equilibrium.max;
  j["solver"]["net_force_ratio"] = equilibrium.last_net_force;  // |sum F| / sum |F| of the reactions
  j["solver"]["max_net_force_ratio"] = equilibrium.max_net_force;
  const bool saved = a.save_state && stopped.empty();
  j["state"] = saved && so.mode != qs::BoundaryMode::Walls ? nlohmann::json("state.txt") : nlohmann::json(nullptr);
  if (a.save_state || !a.state_file.empty())  // a periodic cell is not a jammed state's box (yet)
    j["jammed_state"] = {{"from", a.state_file},
                         {"saved", saved && so.mode != qs::BoundaryMode::Periodic ? "jammed.json" : ""}};
  j["timing_s"] = {{"wall", wall},           {"assemble", tm.assemble}, {"neighbours", tm.neighbours},
                   {"analyse", tm.analyse},  {"factorise", tm.factorise}, {"solve", tm.solve}};
  return j;
}

int run_compact(const PackArgs& pa, const CompactArgs& a, const RunArgs& ra, const fs::path& out) {
  using namespace netdem;
  qs::SolverOptions so;
  qs::CompactionOptions co;
  compact_options(a, so, co);
  std::vector<double> snaps = a.snapshots;  // a set of densities (the file names carry each): any order
  std::sort(snaps.begin(), snaps.end());

  const std::string input = a.state_file.empty() ? a.packing_file : a.state_file;
  app::check_run_dir(out, run_dir_options(ra, input));
  std::string source;
  const auto jammed = input_state(a, so);
  if (input.empty()) app::netsolve::check_deposition_size(pa, true);
  activity() = input.empty() ? "building the ballistic deposition" : "reading " + input;
  const bool periodic = so.mode == qs::BoundaryMode::Periodic;
  packing::Packing pk =
      jammed ? jammed->packing()
             : app::netsolve::input_packing(a.packing_file, pa, source, "netsolve compact",
                                            periodic ? app::netsolve::PeriodicInput::Require : app::netsolve::PeriodicInput::Refuse);
  if (jammed) source = "jammed state " + a.state_file;
  // the walls enclose every disk at the start (as demsolve compact --boundary walls); a state has its box
  if (so.mode == qs::BoundaryMode::Walls && !jammed) pk.box = app::netsolve::walls_box(pk);
  co.validate(pk.density());
  activity() = "setting up the network solver";
  app::open_run_dir(out, g_command, run_dir_options(ra, input));
  packing::write_packing_csv(pk, out / "packing.csv");
  if (!a.quiet) std::fprintf(stderr, "netsolve: %zu particles, D0 = %.4f, seed %llu (%s)\n", pk.size(), pk.density(),
                             static_cast<unsigned long long>(pk.seed), source.c_str());

  const auto t0 = std::chrono::steady_clock::now();
  qs::NetworkSolver solver = jammed ? qs::NetworkSolver(*jammed, so) : qs::NetworkSolver(pk, so);
  write_snapshot(solver, out, "initial");
  std::string csv =
      "increment,E11,E22,E12,D,S11,S22,S12,S_asym,S11_contacts,S22_contacts,Z,contacts,sliding,mean_fn,"
      "dev_un_mean_ratio,dev_un_ratio_of_means,dev_ut_centres,dev_ut_rotations,affine_ut,residual,residual_rms,newton_residual,newton,"
      "linear_iterations,converged,net_force_ratio,eq13_vs_contacts,substeps,instability,drag_work_fraction\n";
  std::size_t next_snap = 0;
  int unconverged = 0;
  double max_residual = 0.0;
  qs::StateMeasures last;
  app::Progress progress("compact", co.increments, a.quiet);
  const double sy = so.law.sigma_y;
  app::netsolve::ConvergenceRecord conv;
  conv.tol = so.residual_tol;
  if (so.iteration == qs::Iteration::PseudoTransient) conv.max_unconverged_fraction = 0.0;
  int instabilities = 0, cut_increments = 0;
  double drag_work = 0.0, contact_work = 0.0;
  app::netsolve::EquilibriumRecord equilibrium;
  app::netsolve::ResidualGrowth growth;
  growth.tol = so.residual_tol;
  int done = 0;
  std::string stopped;  // why the run stopped before the target, or ""
  const auto on_row = [&](const qs::CompactionRow& row) {
    const auto& m = row.state;
    csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{:.9g},"
                       "{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.3e},{:.3e},{:.3e},{},{},{},{:.3e},{:.3e},{},{},{:.3e}\n",
                       row.increment, m.E11, m.E22, m.E12, m.density, m.S11 / sy, m.S22 / sy, m.S12 / sy, m.S_asym / sy,
                       m.S11_contacts / sy, m.S22_contacts / sy, m.Z, m.contacts, m.sliding, m.mean_normal_force,
                       m.dev_normal_mean_ratio, m.dev_normal_ratio_of_means, m.dev_tangential_centres,
                       m.dev_tangential_rotations, m.affine_tangential, row.report.residual, row.report.residual_rms, row.report.newton_residual,
                       row.report.newton_iterations, row.report.linear_iterations, row.report.converged ? 1 : 0,
                       m.net_force_ratio, m.eq13_vs_contacts, row.report.substeps, row.report.instability ? 1 : 0,
                       qs::drag_work_fraction(row.report));
    if (row.increment > 0) {
      instabilities += row.report.instability;
      cut_increments += row.report.substeps > 1;
      drag_work += row.report.drag_work;
      contact_work += row.report.contact_work;
      unconverged += !row.report.converged;
      max_residual = std::max(max_residual, row.report.residual);
      conv.add(row.increment, row.report.converged, row.report.newton_residual);
      equilibrium.add(row.increment, m.eq13_vs_contacts, m.net_force_ratio);
    }
    done = row.increment;
    while (next_snap < snaps.size() && m.density >= snaps[next_snap] - 1e-9) {
      write_snapshot(solver, out, fmt::format("D{:.3f}", snaps[next_snap]));
      ++next_snap;
    }
    if (row.increment % 20 == 0) app::write_file_atomic(out / "history.csv", csv);  // checkpoint
    progress.update(row.increment);
    last = m;
    if (row.increment > 0 && growth.add(row.increment, row.report.newton_residual))
      throw app::netsolve::StopRun{growth.message(row.increment, row.report.newton_residual)};
    activity() = fmt::format("compacting (increment {} of {})", row.increment + 1, co.increments);
  };
  activity() = "compacting";
  try {
    qs::run_compaction(solver, co, on_row);
  } catch (const app::netsolve::StopRun& s) {
    stopped = s.reason;
  } catch (const qs::DivergedError& e) {
    stopped = fmt::format("increment {}: {}", done + 1, e.what());
  }
  progress.finish();
  if (!stopped.empty()) csv += "# stopped: " + stopped + "\n";  // history readers skip '#' lines
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  app::write_file_atomic(out / "history.csv", csv);
  if (stopped.empty()) {  // a stopped run keeps what it wrote up to its last good increment
    write_snapshot(solver, out, "final");
    if (a.save_state && so.mode != qs::BoundaryMode::Walls) qs::save_state(solver.state(), (out / "state.txt").string());
    if (a.save_state && !periodic) sys::write_jammed_state(solver.jammed_state(), (out / "jammed.json").string());
  }
  // die mode prescribes only the peripheral layer: a (frictionless) packing can squeeze disks out
  // of the box between peripheral disks; count them and say so (docs/quasistatic.md)
  // die mode can squeeze disks out between the peripheral disks: count them and say so
  const int outside = periodic ? 0 : centres_outside(solver, pk.box);  // a periodic cell has no outside
  if (outside > 0)
    std::fprintf(stderr, "netsolve: warning: %d disk centres left the box between the peripheral disks (die mode)\n",
                 outside);
  app::netsolve::RunStatus status;
  if (!stopped.empty()) status.add("unstable", "stopped: " + stopped);
  conv.judge(status, "");
  if (stopped.empty()) equilibrium.judge(status);
  if (outside > 0) status.add("unstable", fmt::format("{} disk centres left the box between the peripheral disks", outside));
  if (last.Z < 2.0) status.add("unstable", fmt::format("final Z = {:.3g} < 2: the network is a mechanism", last.Z));
  const nlohmann::json j = compact_summary(a, ra, so, co, pk, solver, status,
                                           {source, done, unconverged, outside, max_residual, wall, last, conv, equilibrium, stopped,
                                            instabilities, cut_increments, drag_work, contact_work});
  app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  app::close_run_dir(out);
  std::printf("D = %.4f: S11/sy = %.4f, S22/sy = %.4f, Z = %.3f, %d unconverged increments (max residual %.2e), %.2f s -> %s\n",
              last.density, last.S11 / sy, last.S22 / sy, last.Z, unconverged, max_residual, wall, out.c_str());
  if (!stopped.empty()) {
    std::fprintf(stderr, "netsolve: error: unstable: %s (history.csv and summary.json keep increments 0..%d)\n",
                 stopped.c_str(), done);
  } else if (!status.ok()) {
    std::fprintf(stderr, "netsolve: %s: %s: %s\n", ra.allow_unconverged ? "warning (--allow-unconverged)" : "error",
                 status.status.c_str(), status.reason().c_str());
  }
  return stopped.empty() ? status.exit_code(ra.allow_unconverged) : app::exit_code::untrustworthy;
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

int main(int argc, char** argv) {
  g_command = netdem::app::shell_command(argc, argv);
  if (argc > 1 && (std::string(argv[1]) == "yield" || std::string(argv[1]) == "yield-merge")) return run_yield_command(argc, argv);
  if (argc > 1 && std::string(argv[1]) == "sinter-pair") return run_sinter_pair_command(argc, argv);
  if (argc > 1 && std::string(argv[1]) == "sinter") return run_sinter_command(argc, argv);
  if (argc > 1 && argv[1][0] != '-' && std::string(argv[1]) != "pack" && std::string(argv[1]) != "compact") {
    std::string word;
    for (const char* c = argv[1]; *c != '\0' && word.size() < 80; ++c) word += std::isprint(static_cast<unsigned char>(*c)) ? *c : '?';
    std::fprintf(stderr, "netsolve: error: unknown subcommand '%s': use pack, compact, yield, yield-merge, sinter-pair or sinter (see --help)\n",
                 word.c_str());
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
  auto* o_packing = comp->add_option("--packing", ca.packing_file, "packing CSV (id,x,y,r with '# box' line) instead of a new deposition");
  comp->add_flag("--affine", ca.affine, "affine motion of every particle centre (default: die, peripheral layer only)");
  comp->add_option("--boundary", ca.boundary,
                   "layer: the peripheral layer follows the strain (die mode, section 2.4); walls: nothing prescribed, four "
                   "rigid frictionless walls at the box faces move with the box (E12 = 0; Eq 13 from the wall forces); periodic: a "
                   "periodic packing (--packing with '# periodic') in a cell that follows the strain, the contact stress")
      ->check(CLI::IsMember({"layer", "walls", "periodic"}))
      ->capture_default_str();
  comp->add_option("--path", ca.path, "hydrostatic | closed-die | E11,E22,E12 strain-rate direction")->capture_default_str();
  comp->add_flag("--no-rotation", ca.no_rotation, "forbid all particle rotations");
  auto* o_density = comp->add_option("--to-density", ca.to_density, "target relative density D")->capture_default_str();
  auto* o_strain = comp->add_option("--to-strain", ca.to_strain,
                                    "run to this equivalent strain |E| = sqrt(E11^2 + E22^2 + 2 E12^2) along --path instead "
                                    "of to a density, in [1e-9, 1]; any direction, e.g. pure shear --path 1,-1,0 at constant volume");
  o_strain->excludes(o_density);
  comp->add_option("--increments", ca.increments, "number of strain increments to the target density")->capture_default_str();
  netdem::app::netsolve::add_list_option(*comp, "--snapshots", ca.snapshots,
                                         "densities at which VTK snapshots are written, a comma list in any order (\"\": none)");
  comp->add_option("--slide-fraction", ca.solver.slide_stiffness_fraction, "tangential stiffness kept by sliding contacts in the iteration matrix")->capture_default_str();
  comp->add_option("--linear-tol", ca.solver.linear_tolerance, "GMRES tolerance relative to the Newton residual")->capture_default_str();
  comp->add_option("--max-step", ca.solver.max_step, "cap on a Newton step's translation of one particle [R]")->capture_default_str();
  comp->add_option("--max-rotation-step", ca.solver.max_rotation_step, "cap on a Newton step's rotation of one particle [rad]")->capture_default_str();
  comp->add_option("--freeze-after", ca.solver.freeze_after, "contacts that flipped stick/slip this often in an increment keep their stick stiffness in the iteration matrix")->capture_default_str();
  comp->add_option("--chord-steps", ca.solver.chord_steps, "modified Newton: iterations that reuse the last tangent and its factorisation after each fresh one (0: off)")->capture_default_str();
  comp->add_option("--backtracks", ca.solver.backtracks, "residual line search: step lengths tried (1, 1/2, 1/4, ...)")->capture_default_str();
  comp->add_option("--threads", ca.solver.threads, "threads for the force evaluations (line search, chord steps); the linear algebra stays serial; results are identical for any number")->capture_default_str();
  comp->add_option("--local-sweeps", ca.solver.local_sweeps, "nonlinear Gauss-Seidel sweeps over the worst particles after each Newton step (0: off)")->capture_default_str();
  comp->add_option("--local-iterations", ca.solver.local_iterations, "damped Newton iterations per particle in a local sweep")->capture_default_str();
  comp->add_option("--local-threshold", ca.solver.local_threshold, "local sweeps treat particles whose residual exceeds this multiple of the RMS residual")->capture_default_str();
  comp->add_option("--viscosity-strain", ca.solver.viscosity_strain, "drag per unit strain: an increment dE gets the drag --viscosity x mean stiffness x this / |dE|, i.e. --viscosity at |dE| = this (default: the increment of the 100-increment default run); 0: --viscosity in every increment whatever its size")->capture_default_str();
  netdem::app::netsolve::add_law_options(*comp, ca.law,
                  "normal law on unloading: 'reversible' retraces Eq 2 (the paper's compaction, sections 2-3.3), "
                  "'elastic' follows the 10^3 stiffer unloading line of section 3.4");
  comp->add_flag("--save-state", ca.save_state, "write the final state: jammed.json (the jammed state netsolve and demsolve compact --state start from) "
                 "and, except with --boundary walls, state.txt (exact; netsolve yield --from-state continues from it)");
  comp->add_option("--state", ca.state_file, "a jammed state (jammed.json of netsolve or demsolve compact --save-state) instead of "
                   "a packing: its disks, box, walls and contact histories");
  comp->add_flag("--verbose", ca.verbose, "print every Newton iteration");
  comp->add_flag("--quiet", ca.quiet, "no progress on stderr");
  comp->add_flag("--allow-unconverged", ra.allow_unconverged,
                 "exit 0 for a finished run that summary.json marks 'unconverged' or 'unstable' (the status is kept; a run "
                 "stopped by a growing residual still exits 3)");
  comp->add_option("--out", out, "output folder")->default_val("results/compact");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "netsolve: error: %s (see --help)\n", e.what());
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
    if (o_packing->count() > 0 && ca.packing_file.empty())
      throw netdem::app::UsageError("--packing is empty: give a packing CSV file, or leave --packing out for a new deposition");
    using CO = netdem::qs::CompactionOptions;
    if (o_strain->count() > 0 && !(ca.to_strain >= CO::kMinTargetStrain && ca.to_strain <= CO::kMaxTargetStrain))
      throw netdem::app::UsageError(fmt::format("--to-strain must be in [{:g}, {:g}], got {}", CO::kMinTargetStrain,
                                                CO::kMaxTargetStrain, ca.to_strain));
    return run_compact(pa, ca, ra, out);
  });
}
