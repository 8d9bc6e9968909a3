#pragma once
// The contact table of a solver in dimension D (issue 26): one row per neighbour pair, keys i < j
// sorted by (i, j), the committed history of the contact law per row, and the adjacency (the rows
// of each particle, CSR in increasing row order). rebuild() finds every pair with a gap below the
// skin over one cell grid (packing::CellGridT<D>) and carries the committed history of the rows
// that stay; per-row data of the solver follows with carry().
//
// Lifecycle, read from the law (law.hpp):
//   * a row is created with a fresh history (History{}) when a pair comes within the skin;
//   * it keeps its history across rebuilds while the pair stays within the skin, if the law's
//     history outlives separation (L::kHistoryOutlivesSeparation, e.g. the plastic flattening
//     u_max); a law whose history ends at separation gets a fresh one for a pair found apart;
//   * it is dropped, history and all, when a rebuild finds the pair farther apart than the skin
//     (the skin is chosen so that such a pair cannot touch before the next rebuild, which
//     needs_rebuild() guarantees).
// with_history(law) counts the rows whose history the law says matters (L::has_history).
//
// Periodic cells (issue 29): rebuild() with a cell finds the pairs through the images of the
// cell (packing/periodic.hpp) and keeps per row the image n of j: the branch is x_j + h n - x_i
// with h the current cell vectors. Positions stay unwrapped, so a row's image never changes while
// the row lives; without a cell every shift is zero.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "netdem/contact/law.hpp"
#include "netdem/packing/cell_grid.hpp"
#include "netdem/packing/periodic.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::sys {

template <class History, int D>
class ContactTable {
 public:
  static constexpr int kDim = D;
  using Mat = Eigen::Matrix<double, D, D>;
  using Vec = Eigen::Matrix<double, D, 1>;

  using Shift = std::array<int, D>;
  std::vector<int> pi, pj;           ///< the rows' particles, i < j, sorted by (i, j)
  std::vector<Shift> shift;          ///< the image of j per row (periodic cells; else zero)
  std::vector<History> hist;         ///< committed history per row
  std::vector<int> adj_start, adj_pair;  ///< rows of each particle (CSR, increasing row index)
  std::vector<double> pos_build;     ///< D per particle: the centres at the last rebuild
  Mat F_build = Mat::Identity();     ///< the box deformation at the last rebuild

  std::size_t pairs() const { return pi.size(); }

  /// New rows: every pair with gap < skin (radii up to r_max) merged with the committed history
  /// (the lifecycle above); F is the current box deformation (kept for needs_rebuild()); `cell`,
  /// if given, the current periodic cell (the pairs through its images).
  template <contact::ContactLaw L>
  void rebuild(const L&, const ParticleSet<D>& ps, double skin, double r_max, const Mat& F,
               const packing::PeriodicCellT<D>* cell = nullptr) {
    const int n = static_cast<int>(ps.size());
    found_.clear();
    found_shift_.clear();
    if (cell) {
      for (const auto& pr : periodic_.find(ps.pos, ps.r, *cell, skin)) {
        found_.emplace_back(pr.i, pr.j);
        found_shift_.push_back(pr.n);
      }
    } else {
      find_pairs(ps, skin, r_max);
    }
    // merge with the old rows (both sorted); rows farther apart than the skin are dropped
    from_.assign(found_.size(), -1);
    std::vector<History> nh(found_.size());
    std::size_t o = 0;
    for (std::size_t k = 0; k < found_.size(); ++k) {
      while (o < pi.size() && std::make_pair(pi[o], pj[o]) < found_[k]) ++o;
      if (o < pi.size() && pi[o] == found_[k].first && pj[o] == found_[k].second) {
        from_[k] = static_cast<int>(o);
        const Shift sk = cell ? found_shift_[k] : Shift{};
        const Vec image = cell ? cell->image(sk) : Vec::Zero();
        if (L::kHistoryOutlivesSeparation || gap(ps, found_[k].first, found_[k].second, image) < 0.0) nh[k] = hist[o];
      }
    }
    pi.resize(found_.size());
    pj.resize(found_.size());
    shift.assign(found_.size(), Shift{});
    for (std::size_t k = 0; k < found_.size(); ++k) {
      pi[k] = found_[k].first;
      pj[k] = found_[k].second;
      if (cell) shift[k] = found_shift_[k];
    }
    hist.swap(nh);
    pos_build = ps.pos;
    F_build = F;
    build_adjacency(n);
  }

  /// Per-row data of the solver after rebuild(): the value of the old row a new row continues,
  /// `fresh` for a new pair.
  template <class T>
  void carry(std::vector<T>& v, const T& fresh) const {
    std::vector<T> out(from_.size(), fresh);
    for (std::size_t k = 0; k < from_.size(); ++k)
      if (from_[k] >= 0) out[k] = v[static_cast<std::size_t>(from_[k])];
    v.swap(out);
  }
  /// Per new row: the old row it continues, -1 for a new pair (the last rebuild).
  const std::vector<int>& carried_from() const { return from_; }

