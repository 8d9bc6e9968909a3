#pragma once
// Uniform cell grids over particle centres, the one neighbour search of the toolkit, in 2D and 3D
// (the dimension D a template parameter): the packing queries (packing.cpp), ballistic deposition
// in 2D and 3D and the random fills (they insert as they place), the DEM's Verlet table
// (dynamic/solver.cpp, rebuilt often over the current positions), the network solver's neighbour
// list and the staggered scheme's contact detection.
//
// Two containers over one layout (GridLayoutT<D>: box-shaped cells of side `cell[a]` along axis a,
// `count[a]` cells from `origin[a]`; a coordinate outside maps to the nearest edge cell, NaN to
// cell 0, so every point and every query lands in some cell and nothing crashes):
//   * CellGridT<D>: counting-sort (CSR) layout over a fixed point set; rebuild() reuses its
//     storage, so a warm grid rebuilt over the same number of points allocates nothing. The layout
//     fits the points' bounding box with cubic cells of at least `min_cell`, doubled until there
//     are at most 4 N + 64 cells (sparse sets stay cheap); a non-finite extent gives one cell.
//   * GrowingCellGridT<D>: a fixed layout (given by the caller) into which points are inserted one
//     by one, for placement algorithms that query the points placed so far.
// Both visit the cells of a query box with axis 0 fastest and the last axis slowest (2D: rows by
// y, each row by x; 3D: layers by z, then y, then x), and the points of a cell in insertion
// (CellGridT: index) order. The cell index is ((c[D-1] count[D-2] + ...) count[0] + c[0]).
//
// Correctness rule: for_each_near(p, reach, f) visits every point within distance `reach` of p
// (and others, the caller filters). For particles of radii up to r_max and a pair range of
// r_i + r_j + skin, query with reach = r_i + r_max + skin: any cell size is correct, a cell of
// 2 r_max + skin keeps the visit to 3^D cells.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

namespace netdem::packing {

template <int D>
struct GridLayoutT {
  static_assert(D == 2 || D == 3, "grids are 2D or 3D");
  static constexpr int kDim = D;
  using Point = std::array<double, D>;
  using Cell = std::array<long, D>;
  Point origin{};  ///< lower corner of cell (0, ..., 0)
  Point cell = filled(1.0);  ///< side of a cell along each axis (> 0)
  Cell count = filled_long(1);  ///< cells along each axis (>= 1)

  /// Cubic cells of side >= min_cell over [lo, hi] (per axis), the side doubled until the total
  /// is at most max_cells; a non-finite extent (or min_cell not finite and > 0) gives one cell.
  static GridLayoutT fit(const Point& lo, const Point& hi, double min_cell, double max_cells);

  long cells() const {
    long n = 1;
    for (long c : count) n *= c;
    return n;
  }
  /// Cell coordinate of v along `axis`, clamped to [0, count - 1]; NaN -> 0.
  long coord(int axis, double v) const {
    const auto a = static_cast<std::size_t>(axis);
    const double c = std::floor((v - origin[a]) / cell[a]);
    const long n = count[a];
    if (!(c >= 0)) return 0;  // also NaN
    return c >= static_cast<double>(n - 1) ? n - 1 : static_cast<long>(c);
  }
  long index(const Cell& c) const {
    long k = c[D - 1];
    for (int a = D - 2; a >= 0; --a) k = k * count[static_cast<std::size_t>(a)] + c[static_cast<std::size_t>(a)];
    return k;
  }
  Cell cell_of(const Point& p) const {
    Cell c{};
    for (int a = 0; a < D; ++a) c[static_cast<std::size_t>(a)] = coord(a, p[static_cast<std::size_t>(a)]);
    return c;
  }
  long index_of(const Point& p) const { return index(cell_of(p)); }

  /// Calls f(cell index) for the cells overlapping the box [lo, hi], the last axis slowest; stops
  /// early and returns true as soon as f returns true (f returning void never stops).
  template <class F>
  bool for_each_cell(const Point& lo, const Point& hi, F&& f) const {
    const Cell c0 = cell_of(lo), c1 = cell_of(hi);
    return visit<D - 1>(c0, c1, 0, f);
  }

