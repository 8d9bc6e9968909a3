#pragma once
// Compaction driver: strain paths and the increment loop to a target density or strain
// (Redanz & Fleck 2001 section 2.4: hydrostatic E11 = E22, E12 = 0; closed die E22 < 0, E11 = E12 = 0).
#include <functional>
#include <string>

#include <Eigen/Core>

#include "netdem/quasistatic/network_solver.hpp"

namespace netdem::qs {

/// A proportional strain-rate direction (E11, E22, E12); its magnitude is irrelevant.
struct StrainPath {
  std::string name = "hydrostatic";
  double E11 = -1.0, E22 = -1.0, E12 = 0.0;
  Eigen::Matrix2d rate() const;
  static StrainPath hydrostatic();
  static StrainPath closed_die();
  /// "hydrostatic", "closed-die" or "E11,E22,E12"; throws std::invalid_argument (one line).
  static StrainPath parse(const std::string& text);
};

struct CompactionOptions {
  StrainPath path;
  double target_density = 0.85;
  /// If > 0: run to this equivalent strain |E| = sqrt(E:E) = sqrt(E11^2 + E22^2 + 2 E12^2) along
  /// `path` instead of to target_density (which is then ignored). Any direction, also one that
  /// keeps the volume (pure shear 1,-1,0) or dilates; in [kMinTargetStrain, kMaxTargetStrain], and
  /// a compacting path must end below density 1.
  double target_strain = 0.0;
  static constexpr double kMinTargetStrain = 1e-9, kMaxTargetStrain = 1.0;
  int increments = 100;  ///< increments from the initial state to the target (equal strain steps)
  /// If > 0: a hydrostatic precompaction first (leg 0), from the initial density to this density
  /// in precompact_increments equal increments; then `path` (leg 1) from there to target_density
  /// or target_strain in `increments` increments. Must lie in (initial density, 1).
  double precompact_density = 0.0;
  int precompact_increments = 20;
  bool precompacts() const { return precompact_density != 0.0; }
  /// Throws std::invalid_argument (one line). With a precompaction, the path's target is checked
  /// from the precompaction density.
  void validate(double initial_density) const;
  /// The strain of each increment of the path (leg 1) from a state of density `initial_density`.
  Eigen::Matrix2d increment_strain(double initial_density) const;
  /// The hydrostatic precompaction leg alone (to precompact_density in precompact_increments).
  CompactionOptions precompaction() const;

 private:
  /// The checks of the path's target from `density`, a start called `from` in the messages.
  void validate_path(double density, const char* from) const;
};

struct CompactionRow {
  int increment = 0;  ///< counted through both legs
  int leg = 1;        ///< 0: the precompaction (and the initial row of a run that precompacts), 1: the path
  StateMeasures state;
  IncrementReport report;
};

/// Runs the compaction (the precompaction first, if any); calls on_row for the initial state
/// (increment 0) and after each increment, numbered through both legs.
void run_compaction(NetworkSolver& solver, const CompactionOptions& options,
                    const std::function<void(const CompactionRow&)>& on_row);

}  // namespace netdem::qs
