#pragma once
// Periodic cells (issue 29): the cell of a periodic packing, and the neighbour search across its
// boundary, in 2D and 3D (the dimension D a template parameter).
//
// A cell is a parallelogram (parallelepiped) with lower corner `origin` and the cell vectors as
// the columns of `h`; a point x has fractional coordinates s = h^-1 (x - origin), and is inside
// the cell for 0 <= s_a < 1. The images of x are x + h n for integer n. A solver keeps its
// positions unwrapped (particles move continuously, never remapped) and stores with each pair
// (i, j) the image n of j it interacts with: the branch vector is x_j + h n - x_i. Under a
// deformation F of the cell (h -> F h), that branch vector moves with the particles and the cell,
// so the stored image stays right as long as the pair table is rebuilt before a particle moves
// half a cell.
//
// The search (PeriodicPairsT) bins the wrapped centres into a grid over fractional coordinates
// with m_a = floor(w_a / range) cells along axis a (w_a the cell's width across axis a, range the
// largest interaction distance) and visits the 3^D neighbour cells with wrap-around: a pair
// within `range` differs by at most w_a^-1 range <= 1 / m_a in s_a, hence by at most one cell.
// With m_a < 3 the same cell is reached through two wraps; each (cell, wrap) is visited once, so
// every image within range is seen once. The cell must be at least 2 range wide across every
// axis, so that a pair is within range through one image at most and no particle meets its own.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

namespace netdem::packing {

struct Packing;

template <int D>
struct PeriodicCellT {
  static_assert(D == 2 || D == 3, "cells are 2D or 3D");
  using Mat = Eigen::Matrix<double, D, D>;
  using Vec = Eigen::Matrix<double, D, 1>;
  using Shift = std::array<int, D>;

  Mat h = Mat::Identity();  ///< the cell vectors (columns)
  Vec origin = Vec::Zero();  ///< the lower corner

  /// |det h|: the cell's area (2D) or volume (3D).
  double measure() const { return std::abs(h.determinant()); }
  /// The cell's width across axis a (the distance between the two faces s_a = 0 and s_a = 1).
  double width(int a) const { return 1.0 / h.inverse().row(a).norm(); }
  double min_width() const {
    double w = width(0);
    for (int a = 1; a < D; ++a) w = std::min(w, width(a));
    return w;
  }
  Vec fractional(const Vec& x) const { return h.inverse() * (x - origin); }
  /// The offset of image n: h n.
  Vec image(const Shift& n) const {
    Vec s;
    for (int a = 0; a < D; ++a) s[a] = n[static_cast<std::size_t>(a)];
    return h * s;
  }
  /// x moved into the cell by a whole image (0 <= s_a < 1 up to rounding).
  Vec wrap(const Vec& x) const {
    Vec s = fractional(x);
    for (int a = 0; a < D; ++a) s[a] -= std::floor(s[a]);
    return origin + h * s;
  }
  /// The same cell deformed by F (h -> F h, origin -> F origin).
  PeriodicCellT deformed(const Mat& F) const { return PeriodicCellT{F * h, F * origin}; }
};

/// The cell of a periodic packing (Packing::periodic) of dimension D: the box's lower corner and
/// the box's edges, or the vectors of its '# cell' line. Throws std::invalid_argument (one line)
/// for a packing that is not periodic or of another dimension.
template <int D>
PeriodicCellT<D> periodic_cell(const Packing& p);

/// The periodic part of validate() (packing.hpp): the cell numbers, every centre in the cell, the
/// cell at least 4 r_max wide, no pair closer than max(r_i, r_j) through an image. Throws
/// std::invalid_argument ("invalid packing: ...", one line).
void validate_periodic(const Packing& p);

/// touching_pairs() of a periodic packing: each pair once, through its nearest image.
std::vector<std::pair<int, int>> touching_pairs_periodic(const Packing& p, double tol);

/// The pairs within range across a periodic cell; storage reused across searches.
template <int D>
class PeriodicPairsT {
 public:
  using Cell = PeriodicCellT<D>;
  using Shift = typename Cell::Shift;
  struct Pair {
    int i, j;   ///< i < j
    Shift n;    ///< the image of j: branch x_j + h n - x_i (unwrapped positions)
  };

  /// Every pair i < j (and image n) whose centre distance is below r_i + r_j + extra. `pos` holds
  /// D coordinates per particle (unwrapped), `r` the radii. Throws std::invalid_argument (one
  /// line) if the cell is narrower than 2 (2 r_max + extra) across some axis, or a position or the
  /// cell is not finite. The pairs are sorted by (i, j).
  const std::vector<Pair>& find(std::span<const double> pos, std::span<const double> r, const Cell& cell, double extra);
  /// Heap bytes held (the vectors' capacities).
  std::size_t memory_bytes() const {
    return sizeof(Pair) * pairs_.capacity() + sizeof(double) * s_.capacity() + sizeof(int) * wrap_.capacity() +
           sizeof(std::uint32_t) * (start_.capacity() + ids_.capacity() + cell_of_.capacity() + fill_.capacity());
  }

 private:
  std::vector<Pair> pairs_;
  std::vector<double> s_;            ///< wrapped fractional coordinates, D per particle
  std::vector<int> wrap_;            ///< the whole images that wrapped them, D per particle
  std::vector<std::uint32_t> start_, ids_, cell_of_, fill_;
};

using PeriodicCell = PeriodicCellT<2>;
using PeriodicCell3 = PeriodicCellT<3>;

}  // namespace netdem::packing
