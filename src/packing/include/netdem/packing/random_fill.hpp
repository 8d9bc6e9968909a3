#pragma once
// Random sequential placement of disks without overlap ("random fill"), the starting sample of
// the DEM (demsolve prepare / sinter, bench_dem), and the toolkit's one uniform draw.
#include <cstddef>
#include <cstdint>
#include <random>
#include <span>

#include "netdem/packing/packing.hpp"

namespace netdem::packing {

/// Uniform in [0, 1) from one 64-bit output u of the generator: (u >> 11) 2^-53. Platform
/// independent (std::uniform_real_distribution is not); every random draw of the toolkit.
inline double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Places the disks of `radii` one by one, in the given order, inside `box`: each attempt draws
/// x = x_min + r + (W - 2 r) U, then y = y_min + r + (H - 2 r) U (uniform01), and the disk is kept
/// at the first attempt whose distance to every disk placed before is at least r + r_k
/// (std::hypot; touching is allowed). The returned packing holds the disks in `radii` order, with
/// box = `box` and seed 0. Throws std::invalid_argument for a box without positive finite size or
/// a radius that is not finite and > 0 or does not fit; std::runtime_error with one line
/// ("could not place disk i ...") if a disk has no free position after max_attempts attempts.
Packing random_fill(std::span<const double> radii, const Box& box, std::mt19937_64& rng,
                    long max_attempts = 100000);

/// A random cloud of spheres (3D; the first phase of the green-body route of Ivannikov et al.,
/// section 3.2, Yade's makeCloud): n spheres with radii uniform in mean_radius (1 +- dispersion),
/// placed without overlap inside `box` (3D).
struct RandomFill3dOptions {
  std::size_t n = 805;
  double mean_radius = 25e-6;  ///< any length unit (the green-body route uses metres)
  double dispersion = 0.1;     ///< radii uniform in mean_radius [1 - dispersion, 1 + dispersion], in [0, 1)
  Box box{0, 0, 0, 0, 0, 0};  ///< x_min, y_min, x_max, y_max, z_min, z_max
  std::uint64_t seed = 1;
  long max_attempts = 100000;  ///< per sphere
  /// Throws std::invalid_argument with one line: n == 0 or above 10^7, a non-finite or
  /// non-positive radius, dispersion outside [0, 1), a box that is not finite with positive
  /// extents, a sphere of the largest radius that does not fit, a cloud whose solid volume
  /// (expected, from the mean of r^3) exceeds kMaxCloudFraction of the box, max_attempts < 1.
  void validate() const;
};

/// Largest solid fraction a random cloud is asked to hold: random sequential addition of spheres
/// jams near 0.38 (monosized), and attempts per sphere grow steeply well before it.
inline constexpr double kMaxCloudFraction = 0.30;

/// Draws all radii first (r_i = mean (1 + dispersion (2U - 1)), U = uniform01, in index order),
/// then places sphere i = 0, 1, ... at x = x_min + r + (W - 2r) U, then y, then z likewise, at the
/// first attempt whose distance to every sphere placed before is at least r + r_k. dim = 3,
/// box = options.box, seed = options.seed; deterministic for the options. Throws
/// std::invalid_argument (validate()) or std::runtime_error with one line ("could not place
/// sphere i ... in N attempts: the box is too full ...").
Packing random_fill_3d(const RandomFill3dOptions& options);

}  // namespace netdem::packing
