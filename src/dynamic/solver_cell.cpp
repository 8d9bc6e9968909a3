// Explicit DEM solver: the periodic cell under a general velocity gradient, and its Lees-Edwards
// re-mapping (issue 29; solver.hpp set_velocity_gradient, cell_remaps; docs/dynamic.md "Periodic cell").
#include "netdem/dynamic/solver.hpp"
#include "solver_detail.hpp"

#include <cmath>

#include <fmt/format.h>

namespace netdem::dem {

using detail::fail;

template <int D>
void DynamicSolverT<D>::set_velocity_gradient(const Eigen::Matrix<double, D, D>& L) {
  if (!periodic_) fail("set_velocity_gradient: a general velocity gradient needs a periodic cell");
  if (!L.allFinite()) fail("set_velocity_gradient: the velocity gradient must be finite");
  const Eigen::Matrix<double, D, D> E = 0.5 * (L + L.transpose());
  if constexpr (D == 2) {
    set_strain_rate(E(0, 0), E(1, 1), E(0, 1));
  } else {
    set_strain_rate3(E(0, 0), E(1, 1), E(2, 2), E(1, 2), E(0, 2), E(0, 1));
  }
  spun_ = false;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) {
      W_[a][b] = 0.5 * (L(a, b) - L(b, a));
      spun_ = spun_ || W_[a][b] != 0.0;
    }
}

// One step of the affine motion with a spin (periodic cells only): G = exp(L dt) - I by its series
// (|L dt| is small; a simple shear's L is nilpotent and the series ends), the positions and the cell
// advected by G, and the accumulated map F <- (I + G) F.
template <int D>
void DynamicSolverT<D>::impose_general_motion(double dt) {
  using Mat = Eigen::Matrix<double, D, D>;
  Mat L;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) L(a, b) = velocity_gradient(a, b);
  const Mat A = L * dt;
  Mat G = A, term = A;
  for (int k = 2; k <= 20; ++k) {
    term = term * A / static_cast<double>(k);
    if (term.cwiseAbs().maxCoeff() <= 1e-20 * G.cwiseAbs().maxCoeff()) break;
    G += term;
  }
  advect_periodic(G);
  if constexpr (D == 2) {
    const auto F = F_;
    const double m0 = 1.0 + G(0, 0), m1 = G(0, 1), m2 = G(1, 0), m3 = 1.0 + G(1, 1);
    F_ = {m0 * F[0] + m1 * F[2], m0 * F[1] + m1 * F[3], m2 * F[0] + m3 * F[2], m2 * F[1] + m3 * F[3]};
  } else {
    for (int a = 0; a < 3; ++a) F3_[static_cast<std::size_t>(a)] *= std::exp(edot3_[a] * dt);
    const auto F = F3m_;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double v = F[static_cast<std::size_t>(3 * a + b)];
        for (int k = 0; k < 3; ++k) v += G(a, k) * F[static_cast<std::size_t>(3 * k + b)];
        F3m_[static_cast<std::size_t>(3 * a + b)] = v;
      }
  }
}

// The Lees-Edwards re-mapping in general form (Lagrange-Gauss reduction of the cell vectors): while
// some vector b projects onto another vector a by more than half of a's length, b <- b - k a with k
// the nearest integer to b.a / a.a. The lattice of images, the cell's measure and the origin are
// unchanged; the table build that calls this finds every pair and its image in the reduced cell.
template <int D>
void DynamicSolverT<D>::reduce_cell() {
  if (!opt_.cell_remap) return;
  bool any = false;
  for (int pass = 0; pass < 64; ++pass) {
    bool changed = false;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) {
        if (a == b) continue;
        const double q = cell_.h.col(b).dot(cell_.h.col(a)) / cell_.h.col(a).squaredNorm();
        if (!(std::abs(q) > 0.5 + 1e-9)) continue;
        cell_.h.col(b) -= std::round(q) * cell_.h.col(a);
        changed = true;
      }
    if (!changed) break;
    any = true;
  }
  if (!any) return;
  ++cell_remaps_;
  set_box_to_cell();
}

template void DynamicSolverT<2>::set_velocity_gradient(const Eigen::Matrix2d& L);
template void DynamicSolverT<3>::set_velocity_gradient(const Eigen::Matrix3d& L);
template void DynamicSolverT<2>::impose_general_motion(double dt);
template void DynamicSolverT<3>::impose_general_motion(double dt);
template void DynamicSolverT<2>::reduce_cell();
template void DynamicSolverT<3>::reduce_cell();

}  // namespace netdem::dem
