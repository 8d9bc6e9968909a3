#pragma once
// netsolve compact: the network solver's compaction of a packing or a jammed state along a strain
// path to a density or an equivalent strain, optionally after a hydrostatic precompaction
// (--precompact-density; issue 29), with its files (README.md "netsolve", docs/quasistatic.md).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "netdem/quasistatic/solver_options.hpp"
#include "netdem/system/jammed_state.hpp"
#include "output.hpp"
#include "setup.hpp"

namespace netdem::app::netsolve {

/// The jammed state of --state (none if `state_file` is empty), checked against the options: it
/// excludes a packing file, is of dimension D, has walls exactly when `so.mode` is walls, and has
/// the options' contact law. UsageError (one line, naming `command` and its option
/// `walls_option`) otherwise.
template <int D = 2>
std::optional<sys::JammedStateT<D>> jammed_input(const std::string& state_file, const std::string& packing_file,
                                                 const qs::SolverOptions& so, const char* command,
                                                 const char* walls_option);

/// The default of --factor-reuse with --dim 3: the kept factor solves up to 20 fresh tangents in a
/// row by GMRES (measured, periodic sticking hydrostatic compaction: 1.4x faster at 2000 spheres,
/// 3x at 10^4; docs/performance.md "Issue 30, part 3"). 2D keeps a factorisation per tangent.
inline constexpr int kFactorReuse3d = 20;

/// Options of every run that writes a folder.
struct RunArgs {
  bool overwrite = false, allow_unconverged = false;
};

inline RunDirOptions run_dir_options(const RunArgs& r, const std::string& input = "") {
  RunDirOptions o;
  o.overwrite = r.overwrite;
  if (!input.empty()) o.inputs.emplace_back(input);
  return o;
}

// The defaults of `compact` are the library preset qs::SolverOptions::compact()
// (solver_options.hpp; why each value: docs/quasistatic.md "Presets").
struct CompactArgs {
  bool affine = false, no_rotation = false, quiet = false, verbose = false, save_state = false;
  std::string path = "hydrostatic", packing_file, boundary = "layer";
  std::string state_file;  ///< a jammed state to start from (netdem/system/jammed_state.hpp)
  std::vector<double> snapshots = {0.82, 0.84, 0.85};  ///< densities, a set: sorted before use
  double to_density = 0.85, to_strain = 0.0;  // to_strain > 0: run to |E| = to_strain instead
  int increments = 100;
  /// > 0: a hydrostatic precompaction to this density first (history.csv column `leg`)
  double precompact_density = 0.0;
  int precompact_increments = 20;
  qs::SolverOptions solver = qs::SolverOptions::compact();  // bound directly by the command line
  /// --factor-reuse; -1 (not given): kFactorReuse3d with --dim 3, the preset's 0 in 2D
  int factor_reuse = -1;
  /// --preconditioner: auto, full or translations (qs::IterationOptions::Preconditioner)
  std::string preconditioner = "auto";
  LawArgs law = law_args(solver);
};

/// The options of `compact` that its checks after parsing look at.
struct CompactCli {
  CLI::Option* packing = nullptr;
  CLI::Option* density = nullptr;
  CLI::Option* strain = nullptr;
  CLI::Option* precompact_density = nullptr;
  CLI::Option* precompact_increments = nullptr;
};

/// Binds the options of `compact` but the deposition's (--width, --seed, ..., --overwrite, which
/// main shares with `pack`) to `ca`, `ra` and `out`.
CompactCli add_compact_options(CLI::App* comp, CompactArgs& ca, RunArgs& ra, std::string& out);

/// The checks of the parsed options (UsageError, one line), then the run; its exit status.
int run_compact_cli(const CompactCli& cli, const PackArgs& pa, const CompactArgs& ca, const RunArgs& ra,
                    const std::string& command, const std::filesystem::path& out);

}  // namespace netdem::app::netsolve
