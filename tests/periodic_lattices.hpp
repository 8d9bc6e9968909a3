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
