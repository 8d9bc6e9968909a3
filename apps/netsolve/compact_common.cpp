#include "compact_common.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "netdem/quasistatic/linear_solver.hpp"

namespace netdem::app::netsolve {

qs::SolverOptions compact_solver_options(const CompactArgs& a) {
  qs::SolverOptions so = a.solver;  // the Newton knobs bound directly by the command line
  if (a.factor_reuse >= 0) so.factor_reuse = a.factor_reuse;  // else the preset's (2D; run_compact_3d: kFactorReuse3d)
  so.mode = a.affine                 ? qs::BoundaryMode::Affine
            : a.boundary == "walls"    ? qs::BoundaryMode::Walls
            : a.boundary == "periodic" ? qs::BoundaryMode::Periodic
                                       : qs::BoundaryMode::Die;
  if (a.affine && a.boundary != "layer" && a.boundary != "periodic")
    throw std::invalid_argument(fmt::format("--affine and --boundary {} exclude each other (--affine prescribes every centre)",
                                            a.boundary));
  if (a.affine && a.boundary == "periodic") {  // every centre follows the periodic cell, the histories kept
    so.mode = qs::BoundaryMode::Periodic;
    so.affine_centres = true;
  }
  if (so.mode == qs::BoundaryMode::Periodic && !a.state_file.empty())
    throw netdem::app::UsageError("--state: a jammed state has walls or a layer, not a periodic cell (--boundary periodic)");
  so.rotations = !a.no_rotation;
  so.preconditioner = preconditioner_of(a.preconditioner);
  apply_law_args(a.law, so);
  so.verbose = a.verbose;
  so.validate();
  return so;
}

template <int D>
qs::CompactionOptionsT<D> compact_compaction_options(const CompactArgs& a, const qs::SolverOptions& so) {
  qs::CompactionOptionsT<D> co;
  co.path = qs::StrainPathOf<D>::parse(a.path);
  co.target_density = a.to_density;
  co.target_strain = a.to_strain;
  co.increments = a.increments;
  co.precompact_density = a.precompact_density;
  co.precompact_increments = a.precompact_increments;
  if constexpr (D == 2) {
    if (so.mode == qs::BoundaryMode::Walls && co.path.E12 != 0.0)
      throw std::invalid_argument(fmt::format("--boundary walls: the walls stay axis-parallel, so the path needs E12 = 0, got {}",
                                              co.path.E12));
  } else {
    if (so.mode == qs::BoundaryMode::Walls && (co.path.E[3] != 0.0 || co.path.E[4] != 0.0 || co.path.E[5] != 0.0))
      throw std::invalid_argument(fmt::format("--boundary walls: the walls stay axis-parallel, so the path needs E23 = E13 "
                                              "= E12 = 0, got {}, {}, {}", co.path.E[3], co.path.E[4], co.path.E[5]));
  }
  return co;
}
template qs::CompactionOptionsT<2> compact_compaction_options<2>(const CompactArgs&, const qs::SolverOptions&);
template qs::CompactionOptionsT<3> compact_compaction_options<3>(const CompactArgs&, const qs::SolverOptions&);

qs::SolverOptions yield_probe_options(const qs::SolverOptions& pre, qs::BoundaryMode probe_mode) {
  qs::SolverOptions probe = qs::SolverOptions::yield_probe();
  probe.mode = probe_mode;
  if (pre.mode == qs::BoundaryMode::Periodic && probe.mode == qs::BoundaryMode::Affine) {
    probe.mode = qs::BoundaryMode::Periodic;  // affine probing of the periodic state: every centre
    probe.affine_centres = true;              // prescribed, the histories kept
  }
  probe.law = pre.law;  // unloading switches it to the elastic branch (set_reversible_normal)
  probe.iteration = pre.iteration;  // the iteration and its regularisation knob cover the probes too
  probe.regularisation_scale = pre.regularisation_scale;
  probe.max_cuts = pre.max_cuts;
  probe.energy_merit = pre.energy_merit;
  probe.friction_energy_merit = pre.friction_energy_merit;
  probe.preconditioner = pre.preconditioner;  // the linear solver's too
  if (probe.iteration == qs::Iteration::PseudoTransient) probe.max_newton = pre.max_newton;
  probe.validate();
  return probe;
}

IncrementTally::IncrementTally(const qs::SolverOptions& so) {
  conv.tol = so.residual_tol;
  if (so.iteration == qs::Iteration::PseudoTransient) conv.max_unconverged_fraction = 0.0;
}

void IncrementTally::add(int increment, const qs::IncrementReport& r, double eq13_vs_contacts, double net_force_ratio) {
  instabilities += r.instability;
  unjammed += r.unjammed;
  cut_increments += r.substeps > 1;
  unconverged_substeps += r.unconverged_substeps;
  drag_work += r.drag_work;
  contact_work += r.contact_work;
  unconverged += !r.converged;
  max_residual = std::max(max_residual, r.residual);
  conv.add(increment, r.converged, r.newton_residual);
  equilibrium.add(increment, eq13_vs_contacts, net_force_ratio);
}

nlohmann::json solver_summary(const qs::SolverOptions& so, const qs::SolverTimings& tm, int free_dofs,
                              const IncrementTally& t, int dim) {
  nlohmann::json j = {{"unconverged_increments", t.unconverged}, {"max_residual", t.max_residual},
                      {"free_dofs", free_dofs},                  {"newton_iterations", tm.newton_iterations},
                      {"analyses", tm.analyses},                 {"factorisations", tm.factorisations},
                      {"solves", tm.solves},                     {"tol", so.residual_tol},
                      {"max_newton", so.max_newton},             {"viscosity", so.viscosity},
                      {"viscosity_strain", so.viscosity_strain}, {"linear_tol", so.linear_tolerance}};
  j["iteration"] = iteration_name(so.iteration);
  j["regularisation_scale"] = so.regularisation_scale;
  j["max_cuts"] = so.max_cuts;
  j["factor_reuse"] = so.factor_reuse;
  j["preconditioner"] = preconditioner_name(so.resolved_preconditioner(dim));  // as resolved for this run
  // the merit the iteration used (energy, energy-friction or residual)
  if (so.iteration == qs::Iteration::PseudoTransient) j["merit"] = so.merit_name();
  if (so.uses_energy_merit()) j["unjammed_increments"] = t.unjammed;
  j["instability_events"] = t.instabilities;
  j["cut_increments"] = t.cut_increments;
  j["unconverged_substeps"] = t.unconverged_substeps;
  j["drag_work_fraction"] = t.contact_work > 0.0 ? t.drag_work / t.contact_work : 0.0;
  j["max_newton_residual"] = t.conv.max_newton_residual;
  j["last_increment_converged"] = t.conv.last_converged;
  j["eq13_vs_contacts"] = t.equilibrium.last;  // judged in the run status (origin-free Eq 13)
  j["max_eq13_vs_contacts"] = t.equilibrium.max;
  j["net_force_ratio"] = t.equilibrium.last_net_force;  // |sum F| / sum |F| of the reactions
  j["max_net_force_ratio"] = t.equilibrium.max_net_force;
  return j;
}

void add_run_records(nlohmann::json& j, const qs::SolverTimings& tm, double wall) {
  std::string why;
  const bool inl = qs::cholmod_inline_openmp(&why);
  j["cholmod_inline_openmp"] = {{"active", inl}, {"why_not", inl ? nlohmann::json(nullptr) : nlohmann::json(why)}};
  j["timing_s"] = {{"wall", wall},          {"assemble", tm.assemble}, {"neighbours", tm.neighbours},
                   {"analyse", tm.analyse}, {"factorise", tm.factorise}, {"solve", tm.solve}};
}

void end_compact_row(int increment, double newton_residual, int total, const std::string& csv, SnapshotSeries& series,
                     Progress& progress, ResidualGrowth& growth) {
  if (increment % 20 == 0) write_file_atomic(series.dir() / "history.csv", csv);  // checkpoint
  progress.update(increment);
  if (increment > 0 && growth.add(increment, newton_residual)) throw StopRun{growth.message(increment, newton_residual)};
  activity() = fmt::format("compacting (increment {} of {})", increment + 1, total);
}

int finish_compact_run(const std::string& stopped, int done, const RunStatus& status, const RunArgs& ra) {
  if (!stopped.empty()) {
    print_error_line(fmt::format("netsolve: error: unstable: {} (history.csv and summary.json keep increments 0..{})",
                                 stopped, done));
  } else if (!status.ok()) {
    print_error_line(fmt::format("netsolve: {}: {}: {}", ra.allow_unconverged ? "warning (--allow-unconverged)" : "error",
                                 status.status, status.reason()));
  }
  return stopped.empty() ? status.exit_code(ra.allow_unconverged) : exit_code::untrustworthy;
}

}  // namespace netdem::app::netsolve
