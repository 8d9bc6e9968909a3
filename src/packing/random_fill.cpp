// Random sequential placement (netdem/packing/random_fill.hpp).
#include "netdem/packing/random_fill.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "netdem/packing/cell_grid.hpp"

namespace netdem::packing {

Packing random_fill(std::span<const double> radii, const Box& box, std::mt19937_64& rng, long max_attempts) {
  if (!std::isfinite(box.x_min) || !std::isfinite(box.y_min) || !std::isfinite(box.x_max) ||
      !std::isfinite(box.y_max) || !(box.width() > 0) || !(box.height() > 0))
    throw std::invalid_argument("random_fill: the box must be finite with positive size");
  double rmax = 0.0;
  for (std::size_t i = 0; i < radii.size(); ++i) {
    const double r = radii[i];
    if (!std::isfinite(r) || !(r > 0) || 2 * r > box.width() || 2 * r > box.height())
      throw std::invalid_argument(fmt::format("random_fill: radius {} of disk {} is not > 0 or does not fit", r, i));
    rmax = std::max(rmax, r);
  }
  Packing p;
  p.box = box;
  p.x.reserve(radii.size());
  p.y.reserve(radii.size());
  p.r.assign(radii.begin(), radii.end());
  const double w = box.width(), h = box.height();
  // cells of at least the largest diameter, at most ~4 N of them
  GrowingCellGrid grid(GridLayout::fit({box.x_min, box.y_min}, {box.x_max, box.y_max}, 2.0 * rmax,
                                       4.0 * static_cast<double>(radii.size()) + 64.0));
  for (std::size_t i = 0; i < radii.size(); ++i) {
    const double r = radii[i];
    bool placed = false;
    for (long attempt = 0; attempt < max_attempts && !placed; ++attempt) {
      const double x = box.x_min + (r + (w - 2 * r) * uniform01(rng));
      const double y = box.y_min + (r + (h - 2 * r) * uniform01(rng));
      placed = !grid.any_near(x, y, r + rmax, [&](std::uint32_t k) {
        return std::hypot(x - p.x[k], y - p.y[k]) < r + p.r[k];
      });
      if (placed) {
        grid.insert(static_cast<std::uint32_t>(i), x, y);
        p.x.push_back(x);
        p.y.push_back(y);
      }
    }
    if (!placed)
      throw std::runtime_error(fmt::format("could not place disk {} (r = {}) without overlap in {} attempts", i, r,
                                           max_attempts));
  }
  return p;
}

void RandomFill3dOptions::validate() const {
  const auto fin = [](double v) { return std::isfinite(v); };
  if (n == 0 || n > 10000000)
    throw std::invalid_argument(fmt::format("random_fill_3d: the number of spheres must be in [1, 1e7], got {}", n));
  if (!(fin(mean_radius) && mean_radius > 0.0))
    throw std::invalid_argument(fmt::format("random_fill_3d: the mean radius must be positive and finite, got {}", mean_radius));
  if (!(fin(dispersion) && dispersion >= 0.0 && dispersion < 1.0))
    throw std::invalid_argument(fmt::format("random_fill_3d: the dispersion must be in [0, 1), got {}", dispersion));
  if (!(fin(box.x_min) && fin(box.y_min) && fin(box.z_min) && fin(box.x_max) && fin(box.y_max) && fin(box.z_max) &&
        box.width() > 0.0 && box.height() > 0.0 && box.depth() > 0.0))
    throw std::invalid_argument("random_fill_3d: the box must be finite with positive extents along x, y and z");
  if (max_attempts < 1)
    throw std::invalid_argument(fmt::format("random_fill_3d: max_attempts must be >= 1, got {}", max_attempts));
  const double rmax = mean_radius * (1.0 + dispersion);
  const double side = std::min({box.width(), box.height(), box.depth()});
  if (2.0 * rmax > side)
    throw std::invalid_argument(fmt::format("random_fill_3d: a sphere of the largest radius {:.6g} (diameter {:.6g}) does "
                                            "not fit in the box, whose smallest side is {:.6g}",
                                            rmax, 2.0 * rmax, side));
  // <(1 + d (2U - 1))^3> = 1 + d^2 for U uniform in [0, 1)
  const double solid = static_cast<double>(n) * 4.0 / 3.0 * std::numbers::pi * mean_radius * mean_radius * mean_radius *
                       (1.0 + dispersion * dispersion);
  const double fraction = solid / box.volume();
  if (!(fraction <= kMaxCloudFraction))
    throw std::invalid_argument(fmt::format("random_fill_3d: {} spheres of mean radius {:.6g} fill {:.3g} of the box "
                                            "{:.6g} x {:.6g} x {:.6g}, above the {} a random cloud can hold; use a larger box",
                                            n, mean_radius, fraction, box.width(), box.height(), box.depth(),
                                            kMaxCloudFraction));
}

namespace {

/// The layout of the sequential 3D placement: cubic cells of at least the largest diameter from
/// the box's lower corner, at most about 4 n + 64 of them.
GridLayout3 cloud_layout(const Box& b, double min_cell, std::size_t n) {
  const double v = b.volume() / (4.0 * static_cast<double>(n) + 64.0);
  const double cell = std::max(min_cell, std::cbrt(v));
  GridLayout3 g;
  g.origin = {b.x_min, b.y_min, b.z_min};
  g.cell = {cell, cell, cell};
  const double ext[3] = {b.width(), b.height(), b.depth()};
  for (std::size_t a = 0; a < 3; ++a) g.count[a] = std::max(1L, static_cast<long>(std::ceil(ext[a] / cell)));
  return g;
}

}  // namespace

Packing random_fill_3d(const RandomFill3dOptions& o) {
  o.validate();
  std::mt19937_64 rng(o.seed);
  Packing p;
  p.dim = 3;
  p.box = o.box;
  p.seed = o.seed;
  p.r.resize(o.n);
  for (std::size_t i = 0; i < o.n; ++i) p.r[i] = o.mean_radius * (1.0 + o.dispersion * (2.0 * uniform01(rng) - 1.0));
  const double rmax = *std::max_element(p.r.begin(), p.r.end());
  p.x.reserve(o.n);
  p.y.reserve(o.n);
  p.z.reserve(o.n);
  const Box& b = o.box;
  GrowingCellGrid3 grid(cloud_layout(b, 2.0 * rmax, o.n));
  for (std::size_t i = 0; i < o.n; ++i) {
    const double r = p.r[i];
    bool placed = false;
    for (long attempt = 0; attempt < o.max_attempts && !placed; ++attempt) {
      const double x = b.x_min + (r + (b.width() - 2 * r) * uniform01(rng));
      const double y = b.y_min + (r + (b.height() - 2 * r) * uniform01(rng));
      const double z = b.z_min + (r + (b.depth() - 2 * r) * uniform01(rng));
      placed = !grid.any_near(x, y, z, r + rmax, [&](std::uint32_t k) {
        const double dx = x - p.x[k], dy = y - p.y[k], dz = z - p.z[k], s = r + p.r[k];
        return dx * dx + dy * dy + dz * dz < s * s;
      });
      if (placed) {
        grid.insert(static_cast<std::uint32_t>(i), x, y, z);
        p.x.push_back(x);
        p.y.push_back(y);
        p.z.push_back(z);
      }
    }
    if (!placed)
      throw std::runtime_error(fmt::format("random_fill_3d: could not place sphere {} of {} (r = {:.6g}) without overlap in "
                                           "{} attempts: the box is too full for a random cloud; use a larger box",
                                           i, o.n, r, o.max_attempts));
  }
  return p;
}

}  // namespace netdem::packing
