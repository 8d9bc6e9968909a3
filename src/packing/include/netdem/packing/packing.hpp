#pragma once
// Packing data types for 2D disk (cylinder, unit depth) aggregates and the geometric queries the
// solvers need: touching pairs, contact statistics, the peripheral layer (Redanz & Fleck, Acta
// Mater. 49 (2001) 4325, sections 2.2 and 2.4) and a validity check.
//
// Gravity points along -y; the container is the axis-aligned box `Packing::box` with a floor at
// y_min, side walls at x_min / x_max and an open lid at y_max (disks must nevertheless lie inside
// the box). Lengths are in units of the reference radius R used to build the packing.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace netdem::packing {

struct Box {
  double x_min = 0, y_min = 0, x_max = 0, y_max = 0;
  double width() const { return x_max - x_min; }
  double height() const { return y_max - y_min; }
  double area() const { return width() * height(); }
};

/// Structure of arrays, one entry per disk (2D, unit depth).
struct Packing {
  std::vector<double> x, y, r;
  Box box;
  std::uint64_t seed = 0;              ///< 0 if unknown (hand-made file)
  std::vector<std::string> comments;  ///< extra '# ...' lines carried through I/O (without the '# ')

  std::size_t size() const { return x.size(); }
  double solid_area() const;  ///< sum pi r^2
  double density() const;     ///< solid_area / box.area() (relative density D, section 2.2)
};

struct ContactStats {
  std::size_t particles = 0;      ///< N (nodes of the contact network)
  std::size_t disk_contacts = 0;  ///< disk-disk contacts (elements of the network)
  std::size_t wall_contacts = 0;  ///< disk-wall contacts: left, right and bottom walls (not the lid)
  double density = 0;             ///< relative density D = solid_area / box area
  double coordination = 0;        ///< Z = 2 * disk_contacts / particles (walls excluded)
};

/// Pairs (i < j, sorted) with |x_i - x_j| <= (r_i + r_j) * (1 + tol). Cell list, not all pairs.
std::vector<std::pair<int, int>> touching_pairs(const Packing& p, double tol = 1e-6);

/// Disk contacts as touching_pairs(); wall contacts: a disk within tol * r of the left, right or
/// bottom wall counts once per wall it touches.
ContactStats contact_stats(const Packing& p, double tol = 1e-6);

/// Peripheral layer for the die-compaction boundary conditions (section 2.4): flag 1 for disks
/// within tol * r of the left, right or bottom wall or of y_max, and for the free top surface
/// ("skyline": a disk is in the top layer if, for some x in its horizontal extent, its upper
/// surface is the highest disk surface at that x). Exact: the upper envelope of the half-circles is
/// evaluated on the breakpoints where it may change owner, not sampled.
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

/// Throws std::invalid_argument with ONE line naming the first problem found: box with NaN/inf or
/// non-positive size, x/y/r size mismatch, empty packing, then per disk in id order NaN/inf
/// coordinate or radius, r <= 0, disk outside the box (its CENTRE outside the box by more than
/// 1e-9 r), then r_max / r_min > kMaxRadiusRatio, and finally pairs closer than max(r_i, r_j)
/// (find_close_pair(); "disk j duplicates disk i" for centres closer than 1e-12 (r_i + r_j)).
/// Disks overlapping each other by less than that, or poking through a wall by less than their
/// radius, are allowed: compacted packings (section 2.4, affine boundary motion) do both.
/// Deposited packings lie entirely inside the box.
void validate(const Packing& p);

}  // namespace netdem::packing
