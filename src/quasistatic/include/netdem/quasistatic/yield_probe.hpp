#pragma once
// Yield-surface probing of a precompacted network (Redanz & Fleck, Acta Mater. 49 (2001) 4325,
// section 3.4, Figs 9-10): elastic unloading by reversing the compaction path, reloading along a
// strain-rate direction theta in the (E11, E22) plane, and the two yield-point definitions of a
// reloading curve (maximum curvature, offset strain). docs/yield.md states the definitions.
//
// The curve functions (elastic_fit, yield_by_curvature, yield_by_offset) are pure functions of
// the sampled curve (x = probe strain magnitude |dE|, y = work-conjugate stress Sigma : E_hat),
// so they are unit-testable on synthetic curves.
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "netdem/quasistatic/analytic_yield.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/yield_curve.hpp"

namespace netdem::qs {

// the curves and their yield points (src/system/yield_curve.hpp)
using sys::ProbeOptions;
using sys::ProbeSample;
using sys::ProbeCurve;
using sys::ElasticFit;
using sys::elastic_fit;
using sys::ProbeSchedule;
using sys::YieldOptions;
using sys::YieldEstimate;
using sys::yield_by_curvature;
using sys::yield_by_offset;
using sys::interpolate_at;


// ------------------------------------------------------------------------------------------------
// Unloading
struct UnloadOptions {
  double tol = 1e-3;        ///< stop when |Sigma| (Frobenius) < tol * sigma_y
  int max_increments = 40;  ///< give up after this many increments (reported, not thrown)
  /// First trial step (strain magnitude). <= 0: 0.2 * 2|E|/unload_ratio, a fifth of the elastic
  /// spring-back of an affine network (every contact gives back 2 u_max / unload_ratio of overlap).
  double first_step = 0.0;
};

/// The measures an unloading step keeps: StateMeasures in 2D, StressMeasuresT<3> in 3D.
template <int D>
using UnloadMeasuresT = std::conditional_t<D == 2, StateMeasures, StressMeasuresT<D>>;

template <int D>
struct UnloadStepT {
  double strain = 0;  ///< accumulated reversal strain magnitude
  UnloadMeasuresT<D> state;
  IncrementReport report;
};
using UnloadStep = UnloadStepT<2>;

template <int D>
struct UnloadResultT {
  bool converged = false;
  double strain = 0;          ///< total reversal strain magnitude |dE|
  double stress_norm = 0;     ///< final |Sigma| / sigma_y
  double loading_norm = 0;    ///< |Sigma| / sigma_y before unloading
  std::vector<UnloadStepT<D>> path;  ///< the state before unloading (strain 0) and after each increment
  std::string message;        ///< empty, or why it stopped early
};
using UnloadResult = UnloadResultT<2>;
using UnloadResult3 = UnloadResultT<3>;

/// Unloads by increments along -direction (the compaction strain-rate direction, any magnitude)
/// until |Sigma| < tol sigma_y. Each step is the secant prediction of the strain left to
/// |Sigma| = 0 from the last two states (Sigma is projected on the stress before unloading; the
/// last positive secant is kept when noise makes the projection rise); unloading is convex
/// (contacts open one after another, the stiffness only drops), so the prediction undershoots and
/// no step has to be taken back. Stops early (converged = false, message says why) when |Sigma|
/// rises again below 5% of the loading stress (noise floor), the projection crosses zero or the
/// reversal reaches 3 x the linear spring-back of the first step, so that a noisy network is never
/// unloaded into a loose one. Never throws for non-convergence;
/// a solver exception propagates.
/// Sigma is the symmetric Eq 13 stress (3D: StressMeasuresT::eq13, the contact stress in a
/// periodic cell). Instantiated for the plastic law in 2D and 3D.
template <int D>
UnloadResultT<D> unload(NetworkSolverT<D>& solver, const Eigen::Matrix<double, D, D>& direction, double sigma_y,
                        double unload_ratio, const UnloadOptions& options = {});

// ------------------------------------------------------------------------------------------------
// Probing
/// Reloads along (cos theta, sin theta) from the solver's current state. Catches solver
/// exceptions (singular / indefinite tangent, e.g. localisation on dilatant probes): the curve
/// then ends there with end = "singular: <message>".
ProbeCurve probe(NetworkSolver& solver, double theta, double sigma_y, const ProbeOptions& options);

/// Reloads along the strain-rate direction `dir` (any dimension; the steps are strain magnitudes
/// |dE|, so `dir` is normalised to a unit Frobenius norm) as probe() does: sample.stress =
/// Sigma : dir / |dir| / sigma_y. `full`, if given, receives the stress tensor / sigma_y of every
/// sample (samples hold S11, S22, S12 only). probe(solver, theta, ...) is this with
/// diag(cos theta, sin theta).
template <int D>
ProbeCurve probe_along(NetworkSolverT<D>& solver, const Eigen::Matrix<double, D, D>& dir, double sigma_y,
                       const ProbeOptions& options, std::vector<Eigen::Matrix<double, D, D>>* full = nullptr);

// ------------------------------------------------------------------------------------------------
// Fabric-resolved affine bound (our addition; docs/yield.md "Fabric-resolved affine bound")

/// The stress (/ sigma_y, tension positive) of the solver's current state if every load-bearing
/// contact that the strain rate (cos theta, sin theta) in (E11dot, E22dot) compresses
/// (n . Edot . n < 0) keeps its normal force and every other contact carries none:
/// Sigma = -(1/A) sum f_N L n n over those contacts (A = current box area, L = centre distance).
/// This is Appendix A's rigid-plastic affine surface evaluated on the packing's own contacts,
/// branch vectors and forces instead of an isotropic distribution of equal disks with a common
/// force; called at the loading point it gives the affine-affine surface that the probes should
/// reach. Tangential forces are left out (frictionless surface).
YieldPoint fabric_affine_point(const NetworkSolver& solver, double theta, double sigma_y);

/// The 3D fabric-resolved affine bound for the strain rate Edot (any symmetric direction): every
/// load-bearing contact that Edot compresses keeps its normal force f_N and, with mu_eff > 0, slides
/// at the cap mu_eff f_N against its affine tangential velocity L (Edot n - (n.Edot.n) n);
/// Sigma = -(1/V) sum L f_N [n n - mu_eff sym(t n)] / sigma_y over them (V = current cell volume,
/// L n = the branch vector, to j's image in a periodic cell). The isotropic form of the same
/// mechanism is analytic_yield3.hpp's. Throws std::invalid_argument for a non-finite or zero rate,
/// sigma_y <= 0 or mu_eff < 0.
Eigen::Matrix3d fabric_affine_stress3(const NetworkSolver3& solver, const Eigen::Matrix3d& Edot, double mu_eff,
                                      double sigma_y);

}  // namespace netdem::qs
