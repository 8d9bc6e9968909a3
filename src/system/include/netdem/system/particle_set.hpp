#pragma once
// The particles of a solver in dimension D (issue 26): structure of arrays, the positions D per
// particle in one flat array (x_p = pos[D p + a]), the rotations Dim<D>::kRotDofs per particle
// (2D: the angle about e3; 3D: the accumulated rotation vector), the radii. Built from a packing
// of the same dimension. Plain data: the solvers read and move it, nothing here knows a solver.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "netdem/contact/dim.hpp"
#include "netdem/packing/packing.hpp"

namespace netdem::sys {

template <int D>
struct ParticleSet {
  static_assert(D == 2 || D == 3, "particles are disks (2) or spheres (3)");
  static constexpr int kDim = D;
  static constexpr int kRotDofs = contact::Dim<D>::kRotDofs;
  using Vec = typename contact::Dim<D>::Vec;

  std::vector<double> pos;  ///< D per particle: (x, y[, z]) of particle p at pos[D p]
  std::vector<double> rot;  ///< kRotDofs per particle
  std::vector<double> r;    ///< radii

  std::size_t size() const { return r.size(); }
  /// Centre of particle p.
  Vec position(std::size_t p) const { return Vec(Eigen::Map<const Vec>(&pos[D * p])); }
  double coord(std::size_t p, int axis) const { return pos[D * p + static_cast<std::size_t>(axis)]; }
  /// The centres' coordinates along one axis (a copy).
  std::vector<double> axis(int a) const {
    std::vector<double> v(size());
    for (std::size_t p = 0; p < v.size(); ++p) v[p] = coord(p, a);
    return v;
  }

  /// Appends a particle at rest (zero rotation) at x with radius `radius`.
  void push_back(const Vec& x, double radius) {
    for (int a = 0; a < D; ++a) pos.push_back(x[a]);
    rot.insert(rot.end(), kRotDofs, 0.0);
    r.push_back(radius);
  }
  /// Whether the arrays hold D centre coordinates and kRotDofs rotations per radius.
  bool consistent() const { return pos.size() == D * r.size() && rot.size() == kRotDofs * r.size(); }

  /// The particles of a packing of dimension D, at rest (zero rotations). Throws
  /// std::invalid_argument (one line) if the packing has another dimension.
  static ParticleSet from_packing(const packing::Packing& pk) {
    if (pk.dim != D)
      throw std::invalid_argument("particle set: the packing has dimension " + std::to_string(pk.dim) +
                                  ", the particle set " + std::to_string(D));
    ParticleSet s;
    const std::size_t n = pk.size();
    s.pos.resize(D * n);
    for (std::size_t p = 0; p < n; ++p) {
      s.pos[D * p] = pk.x[p];
      s.pos[D * p + 1] = pk.y[p];
      if constexpr (D == 3) s.pos[D * p + 2] = pk.z[p];
    }
    s.rot.assign(kRotDofs * n, 0.0);
    s.r = pk.r;
    return s;
  }
};

}  // namespace netdem::sys