 private:
  static constexpr Point filled(double v) {
    Point p{};
    for (auto& x : p) x = v;
    return p;
  }
  static constexpr Cell filled_long(long v) {
    Cell p{};
    for (auto& x : p) x = v;
    return p;
  }
  template <int A, class F>
  bool visit(const Cell& c0, const Cell& c1, long base, F& f) const {
    constexpr auto a = static_cast<std::size_t>(A);
    for (long c = c0[a]; c <= c1[a]; ++c) {
      const long k = base * count[a] + c;
      if constexpr (A == 0) {
        if constexpr (std::is_same_v<decltype(f(k)), bool>) {
          if (f(k)) return true;
        } else {
          f(k);
        }
      } else {
        if (visit<A - 1>(c0, c1, k, f)) return true;
      }
    }
    return false;
  }
};

/// Static grid (CSR) over a point set; see the file comment.
template <int D>
class CellGridT {
 public:
  using Layout = GridLayoutT<D>;
  using Point = typename Layout::Point;
  using Axes = std::array<std::span<const double>, D>;

  CellGridT() = default;
  CellGridT(const Axes& axes, double min_cell) { rebuild(axes, min_cell); }
  CellGridT(std::span<const double> x, std::span<const double> y, double min_cell)
    requires(D == 2)
  {
    rebuild(Axes{x, y}, min_cell);
  }
  CellGridT(std::span<const double> x, std::span<const double> y, std::span<const double> z, double min_cell)
    requires(D == 3)
  {
    rebuild(Axes{x, y, z}, min_cell);
  }

  /// Re-sorts the points (axes[0][i], axes[1][i], ...), i < axes[0].size() (all the same size),
  /// into cells of side >= min_cell (at most 4 N + 64 cells). Reuses the previous build's storage.
  void rebuild(const Axes& axes, double min_cell);
  void rebuild(std::span<const double> x, std::span<const double> y, double min_cell)
    requires(D == 2)
  {
    rebuild(Axes{x, y}, min_cell);
  }
  void rebuild(std::span<const double> x, std::span<const double> y, std::span<const double> z, double min_cell)
    requires(D == 3)
  {
    rebuild(Axes{x, y, z}, min_cell);
  }

  /// Calls f(i) for every point in the cells overlapping the cube of half side `reach` at p.
  template <class F>
  void for_each_near(const Point& p, double reach, F&& f) const {
    Point lo = p, hi = p;
    for (std::size_t a = 0; a < D; ++a) lo[a] -= reach, hi[a] += reach;
    for_each_in(lo, hi, f);
  }
  template <class F>
  void for_each_near(double x, double y, double reach, F&& f) const
    requires(D == 2)
  {
    for_each_near(Point{x, y}, reach, f);
  }
  template <class F>
  void for_each_near(double x, double y, double z, double reach, F&& f) const
    requires(D == 3)
  {
    for_each_near(Point{x, y, z}, reach, f);
  }
  /// Calls f(i) for every point in the cells overlapping the box [lo, hi].
  template <class F>
  void for_each_in(const Point& lo, const Point& hi, F&& f) const {
    if (ids_.empty()) return;
    layout_.for_each_cell(lo, hi, [&](long cell) {
      const auto c = static_cast<std::size_t>(cell);
      for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) f(ids_[k]);
    });
  }
  template <class F>
  void for_each_in(double x_lo, double x_hi, double y_lo, double y_hi, F&& f) const
    requires(D == 2)
  {
    for_each_in(Point{x_lo, y_lo}, Point{x_hi, y_hi}, f);
  }

  const Layout& layout() const { return layout_; }
  std::size_t size() const { return ids_.size(); }
  /// Heap bytes held (the vectors' capacities).
  std::size_t memory_bytes() const {
    return sizeof(std::uint32_t) * (start_.capacity() + ids_.capacity() + cell_of_.capacity());
  }

