// Assembly of the network solver: the sparsity pattern of the free-DOF matrices, the trial
// forces of every pair (threaded, bit-identical for any thread count), the iteration matrix K
// and its symmetric slip-status twin M (preconditioner / direct solve), and the diagonal drag and
// regularisation. The residual, not the matrix, defines the equilibrium: every modification of
// the iteration matrix below changes the Newton path only (docs/quasistatic.md).
#include <algorithm>

#include <omp.h>

#include "solver_impl.hpp"

namespace netdem::qs {

// Sparsity pattern of the free-DOF matrix and the slots of the pairs (pair_pattern.hpp): diagonal
// kN x kN blocks + one block pair per neighbour pair, columns in DOF order; M shares it.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::build_pattern() {
  pattern.build(K, n, kN, dof, nfree, pi.size(), [&](std::size_t k) { return std::pair<int, int>(pi[k], pj[k]); });
  M = K;
  pattern_changed = true;
}

// Trial evaluation of every pair from the committed state and the increment du, with assembly:
// fills f (kN n), pf, the trial results and the values of K and M.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::assemble(bool& any_nonsymmetric) {
  std::fill(f.begin(), f.end(), 0.0);
  pf.resize(kP * pi.size());
  apart.resize(pi.size(), 0);
  pw.resize(pi.size(), 0.0);
  if (friction_energy()) {
    t_kt.assign(pi.size(), 0.0);
    t_limit.assign(pi.size(), 0.0);
  }
  std::fill(K.valuePtr(), K.valuePtr() + K.nonZeros(), 0.0);
  std::fill(M.valuePtr(), M.valuePtr() + M.nonZeros(), 0.0);
  any_nonsymmetric = false;
  const ct::TangentOptions topt;
  Element e;
  for (std::size_t k = 0; k < pi.size(); ++k) {
    const int i = pi[k], j = pj[k];
    const Geometry g1 = ct::pair_geometry(moved(i), moved_j(k), ps.r[i], ps.r[j]);
    // pairs that are apart and have never touched cost only the geometry
    if (g1.overlap <= 0.0 && !law.has_history(hist[k])) {
      set_apart(k);
      open_contact_stiffness(k, g1);
      continue;
    }
    apart[k] = 0;
    ct::pair_element(law, hist[k], g0[k], g1, rotation(i), rotation(j), e, &topt);
    if (friction_energy()) freeze_tangential(k, e.law.f_n);  // assemble() runs at the iterate
    if (energy_mode()) pw[k] = pair_work(k, g1.overlap, e.dslip);
    trial[k] = e.law;
    trial_slip[k] = e.dslip;
    for (int a = 0; a < kP; ++a) pf[kP * k + a] = e.force(a);
    for (int a = 0; a < kN; ++a) {
      f[kN * i + a] += e.force(a);
      f[kN * j + a] += e.force(kN + a);
    }
    if (!e.law.loaded) {
      open_contact_stiffness(k, g1);
      continue;
    }
    if (last_open[k]) open_flips[k] = static_cast<std::uint8_t>(std::min(open_flips[k] + 1, 100));
    last_open[k] = 0;
    if (e.law.sliding) any_nonsymmetric = true;
    const PairVec bn = ct::normal_gradient(g1);
    const SlipGradient bt = ct::slip_gradient(g1);
    double k_t = 0.0;
    const double kn_sym = iteration_stiffness(k, bn, bt, e, k_t);
    last_kn[k] = kn_sym;
    scatter(k, e, bn, bt, kn_sym, k_t);
  }
  // stick tangents differ slightly from M too
  if (opt.law.frictional()) any_nonsymmetric = true;
  wall_forces();
  wall_stiffness();
}

