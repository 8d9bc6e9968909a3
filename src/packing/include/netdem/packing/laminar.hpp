#pragma once
// Homogeneity measures of 3D packings (the green-body route of Ivannikov et al., section 4.1,
// Eq 48 and Fig 10; docs/packing.md "The green-body route"):
//   * laminar_density: the box cut into equal laminae along x, y or z; the relative density of a
//     lamina is the exact volume of the sphere segments inside it over the lamina's volume (Eq 48);
//   * sampled_density: the solid fraction of a sub-box (e.g. the bulk away from the walls) on a
//     regular lattice of points, each point counted once however many spheres hold it;
//   * overlap_stats: the overlaps of touching spheres and of spheres with the box faces;
//   * bounding_box: the tight box of the spheres.
// Geometry only (no solver). Any length unit.
#include <cstddef>
#include <vector>

#include "netdem/packing/packing.hpp"

namespace netdem::packing {

/// Volume of the part of a sphere of radius r, centre c (along one axis), between the planes a and
/// b (a <= b): F(clamp(b - c)) - F(clamp(a - c)) with the spherical-cap integral
/// F(t) = pi (r^2 t - t^3 / 3) + 2/3 pi r^3 for t in [-r, r] (F(-r) = 0, F(r) = 4/3 pi r^3).
double sphere_slab_volume(double c, double r, double a, double b);

/// Eq 48 along one axis: laminae [lo_s, hi_s) of equal width over the box extent L along `axis`
/// (0 = x, 1 = y, 2 = z), their number the nearest whole number to L / q_s (at least 1), so the
/// width is L / count (the requested q_s to within half a lamina over L). density_s = sum over
/// the spheres of sphere_slab_volume(...) over the lamina / (width x the box's cross-section).
/// The parts of spheres poking through the box faces parallel to the axis (wall overlaps) are
/// counted in the laminae they cross; the parts beyond the two faces normal to the axis are in no
/// lamina.
struct LaminarProfile {
  int axis = 0;
  double width = 0.0;               ///< lamina width (L / count)
  std::vector<double> lo, hi;       ///< lamina bounds along the axis
  std::vector<double> density;      ///< Eq 48
  /// min / max / mean of the density over the laminae lying entirely at least `margin` from both
  /// box faces normal to the axis (the interior); count = 0 if there is none.
  struct Range {
    std::size_t count = 0;
    double min = 0.0, max = 0.0, mean = 0.0;
  };
  Range interior(double box_lo, double box_hi, double margin) const;
};
/// Throws std::invalid_argument (one line): dim != 3, axis not 0..2, q_s not finite and > 0, a
/// box extent that is not positive, more than 10^6 laminae.
LaminarProfile laminar_density(const Packing& p, int axis, double q_s);

/// Solid fraction of `region` (3D, inside or overlapping the box) sampled on the lattice of cell
/// centres with n_a = ceil(L_a / spacing) cells per axis: the fraction of the points inside at
/// least one sphere (|x - c| <= r). Exact for the lattice; against the continuum it errs by the
/// lattice resolution: one sphere of radius r at spacing h errs by about 1e-3 relative at
/// h = r / 12 and 1e-4 at h = r / 50 for a generic centre, up to 0.5 % at h = r / 25 for a centre
/// on a symmetry point of the lattice (resonance); a packing's many centres average it. Throws std::invalid_argument (one line):
/// dim != 3, region not finite with positive extents, spacing not finite and > 0, more than 2e8
/// points.
double sampled_density(const Packing& p, const Box& region, double spacing);

/// Overlaps of a 3D packing. Pairs: the overlap d = r_i + r_j - |x_i - x_j| > 0 of every touching
/// pair relative to the pair's mean radius (r_i + r_j) / 2; walls: d = r - (distance of the centre
/// to a box face) > 0 relative to r, for all six faces.
struct OverlapStats {
  std::size_t pairs = 0;          ///< touching pairs (d > 0)
  double pair_mean = 0.0;         ///< mean d / r_pair over the touching pairs (0 if none)
  double pair_max = 0.0;          ///< max d / r_pair
  std::size_t wall_contacts = 0;  ///< sphere-face contacts (d > 0)
  double wall_mean = 0.0, wall_max = 0.0;
  double coordination = 0.0;      ///< 2 pairs / N (walls excluded)
  double lens_volume = 0.0;       ///< sum of the pairs' lens volumes (counted twice in sum 4/3 pi r^3)
};
OverlapStats overlap_stats(const Packing& p);

/// The tight axis-aligned box of the spheres [min(c - r), max(c + r)] along each axis (3D).
Box bounding_box(const Packing& p);

}  // namespace netdem::packing
