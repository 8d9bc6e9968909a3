// Measures of the network solver's committed state: the Eq 13 stress from the reactions of the
// prescribed particles, the Love-Weber contact stress, Z, the affine-deviation measures of Figs 7-8
// (section 3.3), the contact list for output, and the verbose diagnostics of the Newton driver.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/LU>

#include "netdem/system/affine_deviation.hpp"
#include "netdem/system/rattlers.hpp"
#include "solver_impl.hpp"

namespace netdem::qs {

namespace {

/// BoundaryMode::Walls: the reactions are the walls' forces, applied at the contact points on the
/// faces (Eq 13 with the walls as the boundary): added to S (unscaled Eq 13 sum, lever arms from
/// xc), to SW (the wall contacts' share of the contact stress), to the net-force sums, and counted
/// per particle in wall_contacts (the rattlers' load-bearing contacts). Nothing without walls.
template <int D, class Impl>
void add_wall_reactions(const Impl& s, const Eigen::Matrix<double, D, 1>& xc, Eigen::Matrix<double, D, D>& S,
                        Eigen::Matrix<double, D, D>& SW, Eigen::Matrix<double, D, 1>& Fnet, double& Fabs,
                        std::vector<int>& wall_contacts) {
  using Vec = Eigen::Matrix<double, D, 1>;
  constexpr int kW = Impl::kW;
  if (!s.walls() || s.wfn_c.size() != kW * static_cast<std::size_t>(s.n)) return;
  wall_contacts.assign(static_cast<std::size_t>(s.n), 0);
  const double lo[3] = {s.box0.x_min, s.box0.y_min, s.box0.z_min}, hi[3] = {s.box0.x_max, s.box0.y_max, s.box0.z_max};
  for (int p = 0; p < s.n; ++p)
    for (int w = 0; w < kW; ++w) {
      const double fn = s.wfn_c[kW * static_cast<std::size_t>(p) + static_cast<std::size_t>(w)];
      if (!(fn > 0.0)) continue;
      ++wall_contacts[static_cast<std::size_t>(p)];
      const int a = w / 2;
      const Vec xp = s.at(p);
      Vec cp = xp;  // the contact point on the face
      cp(a) = s.Fbox(a, a) * (w % 2 == 0 ? lo[a] : hi[a]);
      const Vec Fapp = fn * (w % 2 == 0 ? 1.0 : -1.0) * Vec::Unit(a);  // inward
      S += Fapp * (cp - xc).transpose();
      SW -= Fapp * (xp - cp).transpose();
      Fnet += Fapp;
      Fabs += Fapp.norm();
    }
}

}  // namespace

template <int D, class L>
StateMeasures NetworkSolverT<D, L>::measures() const
  requires(D == 2)
{
  const auto& s = *impl_;
  StateMeasures m;
  m.E11 = s.E(0, 0);
  m.E22 = s.E(1, 1);
  m.E12 = s.E(0, 1);
  const double V = s.box_area0 * s.Fbox.determinant();
  m.density = s.solid_area / V;
  // Eq 13: reactions of the prescribed particles (translational DOFs prescribed), with the lever
  // arms from the centre of the current box. The reactions sum to the force that the drag and the
  // residual hold on the free particles, not to zero; about the centroid of V that net force, as
  // a uniform body force, has no first moment, and the stress does not depend on the origin
  // (docs/quasistatic.md "Stress, Eq 13").
  const Eigen::Vector2d xc =
      s.Fbox * Eigen::Vector2d(0.5 * (s.box0.x_min + s.box0.x_max), 0.5 * (s.box0.y_min + s.box0.y_max));
  Eigen::Vector2d Fnet = Eigen::Vector2d::Zero();
  double Fabs = 0.0;
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (int p = 0; p < s.n; ++p) {
    if (s.dof[3 * p] >= 0) continue;
    const Eigen::Vector2d Fapp(-s.f_c[3 * p], -s.f_c[3 * p + 1]);
    S += Fapp * (s.at(p) - xc).transpose();
    Fnet += Fapp;
    Fabs += Fapp.norm();
  }
  // the walls' reactions (they also enter the contact stress below); the load-bearing contacts per
  // particle with the walls, and the load-bearing pairs (rattlers)
  Eigen::Matrix2d SW = Eigen::Matrix2d::Zero();  // wall contacts' share of the contact stress
  std::vector<int> wall_contacts, bi, bj;
  add_wall_reactions<2>(s, xc, S, SW, Fnet, Fabs, wall_contacts);
  S /= V;
  m.net_force_ratio = Fabs > 0.0 ? Fnet.norm() / Fabs : 0.0;
  if (s.periodic()) m.net_force_ratio = 0.0;  // one held particle: no boundary to sum over
  m.S11 = S(0, 0);
  m.S22 = S(1, 1);
  m.S12 = 0.5 * (S(0, 1) + S(1, 0));
  m.S_asym = 0.5 * (S(0, 1) - S(1, 0));
  // Love-Weber average over the contacts and the affine-deviation measures
  Eigen::Matrix2d SC = Eigen::Matrix2d::Zero();
  sys::AffineDeviation dev(s.r_mean);
  double sum_tc = 0, sum_tr = 0;
  int loaded = 0;
  double sum_fn = 0;
  for (std::size_t k = 0; k < s.pi.size(); ++k) {
    if (s.fn_c[k] <= 0.0) continue;
    const int i = s.pi[k], j = s.pj[k];
    bi.push_back(i);
    bj.push_back(j);
    const auto g = ct::pair_geometry(s.at(i), s.at_j(k), s.ps.r[i], s.ps.r[j]);
    const Eigen::Vector2d fj = s.fn_c[k] * g.n + s.ft_c[k] * g.t;
    SC -= fj * (g.L * g.n).transpose();
    m.fabric11 += g.n.x() * g.n.x();
    m.fabric22 += g.n.y() * g.n.y();
    m.fabric12 += g.n.x() * g.n.y();
    ++loaded;
    sum_fn += s.fn_c[k];
    m.sliding += s.slide_c[k];
    // Eq 16 with the strain accumulated since the contact formed
    const auto a = sys::affine_approach<2>(g.n, s.E - s.aux[k].E_form, s.ps.r[i] + s.ps.r[j]);
    dev.add(g.overlap, a);
    sum_tc += std::fabs(s.aux[k].centre - a.tangential);
    sum_tr += std::fabs(s.aux[k].slip - a.tangential);
  }
  if (loaded > 0) {
    m.fabric11 /= loaded;
    m.fabric22 /= loaded;
    m.fabric12 /= loaded;
  }
  SC += SW;
  {  // rattlers (issue 28 item 4): fewer than D + 1 load-bearing contacts, walls included, recursively
    const sys::Backbone bb = sys::prune_rattlers(static_cast<std::size_t>(s.n), bi, bj, wall_contacts, D + 1);
    m.rattlers = static_cast<int>(bb.rattlers);
    m.Z_backbone = bb.Z;
  }
  SC /= V;
  m.S11_contacts = SC(0, 0);
  m.S22_contacts = SC(1, 1);
  m.S12_contacts = 0.5 * (SC(0, 1) + SC(1, 0));
  if (s.periodic()) {  // no prescribed boundary, so no Eq 13: the stress is the contact stress
    m.S11 = m.S11_contacts;
    m.S22 = m.S22_contacts;
    m.S12 = m.S12_contacts;
    m.S_asym = 0.5 * (SC(0, 1) - SC(1, 0));
  }
  {  // the equilibrium gap: symmetric parts, Frobenius norms (the off-diagonal counted twice)
    const double d11 = m.S11 - m.S11_contacts, d22 = m.S22 - m.S22_contacts, d12 = m.S12 - m.S12_contacts;
    const double d = std::sqrt(d11 * d11 + d22 * d22 + 2 * d12 * d12);
    const double c = std::sqrt(m.S11_contacts * m.S11_contacts + m.S22_contacts * m.S22_contacts +
                               2 * m.S12_contacts * m.S12_contacts);
    m.eq13_vs_contacts = c > 0.0 ? d / c : (d > 0.0 ? 1.0 : 0.0);
  }
  if (loaded == 0) {  // initial state: count geometric contacts
    for (std::size_t k = 0; k < s.pi.size(); ++k) {
      const int i = s.pi[k], j = s.pj[k];
      const Eigen::Vector2d d = s.at_j(k) - s.at(i);
      const double dist = std::hypot(d.x(), d.y());
      if (dist <= (s.ps.r[i] + s.ps.r[j]) * (1.0 + 1e-6)) ++loaded;
    }
  }
  m.contacts = loaded;
  m.Z = 2.0 * loaded / s.n;
  m.mean_normal_force = loaded > 0 ? sum_fn / loaded : 0.0;
  m.dev_normal_mean_ratio = dev.mean_ratio();
  m.dev_normal_ratio_of_means = dev.ratio_of_means(loaded);
  m.dev_tangential_centres = dev.of_mean_affine_normal(sum_tc, loaded);
  m.dev_tangential_rotations = dev.of_mean_affine_normal(sum_tr, loaded);
  m.affine_tangential = dev.affine_tangential(loaded);
  return m;
}

template <int D, class L>
std::vector<ContactView> NetworkSolverT<D, L>::contacts() const {
  const auto& s = *impl_;
  std::vector<ContactView> out;
  for (std::size_t k = 0; k < s.pi.size(); ++k) {
    if (s.fn_c[k] <= 0.0) continue;
    const int i = s.pi[k], j = s.pj[k];
    const typename Impl::Vec d = s.at_j(k) - s.at(i);
    if constexpr (D == 2) {
      const double dist = std::hypot(d.x(), d.y());
      out.push_back({i, j, s.fn_c[k], s.ft_c[k], s.ps.r[i] + s.ps.r[j] - dist, s.slide_c[k] != 0, {d.x(), d.y(), 0.0}});
    } else {
      const double dist = d.norm();
      out.push_back({i, j, s.fn_c[k], s.ft_c[k].norm(), s.ps.r[i] + s.ps.r[j] - dist, s.slide_c[k] != 0, {d.x(), d.y(), d.z()}});
    }
  }
  return out;
}

template <int D, class L>
std::optional<packing::PeriodicCellT<D>> NetworkSolverT<D, L>::periodic_cell() const {
  if (!impl_->periodic()) return std::nullopt;
  return impl_->cell0.deformed(impl_->Fbox);
}

// The Eq 13 stress of the prescribed particles' reactions or of the walls' (lever arms from the
// centre of the current box, as measures()) and the Love-Weber contact stress, in any dimension.
template <int D, class L>
StressMeasuresT<D> NetworkSolverT<D, L>::stress() const {
  const auto& s = *impl_;
  using Mat = Eigen::Matrix<double, D, D>;
  using Vec = typename Impl::Vec;
  constexpr int kN = Impl::kN;
  StressMeasuresT<D> m;
  m.strain = s.E;
  const double V = s.box_area0 * s.Fbox.determinant();
  m.density = s.solid_area / V;
  Vec c0;
  c0(0) = 0.5 * (s.box0.x_min + s.box0.x_max);
  c0(1) = 0.5 * (s.box0.y_min + s.box0.y_max);
  if constexpr (D == 3) c0(2) = 0.5 * (s.box0.z_min + s.box0.z_max);
  const Vec xc = s.Fbox * c0;
  Vec Fnet = Vec::Zero();
  double Fabs = 0.0;
  Mat S = Mat::Zero();
  for (int p = 0; p < s.n; ++p) {
    if (s.dof[kN * p] >= 0) continue;
    const Vec Fapp = -Eigen::Map<const Vec>(&s.f_c[kN * p]);
    S += Fapp * (s.at(p) - xc).transpose();
    Fnet += Fapp;
    Fabs += Fapp.norm();
  }
  Mat SW = Mat::Zero();
  std::vector<int> wall_contacts, bi, bj;  // per particle with the walls; the load-bearing pairs (rattlers)
  add_wall_reactions<D>(s, xc, S, SW, Fnet, Fabs, wall_contacts);
  S /= V;
  m.net_force_ratio = Fabs > 0.0 ? Fnet.norm() / Fabs : 0.0;
  m.eq13 = 0.5 * (S + S.transpose());
  Mat SC = Mat::Zero();
  double sum_fn = 0.0;
  for (std::size_t k = 0; k < s.pi.size(); ++k) {
    if (s.fn_c[k] <= 0.0) continue;
    const int i = s.pi[k], j = s.pj[k];
    bi.push_back(i);
    bj.push_back(j);
    const auto g = ct::pair_geometry(s.at(i), s.at_j(k), s.ps.r[i], s.ps.r[j]);
    m.fabric += g.n * g.n.transpose();
    Vec fj;
    if constexpr (D == 2) {
      fj = s.fn_c[k] * g.n + s.ft_c[k] * g.t;
    } else {
      fj = s.fn_c[k] * g.n + s.ft_c[k];
    }
    SC -= fj * (g.L * g.n).transpose();
    ++m.contact_count;
    sum_fn += s.fn_c[k];
    m.sliding += s.slide_c[k];
  }
  SC += SW;
  SC /= V;
  m.contacts = 0.5 * (SC + SC.transpose());
  if (s.periodic()) {  // no prescribed boundary, so no Eq 13: the stress is the contact stress
    m.eq13 = m.contacts;
    m.net_force_ratio = 0.0;
  }
  const double c = m.contacts.norm(), d = (m.eq13 - m.contacts).norm();
  m.eq13_vs_contacts = c > 0.0 ? d / c : (d > 0.0 ? 1.0 : 0.0);
  if (m.contact_count > 0) m.fabric /= m.contact_count;
  {
    const sys::Backbone bb = sys::prune_rattlers(static_cast<std::size_t>(s.n), bi, bj, wall_contacts, D + 1);
    m.rattlers = static_cast<int>(bb.rattlers);
    m.Z_backbone = bb.Z;
  }
  m.Z = 2.0 * m.contact_count / s.n;
  if (m.contact_count == 0) {  // before any load: the touching pairs, as measures()
    int touching = 0;
    for (std::size_t k = 0; k < s.pi.size(); ++k) {
      const int i = s.pi[k];
      touching += (s.at_j(k) - s.at(i)).norm() <= (s.ps.r[i] + s.ps.r[s.pj[k]]) * (1.0 + 1e-6);
    }
    m.Z = 2.0 * touching / s.n;
  }
  m.mean_normal_force = m.contact_count > 0 ? sum_fn / m.contact_count : 0.0;
  return m;
}

/// Max |contact force| on the free DOFs / fbar (moments divided by the mean radius): the
/// out-of-balance contact force, i.e. the viscous drag that holds the increment.
template <int D, class L>
double NetworkSolverT<D, L>::Impl::unbalance(double fbar, double* rms) const {
  double m = 0.0, s2 = 0.0;
  int c = 0;
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < kN; ++a)
      if (dof[kN * p + a] >= 0) {
        const double v = std::fabs(f[kN * p + a]) / (is_rotation(a) ? r_mean : 1.0);
        m = std::max(m, v);
        s2 += v * v;
        ++c;
      }
  if (rms) *rms = c > 0 ? std::sqrt(s2 / c) / std::max(fbar, 1e-300) : 0.0;
  return m / std::max(fbar, 1e-300);
}

