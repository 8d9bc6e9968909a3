#pragma once
// Compaction driver: strain paths and the increment loop to a target density or strain
// (Redanz & Fleck 2001 section 2.4: hydrostatic E11 = E22, E12 = 0; closed die E22 < 0, E11 = E12 = 0),
// in both dimensions (issue 30: 3D, closed die along z, any six-component direction).
#include <functional>
#include <string>
#include <type_traits>

#include <Eigen/Core>

#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/strain_path.hpp"

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

/// The 3D direction (Voigt order E11, E22, E33, E23, E13, E12; closed die along z).
struct StrainPath3 {
  std::string name = "hydrostatic";
  sys::Voigt<3> E{-1.0, -1.0, -1.0, 0.0, 0.0, 0.0};
  Eigen::Matrix3d rate() const;
  static StrainPath3 hydrostatic();
  /// "hydrostatic", "closed-die" or "E11,E22,E33[,E23,E13,E12]"; throws (one line).
  static StrainPath3 parse(const std::string& text);
};

template <int D>
using StrainPathOf = std::conditional_t<D == 2, StrainPath, StrainPath3>;

/// What a compaction row measures: the 2D StateMeasures (with the Figs 7-8 deviations), the
/// stresses of StressMeasuresT in 3D.
template <int D>
using CompactionMeasuresOf = std::conditional_t<D == 2, StateMeasures, StressMeasuresT<3>>;

template <int D>
struct CompactionOptionsT {
  using Mat = Eigen::Matrix<double, D, D>;
  StrainPathOf<D> path;
  double target_density = 0.85;
  /// If > 0: run to this equivalent strain |E| = sqrt(E:E) (2D: sqrt(E11^2 + E22^2 + 2 E12^2)) along
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
  Mat increment_strain(double initial_density) const;
  /// The hydrostatic precompaction leg alone (to precompact_density in precompact_increments).
  CompactionOptionsT precompaction() const;

 private:
  /// The checks of the path's target from `density`, a start called `from` in the messages.
  void validate_path(double density, const char* from) const;
};
using CompactionOptions = CompactionOptionsT<2>;
using CompactionOptions3 = CompactionOptionsT<3>;

template <int D>
struct CompactionRowT {
  int increment = 0;  ///< counted through both legs
  int leg = 1;        ///< 0: the precompaction (and the initial row of a run that precompacts), 1: the path
  CompactionMeasuresOf<D> state;
  IncrementReport report;
};
using CompactionRow = CompactionRowT<2>;

/// Runs the compaction (the precompaction first, if any); calls on_row for the initial state
/// (increment 0) and after each increment, numbered through both legs.
/// (on_row's type is not deduced: a lambda converts to it.)
template <int D>
void run_compaction(NetworkSolverT<D>& solver, const CompactionOptionsT<D>& options,
                    const std::type_identity_t<std::function<void(const CompactionRowT<D>&)>>& on_row);

extern template struct CompactionOptionsT<2>;
extern template struct CompactionOptionsT<3>;
extern template void run_compaction<2>(NetworkSolverT<2>&, const CompactionOptionsT<2>&,
                                       const std::type_identity_t<std::function<void(const CompactionRowT<2>&)>>&);
extern template void run_compaction<3>(NetworkSolverT<3>&, const CompactionOptionsT<3>&,
                                       const std::type_identity_t<std::function<void(const CompactionRowT<3>&)>>&);

}  // namespace netdem::qs