 private:
  Layout layout_;
  std::vector<std::uint32_t> start_;    ///< cells + 1 offsets into ids_
  std::vector<std::uint32_t> ids_;      ///< point indices sorted by cell (index order within a cell)
  std::vector<std::uint32_t> cell_of_;  ///< scratch: cell of each point
};

/// Grid with a fixed layout into which points are inserted one at a time; see the file comment.
template <int D>
class GrowingCellGridT {
 public:
  using Layout = GridLayoutT<D>;
  using Point = typename Layout::Point;

  explicit GrowingCellGridT(const Layout& layout)
      : layout_(layout), cells_(static_cast<std::size_t>(layout.cells())) {}

  void insert(std::uint32_t id, const Point& p) {
    cells_[static_cast<std::size_t>(layout_.index_of(p))].push_back(id);
    ++size_;
  }
  void insert(std::uint32_t id, double x, double y)
    requires(D == 2)
  {
    insert(id, Point{x, y});
  }
  void insert(std::uint32_t id, double x, double y, double z)
    requires(D == 3)
  {
    insert(id, Point{x, y, z});
  }
  /// The ids in the cell of index k (layout().index(...)) in insertion order.
  const std::vector<std::uint32_t>& cell(long k) const { return cells_[static_cast<std::size_t>(k)]; }
  /// The ids in cell (cx, cy) in insertion order (0 <= cx < count[0], 0 <= cy < count[1]).
  const std::vector<std::uint32_t>& cell(long cx, long cy) const
    requires(D == 2)
  {
    return cell(layout_.index({cx, cy}));
  }
  template <class F>
  void for_each_near(const Point& p, double reach, F&& f) const {
    Point lo = p, hi = p;
    for (std::size_t a = 0; a < D; ++a) lo[a] -= reach, hi[a] += reach;
    for_each_in(lo, hi, f);
  }
  template <class F>
  void for_each_near(double x, double y, double reach, F&& f) const
    requires(D == 2)
  {
    for_each_near(Point{x, y}, reach, f);
  }
  template <class F>
  void for_each_in(const Point& lo, const Point& hi, F&& f) const {
    layout_.for_each_cell(lo, hi, [&](long c) {
      for (std::uint32_t id : cells_[static_cast<std::size_t>(c)]) f(id);
    });
  }
  template <class F>
  void for_each_in(double x_lo, double x_hi, double y_lo, double y_hi, F&& f) const
    requires(D == 2)
  {
    for_each_in(Point{x_lo, y_lo}, Point{x_hi, y_hi}, f);
  }
  /// Like for_each_near, but stops at the first f(id) that returns true; returns whether one did.
  template <class F>
  bool any_near(const Point& p, double reach, F&& f) const {
    Point lo = p, hi = p;
    for (std::size_t a = 0; a < D; ++a) lo[a] -= reach, hi[a] += reach;
    return layout_.for_each_cell(lo, hi, [&](long c) -> bool {
      for (std::uint32_t id : cells_[static_cast<std::size_t>(c)])
        if (f(id)) return true;
      return false;
    });
  }
  template <class F>
  bool any_near(double x, double y, double reach, F&& f) const
    requires(D == 2)
  {
    return any_near(Point{x, y}, reach, f);
  }
  template <class F>
  bool any_near(double x, double y, double z, double reach, F&& f) const
    requires(D == 3)
  {
    return any_near(Point{x, y, z}, reach, f);
  }

  const Layout& layout() const { return layout_; }
  std::size_t size() const { return size_; }

 private:
  Layout layout_;
  std::vector<std::vector<std::uint32_t>> cells_;
  std::size_t size_ = 0;
};

using GridLayout = GridLayoutT<2>;
using GridLayout3 = GridLayoutT<3>;
using CellGrid = CellGridT<2>;
using CellGrid3 = CellGridT<3>;
using GrowingCellGrid = GrowingCellGridT<2>;
using GrowingCellGrid3 = GrowingCellGridT<3>;

// fit() and rebuild() are defined in cell_grid.cpp for D = 2 and 3.

}  // namespace netdem::packing