/// Diagnostics (verbose): one line per Newton iteration with the branch transitions since the last.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::print_iteration(int it, double newton_res, double newton_max, double fbar) {
  const std::size_t np = pi.size();
  int tr[3][3] = {}, ss = 0;
  if (it == 0 || diag_branch.size() != np) diag_branch.assign(np, 0);  // new rows after a rebuild: no transitions
  for (std::size_t k = 0; k < np; ++k) {
    const int b = static_cast<int>(trial[k].branch), sl = trial[k].sliding ? 1 : 0;
    const int ob = diag_branch[k] & 3, osl = diag_branch[k] >> 2;
    if (it > 0) {
      if (ob != b) ++tr[ob][b];
      if (b != 0 && ob != 0 && sl != osl) ++ss;
    }
    diag_branch[k] = static_cast<std::uint8_t>(b + 4 * sl);
  }
  std::fprintf(stderr,
               "  iteration %d: residual rms %.3e max %.3e (mean contact force %.3e) O>P %d O>E %d P>O %d P>E %d "
               "E>O %d E>P %d stick/slip %d\n",
               it, newton_res, newton_max, fbar, tr[0][1], tr[0][2], tr[1][0], tr[1][2], tr[2][0], tr[2][1], ss);
}

/// Diagnostics (verbose): the particles with the largest Newton residual.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::print_worst(double fbar) const {
  const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
  std::vector<std::pair<double, int>> worst;
  for (int p = 0; p < n; ++p) {
    double m = 0.0;
    for (int a = 0; a < kN; ++a)
      if (dof[kN * p + a] >= 0) {
        const double rv = f[kN * p + a] - (is_rotation(a) ? eta_r : eta_t) * (du[kN * p + a] - du_ref[kN * p + a]);
        m = std::max(m, std::fabs(rv) / (is_rotation(a) ? r_mean : 1.0));
      }
    worst.emplace_back(m / std::max(fbar, 1e-300), p);
  }
  const std::size_t nw = std::min<std::size_t>(6, worst.size());
  std::partial_sort(worst.begin(), worst.begin() + static_cast<std::ptrdiff_t>(nw), worst.end(), std::greater<>());
  std::vector<int> closed(n, 0), slid(n, 0);
  for (std::size_t k = 0; k < pi.size(); ++k)
    if (trial[k].loaded) {
      ++closed[pi[k]];
      ++closed[pj[k]];
      if (trial[k].sliding) {
        ++slid[pi[k]];
        ++slid[pj[k]];
      }
    }
  for (std::size_t w = 0; w < nw; ++w) {
    const int p = worst[w].second;
    std::fprintf(stderr, "    worst p=%d |r|/fbar=%.3e (components", p, worst[w].first);
    for (int a = 0; a < kN; ++a)
      if (dof[kN * p + a] >= 0) {
        const double rv = f[kN * p + a] - (is_rotation(a) ? eta_r : eta_t) * (du[kN * p + a] - du_ref[kN * p + a]);
        const double rel = rv / (is_rotation(a) ? r_mean : 1.0) / std::max(fbar, 1e-300);
        std::fprintf(stderr, " %s%+.2e", is_rotation(a) ? "m/R " : "", rel);
      }
    std::fprintf(stderr, ") contacts=%d sliding=%d non-affine motion %.3e R\n", closed[p], slid[p],
                 (D == 2 ? std::hypot(du[kN * p] - du_aff[kN * p], du[kN * p + 1] - du_aff[kN * p + 1])
                         : (Eigen::Map<const Vec>(&du[kN * p]) - Eigen::Map<const Vec>(&du_aff[kN * p])).norm()) /
                     r_mean);
    if (w >= 2) continue;
    for (std::size_t k = 0; k < pi.size(); ++k)
      if ((pi[k] == p || pj[k] == p) && trial[k].loaded)
        std::fprintf(stderr, "      pair %d-%d f_n %.4e |f_t|/f_n %.4f%s (iteration matrix k_n %.4e) branch %d\n", pi[k],
                     pj[k], trial[k].f_n, ct::tan_norm(trial[k].f_t) / std::max(trial[k].f_n, 1e-300),
                     trial[k].sliding ? " sliding" : "", last_kn[k], static_cast<int>(trial[k].branch));
  }
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template class NetworkSolverT<2>;
// 3D: member by member (measures() is 2D only, and clang 14 instantiates constrained members too)
template std::vector<ContactView> NetworkSolverT<3>::contacts() const;
template std::optional<packing::PeriodicCellT<3>> NetworkSolverT<3>::periodic_cell() const;
template StressMeasuresT<3> NetworkSolverT<3>::stress() const;
template struct NetworkSolverT<3>::Impl;
#else
template class NetworkSolverT<2, LinearLawT<2>>;
template std::vector<ContactView> NetworkSolverT<3, LinearLawT<3>>::contacts() const;
template std::optional<packing::PeriodicCellT<3>> NetworkSolverT<3, LinearLawT<3>>::periodic_cell() const;
template StressMeasuresT<3> NetworkSolverT<3, LinearLawT<3>>::stress() const;
template struct NetworkSolverT<3, LinearLawT<3>>::Impl;
#endif

}  // namespace netdem::qs
