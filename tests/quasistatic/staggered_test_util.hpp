#pragma once
// Shared by the staggered scheme's tests (test_staggered.cpp, test_staggered_run.cpp): the Cu
// benchmark's material and temperature, simple cubic samples, and the state compared bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/quasistatic/staggered.hpp"

namespace netdem::test {

inline const contact::sinter::SinterMaterial& cu() {
  static const contact::sinter::SinterMaterial m = contact::sinter::builtin_sinter_material("cu");
  return m;
}
constexpr double kT = 1293.0;  // the Cu benchmark's temperature [K]

inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// spheres on a simple cubic grid of spacing 2 r, radii r (1 +- jitter), seeded
inline qs::staggered::Particles cubic(int n, double r, double jitter, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  qs::staggered::Particles p;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double ri = r * (1.0 + jitter * u(gen));
        p.push_back(Eigen::Vector3d(r + 2.0 * r * i, r + 2.0 * r * j, r + 2.0 * r * k), ri);
      }
  return p;
}

// A polydisperse sample: some neighbours touch, some only later (new contacts), the bonds pull
// against each other (Eq 44 is not zero).
inline qs::staggered::Staggered jittered(double E, int strategy = 2) {
  qs::staggered::StaggeredOptions o;
  o.strategy = strategy;
  o.E = E;
  return qs::staggered::Staggered(cubic(3, 25e-6, 0.01, 7), cu(), contact::sinter::TemperatureProfile::constant(kT), o);
}

// time, dt, positions, contacts and their pair states, bit for bit
inline void expect_same(const qs::staggered::Staggered& a, const qs::staggered::Staggered& b) {
  ASSERT_EQ(a.particles().size(), b.particles().size());
  ASSERT_EQ(a.contacts().size(), b.contacts().size());
  EXPECT_TRUE(same_bits(a.time(), b.time()));
  EXPECT_TRUE(same_bits(a.dt(), b.dt()));
  for (std::size_t i = 0; i < a.particles().size(); ++i)
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(same_bits(a.particles().coord(i, k), b.particles().coord(i, k))) << i << " " << k;
  for (std::size_t i = 0; i < a.contacts().size(); ++i) {
    const auto &ca = a.contacts()[i], &cb = b.contacts()[i];
    ASSERT_EQ(ca.a, cb.a);
    ASSERT_EQ(ca.b, cb.b);
    ASSERT_EQ(ca.frozen, cb.frozen);
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(same_bits(ca.pair.q[k], cb.pair.q[k])) << "contact " << i;
    ASSERT_TRUE(same_bits(ca.dL_bar, cb.dL_bar));
  }
}

}  // namespace netdem::test
