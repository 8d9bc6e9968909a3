// Explicit DEM solver: the history stores and the Verlet table on the cell grid (solver.hpp).
#include "netdem/dynamic/solver.hpp"
#include "solver_detail.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "netdem/contact/luding_law.hpp"

namespace netdem::dem {

using detail::displacement_limit;
using detail::fail;

namespace {
/// The row of pair (i, j), i < j, or -1.
template <int D>
std::ptrdiff_t find_row(const sys::PairRows<D>& rows, std::uint32_t i, std::uint32_t j) {
  const auto lo = std::lower_bound(rows.pi.begin(), rows.pi.end(), static_cast<int>(i));
  const auto hi = std::upper_bound(lo, rows.pi.end(), static_cast<int>(i));
  const auto b = rows.pj.begin() + (lo - rows.pi.begin()), e = rows.pj.begin() + (hi - rows.pi.begin());
  const auto it = std::lower_bound(b, e, static_cast<int>(j));
  return it != e && *it == static_cast<int>(j) ? it - rows.pj.begin() : -1;
}
}  // namespace

// ---- the history table of the law (HistoryTables) ------------------------------------------------
template <int D>
void DynamicSolverT<D>::make_tables(std::size_t n) {
  visit_law([&](const auto& law) {
    using H = typename std::decay_t<decltype(law)>::History;
    hist_.template emplace<HistoryTable<H>>();
    table<H>().wall.assign(kWalls * n, H{});
  });
}

// The committed histories of the pairs that stay in the table (rows_.carry: every history is
// carried, the law clears it at separation in the force loop); a pair is live (evaluated while
// apart) when the law says its history holds something (Law::has_history: the lifecycle is the
// law's).
template <int D>
template <class Law>
void DynamicSolverT<D>::carry_histories(const Law& law) {
  using H = typename Law::History;
  std::vector<H>& h = table<H>().pair;
  rows_.carry(h, H{}, table<H>().next);
  pair_live_.assign(h.size(), 0);
  const std::vector<int>& from = rows_.carried_from();
  for (std::size_t k = 0; k < h.size(); ++k)
    if (from[k] >= 0) pair_live_[k] = law.has_history(h[k]) ? 1 : 0;
}

// ---- neighbour search: cell list + Verlet table ------------------------------------------------

template <int D>
bool DynamicSolverT<D>::needs_rebuild() const {
  double lim = displacement_limit(skin_, radius_ref_max_, radius_scale_, radius_scale_build_);
  // periodic: the positions at the build are advected with the cell; a pair's branch stretches by
  // at most |F_build - I| range_max besides
  if (periodic_) lim -= 0.5 * (F_build_ - Eigen::Matrix<double, D, D>::Identity()).norm() * range_max_;
  if (!(lim > 0.0) || walls_moved()) return true;
  const double lim2 = lim * lim;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double* const x = &P_.pos[D * i];
    const double* const xb = &pos_build_[D * i];
    const double dx = x[0] - xb[0], dy = x[1] - xb[1];
    double d2 = dx * dx + dy * dy;
    if constexpr (D == 3) {
      const double dz = x[2] - xb[2];
      d2 += dz * dz;
    }
    if (d2 > lim2) return true;
  }
  return false;
}

// Wall candidates: particles within a_i + skin of a wall. Any other particle's wall histories
// are cleared here (it does not touch a wall, so the next evaluation would clear them anyway).
template <int D>
void DynamicSolverT<D>::build_wall_list() {
  const std::size_t n = P_.size();
  wall_list_.clear();
  wall_list_valid_ = walls_active();
  if (!walls_active()) return;
  box_build_[0] = box_.x_min;
  box_build_[1] = box_.x_max;
  box_build_[2] = box_.y_min;
  box_build_[3] = box_.y_max;
  if constexpr (D == 3) {
    box_build_[4] = box_.z_min;
    box_build_[5] = box_.z_max;
  }
  constexpr std::uint8_t kAll = (1u << kWalls) - 1u;
  if (wall_touch_.size() != n) wall_touch_.assign(n, kAll);
  for (std::size_t i = 0; i < n; ++i) {
    const double xi = P_.pos[D * i], yi = P_.pos[D * i + 1], reach = P_.r[i] + skin_;
    bool near = xi - box_.x_min < reach || box_.x_max - xi < reach ||
                yi - box_.y_min < reach || box_.y_max - yi < reach;
    if constexpr (D == 3) {
      const double zi = P_.pos[D * i + 2];
      near = near || zi - box_.z_min < reach || box_.z_max - zi < reach;
    }
    if (near) {
      wall_list_.push_back(static_cast<std::uint32_t>(i));
      wall_touch_[i] = kAll;  // the next evaluation visits its wall histories
    } else if (wall_touch_[i] != 0) {
      std::visit([&](auto& t) {
        for (std::size_t w = 0; w < kWalls; ++w) t.wall[kWalls * i + w] = {};
      }, hist_);
      wall_touch_[i] = 0;
    }
  }
}

template <int D>
bool DynamicSolverT<D>::walls_moved() const {
  if (!walls_active()) return false;
  const double lim = 0.5 * skin_;
  bool stay = std::fabs(box_.x_min - box_build_[0]) < lim && std::fabs(box_.x_max - box_build_[1]) < lim &&
              std::fabs(box_.y_min - box_build_[2]) < lim && std::fabs(box_.y_max - box_build_[3]) < lim;
  if constexpr (D == 3)
    stay = stay && std::fabs(box_.z_min - box_build_[4]) < lim && std::fabs(box_.z_max - box_build_[5]) < lim;
  return !stay;
}

