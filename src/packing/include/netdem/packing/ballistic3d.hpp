#pragma once
// 3D ballistic deposition with steepest descent (issue 16, the 3D form of ballistic.hpp; rules and
// measurements in docs/packing.md, "3D ballistic deposition"). Spheres with radii uniform in
// [r_min, r_max] R are dropped one at a time at a random (x, y) into the box [0, W] x [0, W] x
// [0, H], gravity along -z, and follow the path of steepest descent (purely geometric, no inertia)
// until they are in static equilibrium; then they are frozen and the next sphere is dropped.
//
// Motion (analytic, not time-stepped). At every stop the contact set (spheres within a relative
// gap of 1e-10, the side walls, the floor) is collected and gravity g = (0, 0, -1) is projected
// onto the cone of admissible motions {d : n_c . d >= 0 for every contact normal n_c} (the
// projection is the small quadratic programme min |d - g| solved by enumerating the active sets
// of size 0..3 and checking the KKT conditions). Its result is one of
//   * free fall (no active contact; a vertical wall never blocks it),
//   * rolling over one sphere j: along the great circle through the top of j (the meridian),
//   * rolling over two supports (two spheres, or a sphere and a side wall): along the circle of
//     the positions touching both,
//   * rest (the projection is zero: -g lies in the cone of the contact normals: a floor contact,
//     three supports whose triangle contains the centre's vertical projection, two supports at the
//     lowest point of their circle, or combinations with side walls).
// Every path is a circle (or a vertical line) and every event along it is a zero of
// a0 + a1 cos t + a2 sin t, solved in closed form: the first touch of another sphere (squared
// distance), of the floor or a wall (a plane), the equator of a single support (its normal turns
// horizontal: the sphere falls off), the lowest point of a two-support circle, and a support's
// lift-off (its KKT multiplier, linear in cos t and sin t because the Gram matrix of the two
// normals is constant on the circle, crosses zero). The sphere then stops exactly there and the
// contact set is re-evaluated. Contact distances hold to rounding (~1e-15 relative).
// A contact with n_z <= 1e-6 carries no weight for a fall (as in 2D); a sphere exactly on top of one
// sphere (|n_xy| <= 1e-9) is an unstable equilibrium and rolls off towards the first admissible
// direction of +x, -x, +y, -y, then the diagonals; a two-support equilibrium above the centre of
// the supports' circle (e.g. three monosized spheres in one wall's plane) is unstable too and rolls
// on along the circle (towards +x first).
//
// Lateral boundary (`Lateral`): Walls (planes x = 0, W and y = 0, W; drops at x, y in
// [r, W - r]) or Periodic in x and y (drops at x, y in [0, W), minimum image: contacts across the
// boundary count; stored centres are wrapped into [0, W)).
//
// Stop rule (as in 2D, Lid::Inside): a sphere whose resting top would be above the lid (z + r > H)
// is discarded; deposition stops after `max_rejections` consecutive discards.
//
// Random draws (std::mt19937_64 seeded with `seed`, U = (u >> 11) * 2^-53, platform independent):
// per dropped sphere the radius r = R (r_min + (r_max - r_min) U) (no draw when r_min == r_max),
// then x, then y (walls: r + (W - 2r) U; periodic: W U). Discarded spheres consume their draws.
#include <array>
#include <cstddef>
#include <cstdint>

#include "netdem/packing/packing.hpp"

namespace netdem::packing {

enum class Lateral { Walls, Periodic };

struct Deposition3dOptions {
  double width = 10.0;   ///< box side W (x and y) in units of the reference radius R
  double height = -1.0;  ///< box height H (z); < 0 means H = W
  double radius = 1.0;   ///< reference radius R
  double r_min = 0.9, r_max = 1.1;  ///< radii uniform in [r_min, r_max] * R; equal -> monosized
  std::uint64_t seed = 1;
  std::size_t max_rejections = 1000;  ///< stop after this many consecutive discards (>= 1)
  Lateral lateral = Lateral::Walls;

  double box_height() const { return height < 0 ? width : height; }
  /// Throws std::invalid_argument with a one-line message: NaN/inf, radius <= 0, r_min <= 0,
  /// r_min > r_max, width or height < 2 r_max (periodic: width < 4 r_max), max_rejections == 0.
  void validate() const;
};

/// Counts of a deposition (how the accepted spheres came to rest), for the documentation and the tests.
struct Deposition3dReport {
  std::size_t floor = 0;          ///< rests with a floor contact
  std::size_t three = 0;          ///< rests with >= 3 active supports (spheres and walls), no floor
  std::size_t two = 0;            ///< rests on two supports (lowest point of their circle)
  std::size_t on_top = 0;         ///< roll-offs from unstable equilibria (on top of one sphere, above a two-support circle)
  std::size_t discarded = 0;      ///< spheres discarded by the stop rule
  std::size_t unresolved = 0;     ///< stops where no active set satisfied the KKT test (taken as rest)
  std::size_t max_steps = 0;      ///< the most motion steps one sphere needed
};

/// Ballistic deposition into [0, W]^2 x [0, H] (dim = 3, box {0, 0, 0, W, W, H}, seed = options.seed;
/// spheres in deposition order). Deterministic for a given options set.
Packing ballistic_deposition_3d(const Deposition3dOptions& options, Deposition3dReport* report = nullptr);

/// Resting centre of ONE sphere of radius r dropped at (x0, y0) onto `base` (a 3D packing: fixed
/// obstacles, box.z_min the floor, the side walls or the x-y period of its box), by the rules of
/// ballistic_deposition_3d(); the lid is ignored. For analytic checks and hand-built packings.
/// Throws std::invalid_argument for a 2D base, r <= 0 or a start outside the box (walls: x0, y0
/// in [min + r, max - r]).
std::array<double, 3> drop_sphere(const Packing& base, double x0, double y0, double r, Lateral lateral);

}  // namespace netdem::packing
