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

}  // namespace netdem::packing