template <int D>
void DynamicSolverT<D>::build_table() {
  if (periodic_) {
    build_table_periodic();
    return;
  }
  ++rebuilds_;
  radius_scale_build_ = radius_scale_;
  pos_build_ = P_.pos;
  build_wall_list();
  double rmax = 0.0;
  for (double r : P_.r) rmax = std::max(rmax, r);
  rows_csr_ok_ = false;  // (the threads' row lists follow the new rows; cleared first: a throw below)
  rows_.find(P_, skin_, rmax);
  visit_law([&](const auto& law) { carry_histories(law); });
}

// The periodic table (issue 29): the pairs within r_i + r_j + skin through the images of the
// cell (packing::PeriodicPairsT, sorted by (i, j): a pair has one image within range, the cell
// being at least two ranges wide), each with its image n; the histories are carried by (i, j), as
// the image of a pair does not change while the positions stay unwrapped. The mean fluctuation
// velocity (the rigid translation, conserved by the pair forces up to rounding) is removed here.
template <int D>
void DynamicSolverT<D>::build_table_periodic() {
  const std::size_t n = P_.size();
  ++rebuilds_;
  radius_scale_build_ = radius_scale_;
  pos_build_ = P_.pos;
  F_build_.setIdentity();
  wall_list_.clear();
  wall_list_valid_ = false;
  double rmax = 0.0;
  for (double r : P_.r) rmax = std::max(rmax, r);
  range_max_ = 2.0 * rmax + skin_;
  reduce_cell();
  if (n >= 2 && !(cell_.min_width() >= 2.0 * range_max_))
    breach("cell",
           fmt::format("the periodic cell is {:.4g} wide across an axis, less than twice the largest interaction "
                       "range 2 r_max + skin = {:.4g}", cell_.min_width(), range_max_),
           "the cell was compressed or sheared too far for its number of particles (a larger packing)");
  rows_csr_ok_ = false;
  rows_.find(P_, skin_, rmax, &cell_);
  visit_law([&](const auto& law) { carry_histories(law); });
  remove_mean_velocity();
}

template <int D>
void DynamicSolverT<D>::remove_mean_velocity() {
  double m = 0.0, p[3] = {0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < P_.size(); ++i) {
    m += P_.mass[i];
    for (int a = 0; a < D; ++a) p[a] += P_.mass[i] * P_.vel[D * i + a];
  }
  if (!(m > 0.0)) return;
  for (std::size_t i = 0; i < P_.size(); ++i)
    for (int a = 0; a < D; ++a) P_.vel[D * i + a] -= p[a] / m;
}

template <int D>
void DynamicSolverT<D>::touching_pairs(
    std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const {
  out.clear();
  for (std::size_t k = 0; k < rows_.pairs(); ++k) {
    const auto i = static_cast<std::uint32_t>(rows_.pi[k]), j = static_cast<std::uint32_t>(rows_.pj[k]);
    double d[3];
    branch(k, i, j, d);
    const double s = P_.r[i] + P_.r[j];
    double L2 = d[0] * d[0] + d[1] * d[1];
    if constexpr (D == 3) L2 += d[2] * d[2];
    if (L2 < s * s) out.emplace_back(i, j);
  }
}

template <int D>
auto DynamicSolverT<D>::history(std::uint32_t i, std::uint32_t j) const -> const LudingHist* {
  const std::ptrdiff_t k = find_row(rows_, i, j);
  const HistoryTable<LudingHist>* t = table_if<LudingHist>();
  if (!t || k < 0) return nullptr;
  return &t->pair[static_cast<std::size_t>(k)];
}

template <int D>
auto DynamicSolverT<D>::plastic_history(std::uint32_t i, std::uint32_t j) const -> const PlasticHist* {
  const std::ptrdiff_t k = find_row(rows_, i, j);
  const HistoryTable<PlasticHist>* t = table_if<PlasticHist>();
  if (!t || k < 0) return nullptr;
  return &t->pair[static_cast<std::size_t>(k)];
}

template bool DynamicSolverT<2>::needs_rebuild() const;
template void DynamicSolverT<2>::build_wall_list();
template bool DynamicSolverT<2>::walls_moved() const;
template void DynamicSolverT<2>::build_table();
template void DynamicSolverT<2>::build_table_periodic();
template void DynamicSolverT<2>::remove_mean_velocity();
template void DynamicSolverT<2>::touching_pairs( std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const;
template auto DynamicSolverT<2>::history(std::uint32_t i, std::uint32_t j) const -> const LudingHist*;
template auto DynamicSolverT<2>::plastic_history(std::uint32_t i, std::uint32_t j) const -> const PlasticHist*;

template bool DynamicSolverT<3>::needs_rebuild() const;
template void DynamicSolverT<3>::build_wall_list();
template bool DynamicSolverT<3>::walls_moved() const;
template void DynamicSolverT<3>::build_table();
template void DynamicSolverT<3>::build_table_periodic();
template void DynamicSolverT<3>::remove_mean_velocity();
template void DynamicSolverT<3>::touching_pairs( std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const;
template auto DynamicSolverT<3>::history(std::uint32_t i, std::uint32_t j) const -> const LudingHist*;
template auto DynamicSolverT<3>::plastic_history(std::uint32_t i, std::uint32_t j) const -> const PlasticHist*;

template void DynamicSolverT<2>::make_tables(std::size_t n);
template void DynamicSolverT<3>::make_tables(std::size_t n);

}  // namespace netdem::dem
