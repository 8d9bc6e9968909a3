// Homogeneity measures of 3D packings (netdem/packing/laminar.hpp).
#include "netdem/packing/laminar.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace netdem::packing {

namespace {

constexpr double kPi = std::numbers::pi;

/// Volume of the sphere (radius r, centre 0) below the plane t, t clamped to [-r, r].
double cap_below(double t, double r) {
  t = std::clamp(t, -r, r);
  return kPi * (r * r * t - t * t * t / 3.0) + 2.0 / 3.0 * kPi * r * r * r;
}

double box_lo(const Box& b, int axis) { return axis == 0 ? b.x_min : axis == 1 ? b.y_min : b.z_min; }
double box_hi(const Box& b, int axis) { return axis == 0 ? b.x_max : axis == 1 ? b.y_max : b.z_max; }
const std::vector<double>& coords(const Packing& p, int axis) { return axis == 0 ? p.x : axis == 1 ? p.y : p.z; }

void need_3d(const Packing& p, const char* what) {
  if (p.dim != 3 || p.z.size() != p.size() || p.y.size() != p.size() || p.r.size() != p.size())
    throw std::invalid_argument(fmt::format("{}: needs a 3D packing (dim 3, x, y, z and r of equal size)", what));
}

}  // namespace

double sphere_slab_volume(double c, double r, double a, double b) {
  if (!(b > a)) return 0.0;
  return cap_below(b - c, r) - cap_below(a - c, r);
}

LaminarProfile::Range LaminarProfile::interior(double lo_box, double hi_box, double margin) const {
  Range out;
  out.min = std::numeric_limits<double>::infinity();
  out.max = -std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (std::size_t s = 0; s < density.size(); ++s) {
    if (lo[s] < lo_box + margin - 1e-12 * width || hi[s] > hi_box - margin + 1e-12 * width) continue;
    ++out.count;
    out.min = std::min(out.min, density[s]);
    out.max = std::max(out.max, density[s]);
    sum += density[s];
  }
  if (out.count == 0) return Range{};
  out.mean = sum / static_cast<double>(out.count);
  return out;
}

LaminarProfile laminar_density(const Packing& p, int axis, double q_s) {
  need_3d(p, "laminar_density");
  if (axis < 0 || axis > 2) throw std::invalid_argument(fmt::format("laminar_density: axis must be 0, 1 or 2, got {}", axis));
  if (!(std::isfinite(q_s) && q_s > 0.0))
    throw std::invalid_argument(fmt::format("laminar_density: the lamina width q_s must be positive and finite, got {}", q_s));
  const Box& b = p.box;
  if (!(b.width() > 0.0 && b.height() > 0.0 && b.depth() > 0.0))
    throw std::invalid_argument("laminar_density: the box must have positive extents along x, y and z");
  const double lo_box = box_lo(b, axis), hi_box = box_hi(b, axis), L = hi_box - lo_box;
  const double ratio = L / q_s;
  if (!(ratio <= 1e6))
    throw std::invalid_argument(fmt::format("laminar_density: q_s = {:.6g} cuts the box extent {:.6g} into more than 1e6 laminae", q_s, L));
  const auto count = static_cast<std::size_t>(std::max(1.0, std::round(ratio)));
  LaminarProfile out;
  out.axis = axis;
  out.width = L / static_cast<double>(count);
  out.lo.resize(count);
  out.hi.resize(count);
  for (std::size_t s = 0; s < count; ++s) {
    out.lo[s] = lo_box + static_cast<double>(s) * out.width;
    out.hi[s] = s + 1 == count ? hi_box : lo_box + static_cast<double>(s + 1) * out.width;
  }
  std::vector<double> vol(count, 0.0);
  const std::vector<double>& c = coords(p, axis);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i];
    const double first = std::floor((c[i] - r - lo_box) / out.width), last = std::floor((c[i] + r - lo_box) / out.width);
    const auto s0 = static_cast<std::size_t>(std::clamp(first, 0.0, static_cast<double>(count - 1)));
    const auto s1 = static_cast<std::size_t>(std::clamp(last, 0.0, static_cast<double>(count - 1)));
    for (std::size_t s = s0; s <= s1; ++s) vol[s] += sphere_slab_volume(c[i], r, out.lo[s], out.hi[s]);
  }
  const double section = b.volume() / L;
  out.density.resize(count);
  for (std::size_t s = 0; s < count; ++s) out.density[s] = vol[s] / ((out.hi[s] - out.lo[s]) * section);
  return out;
}

