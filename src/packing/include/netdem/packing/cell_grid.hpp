#pragma once
// Uniform cell grids over disk centres, the one neighbour search of the toolkit: the packing
// queries (packing.cpp), ballistic deposition and random fill (they insert as they place), the
// DEM's Verlet table (dynamic/solver.cpp, rebuilt often over the current positions) and the
// network solver's neighbour list.
//
// Two containers over one layout (GridLayout: square cells of side `cell`, `count[a]` cells
// along axis a from `origin[a]`; a coordinate outside maps to the nearest edge cell, NaN to cell
// 0, so every point and every query lands in some cell and nothing crashes):
//   * CellGrid: counting-sort (CSR) layout over a fixed point set; rebuild() reuses its storage,
//     so a warm grid rebuilt over the same number of points allocates nothing. The layout fits
//     the points' bounding box with cells of at least `min_cell`, doubled until there are at most
//     ~4 N cells (sparse sets stay cheap); a non-finite extent gives one cell.
//   * GrowingCellGrid: a fixed layout (given by the caller) into which points are inserted one by
//     one, for placement algorithms that query the points placed so far.
// Both visit the cells of a query rectangle row by row (axis 1 ascending), each row by column
// (axis 0 ascending), and the points of a cell in insertion (CellGrid: index) order.
//
// Correctness rule: for_each_near(x, y, reach, f) visits every point within distance `reach`
// of (x, y) (and others, the caller filters). For disks of radii up to r_max and a pair range of
// r_i + r_j + skin, query with reach = r_i + r_max + skin: any cell size is correct, a cell of
// 2 r_max + skin keeps the visit to 3 x 3 cells. The axis is an index (0 = x, 1 = y) so that the
// dimension can become a template parameter (issue 16, 3D).
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace netdem::packing {

struct GridLayout {
  static constexpr int kDim = 2;
  std::array<double, kDim> origin{0.0, 0.0};  ///< lower corner of cell (0, 0)
  double cell = 1.0;                          ///< side of a cell (> 0)
  std::array<long, kDim> count{1, 1};         ///< cells along each axis (>= 1)

  /// Cells of side >= min_cell over [lo, hi] (per axis), the side doubled until the total is at
  /// most max_cells; a non-finite extent (or min_cell not finite and > 0) gives one cell.
  static GridLayout fit(const std::array<double, kDim>& lo, const std::array<double, kDim>& hi, double min_cell,
                        double max_cells);

  long cells() const { return count[0] * count[1]; }
  /// Cell coordinate of v along `axis`, clamped to [0, count - 1]; NaN -> 0.
  long coord(int axis, double v) const {
    const double c = std::floor((v - origin[static_cast<std::size_t>(axis)]) / cell);
    const long n = count[static_cast<std::size_t>(axis)];
    if (!(c >= 0)) return 0;  // also NaN
    return c >= static_cast<double>(n - 1) ? n - 1 : static_cast<long>(c);
  }
  long index(long cx, long cy) const { return cy * count[0] + cx; }
  long index_of(double x, double y) const { return index(coord(0, x), coord(1, y)); }

  /// Calls f(cell index) for the cells overlapping [x_lo, x_hi] x [y_lo, y_hi], by rows.
  template <class F>
  void for_each_cell(double x_lo, double x_hi, double y_lo, double y_hi, F&& f) const {
    const long c0 = coord(0, x_lo), c1 = coord(0, x_hi), r0 = coord(1, y_lo), r1 = coord(1, y_hi);
    for (long r = r0; r <= r1; ++r)
      for (long c = c0; c <= c1; ++c) f(index(c, r));
  }
};

/// Static grid (CSR) over a point set; see the file comment.
class CellGrid {
 public:
  CellGrid() = default;
  CellGrid(std::span<const double> x, std::span<const double> y, double min_cell) { rebuild(x, y, min_cell); }

  /// Re-sorts the points (x[i], y[i]), i < x.size() (== y.size()), into cells of side >= min_cell
  /// (at most ~4 N + 64 cells). Reuses the storage of the previous build.
  void rebuild(std::span<const double> x, std::span<const double> y, double min_cell);

  /// Calls f(i) for every point in the cells overlapping the square of half side `reach` at (x, y).
  template <class F>
  void for_each_near(double x, double y, double reach, F&& f) const {
    for_each_in(x - reach, x + reach, y - reach, y + reach, f);
  }
  /// Calls f(i) for every point in the cells overlapping [x_lo, x_hi] x [y_lo, y_hi].
  template <class F>
  void for_each_in(double x_lo, double x_hi, double y_lo, double y_hi, F&& f) const {
    if (ids_.empty()) return;
    layout_.for_each_cell(x_lo, x_hi, y_lo, y_hi, [&](long cell) {
      const auto c = static_cast<std::size_t>(cell);
      for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) f(ids_[k]);
    });
  }

  const GridLayout& layout() const { return layout_; }
  std::size_t size() const { return ids_.size(); }

 private:
  GridLayout layout_;
  std::vector<std::uint32_t> start_;    ///< cells + 1 offsets into ids_
  std::vector<std::uint32_t> ids_;      ///< point indices sorted by cell (index order within a cell)
  std::vector<std::uint32_t> cell_of_;  ///< scratch: cell of each point
};

