// The staggered scheme: its contacts (staggered_impl.hpp; docs/staggered.md, steps 1 and 5 of a
// step): a new contact's pair state, the detection of new contacts on the cell grid, and the move
// of the nodes with the shrinkage correction (Eqs 41-44).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "staggered_impl.hpp"

namespace netdem::qs::staggered {

void Staggered::Impl::add_contact(int a, int b, double d) {
  const double ra = p.r[a], rb = p.r[b];
  const double hA = (d * d + ra * ra - rb * rb) / (2.0 * d);  // the radical plane of the two spheres
  const double hB = d - hA;
  if (!(hA > 0.0 && hB > 0.0))
    throw std::runtime_error(fmt::format(
        "staggered: particles {} and {} overlap too far (centre distance {:.4g} m, radii {:.4g}, {:.4g})", a, b, d, ra, rb));
  const double Rmin = std::min(ra, rb);
  const double a2 = std::max(0.0, ra * ra - hA * hA);  // lens radius^2 (the same from either side)
  Contact k;
  k.a = a;
  k.b = b;
  // x0 = 0.01 R_min (the paper), raised above the lens radius of an overlapping pair so that the
  // cap-cone geometry exists (x^2 + h^2 > R^2 needs x > the lens radius)
  const double x0 = std::max(opt.x0_over_R * Rmin, 1.02 * std::sqrt(a2));
  k.pair.q = k.pair.q0 = State{x0, ra, hA, rb, hB};
  k.pair.t = t;
  k.t_created = t;
  k.L_created = d;
  k.x_start = x0;
  const cs::PairStatus s = cs::check_state(k.pair.q, Rmin, x_max);
  if (s == cs::PairStatus::NeckLimit) {
    k.frozen = true;
    k.pair.status = s;
  } else if (s != cs::PairStatus::Ok) {
    throw std::runtime_error(fmt::format("staggered: the new contact {}-{} has no valid geometry ({})", a, b,
                                         cs::to_string(s)));
  }
  adj[a].push_back(static_cast<int>(c.size()));
  adj[b].push_back(static_cast<int>(c.size()));
  c.push_back(k);
  pattern_dirty = true;
}

bool Staggered::Impl::bonded(int a, int b) const {
  const auto& la = adj[a].size() <= adj[b].size() ? adj[a] : adj[b];
  for (int k : la)
    if ((c[k].a == a && c[k].b == b) || (c[k].a == b && c[k].b == a)) return true;
  return false;
}

// New contacts: spheres closer than r_a + r_b without a bond, found through the toolkit's cell
// grid (cells of at least 2 r_max); pairs in index order, so the contact order does not depend
// on the grid. The grid, the coordinate arrays and the list are reused (no allocation per step
// once their sizes settle).
int Staggered::Impl::detect() {
  const int n = N();
  double rmax = 0.0;
  for (int k = 0; k < 3; ++k) grid_xyz[k].resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    rmax = std::max(rmax, p.r[i]);
    for (int k = 0; k < 3; ++k) grid_xyz[k][static_cast<std::size_t>(i)] = p.coord(i, k);
  }
  grid.rebuild(grid_xyz[0], grid_xyz[1], grid_xyz[2], 2.0 * kTouch * rmax);
  found.clear();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d xi = centre(i);
    grid.for_each_near(xi[0], xi[1], xi[2], kTouch * (p.r[i] + rmax), [&](std::uint32_t jj) {
      const int j = static_cast<int>(jj);
      if (j <= i) return;
      const double rr = kTouch * (p.r[i] + p.r[j]);
      if ((centre(j) - xi).squaredNorm() < rr * rr && !bonded(i, j)) found.emplace_back(i, j);
    });
  }
  std::sort(found.begin(), found.end());
  for (const auto& [i, j] : found) add_contact(i, j, (centre(j) - centre(i)).norm());
  return static_cast<int>(found.size());
}

// Moves the nodes by the solve's translations, then corrects the shrinkage (Eqs 41-44) and
// advances every contact's state to t_new (freezing those that left the model's domain).
void Staggered::Impl::move_and_correct(StepRecord& rec, const VecX& uhat, double t_new) {
  u.assign(N(), Eigen::Vector3d::Zero());
  for (int i = 0; i < N(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int g = dof[6 * i + k];
      if (g >= 0) u[i][k] = uhat[g];  // translations are not scaled
    }
  remove_rigid_motions(u);
  for (int i = 0; i < N(); ++i)
    for (int k = 0; k < 3; ++k) p.pos[3 * static_cast<std::size_t>(i) + static_cast<std::size_t>(k)] += u[i][k];
  for (std::size_t i = 0; i < c.size(); ++i) {
    Contact& k = c[i];
    const State qold = k.pair.q;
    const State qf = (k.frozen || freeze[i] == 2) ? qold : qnew[i];
    const double d = (centre(k.b) - centre(k.a)).norm();
    const auto [y4, y7] = corrected_split(qold[kHA], qold[kHB], qf[kHA], qf[kHB], d, qold[kRA], qold[kRB]);
    k.dL_bar = (y4 + y7) - (qf[kHA] + qf[kHB]);  // Eq 44
    k.pair.q = qf;
    k.pair.q[kHA] = y4;
    k.pair.q[kHB] = y7;
    rec.max_shrink_error = std::max(rec.max_shrink_error, std::fabs(y4 + y7 - d) / d);
    if (k.frozen) continue;
    k.pair.t = t_new;
    ++k.pair.steps;
    if (freeze[i] == 2) {
      k.frozen = true;
      k.pair.status = cs::PairStatus::ConeDegenerate;
      ++rec.newly_frozen;
      continue;
    }
    const cs::PairStatus s = cs::check_state(k.pair.q, k.pair.R_min0(), x_max);
    if (s != cs::PairStatus::Ok) {
      k.frozen = true;
      k.pair.status = s;
      ++rec.newly_frozen;
    }
  }
}

}  // namespace netdem::qs::staggered
