// Random sequential placement (netdem/packing/random_fill.hpp).
#include "netdem/packing/random_fill.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

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

}  // namespace netdem::packing
