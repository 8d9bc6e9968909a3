#pragma once
// The DEM compaction protocol (issue 26: it lived in demsolve as a 2D and a 3D twin): a sample of
// plastic-indentation particles driven along a strain-rate direction at a fixed inertial number
// until a target density, measured as netsolve measures its networks (Redanz & Fleck 2001 Eq 13
// and Eq 16, netsolve's sign: compression negative), for disks and spheres alike.
//
// Options in, Summary out (Ceres style); the rows of the run reach the caller through an Observer,
// which writes the files (the library writes none). docs/dynamic.md "demsolve compact".
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "netdem/dynamic/solver.hpp"
#include "netdem/system/strain_path.hpp"

namespace netdem::dem {

using sys::kVoigt;
using sys::Voigt;

/// One sample of the measured state; a history row is the mean of the samples of its window.
/// Stresses in Voigt order (2D 11, 22, 12; 3D 11, 22, 33, 23, 13, 12), compression negative.
template <int D>
struct CompactionSampleT {
  Voigt<D> S{};   ///< Eq 13: the boundary reactions (layer, affine) or the wall forces (walls)
  Voigt<D> Sc{};  ///< the contact (Love-Weber) stress
  /// the kinetic stress of the fluctuations (DynamicSolverT::kinetic_stress, the same sign), apart
  /// from S and Sc; in a periodic cell S is the contact stress (no boundary carries a reaction)
  Voigt<D> Sk{};
  double Z = 0, contacts = 0, sliding = 0, mean_fn = 0;
  double dev_mean_ratio = 0, dev_ratio_of_means = 0, affine_ut = 0;  ///< Eq 16 (sys::AffineDeviation)
  /// 2D, Redanz & Fleck Figs 7-8 as netsolve measures them: mean |u_T - u_T^a| over the mean u_N^a,
  /// u_T the tangential displacement of the centres (L dphi, "centres") or of the contact points
  /// (Eq 5 with the rotations, "rotations") accumulated since the contact was first seen (0 in 3D)
  double dev_ut_centres = 0, dev_ut_rotations = 0;
  double kinetic = 0;  ///< kinetic energy of the motion relative to the affine field, spins included
  double work = 0;     ///< sum F_N u_N / 2 over the loaded particle contacts (spring force)
  void add(const CompactionSampleT& o, double w);
};

/// The measures of a state: Z, the mean normal force, the elastic work and the Eq 16 measures over
/// the loaded particle-particle contacts: those whose spring force (the law on the committed
/// history at zero relative velocity, without the dashpot: ContactInfo::f_spring) is positive, as
/// netsolve counts its quasi-static contacts.
template <int D>
class CompactionMeterT {
 public:
  /// walls: Eq 13 from the wall forces (BoundaryMode walls) instead of the prescribed particles'
  /// reactions.
  CompactionMeterT(bool walls, double r_mean) : walls_(walls), r_mean_(r_mean) {}
  /// E: the macroscopic strain accumulated so far (Voigt); each contact's Eq 16 uses the strain
  /// since it formed (first seen: the strain of the previous sample).
  CompactionSampleT<D> measure(const DynamicSolverT<D>& s, const Voigt<D>& E);
  const std::vector<ContactInfo>& last_contacts() const { return cs_; }

