// netsolve compact --dim 3 (issue 30): sphere packings on the network core NetworkSolverT<3> with
// the 3D plastic-indentation law, affine (--affine), in the die of the peripheral layer (--boundary
// layer), between six rigid frictionless walls (--boundary walls) or in a periodic cell (--boundary
// periodic), along hydrostatic, closed-die (along z, the deposition's gravity axis) or any
// six-component strain-rate direction. The same files as in 2D: history.csv (Voigt components,
// the fabric <n x n>), summary.json, the .vtp snapshots in snapshots.pvd, the run status; the
// jammed state both solvers share (--state, --save-state: jammed.json). 2D-only for now: the exact
// continuation file state.txt and the Figs 7-8 deviation columns. README.md "netsolve",
// docs/quasistatic.md.
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "compact.hpp"
#include "compact3.hpp"
#include "compact_common.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/jammed_state.hpp"
#include "netdem/system/strain_path.hpp"
#include "output.hpp"
#include "run_status.hpp"
#include "status.hpp"

namespace fs = std::filesystem;

namespace netdem::app::netsolve {

using Mat3 = Eigen::Matrix3d;
using Row3 = qs::CompactionRowT<3>;

/// The Voigt components of a symmetric 3x3 tensor (E11, E22, E33, E23, E13, E12 order).
sys::Voigt<3> voigt(const Mat3& m) {
  sys::Voigt<3> v{};
  for (int k = 0; k < 6; ++k) v[static_cast<std::size_t>(k)] = m(sys::voigt_row<3>(k), sys::voigt_col<3>(k));
  return v;
}

/// {"11": m11, ..., "12": m12} / scale.
nlohmann::json voigt_json(const Mat3& m, const char* prefix, double scale) {
  nlohmann::json j;
  const auto v = voigt(m);
  for (int k = 0; k < 6; ++k)
    j[fmt::format("{}{}", prefix, sys::voigt_labels<3>()[static_cast<std::size_t>(k)])] = v[static_cast<std::size_t>(k)] / scale;
  return j;
}

/// particles_TAG.vtp, contacts_TAG.vtp and (periodic) cell_TAG.vtp, listed in `series` at the
/// density of the state: the 3D counterpart of compact.cpp's snapshot.
void write_snapshot_3d(const qs::NetworkSolver3& s, SnapshotSeries& series, const std::string& tag, double density) {
  const fs::path out = series.dir();
  const auto& P = s.particles();
  std::vector<double> x = P.axis(0), y = P.axis(1), z = P.axis(2);
  const auto cell = s.periodic_cell();
  if (cell) {  // the centres wrapped into the cell; contacts drawn to j's image; the cell's 12 edges
    for (std::size_t p = 0; p < x.size(); ++p) {
      const Eigen::Vector3d w = cell->wrap(Eigen::Vector3d(x[p], y[p], z[p]));
      x[p] = w.x(), y[p] = w.y(), z[p] = w.z();
    }
    std::vector<double> cx, cy, cz;
    for (int corner = 0; corner < 8; ++corner) {
      Eigen::Vector3d c = cell->origin;
      for (int a = 0; a < 3; ++a)
        if ((corner >> a) & 1) c += cell->h.col(a);
      cx.push_back(c.x()), cy.push_back(c.y()), cz.push_back(c.z());
    }
    std::vector<int> ei, ej;
    for (int c = 0; c < 8; ++c)
      for (int a = 0; a < 3; ++a)
        if (!((c >> a) & 1)) ei.push_back(c), ej.push_back(c | (1 << a));
    write_file_atomic(out / fmt::format("cell_{}.vtp", tag), vtp_network_3d(cx, cy, &cz, ei, ej, {}));
  }
  std::vector<double> per(s.peripheral().begin(), s.peripheral().end());
  write_file_atomic(out / fmt::format("particles_{}.vtp", tag),
                    vtp_particles_3d(x, y, &z, {{"radius", 1, s.radius()}, {"peripheral", 1, per}}));
  std::vector<int> ci, cj;
  Field fn{"normal_force", 1, {}}, ft{"tangential_force", 1, {}}, ov{"overlap", 1, {}}, sl{"sliding", 1, {}};
  std::vector<double> nx = x, ny = y, nz = z;  // the centres, then the images a contact reaches
  for (const auto& c : s.contacts()) {
    int j = c.j;
    if (cell) {
      const Eigen::Vector3d e(x[c.i] + c.l[0], y[c.i] + c.l[1], z[c.i] + c.l[2]);
      if ((e - Eigen::Vector3d(x[c.j], y[c.j], z[c.j])).norm() > 1e-9 * (e.cwiseAbs().sum() + 1.0)) {
        j = static_cast<int>(nx.size());
        nx.push_back(e.x()), ny.push_back(e.y()), nz.push_back(e.z());
      }
    }
    ci.push_back(c.i);
    cj.push_back(j);
    fn.values.push_back(c.f_n);
    ft.values.push_back(c.f_t);
    ov.values.push_back(c.overlap);
    sl.values.push_back(c.sliding ? 1.0 : 0.0);
  }
  write_file_atomic(out / fmt::format("contacts_{}.vtp", tag), vtp_network_3d(nx, ny, &nz, ci, cj, {fn, ft, ov, sl}));
  series.add(density, tag);
}

/// Sphere centres outside the initial box (die mode: the peripheral layer alone holds the box).
int centres_outside_3d(const qs::NetworkSolver3& s, const packing::Box& box) {
  int outside = 0;
  const Mat3 Finv = s.box_deformation().inverse();
  for (std::size_t p = 0; p < s.size(); ++p) {
    Eigen::Vector3d x;
    for (int a = 0; a < 3; ++a) x(a) = s.particles().coord(p, a);
    const Eigen::Vector3d q = Finv * x;
    outside += q.x() < box.x_min || q.x() > box.x_max || q.y() < box.y_min || q.y() > box.y_max ||
               q.z() < box.z_min || q.z() > box.z_max;
  }
  return outside;
}

/// summary.json's description of the state `m`: D, the stresses / sigma_y, Z, the counts.
nlohmann::json state_json(const qs::StressMeasuresT<3>& m, double sy) {
  nlohmann::json j = voigt_json(m.eq13, "S", sy);
  j.update(voigt_json(m.strain, "E"));
  j.update(voigt_json(m.fabric, "fabric"));
  const auto v = voigt(m.contacts);
  for (int k = 0; k < 6; ++k)
    j[fmt::format("S{}_contacts", sys::voigt_labels<3>()[static_cast<std::size_t>(k)])] = v[static_cast<std::size_t>(k)] / sy;
  j["D"] = m.density;
  j["Z"] = m.Z;
  j["contacts"] = m.contact_count;
  j["sliding"] = m.sliding;
  j["rattlers"] = m.rattlers;
  j["Z_backbone"] = m.Z_backbone;
  return j;
}

// ------------------------------------------------------------------------------------------------
Compact3Rows::Compact3Rows(const qs::NetworkSolver3& s, SnapshotSeries& snapshot_series, std::vector<double> snapshots,
                           const qs::SolverOptions& so, const qs::CompactionOptions3& co, bool quiet)
    : solver(s), series(snapshot_series), snaps(std::move(snapshots)), sy(so.law.sigma_y), legs(co.precompacts()),
      total(co.increments + (legs ? co.precompact_increments : 0)), progress("compact", total, quiet), tally(so) {
  growth.tol = so.residual_tol;
  csv = legs ? "increment,leg" : "increment";
  for (const char* pre : {"E", "", "S", "S_contacts:", "fabric"}) {
    if (*pre == '\0') {
      csv += ",D";
      continue;
    }
    const std::string p(pre);
    for (const char* l : sys::voigt_labels<3>())
      csv += p.back() == ':' ? fmt::format(",S{}_contacts", l) : fmt::format(",{}{}", p, l);
  }
  csv += ",Z,contacts,sliding,mean_fn,residual,residual_rms,newton_residual,newton,linear_iterations,converged,"
         "net_force_ratio,eq13_vs_contacts,substeps,instability,drag_work_fraction,unconverged_substeps,rattlers,"
         "Z_backbone\n";
}

void Compact3Rows::add(const Row3& row) {
  const auto& m = row.state;
  const auto& r = row.report;
  csv += fmt::format("{}", row.increment);
  if (legs) csv += fmt::format(",{}", row.leg);
  for (double v : voigt(m.strain)) csv += fmt::format(",{:.9g}", v);
  csv += fmt::format(",{:.9g}", m.density);
  for (double v : voigt(m.eq13)) csv += fmt::format(",{:.9g}", v / sy);
  for (double v : voigt(m.contacts)) csv += fmt::format(",{:.9g}", v / sy);
  for (double v : voigt(m.fabric)) csv += fmt::format(",{:.9g}", v);
  csv += fmt::format(",{:.6g},{},{},{:.9g},{:.3e},{:.3e},{:.3e},{},{},{},{:.3e},{:.3e},{},{},{:.3e},{},{},{:.6g}\n", m.Z,
                     m.contact_count, m.sliding, m.mean_normal_force, r.residual, r.residual_rms, r.newton_residual,
                     r.newton_iterations, r.linear_iterations, r.converged ? 1 : 0, m.net_force_ratio,
                     m.eq13_vs_contacts, r.substeps, r.instability ? 1 : 0, qs::drag_work_fraction(r),
                     r.unconverged_substeps, m.rattlers, m.Z_backbone);
  if (row.increment > 0) tally.add(row.increment, r, m.eq13_vs_contacts, m.net_force_ratio);
  done = row.increment;
  leg_end[row.leg == 0 ? 0 : 1] = row;
  reached[row.leg == 0 ? 0 : 1] = true;
  while (next_snap < snaps.size() && m.density >= snaps[next_snap] - 1e-9) {
    write_snapshot_3d(solver, series, fmt::format("D{:.3f}", snaps[next_snap]), m.density);
    ++next_snap;
  }
  last = m;
  end_compact_row(row.increment, r.newton_residual, total, csv, series, progress, growth);
}

int run_compact_3d(const PackArgs& pa, const CompactArgs& a, const RunArgs& ra, const std::string& command,
                   const fs::path& out) {
  qs::SolverOptions so = compact_solver_options(a);
  if (a.factor_reuse < 0) so.factor_reuse = kFactorReuse3d;
  const qs::CompactionOptions3 co = compact_compaction_options<3>(a, so);
  std::vector<double> snaps = a.snapshots;
  std::sort(snaps.begin(), snaps.end());
  const bool periodic = so.mode == qs::BoundaryMode::Periodic;
  if (periodic && a.packing_file.empty())
    throw UsageError("--boundary periodic needs --packing FILE with a periodic packing (a '# periodic' line; netsolve "
                     "pack --dim 3 --periodic)");
  const std::string input = a.state_file.empty() ? a.packing_file : a.state_file;
  check_run_dir(out, run_dir_options(ra, input));
  const auto jammed = jammed_input<3>(a.state_file, a.packing_file, so, "netsolve compact --dim 3", "--boundary walls");
  if (input.empty()) check_deposition_size(pa, true);
  std::string source;
  activity() = input.empty() ? "building the 3D ballistic deposition" : "reading " + input;
  packing::Packing pk = jammed ? jammed->packing() : input_packing_3d(a.packing_file, pa, source, "the network solver");
  if (jammed) source = "jammed state " + a.state_file;
  // the walls enclose every sphere at the start (as demsolve compact --boundary walls); a state has its box
  if (so.mode == qs::BoundaryMode::Walls && !jammed) pk.box = walls_box(pk);
  if (pk.periodic && !periodic)
    throw UsageError(fmt::format("--packing {} is a periodic packing (a '# periodic' line): run it with --boundary periodic",
                                 packing::quote_input(a.packing_file)));
  if (!pk.periodic && periodic)
    throw UsageError(fmt::format("--boundary periodic needs a periodic packing, and --packing {} has no '# periodic' line",
                                 packing::quote_input(a.packing_file)));
  co.validate(pk.density());
  activity() = "setting up the network solver";
  open_run_dir(out, command, run_dir_options(ra, input));
  packing::write_packing_csv(pk, out / "packing.csv");
  if (!a.quiet)
    std::fprintf(stderr, "netsolve: %zu spheres, D0 = %.4f, seed %llu (%s)\n", pk.size(), pk.density(),
                 static_cast<unsigned long long>(pk.seed), source.c_str());

  const auto t0 = std::chrono::steady_clock::now();
  qs::NetworkSolver3 solver = jammed ? qs::NetworkSolver3(*jammed, so) : qs::NetworkSolver3(pk, so);
  std::vector<std::string> kinds = {"particles", "contacts"};
  if (periodic) kinds.emplace_back("cell");
  SnapshotSeries series(out / "snapshots.pvd", kinds);
  write_snapshot_3d(solver, series, "initial", solver.stress().density);
  Compact3Rows rows(solver, series, snaps, so, co, a.quiet);
  std::string stopped;
  activity() = "compacting";
  try {
    qs::run_compaction(solver, co, [&](const Row3& row) { rows.add(row); });
  } catch (const StopRun& s) {
    stopped = s.reason;
  } catch (const qs::DivergedError& e) {
    stopped = fmt::format("increment {}: {}", rows.done + 1, e.what());
  }
  rows.progress.finish();
  if (!stopped.empty()) rows.csv += "# stopped: " + stopped + "\n";
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_file_atomic(out / "history.csv", rows.csv);
  if (stopped.empty()) {  // a stopped run keeps what it wrote up to its last good increment
    write_snapshot_3d(solver, series, "final", rows.last.density);
    if (a.save_state) qs::save_state(solver.state(), (out / "state.txt").string());  // exact (kind network3d)
    if (a.save_state && !periodic) sys::write_jammed_state(solver.jammed_state(), (out / "jammed.json").string());
  }
  const int outside = periodic ? 0 : centres_outside_3d(solver, pk.box);
  if (outside > 0)
    std::fprintf(stderr, "netsolve: warning: %d sphere centres left the box between the peripheral spheres (die mode)\n",
                 outside);
  RunStatus status;
  if (!stopped.empty()) status.add("unstable", "stopped: " + stopped);
  rows.tally.conv.judge(status, "");
  if (stopped.empty()) rows.tally.equilibrium.judge(status);
  if (outside > 0) status.add("unstable", fmt::format("{} sphere centres left the box between the peripheral spheres", outside));
  if (so.mode == qs::BoundaryMode::Walls && a.state_file.empty() && rows.tally.unconverged > 0 && !status.ok())
    status.add("unconverged", "a loose packing between walls is a mechanism until the walls jam it: start from a "
                              "jammed state (--state, e.g. demsolve compact --dim 3 --boundary walls --save-state)");
  const auto& last = rows.last;
  if (last.Z < 3.0) status.add("unstable", fmt::format("final Z = {:.3g} < 3: the network is a mechanism", last.Z));

  const double sy = so.law.sigma_y;
  const auto& tm = solver.timings();
  nlohmann::json j;
  j["command"] = command;
  status.write(j);
  j["allow_unconverged"] = ra.allow_unconverged;
  j["dim"] = 3;
  j["increments_done"] = rows.done;
  j["centres_outside_box"] = outside;
  j["packing"] = source;
  j["seed"] = pk.seed;
  j["particles"] = pk.size();
  j["initial_density"] = solver.initial_density();
  j["sigma_y"] = sy;
  j["friction"] = a.law.friction;
  j["mode"] = a.affine ? (periodic ? "affine (periodic cell)" : "affine")
              : periodic ? "periodic"
              : so.mode == qs::BoundaryMode::Walls ? "walls"
                                                   : "die";
  if (periodic) j["stress_measure"] = "contact stress (periodic cell: S = S_contacts, eq13_vs_contacts 0 by construction)";
  j["rotations"] = !a.no_rotation;
  j["path"] = {{"name", co.path.name}, {"E", co.path.E}};
  j["increments"] = co.increments;
  if (co.target_strain > 0.0) j["to_strain"] = co.target_strain;
  if (co.precompacts()) {
    j["legs"] = nlohmann::json::array();
    for (int k = 0; k < 2; ++k) {
      const std::size_t u = static_cast<std::size_t>(k);
      nlohmann::json l = {{"leg", k}, {"name", k == 0 ? "precompaction" : "path"},
                          {"path", k == 0 ? "hydrostatic" : co.path.name},
                          {"increments", k == 0 ? co.precompact_increments : co.increments}};
      if (k == 0 || co.target_strain == 0.0) {
        l["to_density"] = k == 0 ? co.precompact_density : co.target_density;
      } else {
        l["to_strain"] = co.target_strain;
      }
      l["end"] = rows.reached[u] ? state_json(rows.leg_end[u].state, sy) : nlohmann::json(nullptr);
      if (rows.reached[u]) l["end"]["increment"] = rows.leg_end[u].increment;
      if (k == 1 && rows.reached[0] && rows.reached[1])  // the path's |E| from the end of the precompaction
        l["end"]["strain"] = (rows.leg_end[1].state.strain - rows.leg_end[0].state.strain).norm();
      j["legs"].push_back(l);
    }
  }
  j["k_t"] = so.law.k_t;
  j["first_touch"] = so.law.first_touch;
  j["normal_unloading"] = a.law.normal_unloading;
  j["final"] = state_json(last, sy);
  j["solver"] = solver_summary(so, tm, solver.free_dofs(), rows.tally, 3);
  const bool saved = a.save_state && stopped.empty();
  j["state"] = saved ? nlohmann::json("state.txt") : nlohmann::json(nullptr);
  if (a.save_state || !a.state_file.empty())  // a periodic cell is not a jammed state's box (yet)
    j["jammed_state"] = {{"from", a.state_file}, {"saved", saved && !periodic ? "jammed.json" : ""}};
  add_run_records(j, tm, wall);
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  summary_printf("D = %.4f: S11/sy = %.4f, S22/sy = %.4f, S33/sy = %.4f, Z = %.3f, %d unconverged increments (max "
                 "residual %.2e), %.2f s -> %s\n",
                 last.density, last.eq13(0, 0) / sy, last.eq13(1, 1) / sy, last.eq13(2, 2) / sy, last.Z,
                 rows.tally.unconverged, rows.tally.max_residual, wall, out.c_str());
  return finish_compact_run(stopped, rows.done, status, ra);
}

}  // namespace netdem::app::netsolve
