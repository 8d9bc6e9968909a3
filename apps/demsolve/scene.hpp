#pragma once
// demsolve's plastic-indentation scenes (compact, yield): the options of the law, the prescribed
// particles and netsolve's snapshot files.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "netdem/dynamic/compaction.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/packing.hpp"
#include "output.hpp"
#include "setup.hpp"

namespace netdem::app::dem {

using netdem::dem::ContactInfo;
using netdem::dem::DynamicSolver;

/// The 2D measures of the protocols (netdem/dynamic/compaction.hpp).
using Sample = netdem::dem::CompactionSampleT<2>;
using Meter = netdem::dem::CompactionMeterT<2>;

/// netsolve's snapshot files and field names (apps/netsolve/compact.cpp write_snapshot), plus the
/// velocities: particles_<tag>.vtp, contacts_<tag>.vtp (the loaded particle-particle contacts),
/// cell_<tag>.vtp (periodic), in series.dir(), listed in `series` at the density D of the state.
/// 3D: positions x, y, z; the spin vector; the tangential force's magnitude.
template <int D>
void write_compact_snapshot(const netdem::dem::DynamicSolverT<D>& s, SnapshotSeries& series, const std::string& tag,
                            std::vector<ContactInfo>& cs);
/// The series of those snapshots, snapshots.pvd: ParaView's time is the density D (the quantity
/// --snapshots names); parts particles, contacts and (periodic) cell.
SnapshotSeries compact_snapshot_series(const std::filesystem::path& out, bool periodic);


/// The explicit solver's options for the plastic-indentation law on netsolve's scenes (sigma_y = 1,
/// frictionless die walls); damping: both dashpots, fractions of critical damping of the chord.
netdem::dem::DynamicOptions plastic_options(double mu, double k_t, bool reversible, double first_touch, double damping,
                                            double drag, double steps_per_contact);

/// The run folder's door for a run on a packing file or netsolve's deposition: the folder is free
/// (or --overwrite), the deposition's size is within reach; returns the folder options to open it
/// with once every value is checked.
RunDirOptions check_scene_run_dir(const std::filesystem::path& out, bool overwrite, const std::string& packing_file,
                                  const netdem::app::netsolve::PackArgs& pack);

/// The prescribed particles: every one (affine), none (walls) or netsolve's peripheral layer.
std::vector<std::uint32_t> prescribed_particles(const packing::Packing& pk, bool affine, bool walls);

}  // namespace netdem::app::dem