// Modifications of a closed pair's consistent tangent e.stiffness for the iteration matrix, from
// the law's iteration stiffness (law.hpp); returns the normal stiffness of the symmetric matrix M
// and its tangential stiffness in k_t.
template <int D, class L>
double NetworkSolverT<D, L>::Impl::iteration_stiffness(std::size_t k, const PairVec& bn, const SlipGradient& bt,
                                                    Element& e, double& k_t) {
  const ct::IterationStiffness is = law.iteration_stiffness(hist[k], e.kin, e.law);
  const double kn_extra = is.k_n_add;
  if (kn_extra > 0.0) e.stiffness.noalias() += kn_extra * bn * bn.transpose();
  // Sliding contacts keep a fraction slide_stiffness_fraction of their tangential spring: the
  // consistent tangent has none, which leaves the rotation of a particle whose contacts all slide
  // without stiffness. A contact whose stick/slip status flipped freeze_after times in this
  // increment keeps its full spring (elastic predictor; slower, but it cannot cycle).
  if (e.law.sliding != (last_sliding[k] != 0)) flips[k] = static_cast<std::uint8_t>(std::min(flips[k] + 1, 100));
  last_sliding[k] = e.law.sliding ? 1 : 0;
  const double frac = flips[k] >= opt.freeze_after ? 1.0 : opt.slide_stiffness_fraction;
  if (e.law.sliding && frac > 0.0) {
    if constexpr (D == 2) {
      e.stiffness.noalias() += frac * is.k_t * bt * bt.transpose();
    } else {
      e.stiffness.noalias() += frac * is.k_t * bt.transpose() * bt;
    }
  }
  k_t = is.k_t * (e.law.sliding ? frac : 1.0);
  return e.tangent.dfn_dun + kn_extra;
}

// Adds pair k's iteration matrix to K and its symmetric slip-status tangent to M.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::scatter(std::size_t k, const Element& e, const PairVec& bn, const SlipGradient& bt,
                                      double kn_sym, double k_t) {
  const double kt = k_t;
  double* Kv = K.valuePtr();
  double* Mv = M.valuePtr();
  if constexpr (D == 2) {
    pattern.for_each_entry<kP>(k, [&](int q, int a, int b) {
      Kv[q] += e.stiffness(a, b);
      Mv[q] += kn_sym * bn(a) * bn(b) + kt * bt(a) * bt(b);
    });
  } else {
    const PairMat Ms = kn_sym * bn * bn.transpose() + kt * bt.transpose() * bt;
    pattern.for_each_entry<kP>(k, [&](int q, int a, int b) {
      Kv[q] += e.stiffness(a, b);
      Mv[q] += Ms(a, b);
    });
  }
}

/// Pair k has never touched and is apart: zero trial state and force.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::set_apart(std::size_t k) {
  trial[k] = Response{};
  trial_slip[k] = ct::tan_zero<Tan>();
  std::fill_n(&pf[kP * k], kP, 0.0);
  pw[k] = 0.0;
  apart[k] = 1;
}

/// Trial state and force (pf, no tangent) of pair k at the current du; e is scratch. A pair
/// that has never touched and is clearly apart costs a squared distance (its zero trial state
/// and force are written once, then flagged in `apart`).
template <int D, class L>
void NetworkSolverT<D, L>::Impl::pair_forces(std::size_t k, Element& e) {
  const int i = pi[k], j = pj[k];
  const Vec xi = moved(i), xj = moved_j(k);
  if (!law.has_history(hist[k])) {
    const double rs = ps.r[i] + ps.r[j];
    if ((xj - xi).squaredNorm() > rs * rs * (1.0 + 1e-9)) {  // overlap < 0 beyond any rounding
      if (!apart[k]) set_apart(k);
      return;
    }
  }
  apart[k] = 0;  // (a pair this test lets through with overlap <= 0 is set apart below: the same state)
  const Geometry g1 = ct::pair_geometry(xi, xj, ps.r[i], ps.r[j]);
  if (g1.overlap <= 0.0 && !law.has_history(hist[k])) {
    set_apart(k);
    return;
  }
  ct::pair_element(law, hist[k], g0[k], g1, rotation(i), rotation(j), e, nullptr);
  if (energy_mode()) pw[k] = pair_work(k, g1.overlap, e.dslip);
  trial[k] = e.law;
  trial_slip[k] = e.dslip;
  for (int a = 0; a < kP; ++a) pf[kP * k + a] = e.force(a);
}

