// Cell grids: the layout fit and the counting-sort rebuild (netdem/packing/cell_grid.hpp).
#include "netdem/packing/cell_grid.hpp"

#include <algorithm>
#include <cassert>

namespace netdem::packing {

GridLayout GridLayout::fit(const std::array<double, kDim>& lo, const std::array<double, kDim>& hi, double min_cell,
                           double max_cells) {
  GridLayout g;
  g.origin = lo;
  g.cell = min_cell > 0 && std::isfinite(min_cell) ? min_cell : 1.0;
  std::array<double, kDim> extent{};
  for (std::size_t a = 0; a < kDim; ++a) {
    extent[a] = hi[a] - lo[a];
    if (!std::isfinite(extent[a]) || !std::isfinite(lo[a])) {  // NaN/inf: one cell, still correct
      g.origin = {0.0, 0.0};
      g.count = {1, 1};
      return g;
    }
  }
  for (;;) {
    double total = 1.0;
    std::array<double, kDim> n{};
    for (std::size_t a = 0; a < kDim; ++a) {
      n[a] = std::floor(extent[a] / g.cell) + 1.0;
      total *= n[a];
    }
    if (total <= max_cells) {
      for (std::size_t a = 0; a < kDim; ++a) g.count[a] = static_cast<long>(n[a]);
      return g;
    }
    g.cell *= 2.0;
  }
}

void CellGrid::rebuild(std::span<const double> x, std::span<const double> y, double min_cell) {
  assert(x.size() == y.size());
  const std::size_t n = x.size();
  ids_.resize(n);
  if (n == 0) {
    start_.assign(2, 0);
    layout_ = GridLayout{};
    return;
  }
  const auto [xlo, xhi] = std::minmax_element(x.begin(), x.end());
  const auto [ylo, yhi] = std::minmax_element(y.begin(), y.end());
  layout_ = GridLayout::fit({*xlo, *ylo}, {*xhi, *yhi}, min_cell, 4.0 * static_cast<double>(n) + 64.0);
  const auto cells = static_cast<std::size_t>(layout_.cells());
  start_.assign(cells + 1, 0);
  cell_of_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cell_of_[i] = static_cast<std::uint32_t>(layout_.index_of(x[i], y[i]));
    ++start_[cell_of_[i]];
  }
  for (std::size_t c = 1; c < cells; ++c) start_[c] += start_[c - 1];  // start_[c] = end of cell c
  start_[cells] = static_cast<std::uint32_t>(n);
  // fill each cell's run from its end, points in descending order: start_[c] ends at the run's
  // beginning and the run holds its points in ascending order
  for (std::size_t i = n; i-- > 0;) ids_[--start_[cell_of_[i]]] = static_cast<std::uint32_t>(i);
}

void CellGrid3::rebuild(std::span<const double> x, std::span<const double> y, std::span<const double> z, double min_cell) {
  assert(x.size() == y.size() && x.size() == z.size());
  const std::size_t n = x.size();
  ids_.resize(n);
  origin_ = {0.0, 0.0, 0.0};
  count_ = {1, 1, 1};
  cell_ = min_cell > 0 && std::isfinite(min_cell) ? min_cell : 1.0;
  if (n == 0) {
    start_.assign(2, 0);
    return;
  }
  const std::span<const double> axes[3] = {x, y, z};
  std::array<double, 3> lo{}, extent{};
  bool finite = true;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto [mn, mx] = std::minmax_element(axes[a].begin(), axes[a].end());
    lo[a] = *mn;
    extent[a] = *mx - *mn;
    finite = finite && std::isfinite(lo[a]) && std::isfinite(extent[a]);
  }
  if (finite) {
    origin_ = lo;
    const double max_cells = 4.0 * static_cast<double>(n) + 64.0;
    for (;;) {
      double total = 1.0;
      std::array<double, 3> c{};
      for (std::size_t a = 0; a < 3; ++a) {
        c[a] = std::floor(extent[a] / cell_) + 1.0;
        total *= c[a];
      }
      if (total <= max_cells) {
        for (std::size_t a = 0; a < 3; ++a) count_[a] = static_cast<long>(c[a]);
        break;
      }
      cell_ *= 2.0;
    }
  }
  const auto cells = static_cast<std::size_t>(this->cells());
  start_.assign(cells + 1, 0);
  cell_of_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cell_of_[i] = static_cast<std::uint32_t>((coord(2, z[i]) * count_[1] + coord(1, y[i])) * count_[0] + coord(0, x[i]));
    ++start_[cell_of_[i]];
  }
  for (std::size_t c = 1; c < cells; ++c) start_[c] += start_[c - 1];
  start_[cells] = static_cast<std::uint32_t>(n);
  for (std::size_t i = n; i-- > 0;) ids_[--start_[cell_of_[i]]] = static_cast<std::uint32_t>(i);
}

}  // namespace netdem::packing
