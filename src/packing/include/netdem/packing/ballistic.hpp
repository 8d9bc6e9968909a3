#pragma once
// 2D ballistic deposition with steepest descent (Redanz & Fleck, Acta Mater. 49 (2001) 4325,
// section 2.2): disks are dropped one at a time at a random x into the box [0,W]x[0,H] and follow
// the path of steepest descent (purely geometric, no inertia) until they are in static equilibrium;
// then they are frozen and the next disk is dropped, "until the box has filled".
//
// Motion (exact circle-circle geometry, analytic, not time-stepped). At every stop the contact set
// (disks within 1e-10 relative gap, side walls, floor) is collected and gravity g = (0,-1) is
// projected onto the cone of admissible motions {d : n_c . d >= 0 for every contact normal n_c};
// the result is one of
//   * free fall (g itself admissible; a vertical wall never blocks it, so "sliding down a wall" is
//     a free fall with the wall touching),
//   * rolling over one disk j (the tangent of j pointing downhill), kept until the moving disk hits
//     another disk, a side wall or the floor, or passes j's equator (x = x_j +- (r + r_j), then
//     it falls freely again),
//   * rest (the projection is zero): two supports whose normal cone contains -g, i.e. the centre's x
//     lies between the x of the two support points (disk-disk, or disk and the side wall on the far
//     side), or a floor contact.
// A disk exactly on top of a single disk (|n_x| <= 1e-10, e.g. a monosized disk sliding down a
// wall onto a disk that touches the same wall) is an unstable equilibrium: it rolls off to +x if
// that is admissible, else to -x (away from the wall). A contact with n_y <= 1e-6 (at the
// equator) carries no weight and is passed by falls and rolls (overlap <= 5e-13 (r + r_k)): a
// monosized disk must fall through a gap of exactly one diameter, not bridge it on rounding.
//
// Stop rule ("until the box has filled", our choice, see docs/packing.md): a disk whose resting
// position would put its top above y_max = H is discarded (not added); deposition stops after
// `DepositionOptions::max_rejections` consecutive discards (default 1000: the box is then full to
// within ~0.1% of the count; 1 = stop at the first misfit, which leaves the top under-filled).
// Every accepted disk lies entirely inside the box. The paper's N and D0 count every disk that
// reaches into the box (see docs/packing.md); our D0 is ~0.017 lower because of the loose layer
// below the lid.
//
// Box: [0, width R] x [0, box_height() R]; the returned disks are in deposition order, so disk i
// rests on disks with smaller ids (and walls / floor).
//
// Random draws (std::mt19937_64 seeded with `seed`, one 64-bit output u per draw, converted to
// [0,1) by (u >> 11) * 2^-53; platform independent): per dropped disk, first the radius
// r = R (r_min + (r_max - r_min) U) (no draw if r_min == r_max), then the drop abscissa
// x = r + (W - 2r) U.
#include <cstddef>
#include <cstdint>
#include <utility>

#include "netdem/packing/packing.hpp"

namespace netdem::packing {

/// Which disks count as inside the box (the stop rule's fit test). Inside: the whole disk is
/// below the lid. Centre: the centre is below the lid, so the top layer may stick out by less
/// than a radius; its density is then close to the bulk and to the paper's D0 (docs/packing.md).
enum class Lid { Inside, Centre };

struct DepositionOptions {
  double width = 80.0;   ///< box width W in units of the reference radius R
  double height = -1.0;  ///< box height; < 0 means square (= width)
  double radius = 1.0;   ///< reference radius R
  double r_min = 0.9, r_max = 1.1;  ///< radii uniform in [r_min, r_max] * R; equal -> monosized
  std::uint64_t seed = 1;
  /// Stop after this many consecutive disks that do not fit below y_max (>= 1). [extension]
  std::size_t max_rejections = 1000;
  Lid lid = Lid::Inside;  ///< fit test of the stop rule [extension]

  double box_height() const { return height < 0 ? width : height; }
  /// Throws std::invalid_argument with a one-line message: NaN/inf, radius <= 0, r_min <= 0,
  /// r_min > r_max, width or height < 2 r_max R, max_rejections == 0.
  void validate() const;
};

/// Ballistic deposition into [0,W]x[0,H] (section 2.2). Deterministic for a given options set.
/// The returned packing has box = {0, 0, W, H} and seed = options.seed.
Packing ballistic_deposition(const DepositionOptions& options);

/// [extension] Resting centre (x, y) of ONE disk of radius r dropped at abscissa x0 onto `base`,
/// by the same rules as ballistic_deposition(): the base disks are fixed obstacles (they need not
/// be stable themselves), box.y_min is the floor, box.x_min / x_max are the walls, the lid is
/// ignored. For analytic checks and for building packings by hand. O(N) set-up per call.
/// Throws std::invalid_argument if r <= 0, x0 is not in [x_min + r, x_max - r], the box is not
/// finite with positive size, or a base disk is not finite with r > 0.
std::pair<double, double> drop_disk(const Packing& base, double x0, double r);

}  // namespace netdem::packing
