#pragma once
// Periodic lattices of touching particles for the periodic-cell tests of both solvers
// (tests/quasistatic/test_periodic_network.cpp, tests/dynamic/test_periodic_dem.cpp).
#include <cmath>

#include "netdem/packing/packing.hpp"

namespace netdem::test {

// A periodic triangular lattice of nc x nr touching disks of radius R (nr even): rows sqrt(3) R
// apart, odd rows offset by R; cell 2 R nc x sqrt(3) R nr. Every disk touches six.
inline packing::Packing triangular_lattice(int nc, int nr, double R = 1.0) {
  packing::Packing p;
  const double h = std::sqrt(3.0) * R;
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c < nc; ++c) {
      p.x.push_back(R * (r % 2) + 2 * R * c + 0.5 * R);
      p.y.push_back(h * r + 0.5 * h);
      p.r.push_back(R);
    }
  p.box = {0.0, 0.0, 2 * R * nc, h * nr};
  p.periodic = true;
  return p;
}

// The contact stress of the infinite triangular lattice of triangular_lattice(nc, nr, R) after the
// uniform strain F = exp(E), E = diag(E11, E22), every disk following it (each is a centre of
// symmetry): the bonds of the directions k = 0 (along x), 1 (60 deg), 2 (120 deg) have the branch
// l_k = F l_k0, |l_k0| = 2 R, the normal force normal(k, u_k) at the overlap u_k = 2 R - |l_k| and
// the tangential force tangential(k, F_k) on j along t = perp(n); nc nr bonds per direction, so
// Sigma = (nc nr / V) sum_k (F_k n_k + T_k t_k) (x) l_k with V the deformed cell's area
// (compression POSITIVE, the DEM's sign; netsolve's S is -Sigma). xy = sum f_x l_y, yx = sum f_y l_x.
struct LatticeStress {
  double xx = 0.0, yy = 0.0, xy = 0.0, yx = 0.0;
  int loaded = 0;  ///< contacts with a positive normal force
};
template <class Normal, class Tangential>
LatticeStress triangular_lattice_stress(int nc, int nr, double R, double E11, double E22, Normal normal,
                                        Tangential tangential) {
  const double N = static_cast<double>(nc) * nr;
  const double V = 2 * R * nc * std::sqrt(3.0) * R * nr * std::exp(E11 + E22);
  LatticeStress s;
  for (int k = 0; k < 3; ++k) {
    const double th = k * std::acos(-1.0) / 3.0;
    const double lx = 2 * R * std::cos(th) * std::exp(E11), ly = 2 * R * std::sin(th) * std::exp(E22);
    const double L = std::hypot(lx, ly), nx = lx / L, ny = ly / L;
    const double Fn = normal(k, 2 * R - L), Ft = Fn > 0.0 ? tangential(k, Fn) : 0.0;
    const double fx = Fn * nx - Ft * ny, fy = Fn * ny + Ft * nx;  // t = (-ny, nx)
    s.xx += N * fx * lx / V;
    s.yy += N * fy * ly / V;
    s.xy += N * fx * ly / V;
    s.yx += N * fy * lx / V;
    if (Fn > 0.0) s.loaded += nc * nr;
  }
  return s;
}

// The tangential forces of the lattice sheared along (1, -1, 0) from a hydrostatic state with
// sticking friction, once every slanted bond slides (after a slip of 1 / (sqrt 3 k_t) R, a small
// part of the shear): the shear cap A_c tau_y = F_N / (3 sqrt 3) against the slip. Along x the
// bonds do not slip; j of the 60 degree bond moves along -t relative to i (force +t), that of the
// 120 degree bond along +t (force -t).
inline double sheared_lattice_cap(int k, double Fn) {
  return k == 0 ? 0.0 : (k == 1 ? 1.0 : -1.0) * Fn / (3.0 * std::sqrt(3.0));
}

// A periodic simple cubic lattice of n^3 touching spheres of radius R.
inline packing::Packing cubic_lattice(int n, double R = 1.0) {
  packing::Packing p;
  p.dim = 3;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        p.x.push_back(R + 2 * R * i);
        p.y.push_back(R + 2 * R * j);
        p.z.push_back(R + 2 * R * k);
        p.r.push_back(R);
      }
  p.box = {0.0, 0.0, 2 * R * n, 2 * R * n, 0.0, 2 * R * n};
  p.periodic = true;
  return p;
}

}  // namespace netdem::test