/// Grid with a fixed layout into which points are inserted one at a time; see the file comment.
class GrowingCellGrid {
 public:
  explicit GrowingCellGrid(const GridLayout& layout)
      : layout_(layout), cells_(static_cast<std::size_t>(layout.cells())) {}

  void insert(std::uint32_t id, double x, double y) {
    cells_[static_cast<std::size_t>(layout_.index_of(x, y))].push_back(id);
    ++size_;
  }
  /// The ids in cell (cx, cy) in insertion order (0 <= cx < count[0], 0 <= cy < count[1]).
  const std::vector<std::uint32_t>& cell(long cx, long cy) const {
    return cells_[static_cast<std::size_t>(layout_.index(cx, cy))];
  }
  template <class F>
  void for_each_near(double x, double y, double reach, F&& f) const {
    for_each_in(x - reach, x + reach, y - reach, y + reach, f);
  }
  template <class F>
  void for_each_in(double x_lo, double x_hi, double y_lo, double y_hi, F&& f) const {
    layout_.for_each_cell(x_lo, x_hi, y_lo, y_hi, [&](long c) {
      for (std::uint32_t id : cells_[static_cast<std::size_t>(c)]) f(id);
    });
  }
  /// Like for_each_near, but stops at the first f(id) that returns true; returns whether one did.
  template <class F>
  bool any_near(double x, double y, double reach, F&& f) const {
    const long c0 = layout_.coord(0, x - reach), c1 = layout_.coord(0, x + reach);
    const long r0 = layout_.coord(1, y - reach), r1 = layout_.coord(1, y + reach);
    for (long r = r0; r <= r1; ++r)
      for (long c = c0; c <= c1; ++c)
        for (std::uint32_t id : cell(c, r))
          if (f(id)) return true;
    return false;
  }

  const GridLayout& layout() const { return layout_; }
  std::size_t size() const { return size_; }

 private:
  GridLayout layout_;
  std::vector<std::vector<std::uint32_t>> cells_;
  std::size_t size_ = 0;
};

/// 3D static grid (CSR) over a fixed point set (x, y, z), the 3D form of CellGrid for the packing
/// queries of 3D packings (issue 16): cubic cells of side >= min_cell fitted to the bounding box,
/// the side doubled until there are at most 4 N + 64 cells; coordinates outside map to the nearest
/// edge cell, a non-finite extent gives one cell. for_each_near(x, y, z, reach, f) visits every
/// point within `reach` of (x, y, z) (and others, the caller filters), cells by z, then y, then x,
/// points of a cell in index order.
class CellGrid3 {
 public:
  CellGrid3() = default;
  CellGrid3(std::span<const double> x, std::span<const double> y, std::span<const double> z, double min_cell) {
    rebuild(x, y, z, min_cell);
  }
  void rebuild(std::span<const double> x, std::span<const double> y, std::span<const double> z, double min_cell);

  template <class F>
  void for_each_near(double x, double y, double z, double reach, F&& f) const {
    if (ids_.empty()) return;
    const long x0 = coord(0, x - reach), x1 = coord(0, x + reach);
    const long y0 = coord(1, y - reach), y1 = coord(1, y + reach);
    const long z0 = coord(2, z - reach), z1 = coord(2, z + reach);
    for (long c = z0; c <= z1; ++c)
      for (long b = y0; b <= y1; ++b)
        for (long a = x0; a <= x1; ++a) {
          const auto cell = static_cast<std::size_t>((c * count_[1] + b) * count_[0] + a);
          for (std::uint32_t k = start_[cell]; k < start_[cell + 1]; ++k) f(ids_[k]);
        }
  }
  long coord(int axis, double v) const {
    const auto a = static_cast<std::size_t>(axis);
    const double c = std::floor((v - origin_[a]) / cell_);
    if (!(c >= 0)) return 0;
    return c >= static_cast<double>(count_[a] - 1) ? count_[a] - 1 : static_cast<long>(c);
  }
  long cells() const { return count_[0] * count_[1] * count_[2]; }
  std::size_t size() const { return ids_.size(); }

 private:
  std::array<double, 3> origin_{0.0, 0.0, 0.0};
  double cell_ = 1.0;
  std::array<long, 3> count_{1, 1, 1};
  std::vector<std::uint32_t> start_, ids_, cell_of_;
};

}  // namespace netdem::packing