 private:
  bool walls_;
  double r_mean_;
  std::vector<ContactInfo> cs_;
  std::vector<std::uint8_t> is_pre_;
  /// What each loaded pair carries from sample to sample (key i << 32 | j): the strain when it was
  /// first seen and, in 2D, its geometry and the particles' angles at the last sample and the
  /// tangential displacements accumulated since (Figs 7-8).
  struct Formed {
    std::uint64_t key = 0;
    Voigt<D> E_form{};
    double nx = 0, ny = 0, L = 0, d_i = 0, d_j = 0, theta_i = 0, theta_j = 0;
    double centre = 0, slip = 0;
  };
  /// The pairs of the last sample and of this one, sorted by key (storage reused from sample to
  /// sample: no allocation once it is large enough).
  std::vector<Formed> form_, formed_;
  Voigt<D> prev_{};
};

/// The rate of a compaction at inertial number I = gamma' d sqrt(rho / P_ref) (gamma' = |E'|,
/// Frobenius; d = 2R = 2, rho = 1, P_ref = sigma_y = 1: netsolve's units) and its duration to the
/// target density (D = D0 exp(-tr E' t)).
template <int D>
struct CompactionRateT {
  double gamma_dot = 0.0;
  Voigt<D> rate{};  ///< E' (Voigt)
  double initial_density = 0.0;
  double t_end = 0.0;
};
template <int D>
CompactionRateT<D> compaction_rate(const sys::StrainPathT<D>& path, double inertial_number, double initial_density,
                                   double target_density);
/// The same rate along `path`, for a run to the equivalent strain |E| = target_strain: t_end =
/// target_strain / gamma' (|E'| = gamma' whatever the direction, also a constant-volume one).
template <int D>
CompactionRateT<D> compaction_rate_to_strain(const sys::StrainPathT<D>& path, double inertial_number,
                                             double initial_density, double target_strain);

/// Sets the solver's affine strain rate (Voigt). simple_shear (a periodic cell only): the shear
/// rates as simple shear, the velocity gradient L_ab = 2 E'_ab for a < b and L_ba = 0 (x moves
/// with y; 3D: also x with z and y with z), whose symmetric part is E' and whose antisymmetric
/// part is the spin (DynamicSolverT::set_velocity_gradient): the cell tilts and is re-mapped
/// (Lees-Edwards) instead of stretching along the diagonal.
template <int D>
void set_strain_rate(DynamicSolverT<D>& s, const Voigt<D>& rate, bool simple_shear = false);

struct CompactionOptions {
  double target_density = 0.85;
  /// I = gamma' d sqrt(rho / P_ref); 1.5e-4: docs/dynamic.md "demsolve compact", the fit
  double inertial_number = 1.5e-4;
  int increments = 100;     ///< history rows from the start to the target (equal times)
  /// refuse a run estimated to need more time steps; a run that reaches it stops ("incomplete")
  double max_steps = 1e10;
  bool walls = false;       ///< the stress from the wall forces; the wall-vs-contact gap is recorded
  /// If > 0: run the path to this equivalent strain |E| = sqrt(E:E) (off-diagonal components
  /// counted twice) instead of to target_density (then not read); in [kMinTargetStrain,
  /// kMaxTargetStrain], as netsolve's (qs::CompactionOptions::target_strain).
  double target_strain = 0.0;
  static constexpr double kMinTargetStrain = 1e-9, kMaxTargetStrain = 1.0;
  /// If > 0: a hydrostatic precompaction from the initial density to this density first (leg 0,
  /// precompact_increments windows, at the same inertial number), then the path (leg 1).
  double precompact_density = 0.0;
  int precompact_increments = 20;
  bool precompacts() const { return precompact_density != 0.0; }
  /// A periodic cell's shear rates as simple shear (set_strain_rate); the strain measures (|E|,
  /// the rows' E) are those of the symmetric part.
  bool simple_shear = false;
  /// The numbers alone (inertial number, increments, step limit), before any packing is built.
  void check_numbers() const;
  /// Validates every field; the density checks against the initial density (the precompaction
  /// density for the path of a run that precompacts) and the path. Throws netdem::FieldError
  /// (field: inertial_number, increments, to_density, to_strain, precompact_density,
  /// precompact_increments, max_steps, path).
  template <int D>
  void validate(const sys::StrainPathT<D>& path, double initial_density) const;
};

/// One leg of a run: a constant strain rate for a duration, in windows of equal time.
template <int D>
struct CompactionLegT {
  CompactionRateT<D> rate;        ///< the leg's strain rate, start density and duration t_end
  int increments = 0;             ///< its history rows
  double target_density = 0.0;    ///< its target density, or 0 for a strain target
  double target_strain = 0.0;     ///< its target |E|, or 0
  /// The leg's last step is shortened so that it ends at its duration exactly (step_to): its
  /// strain is then the target's to rounding. Set for every leg of a run that precompacts and for
  /// a strain target; a single leg to a density ends, as always, within one step past it.
  bool exact_end = false;
};

/// The legs of a run of `o` from density D0 along `path`: the precompaction (if any), then the
/// path to o.target_density or o.target_strain. Call o.validate first.
template <int D>
std::vector<CompactionLegT<D>> compaction_legs(const sys::StrainPathT<D>& path, const CompactionOptions& o, double D0);

/// One history row: the window means of the increment just completed.
template <int D>
struct CompactionRowT {
  int increment = 0;  ///< counted through the legs
  int leg = 0;        ///< the leg's index (0 for the initial row)
  Voigt<D> E{};  ///< the macroscopic strain
  double density = 0, time = 0;
  CompactionSampleT<D> mean;
  double I = 0;  ///< the actual inertial number from the contact pressure; NaN where it is not positive
  double kinetic_ratio = 0;
  std::int64_t steps = 0;
  int samples = 0;
  double dt = 0;
  int outside = 0;            ///< centres outside the deformed box
  double density_in_box = 0;  ///< the density of the particles whose centre is inside
  double wall_gap = 0;        ///< walls: |S - Sc| / |Sc| on the diagonal
};

template <int D>
struct CompactionSummaryT {
  std::string status = "ok";  ///< ok | unstable | incomplete (the step limit reached; `last`: the last full window)
  std::string reason;         ///< why, "; "-separated; empty when ok
  std::vector<std::string> warnings;
  int increments_done = 0;
  std::int64_t steps = 0;
  int outside = 0;  ///< centres outside the box at the end
  CompactionRowT<D> last;
  double max_wall_gap = 0, last_wall_gap = 0;
  double dt_first = 0;
  bool instability = false;  ///< the run stopped on an InstabilityError (what, quantity, step, time below)
  std::string instability_what, instability_quantity;
  std::int64_t instability_step = 0;
  double instability_time = 0;
  bool ok() const { return status == "ok"; }
};

template <int D>
class CompactionObserverT {
 public:
  virtual ~CompactionObserverT() = default;
  virtual void row(const CompactionRowT<D>& r) = 0;  ///< after each increment (and increment 0)
  virtual void progress(double /*time*/) {}           ///< every few steps
  virtual void checkpoint(int /*increment*/) {}       ///< every 20 increments
};

/// Runs the legs one after the other (the solver set up by the caller, with the strain rate of
/// the first leg and its velocities; legs from compaction_legs()). At the start of each further leg
/// the strain rate becomes the leg's, and outside a periodic cell the free particles' velocities
/// follow the change of the affine field (shift_affine_velocities). The strain of a row is the
/// strain at the end of the last leg plus the leg's rate times its time so far; the rows are
/// numbered through the legs. o's inertial number, step limit and walls are read, not its targets.
template <int D>
CompactionSummaryT<D> run_compaction(DynamicSolverT<D>& s, const std::vector<CompactionLegT<D>>& legs,
                                     const CompactionOptions& o, CompactionObserverT<D>& obs);

/// Runs the compaction of `s` (its particles, box, law, prescribed set and strain rate set up by
/// the caller, rate from compaction_rate()) to rate.t_end in o.increments windows of equal time
/// (one leg to o.target_density).
/// Each window is measured about every 20 steps (at least 10 samples) and averaged. An
/// InstabilityError stops the run: the summary says so (status unstable) and the row of the
/// last completed increment stays the last one reported. So does o.max_steps time steps (status
/// incomplete): the time step can fall below the first one, on which the door's estimate rests.
template <int D>
CompactionSummaryT<D> run_compaction(DynamicSolverT<D>& s, const CompactionRateT<D>& rate, const CompactionOptions& o,
                                     CompactionObserverT<D>& obs);

}  // namespace netdem::dem
