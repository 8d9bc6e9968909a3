#pragma once
// Periodic packings (issue 29, item 1): a random gas in a periodic square (cubic) cell, compressed
// isotropically by the explicit DEM in a periodic cell until it jams, held by a servo on the cell
// at a small target pressure until it is at rest, so that the overlaps are negligible. The
// packing of the end state is returned with '# periodic' (docs/packing.md "Periodic packings").
//
// The law: ContactModel::Linear of the DEM (Luding's linear spring-dashpot, k_n = 1 per unit
// overlap, tangential spring alpha k_n with Coulomb friction mu, frictionless by default), in
// units of the mean radius R = 1, the stiffness k_n = 1 and the density rho = 1 (disks of unit
// depth; mass rho pi r^2, spheres rho 4/3 pi r^3). The target pressure p / k_n (2D: force per
// length over force per length of overlap, dimensionless) sets the overlaps: at p / k_n = 1e-4
// they are of order 1e-4 R. This is the harmonic soft-disk model of O'Hern et al. (PRE 68,
// 011306, 2003) at a finite pressure, whose density tends to the jamming density phi_J as the
// pressure goes to 0.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "netdem/contact/luding.hpp"
#include "netdem/packing/packing.hpp"

namespace netdem::dem {

struct PeriodicPackOptions {
  std::size_t n = 1600;            ///< particles
  double r_min = 0.9, r_max = 1.1;  ///< radii uniform in [r_min, r_max] (R = 1: their mean should be about 1)
  std::uint64_t seed = 1;
  double friction = 0.0;     ///< Coulomb coefficient of the packing law (0: frictionless)
  double pressure = 1e-4;    ///< target p / k_n at the end (the overlaps' scale)
  double gas_density = 0.3;  ///< the random sequential addition's density
  double pressure_tol = 0.02;  ///< |p / target - 1| at the end
  /// at rest: the RMS unbalanced force (DynamicSolverT::unbalanced_force_rms) below this times the
  /// mean contact force
  double force_tol = 3e-3;
  double max_steps = 2e6;    ///< the run stops there ("unconverged")
  /// Throws netdem::FieldError (fields n, r_min, r_max, friction, pressure, gas_density, max_steps).
  void validate(int dim) const;
};

struct PeriodicPackSummary {
  std::string status = "ok";  ///< ok | unconverged (the step limit before the servo settled)
  std::string reason;
  double density = 0.0;           ///< solid area (volume) / cell area (volume)
  double pressure = 0.0;          ///< p / k_n at the end (contact stress, trace / D)
  double unbalanced = 0.0;        ///< RMS unbalanced force / mean contact force at the end
  double Z = 0.0;                 ///< 2 contacts / N (every particle)
  /// the same without the rattlers (fewer than D + 1 contacts, frictional: fewer than D; removed recursively)
  double Z_backbone = 0.0;
  double rattler_fraction = 0.0;  ///< rattlers / N
  double psi6_global = 0.0;       ///< 2D: |(1/N') sum_j psi6_j|, psi6_j = mean over j's contacts of exp(6 i theta)
  double psi6_local = 0.0;        ///< 2D: (1/N') sum_j |psi6_j| (N': the particles with a contact)
  double max_overlap = 0.0, mean_overlap = 0.0;  ///< over the touching pairs, in units of R (the mean radius)
  std::size_t contacts = 0;
  std::int64_t steps = 0, steps_to_first_contact_pressure = 0;
  double dt = 0.0;
};

/// The contact law of the periodic route (dimension dim, 2 or 3; rho = 1): linear, k_n = 1, normal
/// damping 0.3 of critical for the pair of two particles of radius r_mean, tangential half of it,
/// Coulomb coefficient `friction`, frictionless walls.
contact::LudingParams periodic_packing_law(int dim, double r_mean, double friction);

/// The periodic packing of `o` (dimension dim, 2 or 3) and its summary. `progress` (may be empty)
/// gets the fraction of the step limit used, every few hundred steps.
packing::Packing make_periodic_packing(int dim, const PeriodicPackOptions& o, PeriodicPackSummary& summary,
                                       const std::function<void(double)>& progress = {});

}  // namespace netdem::dem
