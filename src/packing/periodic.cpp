// Periodic cells and the neighbour search across their boundary (periodic.hpp states the rules).
#include "netdem/packing/periodic.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "netdem/packing/packing.hpp"

namespace netdem::packing {

template <int D>
PeriodicCellT<D> periodic_cell(const Packing& p) {
  if (!p.periodic) throw std::invalid_argument("periodic cell: the packing is not periodic");
  if (p.dim != D)
    throw std::invalid_argument(fmt::format("periodic cell: the packing has dimension {}, the cell {}", p.dim, D));
  PeriodicCellT<D> c;
  c.origin[0] = p.box.x_min;
  c.origin[1] = p.box.y_min;
  if constexpr (D == 3) c.origin[2] = p.box.z_min;
  if (p.cell.empty()) {
    c.h = PeriodicCellT<D>::Mat::Zero();
    c.h(0, 0) = p.box.width();
    c.h(1, 1) = p.box.height();
    if constexpr (D == 3) c.h(2, 2) = p.box.depth();
  } else {
    if (p.cell.size() != static_cast<std::size_t>(D * D))
      throw std::invalid_argument(fmt::format("periodic cell: {} cell numbers, expected {}", p.cell.size(), D * D));
    for (int a = 0; a < D; ++a)  // vector a is column a
      for (int b = 0; b < D; ++b) c.h(b, a) = p.cell[static_cast<std::size_t>(D * a + b)];
    // the box is the cell's bounding box: the first corner sits above the box's lower corner by
    // the most negative corner offset along each axis (zero unless a vector has a negative component)
    typename PeriodicCellT<D>::Vec low = PeriodicCellT<D>::Vec::Zero();
    for (int k = 1; k < (1 << D); ++k) {
      typename PeriodicCellT<D>::Vec corner = PeriodicCellT<D>::Vec::Zero();
      for (int a = 0; a < D; ++a)
        if (k & (1 << a)) corner += c.h.col(a);
      low = low.cwiseMin(corner);
    }
    c.origin -= low;
  }
  return c;
}

namespace {

/// Whole images of the wrap of s (s - floor(s) in [0, 1)): returns floor(s) and sets s.
double wrap_unit(double& s) {
  double fl = std::floor(s);
  s -= fl;
  if (s >= 1.0) {  // rounding of a tiny negative s
    s = 0.0;
    fl += 1.0;
  }
  return fl;
}

}  // namespace

template <int D>
const std::vector<typename PeriodicPairsT<D>::Pair>& PeriodicPairsT<D>::find(std::span<const double> pos,
                                                                             std::span<const double> r, const Cell& cell,
                                                                             double extra) {
  using Vec = typename Cell::Vec;
  const std::size_t n = r.size();
  pairs_.clear();
  if (!cell.h.allFinite() || !cell.origin.allFinite() || !(cell.measure() > 0.0))
    throw std::invalid_argument("periodic cell: its vectors or origin are not finite, or it has no extent");
  if (pos.size() != D * n) throw std::invalid_argument("periodic pairs: positions and radii differ in count");
  double rmax = 0.0;
  for (double ri : r) rmax = std::max(rmax, ri);
  const double range = 2.0 * rmax + extra;
  std::array<long, D> m{};
  long cells = 1;
  for (int a = 0; a < D; ++a) {
    const double w = cell.width(a);
    if (!(w >= 2.0 * range))
      throw std::invalid_argument(fmt::format("periodic cell: width {:.6g} across axis {} is below 2 (2 r_max + skin) = "
                                              "{:.6g}; a pair would meet through two images",
                                              w, a, 2.0 * range));
    m[static_cast<std::size_t>(a)] = std::max(1L, static_cast<long>(std::min(w / range, 1e6)));
  }
  for (;;) {  // at most 4 N + 64 cells: halve the finest axis (cells only grow, the search stays right)
    cells = 1;
    for (long c : m) cells *= c;
    if (cells <= 4 * static_cast<long>(n) + 64) break;
    auto it = std::max_element(m.begin(), m.end());
    *it = std::max(1L, *it / 2);
  }
  const typename Cell::Mat hinv = cell.h.inverse();
  s_.resize(D * n);
  wrap_.resize(D * n);
  cell_of_.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    const Vec x = Eigen::Map<const Vec>(&pos[D * p]);
    if (!x.allFinite()) throw std::invalid_argument(fmt::format("periodic pairs: particle {} has a non-finite centre", p));
    Vec s = hinv * (x - cell.origin);
    long k = 0;
    for (int a = 0; a < D; ++a) {
      const double fl = wrap_unit(s[a]);
      if (!(std::abs(fl) < 1e9))
        throw std::invalid_argument(fmt::format("periodic pairs: particle {} is {:.3g} cells away from the cell", p, fl));
      s_[D * p + static_cast<std::size_t>(a)] = s[a];
      wrap_[D * p + static_cast<std::size_t>(a)] = -static_cast<int>(fl);
    }
    for (int a = D - 1; a >= 0; --a) {
      const long ma = m[static_cast<std::size_t>(a)];
      k = k * ma + std::min(ma - 1, static_cast<long>(s[a] * static_cast<double>(ma)));
    }
    cell_of_[p] = static_cast<std::uint32_t>(k);
  }
  start_.assign(static_cast<std::size_t>(cells) + 1, 0);
  for (std::size_t p = 0; p < n; ++p) ++start_[cell_of_[p] + 1];
  for (long c = 0; c < cells; ++c) start_[static_cast<std::size_t>(c) + 1] += start_[static_cast<std::size_t>(c)];
  ids_.resize(n);
  fill_.assign(start_.begin(), start_.end() - 1);  // (a member: no allocation once the cell count settles)
  for (std::size_t p = 0; p < n; ++p) ids_[fill_[cell_of_[p]]++] = static_cast<std::uint32_t>(p);
  constexpr int kOffsets = D == 2 ? 9 : 27;
  for (std::size_t p = 0; p < n; ++p) {
    std::array<long, D> c{};
    long k = cell_of_[p];
    for (int a = 0; a < D; ++a) {
      c[static_cast<std::size_t>(a)] = k % m[static_cast<std::size_t>(a)];
      k /= m[static_cast<std::size_t>(a)];
    }
    for (int o = 0; o < kOffsets; ++o) {
      long idx = 0;
      Shift wrap{};
      int code = o;
      std::array<long, D> t{};
      for (int a = 0; a < D; ++a) {
        const auto aa = static_cast<std::size_t>(a);
        long ta = c[aa] + (code % 3) - 1;
        code /= 3;
        wrap[aa] = 0;
        if (ta < 0) ta += m[aa], wrap[aa] = -1;
        else if (ta >= m[aa]) ta -= m[aa], wrap[aa] = 1;
        t[aa] = ta;
      }
      for (int a = D - 1; a >= 0; --a) idx = idx * m[static_cast<std::size_t>(a)] + t[static_cast<std::size_t>(a)];
      for (std::uint32_t kk = start_[static_cast<std::size_t>(idx)]; kk < start_[static_cast<std::size_t>(idx) + 1]; ++kk) {
        const std::size_t q = ids_[kk];
        if (q <= p) continue;  // each pair once, from its lower index; a particle never meets itself
        Vec ds;
        for (int a = 0; a < D; ++a)
          ds[a] = s_[D * q + static_cast<std::size_t>(a)] + wrap[static_cast<std::size_t>(a)] - s_[D * p + static_cast<std::size_t>(a)];
        const double reach = r[p] + r[q] + extra;
        if ((cell.h * ds).squaredNorm() >= reach * reach) continue;
        Pair pr{static_cast<int>(p), static_cast<int>(q), {}};
        for (int a = 0; a < D; ++a) {
          const auto aa = static_cast<std::size_t>(a);
          pr.n[aa] = wrap[aa] + wrap_[D * q + aa] - wrap_[D * p + aa];
        }
        pairs_.push_back(pr);
      }
    }
  }
  std::sort(pairs_.begin(), pairs_.end(), [](const Pair& a, const Pair& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  return pairs_;
}


namespace {

template <int D>
void validate_periodic_d(const Packing& p) {
  auto fail = [](const std::string& msg) { throw std::invalid_argument("invalid packing: " + msg); };
  using Cell = PeriodicCellT<D>;
  if (!p.cell.empty()) {
    if (p.cell.size() != static_cast<std::size_t>(D * D))
      fail(fmt::format("the periodic cell has {} numbers, a {}D cell {}", p.cell.size(), D, D * D));
    for (double v : p.cell)
      if (!std::isfinite(v)) fail("the periodic cell has a non-finite vector component");
  }
  const Cell c = periodic_cell<D>(p);
  if (!(c.measure() > 0.0)) fail("the periodic cell's vectors span no area or volume");
  if (!p.cell.empty()) {  // the box is the cell's bounding box
    typename Cell::Vec lo = c.origin, hi = c.origin;
    for (int k = 1; k < (1 << D); ++k) {
      typename Cell::Vec corner = c.origin;
      for (int a = 0; a < D; ++a)
        if (k & (1 << a)) corner += c.h.col(a);
      lo = lo.cwiseMin(corner);
      hi = hi.cwiseMax(corner);
    }
    const double b_hi[3] = {p.box.x_max, p.box.y_max, p.box.z_max};
    const double scale = c.h.cwiseAbs().maxCoeff();
    const double b_lo[3] = {p.box.x_min, p.box.y_min, p.box.z_min};
    for (int a = 0; a < D; ++a)
      if (!(std::abs(lo[a] - b_lo[a]) <= 1e-9 * scale && std::abs(hi[a] - b_hi[a]) <= 1e-9 * scale))
        fail(fmt::format("the box is not the bounding box of the periodic cell along axis {} (cell from {:.9g} to "
                         "{:.9g}, box from {:.9g} to {:.9g})",
                         a, lo[a], hi[a], b_lo[a], b_hi[a]));
  }
  const typename Cell::Mat hinv = c.h.inverse();
  double rmax = 0.0;
  std::vector<double> pos(D * p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    typename Cell::Vec x;
    x[0] = p.x[i];
    x[1] = p.y[i];
    if constexpr (D == 3) x[2] = p.z[i];
    for (int a = 0; a < D; ++a) pos[D * i + static_cast<std::size_t>(a)] = x[a];
    const typename Cell::Vec s = hinv * (x - c.origin);
    for (int a = 0; a < D; ++a)
      if (!(s[a] >= -1e-9 && s[a] < 1.0 + 1e-9))
        fail(fmt::format("{} {} is outside the periodic cell (fractional coordinate {:.9g} along cell vector {})",
                         D == 3 ? "sphere" : "disk", i, s[a], a));
    rmax = std::max(rmax, p.r[i]);
  }
  if (!(c.min_width() >= 4.0 * rmax))
    fail(fmt::format("the periodic cell is {:.6g} wide, below 4 r_max = {:.6g}", c.min_width(), 4.0 * rmax));
  PeriodicPairsT<D> search;
  for (const auto& pr : search.find(pos, p.r, c, 0.0)) {
    const auto i = static_cast<std::size_t>(pr.i), j = static_cast<std::size_t>(pr.j);
    typename Cell::Vec d = c.image(pr.n);
    for (int a = 0; a < D; ++a) d[a] += pos[D * j + static_cast<std::size_t>(a)] - pos[D * i + static_cast<std::size_t>(a)];
    if (d.norm() < std::max(p.r[i], p.r[j]))
      fail(fmt::format("{}s {} and {} are too close through the periodic boundary: centre distance {:.6g} < max(r_i, "
                       "r_j) = {:.6g}",
                       D == 3 ? "sphere" : "disk", i, j, d.norm(), std::max(p.r[i], p.r[j])));
  }
}

template <int D>
std::vector<std::pair<int, int>> touching_pairs_periodic_d(const Packing& p, double tol) {
  using Cell = PeriodicCellT<D>;
  const Cell c = periodic_cell<D>(p);
  double rmax = 0.0;
  std::vector<double> pos(D * p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    pos[D * i] = p.x[i];
    pos[D * i + 1] = p.y[i];
    if constexpr (D == 3) pos[D * i + 2] = p.z[i];
    rmax = std::max(rmax, p.r[i]);
  }
  std::vector<std::pair<int, int>> out;
  PeriodicPairsT<D> search;
  for (const auto& pr : search.find(pos, p.r, c, 2.0 * rmax * tol)) {
    const auto i = static_cast<std::size_t>(pr.i), j = static_cast<std::size_t>(pr.j);
    typename Cell::Vec d = c.image(pr.n);
    for (int a = 0; a < D; ++a) d[a] += pos[D * j + static_cast<std::size_t>(a)] - pos[D * i + static_cast<std::size_t>(a)];
    if (d.norm() <= (p.r[i] + p.r[j]) * (1.0 + tol)) out.emplace_back(pr.i, pr.j);
  }
  return out;
}

}  // namespace

void validate_periodic(const Packing& p) {
  if (p.dim == 3)
    validate_periodic_d<3>(p);
  else
    validate_periodic_d<2>(p);
}

std::vector<std::pair<int, int>> touching_pairs_periodic(const Packing& p, double tol) {
  return p.dim == 3 ? touching_pairs_periodic_d<3>(p, tol) : touching_pairs_periodic_d<2>(p, tol);
}

template PeriodicCellT<2> periodic_cell<2>(const Packing&);
template PeriodicCellT<3> periodic_cell<3>(const Packing&);
template class PeriodicPairsT<2>;
template class PeriodicPairsT<3>;

}  // namespace netdem::packing
