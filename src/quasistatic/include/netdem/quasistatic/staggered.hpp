#pragma once
// The staggered quasi-static sintering scheme of Ivannikov et al. (sections 2.3, 2.4, 3; Fig 6) in
// 3D: every contact pair is two elements between two 6-DOF nodes (u, theta),
//   (a) the sintering element: the two-particle model (netdem/contact/sintering_pair.hpp) of the
//       pair, integrated over the step; the step's free shrinkage increment
//       Delta L = Delta(y4 + y7) becomes the axial load F_n = E A Delta L / L0 (Eq 10) on the
//       nodes, with the bond's own A = pi R_m^2 and L0 = y4 + y7 of the step start (so that a free
//       pair shortens by exactly Delta L: the shrinkage is counted once);
//   (b) the bond element: the Potyondy-Cundall link of netdem/contact/bond.hpp, Eq 40 (small
//       rotations within a step: the step is linear, one solve).
// A step (Fig 6): detect new contacts; integrate every pair over dt; assemble and solve the bond
// network with the sintering loads (CHOLMOD; the factor is reused, as the preconditioner of GMRES,
// while the contact set does not change); move the nodes; correct the shrinkage (Eqs 41-44):
// y4 + y7 is set to the exact new centre distance, split in proportion Delta y4 : Delta y7 (or the
// radii when |Delta y4 + Delta y7| < 1e-14 R). The bonds are stress-free after the correction.
// Time marching (section 3.3, Eqs 45-47): strategy 1 (one global dt, a step is rejected when one
// contact misses eps_lim) or strategy 2 (a global dt with per-contact sub-steps). The error of a
// contact's step is a step-doubling estimate of RK4.
//
// Units: SI (m, s, K, N). Documentation: docs/staggered.md.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "netdem/contact/bond.hpp"
#include "netdem/contact/sintering_pair.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::qs::staggered {

namespace cs = netdem::contact::sinter;

struct StaggeredOptions {
  int strategy = 2;              ///< 1: global dt with rejection; 2: global dt, per-contact sub-steps
  double dt_initial = 1e-2;      ///< first global step [s]
  double dt_max = 10.0;          ///< largest global step [s]
  double dt_min = 1e-9;          ///< a (sub-)step below this fails the run [s]
  double alpha = 2.0;            ///< step factor of Eqs 45 and 47
  double eps_lim = 1e-6;         ///< tolerance: relative error of x and of y4 + y7 per (sub-)step
  double grow_below = 0.05;      ///< strategy 2: grow dt when fewer contacts than this needed sub-steps
  double shrink_above = 0.15;    ///< strategy 2: shrink dt when more than this did
  bool new_contacts = true;      ///< detect new contacts at every step (the paper's Fig 11c: off)
  double x0_over_R = 0.01;       ///< neck of a new or initial contact, x0 / R_min, in (1e-4, 0.5)
  /// The neck x / R_min at which a contact freezes (its sintering stops; the bond stays). 0: the
  /// dihedral limit sin(psi/2) with cos(psi/2) = gamma_gb / (2 gamma_s) (notes §4.6).
  double x_max_over_R = 0.0;
  /// Boundary conditions of section 3.3: a centre within boundary_factor * r of one of the three
  /// planes (the planes Oxy, Oxz, Oyz of a packing whose box starts at the origin; see
  /// plane_origin) stays on that plane (its normal displacement is fixed).
  bool boundary_planes = true;
  double boundary_factor = 1.001;
  /// Where the three planes are: x = plane_origin[0], y = [1], z = [2] (the lower corner of the
  /// packing's box: the walls of the green-body route, where a sphere pressed into a wall sits up
  /// to ~1 % r beyond it). NaN (the default): the lower faces of the spheres' bounding box.
  std::array<double, 3> plane_origin{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
                                     std::numeric_limits<double>::quiet_NaN()};
  double E = 0.0;   ///< Young's modulus of the bond [Pa]; 0: the material's E
  double nu = -1.0; ///< Poisson's ratio of the bond, in [0, 0.5); -1: the material's nu
  double gmres_tolerance = 1e-12;  ///< relative residual of the network solve with a reused factor
  /// Refactorise for the next step once the solves since the last factorisation took more GMRES
  /// iterations than this, or than a factorisation costs (0.1 nnz(L) / n iterations), the larger.
  int refactor_iterations = 12;
  /// The ranges of every option, checked here once (the command line checks none of them again):
  /// throws netdem::FieldError (a std::invalid_argument, one line naming the quantity; field() is
  /// the member's name, e.g. "x0_over_R") for the first bad value.
  void validate() const;
  /// validate(), the material's own validate(), and what the options need of the material: the
  /// bonds' E and nu (the options' or the material's) and a freeze limit above x0. The constructor
  /// calls it; a caller that makes the particles later (netsolve sinter's green body) calls it first.
  void validate(const cs::SinterMaterial& m) const;
};

/// The spheres of the scheme: the system layer's particles (centres [m], radii [m]). The rotations
/// stay zero: the bonds are stress-free after every step (the shrinkage correction), so a step's
/// rotations are not accumulated.
using Particles = sys::ParticleSet<3>;

/// One contact pair: the two-particle model's state and what the scheme keeps of it.
struct Contact {
  int a = 0, b = 0;            ///< particles A < B
  cs::PairContact pair;        ///< q = (x, R_A, h_A = y4, R_B, h_B = y7), q0 = the state at creation
  bool frozen = false;         ///< reached x_max (or left the model's domain): no more sintering load
  double t_created = 0.0;      ///< [s]
  double L_created = 0.0;      ///< centre distance at creation [m]
  double dL_bar = 0.0;         ///< Eq 44 of the last step [m]: corrected minus free y4 + y7
  double x_start = 0.0;        ///< neck at creation [m] (> x0 when the spheres overlapped)
};

