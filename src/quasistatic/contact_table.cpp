// ContactTable: the neighbour pairs of the network solver and the lifecycle of their committed
// history across neighbour rebuilds (solver_impl.hpp states the rules).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "solver_impl.hpp"

namespace netdem::qs {

// Cell-list neighbour search: all pairs with gap < skin. Merges the committed history.
void ContactTable::rebuild(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& r,
                           double skin, double r_max, const Eigen::Matrix2d& E, const Eigen::Matrix2d& Fbox) {
  const int n = static_cast<int>(x.size());
  grid.rebuild(x, y, 2.0 * r_max + skin);  // the toolkit's one cell grid (netdem/packing/cell_grid.hpp)
  std::vector<std::pair<int, int>> found;
  found.reserve(pi.size() + n);
  for (int p = 0; p < n; ++p) {
    grid.for_each_near(x[p], y[p], r[p] + r_max + skin, [&](std::uint32_t qq) {
      const int q = static_cast<int>(qq);
      if (q <= p) return;
      const double dx = x[q] - x[p], dy = y[q] - y[p];
      const double gap = std::sqrt(dx * dx + dy * dy) - r[p] - r[q];
      if (gap < skin) found.emplace_back(p, q);
    });
  }
  std::sort(found.begin(), found.end());
  // merge the committed history (both lists sorted); pairs farther apart than the skin lose it
  std::vector<int> npi(found.size()), npj(found.size());
  std::vector<Law::History> nh(found.size());
  std::vector<PairAux> na(found.size());
  std::vector<double> nfn(found.size(), 0.0), nft(found.size(), 0.0);
  std::vector<std::uint8_t> nsl(found.size(), 0);
  std::size_t o = 0;
  for (std::size_t k = 0; k < found.size(); ++k) {
    npi[k] = found[k].first;
    npj[k] = found[k].second;
    while (o < pi.size() && std::make_pair(pi[o], pj[o]) < found[k]) ++o;
    if (o < pi.size() && pi[o] == found[k].first && pj[o] == found[k].second) {
      nh[k] = hist[o];
      na[k] = aux[o];
      nfn[k] = fn_c[o];
      nft[k] = ft_c[o];
      nsl[k] = slide_c[o];
    } else {
      na[k].E_form = E;
    }
  }
  pi.swap(npi);
  pj.swap(npj);
  hist.swap(nh);
  aux.swap(na);
  fn_c.swap(nfn);
  ft_c.swap(nft);
  slide_c.swap(nsl);
  xb = x;
  yb = y;
  Fb = Fbox;
  build_adjacency(n);
}

void ContactTable::build_adjacency(int n) {
  adj_start.assign(n + 1, 0);
  for (std::size_t k = 0; k < pi.size(); ++k) {
    ++adj_start[pi[k] + 1];
    ++adj_start[pj[k] + 1];
  }
  for (int p = 0; p < n; ++p) adj_start[p + 1] += adj_start[p];
  adj_pair.assign(2 * pi.size(), 0);
  std::vector<int> fill(adj_start.begin(), adj_start.end() - 1);
  for (std::size_t k = 0; k < pi.size(); ++k) {
    adj_pair[fill[pi[k]]++] = static_cast<int>(k);
    adj_pair[fill[pj[k]]++] = static_cast<int>(k);
  }
}

bool ContactTable::needs_rebuild(const std::vector<double>& x, const std::vector<double>& y,
                                 const Eigen::Matrix2d& Fbox, double skin, double r_max) const {
  const Eigen::Matrix2d A = Fbox * Fb.inverse();
  double dmax = 0.0;
  for (std::size_t p = 0; p < x.size(); ++p) {
    const Eigen::Vector2d xa = A * Eigen::Vector2d(xb[p], yb[p]);
    dmax = std::max(dmax, std::hypot(x[p] - xa.x(), y[p] - xa.y()));
  }
  const double affine_rel = (A - Eigen::Matrix2d::Identity()).norm() * (2.0 * r_max + skin);
  return 2.0 * dmax + affine_rel > skin;
}

void NetworkSolver::Impl::build_neighbours() {
  const auto t0 = std::chrono::steady_clock::now();
  rebuild(x, y, r, opt.skin * r_mean, r_max, E, Fbox);
  apart.assign(pi.size(), 0);  // new pair indices: nothing is known to be zero
  build_pattern();
  tim.neighbours += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace netdem::qs
