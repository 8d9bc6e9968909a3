#pragma once
// The rows of a contact table in dimension D (issue 26): one row per neighbour pair, keys i < j
// sorted by (i, j), and per row the periodic image of j. find() takes every pair whose centres are
// closer than r_i + r_j + skin, over one cell grid (packing::CellGridT<D>) or through the images of
// a periodic cell (packing::PeriodicPairsT<D>), and remembers for every new row the old row it
// continues, so that a solver carries its per-row data (histories and all) with carry().
//
// Both solvers stand on it: the network solver through sys::ContactTable (contact_table.hpp: the
// law's committed history per row, its lifecycle and the rebuild trigger), the explicit DEM
// directly (its histories are one table per law, carried by carry()).
//
// Periodic cells (issue 29): a row keeps the image n of j: the branch is x_j + h n - x_i with h the
// current cell vectors. Positions stay unwrapped, so a row's image never changes while the row
// lives; without a cell every shift is zero.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "netdem/packing/cell_grid.hpp"
#include "netdem/packing/periodic.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::sys {

template <int D>
class PairRows {
 public:
  static constexpr int kDim = D;
  using Shift = std::array<int, D>;
  std::vector<int> pi, pj;   ///< the rows' particles, i < j, sorted by (i, j)
  std::vector<Shift> shift;  ///< the image of j per row (periodic cells; else zero)

  std::size_t pairs() const { return pi.size(); }
  /// Heap bytes held by the rows (pi, pj, shift) and by the search's scratch (capacities).
  std::size_t row_bytes() const {
    return sizeof(int) * (pi.capacity() + pj.capacity()) + sizeof(Shift) * shift.capacity();
  }
  std::size_t scratch_bytes() const {
    std::size_t b = sizeof(int) * from_.capacity() + sizeof(std::uint64_t) * found_.capacity();
    for (const auto& a : axes_) b += sizeof(double) * a.capacity();
    return b + grid_.memory_bytes() + periodic_.memory_bytes();
  }

  /// New rows: every pair with |x_j (+ h n) - x_i| < r_i + r_j + skin (radii up to r_max; `cell`,
  /// if given, the current periodic cell: the pairs through its images), merged with the old rows
  /// (carried_from()).
  void find(const ParticleSet<D>& ps, double skin, double r_max, const packing::PeriodicCellT<D>* cell = nullptr) {
    found_.clear();
    if (cell) {
      const auto& pairs = periodic_.find(ps.pos, ps.r, *cell, skin);  // sorted by (i, j)
      for (const auto& pr : pairs) found_.push_back(key(pr.i, pr.j));
      shift.resize(pairs.size());
      for (std::size_t k = 0; k < pairs.size(); ++k) shift[k] = pairs[k].n;
    } else {
      find_pairs(ps, skin, r_max);
      shift.assign(found_.size(), Shift{});
    }
    from_.assign(found_.size(), -1);  // merge with the old rows (both sorted)
    std::size_t o = 0;
    for (std::size_t k = 0; k < found_.size(); ++k) {
      while (o < pi.size() && key(pi[o], pj[o]) < found_[k]) ++o;
      if (o < pi.size() && key(pi[o], pj[o]) == found_[k]) from_[k] = static_cast<int>(o);
    }
    pi.resize(found_.size());
    pj.resize(found_.size());
    for (std::size_t k = 0; k < found_.size(); ++k) {
      pi[k] = static_cast<int>(found_[k] >> 32);
      pj[k] = static_cast<int>(found_[k] & 0xffffffffu);
    }
  }

  /// Rows set as they are (a restart: the pairs of a state, sorted by (i, j), zero shifts); the
  /// next find() carries them.
  void assign(std::vector<int> i, std::vector<int> j) {
    pi = std::move(i);
    pj = std::move(j);
    shift.assign(pi.size(), Shift{});
    from_.clear();
  }

  /// Per-row data of the solver after find(): the value of the old row a new row continues,
  /// `fresh` for a new pair.
  template <class T>
  void carry(std::vector<T>& v, const T& fresh) const {
    std::vector<T> out;
    carry(v, fresh, out);
  }
  /// The same with a scratch vector whose storage is kept (no allocation once it is large enough).
  template <class T>
  void carry(std::vector<T>& v, const T& fresh, std::vector<T>& scratch) const {
    scratch.assign(from_.size(), fresh);
    for (std::size_t k = 0; k < from_.size(); ++k)
      if (from_[k] >= 0) scratch[k] = v[static_cast<std::size_t>(from_[k])];
    v.swap(scratch);
  }
  /// Per new row: the old row it continues, -1 for a new pair (the last find()).
  const std::vector<int>& carried_from() const { return from_; }

  /// The key of pair (i, j): i in the high half, so that keys sort as (i, j) (the DEM's state
  /// names its rows by it).
  static std::uint64_t key(int i, int j) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) | static_cast<std::uint32_t>(j);
  }

 private:
  /// found_ = every pair within r_i + r_j + skin over the cell grid, sorted.
  void find_pairs(const ParticleSet<D>& ps, double skin, double r_max) {
    const std::size_t n = ps.size();
    if (n < 2) return;
    for (std::size_t a = 0; a < D; ++a) {  // the grid reads the centres by axis (storage reused)
      axes_[a].resize(n);
      for (std::size_t p = 0; p < n; ++p) axes_[a][p] = ps.pos[D * p + a];
    }
    typename packing::CellGridT<D>::Axes spans;
    for (std::size_t a = 0; a < D; ++a) spans[a] = axes_[a];
    grid_.rebuild(spans, 2.0 * r_max + skin);  // cell side >= the largest range: 3^D cells per query
    found_.reserve(pi.size() + n);
    const double* const x = ps.pos.data();
    for (std::size_t p = 0; p < n; ++p) {
      typename packing::CellGridT<D>::Point at;
      for (std::size_t a = 0; a < D; ++a) at[a] = x[D * p + a];
      const double rp = ps.r[p];
      grid_.for_each_near(at, rp + r_max + skin, [&](std::uint32_t q) {
        if (q <= p) return;
        const double dx = x[D * q] - at[0], dy = x[D * q + 1] - at[1];
        double d2 = dx * dx + dy * dy;
        if constexpr (D == 3) {
          const double dz = x[D * q + 2] - at[2];
          d2 += dz * dz;
        }
        const double range = rp + ps.r[q] + skin;
        if (d2 < range * range) found_.push_back(key(static_cast<int>(p), static_cast<int>(q)));
      });
    }
    std::sort(found_.begin(), found_.end());
  }

  packing::CellGridT<D> grid_;                ///< the neighbour search (storage reused across finds)
  std::array<std::vector<double>, D> axes_;  ///< scratch: the centres by axis for the grid
  std::vector<std::uint64_t> found_;         ///< scratch: the pairs of a find (key())
  packing::PeriodicPairsT<D> periodic_;      ///< the periodic search (storage reused)
  std::vector<int> from_;                    ///< per row: the old row it continues or -1
};

}  // namespace netdem::sys
