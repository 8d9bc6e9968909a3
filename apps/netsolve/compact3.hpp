#pragma once
// What `netsolve compact --dim 3` (compact3.cpp) and `netsolve yield --dim 3` (yield3.cpp) share:
// the Voigt components, the .vtp snapshots of a sphere network, the rows of history.csv and the
// summary.json description of a state.
#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "compact_common.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/strain_path.hpp"
#include "output.hpp"
#include "status.hpp"

namespace netdem::app::netsolve {

/// The Voigt components of a symmetric 3x3 tensor (E11, E22, E33, E23, E13, E12 order).
sys::Voigt<3> voigt(const Eigen::Matrix3d& m);

/// {"11": m11, ..., "12": m12} / scale, each key prefixed.
nlohmann::json voigt_json(const Eigen::Matrix3d& m, const char* prefix, double scale = 1.0);

/// particles_TAG.vtp, contacts_TAG.vtp and (periodic) cell_TAG.vtp, listed in `series` at the
/// density of the state: the 3D counterpart of compact.cpp's snapshot.
void write_snapshot_3d(const qs::NetworkSolver3& s, SnapshotSeries& series, const std::string& tag, double density);

/// Sphere centres outside the initial box (die mode: the peripheral layer alone holds the box).
int centres_outside_3d(const qs::NetworkSolver3& s, const packing::Box& box);

/// summary.json's description of the state `m`: D, the stresses / sigma_y, Z, the counts.
nlohmann::json state_json(const qs::StressMeasuresT<3>& m, double sy);

/// The rows of a 3D run: history.csv, the tally, the snapshots, the progress, each leg's last row
/// (compact --dim 3 and the precompaction of yield --dim 3).
struct Compact3Rows {
  Compact3Rows(const qs::NetworkSolver3& s, SnapshotSeries& snapshot_series, std::vector<double> snapshots,
               const qs::SolverOptions& so, const qs::CompactionOptions3& co, bool quiet);
  /// One row: history.csv, the tally, the density snapshots, the progress and the stop rule.
  void add(const qs::CompactionRowT<3>& row);

  const qs::NetworkSolver3& solver;
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
  qs::StressMeasuresT<3> last;
  ResidualGrowth growth;
  std::array<qs::CompactionRowT<3>, 2> leg_end;
  std::array<bool, 2> reached{false, false};
};

}  // namespace netdem::app::netsolve
