#pragma once
// Private helper: uniform cell grids over disk centres (not installed, not part of the API).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace netdem::packing::detail {

/// Immutable grid (counting-sort / CSR layout) over a fixed set of points. Cells are at least
/// `min_cell` wide; the cell count is capped at ~4 N so that very sparse sets stay cheap.
class StaticGrid {
 public:
  StaticGrid(const std::vector<double>& x, const std::vector<double>& y, double min_cell) {
    const std::size_t n = x.size();
    if (n == 0) return;
    const auto [xlo, xhi] = std::minmax_element(x.begin(), x.end());
    const auto [ylo, yhi] = std::minmax_element(y.begin(), y.end());
    x0_ = *xlo;
    y0_ = *ylo;
    const double ex = *xhi - x0_, ey = *yhi - y0_;
    cell_ = min_cell > 0 && std::isfinite(min_cell) ? min_cell : 1.0;
    const double cap = 4.0 * static_cast<double>(n) + 64.0;
    if (!std::isfinite(ex) || !std::isfinite(ey)) {  // NaN/inf coordinates: one cell, still correct
      nx_ = ny_ = 1;
    }
    while (nx_ == 0) {
      const double cx = std::floor(ex / cell_) + 1.0, cy = std::floor(ey / cell_) + 1.0;
      if (cx * cy <= cap) {
        nx_ = static_cast<long>(cx);
        ny_ = static_cast<long>(cy);
        break;
      }
      cell_ *= 2.0;
    }
    start_.assign(static_cast<std::size_t>(nx_ * ny_) + 1, 0);
    std::vector<long> cell_of(n);
    for (std::size_t i = 0; i < n; ++i) {
      cell_of[i] = index(col(x[i]), row(y[i]));
      ++start_[static_cast<std::size_t>(cell_of[i]) + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    ids_.resize(n);
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) ids_[fill[static_cast<std::size_t>(cell_of[i])]++] = static_cast<int>(i);
  }

  /// Calls f(id) for every point in the cells overlapping [x - reach, x + reach] x [y - reach, y + reach].
  template <class F>
  void for_each_near(double x, double y, double reach, F&& f) const {
    for_each_in(x - reach, x + reach, y - reach, y + reach, f);
  }

  /// Calls f(id) for every point in the cells overlapping [x_lo, x_hi] x [y_lo, y_hi].
  template <class F>
  void for_each_in(double x_lo, double x_hi, double y_lo, double y_hi, F&& f) const {
    if (ids_.empty()) return;
    const long c0 = col(x_lo), c1 = col(x_hi), r0 = row(y_lo), r1 = row(y_hi);
    for (long r = r0; r <= r1; ++r)
      for (long c = c0; c <= c1; ++c) {
        const std::size_t cell = static_cast<std::size_t>(index(c, r));
        for (std::size_t k = start_[cell]; k < start_[cell + 1]; ++k) f(ids_[k]);
      }
  }

 private:
  long clampi(double v, long n) const {
    if (!(v >= 0)) return 0;  // also NaN
    return v >= static_cast<double>(n - 1) ? n - 1 : static_cast<long>(v);
  }
  long col(double x) const { return clampi(std::floor((x - x0_) / cell_), nx_); }
  long row(double y) const { return clampi(std::floor((y - y0_) / cell_), ny_); }
  long index(long c, long r) const { return r * nx_ + c; }

  double x0_ = 0, y0_ = 0, cell_ = 1;
  long nx_ = 0, ny_ = 0;
  std::vector<std::size_t> start_;
  std::vector<int> ids_;
};

}  // namespace netdem::packing::detail
