// Packing queries: touching pairs, contact statistics (Redanz & Fleck 2001, section 2.2 / Fig 3),
// peripheral layer (section 2.4) and validation.
#include "netdem/packing/packing.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "netdem/packing/cell_grid.hpp"
#include "netdem/packing/periodic.hpp"

namespace netdem::packing {

namespace {

double max_radius(const Packing& p) {
  double m = 0;
  for (double r : p.r) m = std::max(m, r);
  return m;
}

bool near_left(const Packing& p, std::size_t i, double tol) { return p.x[i] - p.r[i] - p.box.x_min <= tol * p.r[i]; }
bool near_right(const Packing& p, std::size_t i, double tol) { return p.box.x_max - p.x[i] - p.r[i] <= tol * p.r[i]; }
bool near_bottom(const Packing& p, std::size_t i, double tol) { return p.y[i] - p.r[i] - p.box.y_min <= tol * p.r[i]; }
bool near_top(const Packing& p, std::size_t i, double tol) { return p.box.y_max - p.y[i] - p.r[i] <= tol * p.r[i]; }

/// Height of the upper half of disk k at abscissa x (caller guarantees |x - x_k| <= r_k).
double upper_surface(const Packing& p, std::size_t k, double x) {
  const double dx = std::fabs(x - p.x[k]);
  return p.y[k] + std::sqrt(std::max(0.0, (p.r[k] - dx) * (p.r[k] + dx)));
}

}  // namespace

double Packing::solid_area() const {
  double a = 0;
  for (double ri : r) a += ri * ri;
  return std::numbers::pi * a;
}

double Packing::solid_volume() const {
  double v = 0;
  for (double ri : r) v += ri * ri * ri;
  return 4.0 / 3.0 * std::numbers::pi * v;
}

double Packing::density() const {
  if (periodic && !cell.empty() && (cell.size() == 4 || cell.size() == 9)) {
    const double m = dim == 3 ? periodic_cell<3>(*this).measure() : periodic_cell<2>(*this).measure();
    return m > 0 ? solid_measure() / m : 0.0;
  }
  if (dim == 3) {
    const double v = box.volume();
    return v > 0 ? solid_volume() / v : 0.0;
  }
  const double a = box.area();
  return a > 0 ? solid_area() / a : 0.0;
}

namespace {

/// 3D pairs; `periodic`: minimum image in x and y over the box period.
std::vector<std::pair<int, int>> touching_pairs_3d(const Packing& p, double tol, bool periodic) {
  std::vector<std::pair<int, int>> pairs;
  const std::size_t n = p.size();
  if (n < 2) return pairs;
  const double rmax = max_radius(p);
  const double f = 1.0 + tol;
  const double wx = p.box.width(), wy = p.box.height();
  if (periodic && !(wx >= 4 * rmax * f && wy >= 4 * rmax * f))
    throw std::invalid_argument(fmt::format("touching_pairs_periodic_xy: box {} x {} is narrower than 4 r_max (1 + tol) = {}",
                                            wx, wy, 4 * rmax * f));
  const CellGrid3 grid(p.x, p.y, p.z, 2.0 * rmax * f);
  const int images = periodic ? 1 : 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (int sx = -images; sx <= images; ++sx)
      for (int sy = -images; sy <= images; ++sy) {
        const double qx = p.x[i] + sx * wx, qy = p.y[i] + sy * wy;
        grid.for_each_near(qx, qy, p.z[i], (p.r[i] + rmax) * f, [&](std::uint32_t jj) {
          const std::size_t j = jj;
          if (j <= i) return;
          const double dx = p.x[j] - qx, dy = p.y[j] - qy, dz = p.z[j] - p.z[i];
          const double reach = (p.r[i] + p.r[j]) * f;
          if (dx * dx + dy * dy + dz * dz <= reach * reach) pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
        });
      }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // periodic: one pair, one contact
  return pairs;
}

}  // namespace

std::vector<std::pair<int, int>> touching_pairs_periodic_xy(const Packing& p, double tol) {
  if (p.dim != 3) throw std::invalid_argument("touching_pairs_periodic_xy: needs a 3D packing");
  return touching_pairs_3d(p, tol, true);
}

std::vector<std::pair<int, int>> touching_pairs(const Packing& p, double tol) {
  if (p.periodic) return touching_pairs_periodic(p, tol);
  if (p.dim == 3) return touching_pairs_3d(p, tol, false);
  std::vector<std::pair<int, int>> pairs;
  const std::size_t n = p.size();
  if (n < 2) return pairs;
  const double rmax = max_radius(p);
  const double f = 1.0 + tol;
  const CellGrid grid(p.x, p.y, 2.0 * rmax * f);
  for (std::size_t i = 0; i < n; ++i) {
    grid.for_each_near(p.x[i], p.y[i], (p.r[i] + rmax) * f, [&](int j) {
      if (static_cast<std::size_t>(j) <= i) return;
      const double dx = p.x[static_cast<std::size_t>(j)] - p.x[i];
      const double dy = p.y[static_cast<std::size_t>(j)] - p.y[i];
      const double reach = (p.r[i] + p.r[static_cast<std::size_t>(j)]) * f;
      if (dx * dx + dy * dy <= reach * reach) pairs.emplace_back(static_cast<int>(i), j);
    });
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

ContactStats contact_stats(const Packing& p, double tol, bool periodic_xy) {
  ContactStats s;
  s.particles = p.size();
  if (p.periodic) {  // no walls
    if (periodic_xy) throw std::invalid_argument("contact_stats: periodic_xy is for lateral-periodic packings, not periodic ones");
    s.disk_contacts = touching_pairs(p, tol).size();
    s.density = p.density();
    s.coordination = s.particles ? 2.0 * static_cast<double>(s.disk_contacts) / static_cast<double>(s.particles) : 0.0;
    return s;
  }
  if (p.dim == 3) {
    s.disk_contacts = (periodic_xy ? touching_pairs_periodic_xy(p, tol) : touching_pairs(p, tol)).size();
    const Box& b = p.box;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double x = p.x[i], y = p.y[i], r = p.r[i], t = tol * r;
      s.wall_contacts += static_cast<std::size_t>(p.z[i] - r - b.z_min <= t);
      if (!periodic_xy)
        s.wall_contacts += static_cast<std::size_t>(x - r - b.x_min <= t) + (b.x_max - x - r <= t) + (y - r - b.y_min <= t) +
                           (b.y_max - y - r <= t);
    }
    s.density = p.density();
    s.coordination = s.particles ? 2.0 * static_cast<double>(s.disk_contacts) / static_cast<double>(s.particles) : 0.0;
    return s;
  }
  if (periodic_xy) throw std::invalid_argument("contact_stats: periodic_xy needs a 3D packing");
  s.disk_contacts = touching_pairs(p, tol).size();
  for (std::size_t i = 0; i < p.size(); ++i)
    s.wall_contacts += static_cast<std::size_t>(near_left(p, i, tol)) + near_right(p, i, tol) + near_bottom(p, i, tol);
  s.density = p.density();
  s.coordination = s.particles ? 2.0 * static_cast<double>(s.disk_contacts) / static_cast<double>(s.particles) : 0.0;
  return s;
}

std::vector<std::uint8_t> peripheral_layer(const Packing& p, double tol) {
  const std::size_t n = p.size();
  if (p.dim == 3) throw std::invalid_argument("peripheral_layer: 3D packings are not supported yet (issue 16)");
  std::vector<std::uint8_t> flag(n, 0);
  if (n == 0) return flag;
  // Section 2.4: the peripheral layer carries the boundary conditions. Walls and lid first.
  for (std::size_t i = 0; i < n; ++i)
    if (near_left(p, i, tol) || near_right(p, i, tol) || near_bottom(p, i, tol) || near_top(p, i, tol)) flag[i] = 1;

  // Free top surface. Step 1, a cheap exact filter: on bins of width <= r_min/2, lb[b] is a lower
  // bound of the upper envelope over the whole bin (from the disks covering the bin entirely).
  // A disk can be on the envelope only if its top reaches min(lb) over the bins it overlaps.
  double rmin = std::numeric_limits<double>::infinity(), rmax = 0;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
  for (std::size_t i = 0; i < n; ++i) {
    rmin = std::min(rmin, p.r[i]);
    rmax = std::max(rmax, p.r[i]);
    x0 = std::min(x0, p.x[i] - p.r[i]);
    x1 = std::max(x1, p.x[i] + p.r[i]);
  }
  if (!(rmin > 0) || !std::isfinite(x1 - x0) || !std::isfinite(rmax)) return flag;  // invalid input
  double h = 0.5 * rmin;
  if (!(h > 0)) h = rmin;  // r_min subnormal: 0.5 r_min may round to 0 (the doubling below would never end)
  const double max_bins = 8.0 * static_cast<double>(n) + 64.0;
  while ((x1 - x0) / h + 1.0 > max_bins) h *= 2.0;
  const auto nb = static_cast<long>((x1 - x0) / h) + 1;
  std::vector<double> lb(static_cast<std::size_t>(nb), -std::numeric_limits<double>::infinity());
  auto bin_of = [&](double x) { return std::clamp(static_cast<long>(std::floor((x - x0) / h)), 0L, nb - 1); };
  for (std::size_t k = 0; k < n; ++k) {
    const auto b0 = static_cast<long>(std::ceil((p.x[k] - p.r[k] - x0) / h));
    const auto b1 = static_cast<long>(std::floor((p.x[k] + p.r[k] - x0) / h)) - 1;
    for (long b = std::max(b0, 0L); b <= std::min(b1, nb - 1); ++b) {
      const double a = x0 + static_cast<double>(b) * h, e = a + h;
      const double far = std::max(std::fabs(a - p.x[k]), std::fabs(e - p.x[k]));
      if (far > p.r[k]) continue;  // rounding at the ends
      const double v = p.y[k] + std::sqrt((p.r[k] - far) * (p.r[k] + far));
      lb[static_cast<std::size_t>(b)] = std::max(lb[static_cast<std::size_t>(b)], v);
    }
  }

  // Step 2, exact test for the survivors: the owner of the envelope can only change at the ends of
  // the half-circles and at circle-circle intersections, so testing the midpoint of every interval
  // between consecutive breakpoints is exact (up to tol).
  const CellGrid grid(p.x, p.y, 2.0 * rmax);
  std::vector<int> above;
  std::vector<double> brk;
  for (std::size_t i = 0; i < n; ++i) {
    if (flag[i]) continue;
    const double xi = p.x[i], yi = p.y[i], ri = p.r[i];
    double lo = std::numeric_limits<double>::infinity();
    for (long b = bin_of(xi - ri); b <= bin_of(xi + ri); ++b) lo = std::min(lo, lb[static_cast<std::size_t>(b)]);
    if (yi + ri + tol * ri < lo) continue;  // buried

    above.clear();
    grid.for_each_in(xi - ri - rmax, xi + ri + rmax, yi - rmax, std::numeric_limits<double>::infinity(), [&](int k) {
      const auto ku = static_cast<std::size_t>(k);
      if (ku == i || std::fabs(p.x[ku] - xi) >= ri + p.r[ku] || p.y[ku] + p.r[ku] <= yi) return;
      above.push_back(k);
    });
    brk.clear();
    brk.push_back(xi - ri);
    brk.push_back(xi + ri);
    for (int k : above) {
      const auto ku = static_cast<std::size_t>(k);
      brk.push_back(p.x[ku] - p.r[ku]);
      brk.push_back(p.x[ku] + p.r[ku]);
      const double dx = p.x[ku] - xi, dy = p.y[ku] - yi, d = std::hypot(dx, dy);
      if (d == 0 || d > ri + p.r[ku] || d < std::fabs(ri - p.r[ku])) continue;
      const double a = (ri * ri - p.r[ku] * p.r[ku] + d * d) / (2 * d);
      const double hh = std::sqrt(std::max(0.0, ri * ri - a * a));
      brk.push_back(xi + (a * dx + hh * dy) / d);
      brk.push_back(xi + (a * dx - hh * dy) / d);
    }
    std::sort(brk.begin(), brk.end());
    for (std::size_t m = 0; m + 1 < brk.size() && !flag[i]; ++m) {
      const double a = std::max(brk[m], xi - ri), b = std::min(brk[m + 1], xi + ri);
      if (!(b > a)) continue;
      const double xm = 0.5 * (a + b);
      const double si = upper_surface(p, i, xm);
      bool top = true;
      for (int k : above) {
        const auto ku = static_cast<std::size_t>(k);
        if (std::fabs(xm - p.x[ku]) < p.r[ku] && upper_surface(p, ku, xm) > si + tol * ri) {
          top = false;
          break;
        }
      }
      if (top) flag[i] = 1;
    }
  }
  return flag;
}

namespace {

void validate_3d(const Packing& p) {
  auto fail = [](const std::string& msg) { throw std::invalid_argument("invalid packing: " + msg); };
  const Box& b = p.box;
  const double bounds[6] = {b.x_min, b.y_min, b.z_min, b.x_max, b.y_max, b.z_max};
  for (double v : bounds)
    if (!std::isfinite(v))
      fail(fmt::format("box has a non-finite bound ({} {} {} {} {} {})", b.x_min, b.y_min, b.z_min, b.x_max, b.y_max,
                       b.z_max));
  if (!(b.width() > 0) || !(b.height() > 0) || !(b.depth() > 0))
    fail(fmt::format("box has non-positive size (x {}, y {}, z {})", b.width(), b.height(), b.depth()));
  if (p.x.size() != p.y.size() || p.x.size() != p.z.size() || p.x.size() != p.r.size())
    fail(fmt::format("x, y, z, r have different sizes ({}, {}, {}, {})", p.x.size(), p.y.size(), p.z.size(), p.r.size()));
  if (p.size() == 0) fail("packing is empty");
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double x = p.x[i], y = p.y[i], z = p.z[i], r = p.r[i];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
      fail(fmt::format("sphere {} has a non-finite coordinate (x = {}, y = {}, z = {})", i, x, y, z));
    if (!std::isfinite(r)) fail(fmt::format("sphere {} has a non-finite radius (r = {})", i, r));
    if (!(r > 0)) fail(fmt::format("sphere {} has r <= 0 (r = {})", i, r));
    const double t = 1e-9 * r;
    if (x < b.x_min - t || x > b.x_max + t || y < b.y_min - t || y > b.y_max + t || z < b.z_min - t || z > b.z_max + t)
      fail(fmt::format("sphere {} is outside the box (centre ({}, {}, {}) not in [{}, {}] x [{}, {}] x [{}, {}])", i, x, y,
                       z, b.x_min, b.x_max, b.y_min, b.y_max, b.z_min, b.z_max));
  }
  double rmin = p.r[0], rmax = p.r[0];
  for (double r : p.r) rmin = std::min(rmin, r), rmax = std::max(rmax, r);
  if (!(rmax <= kMaxRadiusRatio * rmin))
    fail(fmt::format("r_max / r_min = {:.6g} / {:.6g} = {:.6g} exceeds {:g}", rmax, rmin, rmax / rmin, kMaxRadiusRatio));
  if (const auto c = find_close_pair(p)) {
    if (c->duplicate)
      fail(fmt::format("sphere {} duplicates sphere {} (same centre)", std::max(c->i, c->j), std::min(c->i, c->j)));
    fail(fmt::format("spheres {} and {} are too close: centre distance {:.6g} < max(r_i, r_j) = {:.6g}",
                     std::min(c->i, c->j), std::max(c->i, c->j), c->distance, p.r[c->i]));
  }
}

}  // namespace

void validate(const Packing& p) {
  auto fail = [](const std::string& msg) { throw std::invalid_argument("invalid packing: " + msg); };
  const Box& b = p.box;
  if (p.dim != 2 && p.dim != 3) fail(fmt::format("dim is {}, not 2 or 3", p.dim));
  if (p.dim == 3) {
    validate_3d(p);
    if (p.periodic) validate_periodic(p);
    return;
  }
  if (!std::isfinite(b.x_min) || !std::isfinite(b.y_min) || !std::isfinite(b.x_max) || !std::isfinite(b.y_max))
    fail(fmt::format("box has a non-finite bound ({} {} {} {})", b.x_min, b.y_min, b.x_max, b.y_max));
  if (!(b.width() > 0) || !(b.height() > 0))
    fail(fmt::format("box has non-positive size (width {}, height {})", b.width(), b.height()));
  if (p.x.size() != p.y.size() || p.x.size() != p.r.size())
    fail(fmt::format("x, y, r have different sizes ({}, {}, {})", p.x.size(), p.y.size(), p.r.size()));
  if (!p.z.empty()) fail(fmt::format("a 2D packing has {} z coordinates (z must be empty in 2D)", p.z.size()));
  if (p.size() == 0) fail("packing is empty");
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double x = p.x[i], y = p.y[i], r = p.r[i];
    if (!std::isfinite(x) || !std::isfinite(y))
      fail(fmt::format("disk {} has a non-finite coordinate (x = {}, y = {})", i, x, y));
    if (!std::isfinite(r)) fail(fmt::format("disk {} has a non-finite radius (r = {})", i, r));
    if (!(r > 0)) fail(fmt::format("disk {} has r <= 0 (r = {})", i, r));
    const double t = 1e-9 * r;
    if (x < b.x_min - t || x > b.x_max + t || y < b.y_min - t || y > b.y_max + t)
      fail(fmt::format("disk {} is outside the box (centre ({}, {}) not in [{}, {}] x [{}, {}])", i, x, y, b.x_min,
                       b.x_max, b.y_min, b.y_max));
  }
  double rmin = p.r[0], rmax = p.r[0];
  for (double r : p.r) rmin = std::min(rmin, r), rmax = std::max(rmax, r);
  if (!(rmax <= kMaxRadiusRatio * rmin))
    fail(fmt::format("r_max / r_min = {:.6g} / {:.6g} = {:.6g} exceeds {:g}", rmax, rmin, rmax / rmin, kMaxRadiusRatio));
  if (const auto c = find_close_pair(p)) {
    if (c->duplicate)
      fail(fmt::format("disk {} duplicates disk {} (same centre)", std::max(c->i, c->j), std::min(c->i, c->j)));
    fail(fmt::format("disks {} and {} are too close: centre distance {:.6g} < max(r_i, r_j) = {:.6g}",
                     std::min(c->i, c->j), std::max(c->i, c->j), c->distance, p.r[c->i]));
  }
  if (p.periodic) validate_periodic(p);
}