double sampled_density(const Packing& p, const Box& region, double spacing) {
  need_3d(p, "sampled_density");
  const Box& g = region;
  if (!(std::isfinite(g.x_min) && std::isfinite(g.y_min) && std::isfinite(g.z_min) && std::isfinite(g.x_max) &&
        std::isfinite(g.y_max) && std::isfinite(g.z_max) && g.width() > 0.0 && g.height() > 0.0 && g.depth() > 0.0))
    throw std::invalid_argument("sampled_density: the region must be finite with positive extents along x, y and z");
  if (!(std::isfinite(spacing) && spacing > 0.0))
    throw std::invalid_argument(fmt::format("sampled_density: the spacing must be positive and finite, got {}", spacing));
  const double ext[3] = {g.width(), g.height(), g.depth()}, org[3] = {g.x_min, g.y_min, g.z_min};
  long n[3];
  double h[3];
  double points = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double c = std::ceil(ext[a] / spacing - 1e-9);
    points *= c;
    if (!(points <= 2e8))
      throw std::invalid_argument(fmt::format("sampled_density: spacing {:.6g} gives more than 2e8 points in the region", spacing));
    n[a] = std::max(1L, static_cast<long>(c));
    h[a] = ext[a] / static_cast<double>(n[a]);
  }
  std::vector<std::uint8_t> inside(static_cast<std::size_t>(n[0] * n[1] * n[2]), 0);
  // the lattice indices k with centre org + (k + 1/2) h in [lo, hi], clamped to [0, n - 1]
  const auto range = [&](int a, double lo, double hi, long& k0, long& k1) {
    k0 = static_cast<long>(std::max(0.0, std::ceil((lo - org[a]) / h[a] - 0.5)));
    const double top = std::floor((hi - org[a]) / h[a] - 0.5);
    k1 = top < 0.0 ? -1 : static_cast<long>(std::min(static_cast<double>(n[a] - 1), top));
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i], cx = p.x[i], cy = p.y[i], cz = p.z[i];
    long z0, z1, y0, y1;
    range(2, cz - r, cz + r, z0, z1);
    range(1, cy - r, cy + r, y0, y1);
    for (long kz = z0; kz <= z1; ++kz) {
      const double dz = org[2] + (static_cast<double>(kz) + 0.5) * h[2] - cz;
      for (long ky = y0; ky <= y1; ++ky) {
        const double dy = org[1] + (static_cast<double>(ky) + 0.5) * h[1] - cy;
        const double rem = r * r - dz * dz - dy * dy;
        if (rem < 0.0) continue;
        const double half = std::sqrt(rem);
        long x0, x1;
        range(0, cx - half, cx + half, x0, x1);
        if (x1 < x0) continue;
        std::uint8_t* row = inside.data() + static_cast<std::size_t>((kz * n[1] + ky) * n[0]);
        std::fill(row + x0, row + x1 + 1, std::uint8_t{1});
      }
    }
  }
  std::size_t hit = 0;
  for (std::uint8_t v : inside) hit += v;
  return static_cast<double>(hit) / static_cast<double>(inside.size());
}

OverlapStats overlap_stats(const Packing& p) {
  need_3d(p, "overlap_stats");
  OverlapStats s;
  double sum = 0.0;
  for (const auto& [i, j] : touching_pairs(p, 0.0)) {
    const double dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i], dz = p.z[j] - p.z[i];
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz), r1 = p.r[i], r2 = p.r[j];
    const double u = r1 + r2 - d;
    if (!(u > 0.0)) continue;
    ++s.pairs;
    const double rel = u / (0.5 * (r1 + r2));
    sum += rel;
    s.pair_max = std::max(s.pair_max, rel);
    if (d > 0.0)  // lens of two spheres at distance d
      s.lens_volume += kPi * u * u * (d * d + 2 * d * r1 - 3 * r1 * r1 + 2 * d * r2 + 6 * r1 * r2 - 3 * r2 * r2) / (12.0 * d);
  }
  if (s.pairs > 0) s.pair_mean = sum / static_cast<double>(s.pairs);
  double wsum = 0.0;
  const Box& b = p.box;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i];
    const double dist[6] = {p.x[i] - b.x_min, b.x_max - p.x[i], p.y[i] - b.y_min,
                            b.y_max - p.y[i], p.z[i] - b.z_min, b.z_max - p.z[i]};
    for (double q : dist) {
      const double u = r - q;
      if (!(u > 0.0)) continue;
      ++s.wall_contacts;
      wsum += u / r;
      s.wall_max = std::max(s.wall_max, u / r);
    }
  }
  if (s.wall_contacts > 0) s.wall_mean = wsum / static_cast<double>(s.wall_contacts);
  if (p.size() > 0) s.coordination = 2.0 * static_cast<double>(s.pairs) / static_cast<double>(p.size());
  return s;
}

Box bounding_box(const Packing& p) {
  need_3d(p, "bounding_box");
  Box b{0, 0, 0, 0, 0, 0};
  if (p.size() == 0) return b;
  b.x_min = b.y_min = b.z_min = std::numeric_limits<double>::infinity();
  b.x_max = b.y_max = b.z_max = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i];
    b.x_min = std::min(b.x_min, p.x[i] - r);
    b.x_max = std::max(b.x_max, p.x[i] + r);
    b.y_min = std::min(b.y_min, p.y[i] - r);
    b.y_max = std::max(b.y_max, p.y[i] + r);
    b.z_min = std::min(b.z_min, p.z[i] - r);
    b.z_max = std::max(b.z_max, p.z[i] + r);
  }
  return b;
}

}  // namespace netdem::packing