/// What one accepted step did.
struct StepRecord {
  double t = 0.0, T = 0.0, dt = 0.0;  ///< time at the end of the step, its temperature, its size
  int solves = 0;                     ///< linear solves (1: the step is linear)
  long substeps = 0;                  ///< sub-steps of all contacts (strategy 1: one per contact)
  long contacts_substepped = 0;       ///< contacts that needed more than one sub-step
  int rejected = 0;                   ///< strategy 1: global steps rejected before this one
  int new_contacts = 0;
  int newly_frozen = 0;
  int gmres_iterations = 0;
  bool refactorised = false;
  double max_error = 0.0;             ///< largest error estimate / eps_lim of the accepted (sub-)steps
  double max_shrink_error = 0.0;      ///< max |y4 + y7 - |x_B - x_A|| / |x_B - x_A| after the correction
};

/// Run-time split [s] (steady clock, cumulative).
struct Timers {
  double detect = 0, integrate = 0, assemble = 0, factorise = 0, solve = 0, correct = 0;
};

class Staggered {
 public:
  /// Throws std::invalid_argument (one line) for bad particles, and netdem::FieldError (one too)
  /// for bad options or a material without E or nu (StaggeredOptions::validate(material)).
  /// Initial contacts (centre distance < r_a + r_b) are created at t = 0.
  Staggered(Particles particles, cs::SinterMaterial material, cs::TemperatureProfile temperature,
            StaggeredOptions options);
  ~Staggered();
  Staggered(Staggered&&) noexcept;
  Staggered& operator=(Staggered&&) noexcept;

  /// Fixes one DOF (0-2: u_x, u_y, u_z; 3-5: theta_x, theta_y, theta_z) of a particle, on top of
  /// the boundary planes. A connected cluster of bonded particles without constraint on all
  /// three axes gets its lowest-numbered particle fixed in full (else it would float).
  void fix(int particle, int dof);

  /// One accepted step, ending at most at t_end (and never across a breakpoint of T(t)).
  /// Throws std::runtime_error (one line) when a step cannot be made (dt below dt_min, a singular
  /// network, a failed solve). The state is then that of the last accepted step (positions, time
  /// and pair states untouched), with the new contacts detected at its time and a smaller dt
  /// proposal: save() of it is a valid restart state.
  StepRecord step(double t_end);

  double time() const;
  double dt() const;  ///< the proposal for the next step
  long steps() const;
  const Particles& particles() const;
  const Particles& initial_particles() const;
  const std::vector<Contact>& contacts() const;
  const StaggeredOptions& options() const;
  const cs::SinterMaterial& material() const;
  const cs::TemperatureProfile& temperature() const;
  const Timers& timers() const;
  double x_max_over_R() const;    ///< the freeze limit in use
  int fixed_dofs() const;         ///< constrained DOFs (planes, fix(), anchored clusters)
  /// The particles held on each boundary plane (normal to x, y, z; StaggeredOptions::boundary_planes).
  std::array<int, 3> plane_particles() const;

  /// The least-squares homogeneous strain of the centres since t = 0: x = (I + F) X + c. Shrinkage
  /// along axis i is -F_ii (positive when the sample shrinks).
  Eigen::Matrix3d homogeneous_strain() const;
  /// Sum of the initial particle volumes / volume of the current bounding box of the spheres.
  double density() const;

  /// The whole state in the state archive (JSON, kind "staggered", every double exact;
  /// docs/staggered.md "Restart state"): options, material, temperature profile, particles,
  /// contacts, constraints, the geometry of the last factorisation and the record of origin, so
  /// that a run continued from it is bit-identical to an uninterrupted one.
  std::string save() const;
  /// Reads save(); every field is checked at the door; throws std::invalid_argument (one line,
  /// "ORIGIN: /json/pointer: problem") for a bad file. An old text state is refused with how to
  /// convert it.
  static Staggered load(const std::string& text, const std::string& origin);
  /// The record of origin of the sample (a JSON object, e.g. the seed and the packing of the run
  /// that made it, or null): kept in the state, so that a restart knows it.
  void set_origin_record(const std::string& json_object);
  const std::string& origin_record() const;

 private:
  Staggered();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The Euler-Rodrigues-free part of the scheme that the tests use directly: the corrected split of
/// a new centre distance d_new between y4 and y7 (Eqs 42-43 with the sign of Eq 41 mended): with
/// y4_prev + y7_prev the distance at the step start and Delta y_k = y_k,prev - y_k,free,
/// returns (y4, y7) with y4 + y7 = d_new (one rounding).
std::pair<double, double> corrected_split(double y4_prev, double y7_prev, double y4_free, double y7_free, double d_new,
                                          double R_A, double R_B);

/// The freeze limit x_max / R_min of these options and material (StaggeredOptions::x_max_over_R).
double freeze_limit(const cs::SinterMaterial& m, const StaggeredOptions& o);

/// One contact alone (free sintering, F = 0), integrated as the network integrates each contact
/// under strategy 2: from c.t to t1 with RK4 sub-steps and step doubling, never across a
/// breakpoint of T(t). The reference of the tests (a free pair in the network must follow it).
/// Returns false when a sub-step falls below dt_min or the contact leaves its validity range.
bool advance_free(cs::PairContact& c, const cs::SinterMaterial& m, const cs::TemperatureProfile& T, double t1,
                  const StaggeredOptions& o, long* substeps = nullptr);

}  // namespace netdem::qs::staggered
