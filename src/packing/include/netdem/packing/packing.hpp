#pragma once
// Packing data types for 2D disk (cylinder, unit depth) aggregates and the geometric queries the
// solvers need: touching pairs, contact statistics, the peripheral layer (Redanz & Fleck, Acta
// Mater. 49 (2001) 4325, sections 2.2 and 2.4) and a validity check.
//
// Gravity points along -y; the container is the axis-aligned box `Packing::box` with a floor at
// y_min, side walls at x_min / x_max and an open lid at y_max (disks must nevertheless lie inside
// the box). Lengths are in units of the reference radius R used to build the packing.
//
// 3D (issue 16, `Packing::dim == 3`): spheres with centres (x, y, z), gravity along -z, the box
// [x_min, x_max] x [y_min, y_max] x [z_min, z_max] with the floor at z_min and the lid at z_max;
// `z` is empty and box.z_min = z_max = 0 in 2D. validate(), touching_pairs(), contact_stats() and
// find_close_pair() work in both dimensions; peripheral_layer() is 2D only (throws in 3D).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace netdem::packing {

struct Box {
  double x_min = 0, y_min = 0, x_max = 0, y_max = 0;
  double z_min = 0, z_max = 0;  ///< 3D only (both 0 in 2D)
  double width() const { return x_max - x_min; }
  double height() const { return y_max - y_min; }
  double depth() const { return z_max - z_min; }  ///< 3D: the extent along z (gravity axis)
  double area() const { return width() * height(); }  ///< the 2D box area (x-y)
  double volume() const { return width() * height() * depth(); }  ///< the 3D box volume
};

/// Structure of arrays, one entry per disk (2D, unit depth) or sphere (3D).
struct Packing {
  std::vector<double> x, y, r;
  std::vector<double> z;  ///< 3D only: empty in 2D, size() entries in 3D
  int dim = 2;            ///< 2 (disks, x y r) or 3 (spheres, x y z r)
  Box box;
  std::uint64_t seed = 0;              ///< 0 if unknown (hand-made file)
  std::vector<std::string> comments;  ///< extra '# ...' lines carried through I/O (without the '# ')
  /// Periodic in every axis (issue 29; file line '# periodic'): the box is the cell, or `cell` is.
  bool periodic = false;
  /// '# cell' (periodic only): D x D numbers, cell vector a at [D a, D a + D), lower corner at the
  /// box's lower corner, the box the cell's bounding box; empty: the box's edges (periodic.hpp).
  std::vector<double> cell;

  std::size_t size() const { return x.size(); }
  double solid_area() const;    ///< sum pi r^2 (the 2D solid area, whatever dim)
  double solid_volume() const;  ///< sum 4/3 pi r^3 (spheres)
  double solid_measure() const { return dim == 3 ? solid_volume() : solid_area(); }
  double box_measure() const { return dim == 3 ? box.volume() : box.area(); }
  /// Relative density D: 2D solid_area / box.area() (section 2.2), 3D solid_volume / box.volume();
  /// a periodic packing: over the cell's area or volume.
  double density() const;
};

struct ContactStats {
  std::size_t particles = 0;      ///< N (nodes of the contact network)
  std::size_t disk_contacts = 0;  ///< disk-disk contacts (elements of the network)
  std::size_t wall_contacts = 0;  ///< disk-wall contacts: left, right and bottom walls (not the lid)
  double density = 0;             ///< relative density D = Packing::density() (3D: by volume)
  double coordination = 0;        ///< Z = 2 * disk_contacts / particles (walls excluded)
};

/// Pairs (i < j, sorted) with |x_i - x_j| <= (r_i + r_j) * (1 + tol). Cell list, not all pairs.
/// 3D: the distance of the centres (x, y, z). A periodic packing: through the nearest image.
std::vector<std::pair<int, int>> touching_pairs(const Packing& p, double tol = 1e-6);

/// 3D packings periodic in x and y (ballistic_deposition_3d with Lateral::Periodic): the same
/// with minimum-image distances across the x and y period of the box (a pair counts once).
/// Needs dim == 3 and a box at least 4 r_max (1 + tol) wide in x and y, so that a pair touches
/// in at most one image (throws std::invalid_argument otherwise).
std::vector<std::pair<int, int>> touching_pairs_periodic_xy(const Packing& p, double tol = 1e-6);

/// Disk contacts as touching_pairs(); wall contacts: a disk within tol * r of the left, right or
/// bottom wall counts once per wall it touches. 3D: the four side walls x_min, x_max, y_min,
/// y_max and the floor z_min (not the lid z_max); `periodic_xy` (3D only): the contacts of
/// touching_pairs_periodic_xy() and only the floor as a wall. A periodic packing has no walls.
ContactStats contact_stats(const Packing& p, double tol = 1e-6, bool periodic_xy = false);

/// Peripheral layer for the die-compaction boundary conditions (section 2.4): flag 1 for disks
/// within tol * r of the left, right or bottom wall or of y_max, and for the free top surface
/// ("skyline": a disk is in the top layer if, for some x in its horizontal extent, its upper
/// surface is the highest disk surface at that x). Exact: the upper envelope of the half-circles is
/// evaluated on the breakpoints where it may change owner, not sampled. 2D only: a 3D packing
/// throws std::invalid_argument (not implemented yet, issue 16).
std::vector<std::uint8_t> peripheral_layer(const Packing& p, double tol = 1e-6);

/// Largest radius ratio r_max / r_min a packing may have (validate(), the reader).
inline constexpr double kMaxRadiusRatio = 100.0;

/// A pair of disks whose centres are closer than max(r_i, r_j): r_i >= r_j, `distance` = |x_i - x_j|,
/// `duplicate` if distance <= 1e-12 (r_i + r_j) (the same centre up to rounding).
struct ClosePair {
  std::size_t i = 0, j = 0;
  double distance = 0;
  bool duplicate = false;
};

/// The first pair (scanning the disks i in order, each against the disks j no larger than it,
/// ties by j < i, the smallest such j) whose centre distance is below max(r_i, r_j), or none.
/// Cell grid (cells >= r_min), O(N) for packings whose disks do not overlap that much; a set of
/// 10^5 near-duplicates is rejected after two scans of its cell. Needs finite coordinates and
/// finite positive radii (validate() checks those first).
std::optional<ClosePair> find_close_pair(const Packing& p);

/// Throws std::invalid_argument with ONE line naming the first problem found: dim not 2 or 3, box
/// with NaN/inf or non-positive size (3D: also along z), x/y/r (3D: z) size mismatch (2D: z must
/// be empty), empty packing, then per disk in id order NaN/inf
/// coordinate or radius, r <= 0, disk outside the box (its CENTRE outside the box by more than
/// 1e-9 r), then r_max / r_min > kMaxRadiusRatio, and finally pairs closer than max(r_i, r_j)
/// (find_close_pair(); "disk j duplicates disk i" for centres closer than 1e-12 (r_i + r_j)).
/// Disks overlapping each other by less than that, or poking through a wall by less than their
/// radius, are allowed: compacted packings (section 2.4, affine boundary motion) do both.
/// Deposited packings lie entirely inside the box. A periodic packing (issue 29): `cell` holds 0 or
/// D x D finite numbers spanning a cell whose bounding box is the box (1e-9 relative), every centre
/// lies in the cell (0 <= s < 1, 1e-9 tolerance), the cell is at least 4 r_max wide across every
/// axis, and the close-pair check also runs through the images.
void validate(const Packing& p);

}  // namespace netdem::packing
