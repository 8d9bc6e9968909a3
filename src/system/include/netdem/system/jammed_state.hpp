#pragma once
// The jammed state (issue 28 item 6): the one state both solvers start from and write, so that
// "the same jammed packing" is the same state in the network solver and in the DEM, histories
// included. A document of the state archive (archive.hpp; kind "jammed", version 1; format in
// docs/quasistatic.md "Jammed state"): the particles (centres, rotations, radii), the current box
// and whether its faces are contact walls, the accumulated strain, the plastic-indentation law and
// the walls' friction, and the law's committed histories (u_max, the tangential spring f_t, the
// sliding flag) of every particle pair and wall contact that has one (law.has_history).
//
// It holds nothing a solver keeps for itself (velocities, time step, Newton predictor, neighbour
// lists): a solver that starts from it builds its own tables and evaluates its forces from these
// histories at these positions, at rest. Both solvers' conversions live with them
// (netdem/dynamic/jammed.hpp, netdem/quasistatic/jammed.hpp); this file knows no solver.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::sys {

inline constexpr int kJammedStateVersion = 1;

template <int D>
struct JammedStateT {
  using History = contact::PlasticIndentationHistoryT<D>;
  using Mat = Eigen::Matrix<double, D, D>;
  static constexpr int kWalls = 2 * D;  ///< wall 2a at the minimum of axis a, 2a + 1 at its maximum

  ParticleSet<D> particles;  ///< centres, rotations (2D: the angle; 3D: a rotation vector), radii
  packing::Box box;          ///< the current box
  bool walls = false;        ///< its faces are contact walls (flats, R* = r, friction wall_mu)
  Mat strain = Mat::Zero();  ///< the macroscopic strain accumulated so far (tension positive)
  std::uint64_t seed = 0;    ///< the packing's seed (0 if unknown)
  contact::PlasticIndentationParams law;
  double wall_mu = 0.0;
  std::vector<int> pair_i, pair_j;  ///< i < j < N, sorted by (i, j)
  std::vector<History> pair_history;
  std::vector<int> wall_particle, wall_side;  ///< sorted by (particle, side); side < kWalls
  std::vector<History> wall_history;

  /// The overlap of pair k (r_i + r_j - |x_j - x_i|) and of wall contact k (r_p - the distance
  /// of the centre from the face).
  double pair_overlap(std::size_t k) const;
  double wall_overlap(std::size_t k) const;
  /// The centres and radii in the box, as a packing (its seed; no rotations, no histories).
  packing::Packing packing() const;
  /// Sizes, ranges, order, the packing (packing::validate on the centres, radii and box) and the
  /// histories against the geometry: a history can be impossible (a tangential spring or a
  /// sliding flag on a contact the law says carries no normal force; u_max below the current
  /// overlap; a wall contact without walls). Throws std::invalid_argument (one line, naming the
  /// contact and its particles).
  void validate() const;
};

/// "" if the two laws are the same law (their dashpots aside: each solver keeps its own), else
/// what differs ("friction mu 0.1 vs inf, ..."): a state's histories belong to its law.
std::string law_difference(const contact::PlasticIndentationParams& state, const contact::PlasticIndentationParams& run);

/// The text of a jammed state (one JSON line); validates first.
template <int D>
std::string format_jammed_state(const JammedStateT<D>& s);
/// The dimension of the jammed state in `text` (its header and "dim" checked); throws
/// std::invalid_argument "name: /pointer: problem".
int jammed_state_dim(std::string_view text, const std::string& name);
/// Parses and validates a jammed state of dimension D; every refusal is one line
/// "name: /json/pointer: problem" (std::invalid_argument).
template <int D>
JammedStateT<D> parse_jammed_state(std::string_view text, const std::string& name);
/// parse_jammed_state of the file `path` (a missing file or a folder: one line).
template <int D>
JammedStateT<D> read_jammed_state(const std::string& path);
/// Writes the state atomically (temporary file + rename); std::runtime_error naming the file.
template <int D>
void write_jammed_state(const JammedStateT<D>& s, const std::string& path);

}  // namespace netdem::sys
