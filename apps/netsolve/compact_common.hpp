#pragma once
// What `netsolve compact` in 2D (compact.cpp) and in 3D (compact3.cpp, issue 30) share: the solver
// and compaction options of the command line, the tally of the increments' reports and the
// "solver" block of summary.json.
#include <string>

#include <nlohmann/json.hpp>

#include "compact.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/yield_curve.hpp"
#include "status.hpp"

namespace netdem::app::netsolve {

/// The solver options of `compact` (boundary mode, law, the iteration's knobs), checked
/// (std::invalid_argument or UsageError, one line).
qs::SolverOptions compact_solver_options(const CompactArgs& a);

/// The compaction options of `compact` in dimension D (path, target, increments, precompaction);
/// a walls run needs an axis-parallel path.
template <int D>
qs::CompactionOptionsT<D> compact_compaction_options(const CompactArgs& a, const qs::SolverOptions& so);

/// The increments' reports of a run, summed, with the records the run status judges.
struct IncrementTally {
  int unconverged = 0, instabilities = 0, cut_increments = 0, unconverged_substeps = 0, unjammed = 0;
  double max_residual = 0.0, drag_work = 0.0, contact_work = 0.0;
  ConvergenceRecord conv;
  EquilibriumRecord equilibrium;

  /// Accepted increments only need tol; the pseudo-transient iteration accepts no unconverged one.
  IncrementTally(const qs::SolverOptions& so);
  /// One increment (> 0) with the state's equilibrium measures.
  void add(int increment, const qs::IncrementReport& r, double eq13_vs_contacts, double net_force_ratio);
};

/// netsolve compact --dim 3 (compact3.cpp): the sphere network's run and its files; its exit status.
int run_compact_3d(const PackArgs& pa, const CompactArgs& a, const RunArgs& ra, const std::string& command,
                   const std::filesystem::path& out);

/// The probes' solver options of `yield` (2D and 3D): the probe preset (section 3.4's elastic
/// un/reloading) with the precompaction's law, iteration, regularisation and merit; an affine probe
/// of a periodic cell keeps the cell with every centre prescribed (affine_centres). Validated.
qs::SolverOptions yield_probe_options(const qs::SolverOptions& pre, qs::BoundaryMode probe_mode);

/// netsolve yield --dim 3 (yield3.cpp): argv as `netsolve yield ...`; its exit status.
int run_yield3_command(int argc, char** argv);
/// netsolve yield-merge --dim 3 (yield3_merge.cpp): one yield_points.csv and summary.json in
/// `out_dir` from the folders of `netsolve yield --dim 3 --probe i/N` runs; throws
/// std::invalid_argument (one line) for a folder that is not such a run or has another setup.
int run_yield3_merge(const std::vector<std::string>& dirs, const std::string& out_dir, const std::string& command,
                     bool overwrite);

/// summary.json's "solver": the iteration, its knobs, the counts of the tally and the timings' counts.
/// dim: the network's dimension (the preconditioner recorded is the one resolved for it).
nlohmann::json solver_summary(const qs::SolverOptions& so, const qs::SolverTimings& tm, int free_dofs,
                              const IncrementTally& t, int dim);

/// summary.json's "cholmod_inline_openmp" and "timing_s" (the solver's split and the wall time).
void add_run_records(nlohmann::json& j, const qs::SolverTimings& tm, double wall);

/// The end of a row of history.csv: the checkpoint every 20 increments, the progress, the stop rule
/// of a growing residual (throws StopRun) and the activity line.
void end_compact_row(int increment, double newton_residual, int total, const std::string& csv, SnapshotSeries& series,
                     Progress& progress, ResidualGrowth& growth);

/// The run's last line on stderr (a stopped run, or a status that is not ok) and its exit status.
int finish_compact_run(const std::string& stopped, int done, const RunStatus& status, const RunArgs& ra);

}  // namespace netdem::app::netsolve
