#pragma once
// The contact table of a solver in dimension D (issue 26): the rows of PairRows<D> (pair_rows.hpp:
// keys i < j sorted by (i, j), the periodic image of j), the committed history of the contact law
// per row, and the adjacency (the rows of each particle, CSR in increasing row order). rebuild()
// finds every pair whose centres are closer than r_i + r_j + skin and carries the committed
// history of the rows that stay; per-row data of the solver follows with carry().
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
// cell (pair_rows.hpp).
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
#include "netdem/packing/periodic.hpp"
#include "netdem/system/pair_rows.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::sys {

template <class History, int D>
class ContactTable : public PairRows<D> {
 public:
  using Mat = Eigen::Matrix<double, D, D>;
  using Vec = Eigen::Matrix<double, D, 1>;
  using typename PairRows<D>::Shift;
  using PairRows<D>::pi;
  using PairRows<D>::pj;
  using PairRows<D>::shift;

  std::vector<History> hist;         ///< committed history per row
  std::vector<int> adj_start, adj_pair;  ///< rows of each particle (CSR, increasing row index)
  std::vector<double> pos_build;     ///< D per particle: the centres at the last rebuild
  Mat F_build = Mat::Identity();     ///< the box deformation at the last rebuild

  /// New rows: every pair within r_i + r_j + skin (radii up to r_max) merged with the committed
  /// history (the lifecycle above); F is the current box deformation (kept for needs_rebuild());
  /// `cell`, if given, the current periodic cell (the pairs through its images).
  template <contact::ContactLaw L>
  void rebuild(const L&, const ParticleSet<D>& ps, double skin, double r_max, const Mat& F,
               const packing::PeriodicCellT<D>* cell = nullptr) {
    this->find(ps, skin, r_max, cell);
    const std::vector<int>& from = this->carried_from();
    std::vector<History> nh(from.size());
    for (std::size_t k = 0; k < from.size(); ++k) {
      if (from[k] < 0) continue;
      const Vec image = cell ? cell->image(shift[k]) : Vec::Zero();
      if (L::kHistoryOutlivesSeparation || gap(ps, pi[k], pj[k], image) < 0.0) nh[k] = hist[static_cast<std::size_t>(from[k])];
    }
    hist.swap(nh);
    pos_build = ps.pos;
    F_build = F;
    build_adjacency(static_cast<int>(ps.size()));
  }

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
  std::vector<int> fill_;  ///< scratch of build_adjacency
};

}  // namespace netdem::sys
