#pragma once
// Random sequential placement of disks without overlap ("random fill"), the starting sample of
// the DEM (demsolve prepare / sinter, bench_dem), and the toolkit's one uniform draw.
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

}  // namespace netdem::packing
