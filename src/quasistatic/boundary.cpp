// Boundary conditions of the network solver (Redanz & Fleck 2001 section 2.4, Eqs 14-15): which
// DOFs are prescribed (DofMap) and the prescribed motion and predictor of an increment.
#include "solver_impl.hpp"

namespace netdem::qs {

Eigen::Matrix2d small_expm(const Eigen::Matrix2d& A) {
  Eigen::Matrix2d term = Eigen::Matrix2d::Identity(), sum = Eigen::Matrix2d::Identity();
  for (int k = 1; k <= 8; ++k) {
    term = term * A / static_cast<double>(k);
    sum += term;
  }
  return sum;
}

void DofMap::build(BoundaryMode mode, bool rotations_free, const std::vector<std::uint8_t>& periph) {
  const int n = static_cast<int>(periph.size());
  dof.assign(3 * n, -1);
  nfree = 0;
  for (int p = 0; p < n; ++p) {
    const bool walls = mode == BoundaryMode::Walls;  // nothing prescribed
    const bool translations_free = walls || (mode == BoundaryMode::Die && !periph[p]);
    if (translations_free) {
      dof[3 * p] = nfree++;
      dof[3 * p + 1] = nfree++;
    }
    // peripheral rotations are always held (section 2.4); interior ones are unknowns in both modes
    if (rotations_free && (walls || !periph[p])) dof[3 * p + 2] = nfree++;
  }
}

// The prescribed motion (Eqs 14-15 on current coordinates) is the affine motion of the increment;
// the predictor for the free DOFs is this affine motion plus the previous increment's non-affine
// part (scaled; rotations: the previous rotation increment, scaled) on an unchanged strain path,
// else the affine motion alone. The non-affine part is du_prev minus the previous affine motion
// at the previous increment's start positions, so the predictor does not depend on the origin.
void NetworkSolver::Impl::prescribe(const Eigen::Matrix2d& dE) {
  const Eigen::Matrix2d A = small_expm(dE) - Eigen::Matrix2d::Identity();
  Fbox_trial = small_expm(dE) * Fbox;  // the walls of BoundaryMode::Walls at the end of the increment
  du_aff.assign(3 * n, 0.0);
  for (int p = 0; p < n; ++p) {
    const Eigen::Vector2d u = A * at(p);
    du_aff[3 * p] = u.x();
    du_aff[3 * p + 1] = u.y();
  }
  const double dn = dE.norm(), dpn = dE_prev.norm();
  const bool reuse = !du_prev.empty() && dpn > 0.0 && dn > 0.0 &&
                     (dE.array() * dE_prev.array()).sum() / (dn * dpn) > 0.999;
  const double scale = reuse ? dn / dpn : 0.0;
  for (int q = 0; q < 3 * n; ++q) du[q] = du_aff[q];
  if (!reuse) return;
  // the previous increment's affine part, A_prev x_prev, at its start positions x_prev = x - du_prev
  const Eigen::Matrix2d A_prev = small_expm(dE_prev) - Eigen::Matrix2d::Identity();
  for (int p = 0; p < n; ++p) {
    const Eigen::Vector2d up(du_prev[3 * p], du_prev[3 * p + 1]);
    const Eigen::Vector2d na = up - A_prev * (at(p) - up);
    if (dof[3 * p] >= 0) du[3 * p] += scale * na.x();
    if (dof[3 * p + 1] >= 0) du[3 * p + 1] += scale * na.y();
    if (dof[3 * p + 2] >= 0) du[3 * p + 2] = scale * du_prev[3 * p + 2];
  }
}

void NetworkSolver::set_reversible_normal(bool reversible) {
  auto& s = *impl_;
  if (!reversible && s.opt.law.reversible) {
    for (std::size_t k = 0; k < s.pi.size(); ++k) {
      const int i = s.pi[k], j = s.pj[k];
      const double u =
          ct::pair_geometry(s.at(i), s.at(j), s.ps.r[i], s.ps.r[j]).overlap;
      s.hist[k] = Law::start_unloading_branch(s.hist[k], u);
    }
  }
  SolverOptions o = s.opt;
  o.law.reversible = reversible;
  s.set_options(o);
}

}  // namespace netdem::qs
