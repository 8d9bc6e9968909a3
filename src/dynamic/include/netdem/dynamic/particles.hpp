#pragma once
// The DEM's particles in dimension D (issue 26): the particle set of every solver
// (sys::ParticleSet<D>: centres D per particle, rotations, radii) with what the explicit
// integration adds: velocities, spins, masses, inertias and the force and torque accumulators.
// Structure of arrays, index = particle id; a vector quantity is D (a rotational one kRotDofs)
// consecutive doubles per particle, as the centres: x_p = pos[D p + a], its spin spin[R p + c].
//
//   2D (disks, ParticlesT<2> = Particles): rot = the angle theta [rad] (integrated), spin = omega,
//      torque = the moment, one per particle;
//   3D (spheres, ParticlesT<3> = Particles3): spin and torque are (x, y, z) per particle; rot stays
//      zero (the DEM does not need the spheres' orientation).
#include <array>
#include <cstddef>
#include <numbers>
#include <vector>

#include "netdem/contact/luding.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::dem {

template <int D>
struct ParticlesT : sys::ParticleSet<D> {
  using Set = sys::ParticleSet<D>;
  static constexpr int kRot = Set::kRotDofs;  ///< spin and torque components per particle
  static constexpr int kSpinZ = kRot - 1;     ///< the spin (torque) about e3: spin[kRot p + kSpinZ]

  std::vector<double> vel;      ///< D per particle [m/s]
  std::vector<double> spin;     ///< kRot per particle [rad/s]
  std::vector<double> mass;     ///< [kg]
  std::vector<double> inertia;  ///< [kg m^2]
  std::vector<double> force;    ///< D per particle: accumulator [N]
  std::vector<double> torque;   ///< kRot per particle: accumulator [N m]

  /// Whether every array holds its count per particle (the radii's count).
  bool consistent() const {
    const std::size_t n = this->size();
    return Set::consistent() && vel.size() == D * n && spin.size() == kRot * n && mass.size() == n &&
           inertia.size() == n && force.size() == D * n && torque.size() == kRot * n;
  }
  /// (ParticleSet::push_back would leave the DEM's arrays short: add one of the particles below.)
  void push_back(const typename Set::Vec&, double) = delete;

  /// 2D: adds a disk of radius r and mass m, I = m r^2 / 2, at rest unless velocities are given.
  std::size_t add_with_mass(double px, double py, double r, double m, double pvx = 0.0, double pvy = 0.0,
                            double pomega = 0.0)
    requires(D == 2)
  {
    return append({px, py}, r, m, {pvx, pvy}, {pomega});
  }
  /// 2D: adds a disk of radius r: mass rho_p pi r^2 h (contact::luding_mass), I = m r^2 / 2.
  std::size_t add(double px, double py, double r, const contact::LudingParams& p, double pvx = 0.0,
                  double pvy = 0.0, double pomega = 0.0)
    requires(D == 2)
  {
    return add_with_mass(px, py, r, contact::luding_mass(p, r), pvx, pvy, pomega);
  }
  /// 2D: adds a disk of radius r and unit depth with the areal density rho: m = rho pi r^2.
  std::size_t add_disk(double px, double py, double r, double rho, double pvx = 0.0, double pvy = 0.0,
                       double pomega = 0.0)
    requires(D == 2)
  {
    return add_with_mass(px, py, r, rho * std::numbers::pi * r * r, pvx, pvy, pomega);
  }
  /// 3D: adds a sphere of radius r and mass m, I = 2/5 m r^2, with velocity v and spin w.
  std::size_t add_sphere_with_mass(double px, double py, double pz, double r, double m,
                                   const std::array<double, 3>& v = {0, 0, 0},
                                   const std::array<double, 3>& w = {0, 0, 0})
    requires(D == 3)
  {
    return append({px, py, pz}, r, m, v, w);
  }
  /// 3D: adds a sphere of density rho: m = rho 4/3 pi r^3.
  std::size_t add_sphere(double px, double py, double pz, double r, double rho,
                         const std::array<double, 3>& v = {0, 0, 0})
    requires(D == 3)
  {
    return add_sphere_with_mass(px, py, pz, r, rho * (4.0 / 3.0) * std::numbers::pi * r * r * r, v);
  }

 private:
  std::size_t append(const std::array<double, D>& x, double r, double m, const std::array<double, D>& v,
                     const std::array<double, kRot>& w) {
    this->pos.insert(this->pos.end(), x.begin(), x.end());
    this->rot.insert(this->rot.end(), kRot, 0.0);
    this->r.push_back(r);
    vel.insert(vel.end(), v.begin(), v.end());
    spin.insert(spin.end(), w.begin(), w.end());
    mass.push_back(m);
    inertia.push_back(contact::Dim<D>::kInertia * m * r * r);
    force.insert(force.end(), D, 0.0);
    torque.insert(torque.end(), kRot, 0.0);
    return this->size() - 1;
  }
};

using Particles = ParticlesT<2>;   ///< disks
using Particles3 = ParticlesT<3>;  ///< spheres

}  // namespace netdem::dem
