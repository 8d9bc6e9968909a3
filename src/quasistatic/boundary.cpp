// Boundary conditions of the network solver (Redanz & Fleck 2001 section 2.4, Eqs 14-15): which
// DOFs are prescribed (DofMap) and the prescribed motion and predictor of an increment.
#include "solver_impl.hpp"

namespace netdem::qs {

#ifndef NETDEM_QS_MORE  // (not a template: compiled once, with the 2D solver)
void DofMap::build(int dim, int rot_dofs, BoundaryMode mode, bool rotations_free,
                   const std::vector<std::uint8_t>& periph, int pinned, bool affine_centres) {
  const int n = static_cast<int>(periph.size()), kn = dim + rot_dofs;
  dof.assign(static_cast<std::size_t>(kn) * n, -1);
  nfree = 0;
  for (int p = 0; p < n; ++p) {
    // walls: nothing prescribed; periodic: only the pinned particle's translations (affine_centres:
    // every particle's)
    const bool walls = mode == BoundaryMode::Walls || mode == BoundaryMode::Periodic;
    const bool translations_free =
        (walls && p != pinned && !affine_centres) || (mode == BoundaryMode::Die && !periph[p]);
    if (translations_free)
      for (int a = 0; a < dim; ++a) dof[kn * p + a] = nfree++;
    // peripheral rotations are always held (section 2.4); interior ones are unknowns in both modes
    if (rotations_free && (walls || !periph[p]))
      for (int a = dim; a < kn; ++a) dof[kn * p + a] = nfree++;
  }
}
#endif

// The prescribed motion (Eqs 14-15 on current coordinates) is the affine motion of the increment;
// the predictor for the free DOFs is this affine motion plus the previous increment's non-affine
// part (scaled; rotations: the previous rotation increment, scaled) on an unchanged strain path,
// else the affine motion alone. The non-affine part is du_prev minus the previous affine motion
// at the previous increment's start positions, so the predictor does not depend on the origin.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::prescribe(const Mat& dE) {
  const Mat A = small_expm<D>(dE) - Mat::Identity();
  Fbox_trial = small_expm<D>(dE) * Fbox;  // the walls of BoundaryMode::Walls at the end of the increment
  du_aff.assign(kN * n, 0.0);
  for (int p = 0; p < n; ++p) {
    const Vec u = A * at(p);
    for (int a = 0; a < D; ++a) du_aff[kN * p + a] = u(a);
  }
  const double dn = dE.norm(), dpn = dE_prev.norm();
  const bool reuse = !du_prev.empty() && dpn > 0.0 && dn > 0.0 &&
                     (dE.array() * dE_prev.array()).sum() / (dn * dpn) > 0.999;
  const double scale = reuse ? dn / dpn : 0.0;
  for (int q = 0; q < kN * n; ++q) du[q] = du_aff[q];
  // the energy iteration keeps the affine predictor: a rearrangement of the last increment is not
  // a trend (docs/quasistatic.md "Frictionless: a trust region on the energy")
  if (!reuse || energy_mode()) return;
  // the previous increment's affine part, A_prev x_prev, at its start positions x_prev = x - du_prev
  const Mat A_prev = small_expm<D>(dE_prev) - Mat::Identity();
  // pseudo-transient: a particle without a loaded contact has no equilibrium position of its own
  // (any position away from its neighbours has a zero residual), so it keeps the affine predictor
  // instead of drifting on with the extrapolated motion of the last increment
  const bool held_only = pseudo_transient();
  if (held_only) loaded_particle(predictor_loaded);
  for (int p = 0; p < n; ++p) {
    if (held_only && !predictor_loaded[p]) continue;
    const Vec up = Eigen::Map<const Vec>(&du_prev[kN * p]);
    const Vec na = up - A_prev * (at(p) - up);
    for (int a = 0; a < D; ++a)
      if (dof[kN * p + a] >= 0) du[kN * p + a] += scale * na(a);
    for (int a = D; a < kN; ++a)
      if (dof[kN * p + a] >= 0) du[kN * p + a] = scale * du_prev[kN * p + a];
  }
}

/// loaded[p] = 1 if particle p has a loaded contact (a pair or, in walls mode, a wall) in the
/// committed state.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::loaded_particle(std::vector<std::uint8_t>& loaded) const {
  loaded.assign(n, 0);
  for (std::size_t k = 0; k < pi.size(); ++k)
    if (fn_c[k] > 0.0) loaded[pi[k]] = loaded[pj[k]] = 1;
  for (std::size_t s = 0; s < wfn_c.size(); ++s)
    if (wfn_c[s] > 0.0) loaded[s / kW] = 1;
}

template <int D, class L>
void NetworkSolverT<D, L>::set_reversible_normal(bool reversible) {
  static_assert(kPlastic, "the section 3.4 unloading branch is the plastic-indentation law's");
  auto& s = *impl_;
  if (!reversible && s.opt.law.reversible) {
    for (std::size_t k = 0; k < s.pi.size(); ++k) {
      const int i = s.pi[k], j = s.pj[k];
      const double u = ct::pair_geometry(s.at(i), s.at_j(k), s.ps.r[i], s.ps.r[j]).overlap;
      s.hist[k] = Impl::Law::start_unloading_branch(s.hist[k], u);
    }
  }
  Options o = s.opt;
  o.law.reversible = reversible;
  s.set_options(o);
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template class NetworkSolverT<2>;
template class NetworkSolverT<3>;
#else
// the linear law: the Impl's members only (set_reversible_normal is the plastic law's, and clang 14
// instantiates constrained members too)
template struct NetworkSolverT<2, LinearLawT<2>>::Impl;
template struct NetworkSolverT<3, LinearLawT<3>>::Impl;
#endif

}  // namespace netdem::qs
