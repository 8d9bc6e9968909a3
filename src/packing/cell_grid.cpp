// Cell grids: the layout fit and the counting-sort rebuild (netdem/packing/cell_grid.hpp).
#include "netdem/packing/cell_grid.hpp"

#include <algorithm>
#include <cassert>

namespace netdem::packing {

template <int D>
GridLayoutT<D> GridLayoutT<D>::fit(const Point& lo, const Point& hi, double min_cell, double max_cells) {
  GridLayoutT g;
  g.origin = lo;
  const double side0 = min_cell > 0 && std::isfinite(min_cell) ? min_cell : 1.0;
  g.cell = filled(side0);
  Point extent{};
  for (std::size_t a = 0; a < D; ++a) {
    extent[a] = hi[a] - lo[a];
    if (!std::isfinite(extent[a]) || !std::isfinite(lo[a])) {  // NaN/inf: one cell, still correct
      g.origin = Point{};
      g.count = filled_long(1);
      return g;
    }
  }
  double side = side0;
  for (;;) {
    double total = 1.0;
    Point n{};
    for (std::size_t a = 0; a < D; ++a) {
      n[a] = std::floor(extent[a] / side) + 1.0;
      total *= n[a];
    }
    if (total <= max_cells) {
      for (std::size_t a = 0; a < D; ++a) g.count[a] = static_cast<long>(n[a]);
      g.cell = filled(side);
      return g;
    }
    side *= 2.0;
  }
}

template <int D>
void CellGridT<D>::rebuild(const Axes& axes, double min_cell) {
  const std::size_t n = axes[0].size();
  for ([[maybe_unused]] const auto& s : axes) assert(s.size() == n);
  ids_.resize(n);
  if (n == 0) {
    start_.assign(2, 0);
    layout_ = Layout{};
    return;
  }
  Point lo{}, hi{};
  for (std::size_t a = 0; a < D; ++a) {
    const auto [mn, mx] = std::minmax_element(axes[a].begin(), axes[a].end());
    lo[a] = *mn;
    hi[a] = *mx;
  }
  layout_ = Layout::fit(lo, hi, min_cell, 4.0 * static_cast<double>(n) + 64.0);
  const auto cells = static_cast<std::size_t>(layout_.cells());
  start_.assign(cells + 1, 0);
  cell_of_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Point p;
    for (std::size_t a = 0; a < D; ++a) p[a] = axes[a][i];
    cell_of_[i] = static_cast<std::uint32_t>(layout_.index_of(p));
    ++start_[cell_of_[i]];
  }
  for (std::size_t c = 1; c < cells; ++c) start_[c] += start_[c - 1];  // start_[c] = end of cell c
  start_[cells] = static_cast<std::uint32_t>(n);
  // fill each cell's run from its end, points in descending order: start_[c] ends at the run's
  // beginning and the run holds its points in ascending order
  for (std::size_t i = n; i-- > 0;) ids_[--start_[cell_of_[i]]] = static_cast<std::uint32_t>(i);
}

template struct GridLayoutT<2>;
template struct GridLayoutT<3>;
// rebuild() only: an explicit instantiation of the whole class would also instantiate the members
// constrained to the other dimension with clang 14
template void CellGridT<2>::rebuild(const CellGridT<2>::Axes&, double);
template void CellGridT<3>::rebuild(const CellGridT<3>::Axes&, double);

}  // namespace netdem::packing