std::optional<ClosePair> find_close_pair(const Packing& p) {
  const std::size_t n = p.size();
  if (n < 2) return std::nullopt;
  double rmin = p.r[0];
  for (double r : p.r) rmin = std::min(rmin, r);
  if (p.dim == 3) {  // the same search on a 3D grid (cells >= r_min, at most 4 N + 64)
    const CellGrid3 grid(p.x, p.y, p.z, rmin);
    for (std::size_t i = 0; i < n; ++i) {
      const double ri = p.r[i];
      std::size_t best = n;
      grid.for_each_near(p.x[i], p.y[i], p.z[i], ri, [&](std::uint32_t jj) {
        const std::size_t j = jj;
        if (j == i || p.r[j] > ri || (p.r[j] == ri && j > i) || j >= best) return;
        const double dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i], dz = p.z[j] - p.z[i];
        if (dx * dx + dy * dy + dz * dz < ri * ri) best = j;
      });
      if (best < n) {
        ClosePair c;
        c.i = i;
        c.j = best;
        const double dx = p.x[best] - p.x[i], dy = p.y[best] - p.y[i], dz = p.z[best] - p.z[i];
        c.distance = std::sqrt(dx * dx + dy * dy + dz * dz);
        c.duplicate = c.distance <= 1e-12 * (ri + p.r[best]);
        return c;
      }
    }
    return std::nullopt;
  }
  // Cells of at least r_min: a disk of radius r_i visits ~(2 r_i / cell + 2)^2 cells, and in a
  // packing without such pairs a cell holds O(1) centres; the grid caps the count at ~4 N cells.
  const CellGrid grid(p.x, p.y, rmin);
  for (std::size_t i = 0; i < n; ++i) {
    const double ri = p.r[i];
    std::size_t best = n;
    grid.for_each_near(p.x[i], p.y[i], ri, [&](std::uint32_t jj) {
      const std::size_t j = jj;
      if (j == i || p.r[j] > ri || (p.r[j] == ri && j > i) || j >= best) return;
      const double dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i];
      if (dx * dx + dy * dy < ri * ri) best = j;
    });
    if (best < n) {
      ClosePair c;
      c.i = i;
      c.j = best;
      c.distance = std::hypot(p.x[best] - p.x[i], p.y[best] - p.y[i]);
      c.duplicate = c.distance <= 1e-12 * (ri + p.r[best]);
      return c;
    }
  }
  return std::nullopt;
}

}  // namespace netdem::packing