// Forces only, on opt.threads threads: the pairs (in parallel), then f gathered per particle
// over its pairs in increasing pair order, i.e. the same sums in the same order as the
// assembling loop (bit-identical results for any number of threads).
template <int D, class L>
void NetworkSolverT<D, L>::Impl::evaluate_forces() {
  pf.resize(kP * pi.size());
  apart.resize(pi.size(), 0);
  pw.resize(pi.size(), 0.0);
  const auto np = static_cast<std::ptrdiff_t>(pi.size());
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(1);  // LinearSolver sets 0 to keep CHOLMOD serial
#pragma omp parallel num_threads(opt.threads)
  {
    Element e;
#pragma omp for schedule(static)
    for (std::ptrdiff_t kk = 0; kk < np; ++kk) {
      pair_forces(static_cast<std::size_t>(kk), e);
    }
#pragma omp for schedule(static)
    for (int p = 0; p < n; ++p) {
      double s[kN] = {};
      for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) {
        const auto k = static_cast<std::size_t>(adj_pair[q]);
        const double* fk = &pf[kP * k + (pi[k] == p ? 0 : kN)];
        for (int a = 0; a < kN; ++a) s[a] += fk[a];
      }
      for (int a = 0; a < kN; ++a) f[kN * p + a] = s[a];
    }
  }
  omp_set_max_active_levels(levels);
  wall_forces();  // serial, after the pairs: the same sums in the same order
}

// Open/closed cycling: a pair that closed and opened again within this increment keeps the
// normal stiffness it last had while closed, so that the Newton step lands near touch instead
// of jumping across it (iteration matrix only).
template <int D, class L>
void NetworkSolverT<D, L>::Impl::open_contact_stiffness(std::size_t k, const Geometry& g1) {
  if (!last_open[k]) open_flips[k] = static_cast<std::uint8_t>(std::min(open_flips[k] + 1, 100));
  last_open[k] = 1;
  if (open_flips[k] < 2 || last_kn[k] <= 0.0) return;
  const double kn = last_kn[k];
  const PairVec bn = ct::normal_gradient(g1);
  pattern.for_each_entry<kP>(k, [&](int q, int a, int b) {
    const double v = kn * bn(a) * bn(b);
    K.valuePtr()[q] += v;
    M.valuePtr()[q] += v;
  });
}

/// Re-evaluates (forces only) the pairs of the given particles after their du changed, keeping
/// f, pf and the trial state consistent with du without a full evaluation.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::refresh_particles(const std::vector<int>& group) {
  Element e;
  for (const int p : group)
    for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) {
      const auto k = static_cast<std::size_t>(adj_pair[q]);
      if (refreshed[k]) continue;
      refreshed[k] = 1;
      const int i = pi[k], j = pj[k];
      for (int a = 0; a < kN; ++a) {
        f[kN * i + a] -= pf[kP * k + a];
        f[kN * j + a] -= pf[kP * k + kN + a];
      }
      pair_forces(k, e);
      for (int a = 0; a < kN; ++a) {
        f[kN * i + a] += pf[kP * k + a];
        f[kN * j + a] += pf[kP * k + kN + a];
      }
    }
  for (const int p : group)
    for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) refreshed[static_cast<std::size_t>(adj_pair[q])] = 0;
  if (walls())
    for (const int p : group) {
      wall_particle(p, -1.0);
      wall_particle(p, 1.0);
    }
}

/// Mean translational diagonal of the iteration matrix (rotational if no translation is free).
template <int D, class L>
double NetworkSolverT<D, L>::Impl::mean_diagonal() const {
  double sum = 0.0, rot = 0.0;
  int c = 0, cr = 0;
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < kN; ++a)
      if (const int d = dof[kN * p + a]; d >= 0) {
        if (!is_rotation(a)) {
          sum += M.valuePtr()[pattern.diag(d)];
          ++c;
        } else {
          rot += M.valuePtr()[pattern.diag(d)];
          ++cr;
        }
      }
  if (c > 0 && sum > 0.0) return sum / c;
  if (cr > 0 && rot > 0.0) return rot / cr / (r_mean * r_mean);
  return law.reference_stiffness(r_mean);
}

/// Adds the viscous drag and the tiny regularisation to the diagonal of K and M.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::regularise() {
  const double ref = mean_diagonal();
  const double eps = opt.regularisation * ref;
  const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < kN; ++a)
      if (const int d = dof[kN * p + a]; d >= 0) {
        const double add = eps * (is_rotation(a) ? r_mean * r_mean : 1.0) + (is_rotation(a) ? eta_r : eta_t);
        K.valuePtr()[pattern.diag(d)] += add;
        M.valuePtr()[pattern.diag(d)] += add;
      }
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template struct NetworkSolverT<2>::Impl;
template struct NetworkSolverT<3>::Impl;
#else
template struct NetworkSolverT<2, LinearLawT<2>>::Impl;
template struct NetworkSolverT<3, LinearLawT<3>>::Impl;
#endif

}  // namespace netdem::qs