  /// The adjacency of the current rows over n particles.
  void build_adjacency(int n) {
    adj_start.assign(static_cast<std::size_t>(n) + 1, 0);
    for (std::size_t k = 0; k < pi.size(); ++k) {
      ++adj_start[static_cast<std::size_t>(pi[k]) + 1];
      ++adj_start[static_cast<std::size_t>(pj[k]) + 1];
    }
    for (int p = 0; p < n; ++p) adj_start[p + 1] += adj_start[p];
    adj_pair.assign(2 * pi.size(), 0);
    fill_.assign(adj_start.begin(), adj_start.end() - 1);
    for (std::size_t k = 0; k < pi.size(); ++k) {
      adj_pair[fill_[pi[k]]++] = static_cast<int>(k);
      adj_pair[fill_[pj[k]]++] = static_cast<int>(k);
    }
  }

  /// Whether the rows may miss a pair: twice the largest displacement relative to the affine
  /// motion of the box since the last rebuild, plus the affine part of the relative motion of two
  /// neighbours, exceeds the skin.
  bool needs_rebuild(const ParticleSet<D>& ps, const Mat& F, double skin, double r_max) const {
    const Mat A = F * F_build.inverse();
    double dmax = 0.0;
    for (std::size_t p = 0; p < ps.size(); ++p) {
      const Vec xa = A * Eigen::Map<const Vec>(&pos_build[D * p]);
      if constexpr (D == 2) {
        dmax = std::max(dmax, std::hypot(ps.pos[2 * p] - xa.x(), ps.pos[2 * p + 1] - xa.y()));
      } else {
        dmax = std::max(dmax, (Eigen::Map<const Vec>(&ps.pos[D * p]) - xa).norm());
      }
    }
    const double affine_rel = (A - Mat::Identity()).norm() * (2.0 * r_max + skin);
    return 2.0 * dmax + affine_rel > skin;
  }

  /// Rows whose committed history the law says matters (L::has_history).
  template <contact::ContactLaw L>
  std::size_t with_history(const L& law) const {
    return static_cast<std::size_t>(std::count_if(hist.begin(), hist.end(), [&](const History& h) { return law.has_history(h); }));
  }

  /// The gap between the surfaces of particles p and q (q moved by `image`, a periodic image).
  static double gap(const ParticleSet<D>& ps, int p, int q, const Vec& image = Vec::Zero()) {
    const std::size_t a = D * static_cast<std::size_t>(p), b = D * static_cast<std::size_t>(q);
    const double dx = ps.pos[b] + image[0] - ps.pos[a], dy = ps.pos[b + 1] + image[1] - ps.pos[a + 1];
    double d2 = dx * dx + dy * dy;
    if constexpr (D == 3) {
      const double dz = ps.pos[b + 2] + image[2] - ps.pos[a + 2];
      d2 += dz * dz;
    }
    return std::sqrt(d2) - ps.r[p] - ps.r[q];
  }

 private:
  /// found_ = every pair with gap < skin over the cell grid, sorted.
  void find_pairs(const ParticleSet<D>& ps, double skin, double r_max) {
    const int n = static_cast<int>(ps.size());
    for (std::size_t a = 0; a < D; ++a) {  // the grid reads the centres by axis (storage reused)
      axes_[a].resize(static_cast<std::size_t>(n));
      for (std::size_t p = 0; p < axes_[a].size(); ++p) axes_[a][p] = ps.pos[D * p + a];
    }
    typename packing::CellGridT<D>::Axes spans;
    for (std::size_t a = 0; a < D; ++a) spans[a] = axes_[a];
    grid_.rebuild(spans, 2.0 * r_max + skin);
    found_.reserve(pi.size() + static_cast<std::size_t>(n));
    for (int p = 0; p < n; ++p) {
      typename packing::CellGridT<D>::Point at;
      for (std::size_t a = 0; a < D; ++a) at[a] = ps.pos[D * static_cast<std::size_t>(p) + a];
      grid_.for_each_near(at, ps.r[p] + r_max + skin, [&](std::uint32_t qq) {
        const int q = static_cast<int>(qq);
        if (q <= p) return;
        if (gap(ps, p, q) < skin) found_.emplace_back(p, q);
      });
    }
    std::sort(found_.begin(), found_.end());
  }

  packing::CellGridT<D> grid_;  ///< the neighbour search (storage reused across rebuilds)
  std::array<std::vector<double>, D> axes_;  ///< scratch: the centres by axis for the grid
  std::vector<std::pair<int, int>> found_;   ///< scratch: the pairs of a rebuild
  std::vector<Shift> found_shift_;           ///< scratch: their images (periodic)
  packing::PeriodicPairsT<D> periodic_;      ///< the periodic search (storage reused)
  std::vector<int> from_;                    ///< per row: the old row it continues or -1
  std::vector<int> fill_;                    ///< scratch of build_adjacency
};

}  // namespace netdem::sys
