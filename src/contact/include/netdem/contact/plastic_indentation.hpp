#pragma once
// Plastic indentation of cylinders (Redanz & Fleck, Acta Mater. 49 (2001) 4325, section 2.1).
//
// Parameters, history and evaluation are three things: `PlasticIndentationParams` (per run),
// `PlasticIndentationHistory` (per contact, committed only when an increment is accepted) and the
// const evaluation `evaluate()` (contact frame, scalars) / `element()` (6-vector force and 6x6
// incremental stiffness in global axes). Sign conventions: see kinematics.hpp.
//
// Normal (Eq 2): F_N = 3 sigma_y A_c, A_c = sqrt(8 u_N R*) with R* = R1 R2/(R1+R2), on the plastic
// (loading) branch u_N >= u_max. Its tangent is dF_N/du_N = 3 sigma_y sqrt(2 R*/u_N) (the exact
// derivative of Eq 2; the paper's Eq 3 equals it only for R1 = R2). Below u_max the contact un- and
// reloads elastically (section 3.4) with k_u = unload_ratio * dF_N/du_N(u_max) and separates when
// the force reaches zero; reloading rejoins the plastic branch at u_max.
//
// Contact width: A_c := F_N / (3 sigma_y). On the plastic branch this IS Eq 2; on the elastic
// branch it shrinks with the force (our choice: the load-bearing width), so that the tangential
// force vanishes continuously at separation.
//
// Tangential (Eq 6): the spring acts on the shear stress, tau = F_T/A_c = k_t u_T, written in rate
// form dF_T = -k_t A_c dxi (force stiffness k_t A_c, zero at first touch); the force is limited by
// |F_T| <= min(mu F_N, A_c sigma_y/sqrt 3) = mu_eff F_N with mu_eff = min(mu, 1/(3 sqrt 3))
// (section 3.1: "sticking", mu = inf, acts like mu_eff = 0.192). Slip direction from the trial
// force, i.e. from the slip increment (Eq 5, 7). Rolling moment: zero (section 2.1).
#include <cmath>
#include <cstdint>
#include <limits>

#include "netdem/contact/kinematics.hpp"

namespace netdem::contact {

struct PlasticIndentationParams {
  double sigma_y = 1.0;  ///< yield stress of the solid (force per unit depth / length)
  double mu = std::numeric_limits<double>::infinity();  ///< Coulomb coefficient; inf = sticking
  double k_t = 1.0e3;         ///< tau = k_t u_T: shear stress per unit slip [sigma_y / R]
  double unload_ratio = 1.0e3;  ///< elastic un/reloading stiffness / loading tangent at u_max
  /// true: no elastic unloading branch, unloading follows Eq 2 back (nonlinear elastic normal law,
  /// the incremental Eq 3 read literally); false: the section 3.4 unloading branch
  bool reversible = false;

  /// min(mu, 1/(3 sqrt 3)): the Coulomb limit and the shear cap tau_y = sigma_y/sqrt(3) combined.
  double mu_eff() const { return std::fmin(mu, 1.0 / (3.0 * std::sqrt(3.0))); }
  bool frictional() const { return mu > 0.0; }
  /// The shear stress per unit slip in absolute units, k_t sigma_y (k_t is given in sigma_y / R,
  /// lengths in R): so that every force, and S / sigma_y unchanged, scales with sigma_y.
  double shear_stiffness() const { return k_t * sigma_y; }
  /// Throws std::invalid_argument with a one-line message for an invalid value.
  void validate() const;
};

struct PlasticIndentationHistory {
  double u_max = 0.0;     ///< largest overlap reached (plastic flattening); 0 = never touched
  double f_t = 0.0;       ///< committed tangential force on j along t
  std::uint8_t sliding = 0;  ///< 1 if the last committed increment slid
};

enum class NormalBranch : std::uint8_t { Open = 0, Plastic = 1, Elastic = 2 };

/// Contact-frame result of one trial increment.
struct PlasticIndentationResult {
  double f_n = 0.0;   ///< normal force, >= 0 (repulsive)
  double k_n = 0.0;   ///< dF_N/du_N on the active branch
  double area = 0.0;  ///< A_c = F_N/(3 sigma_y)
  double f_t = 0.0;   ///< tangential force on j along t
  double dft_dun = 0.0;    ///< dF_T/du_N at the trial state
  double dft_dslip = 0.0;  ///< dF_T/d(slip increment) at the trial state
  NormalBranch branch = NormalBranch::Open;
  bool sliding = false;
  PlasticIndentationHistory history;  ///< the history to commit if the increment is accepted
};

/// Eq 2: plastic-branch force and tangent.
inline double plastic_force(const PlasticIndentationParams& p, double r_eff, double u) {
  return u > 0.0 ? 3.0 * p.sigma_y * std::sqrt(8.0 * u * r_eff) : 0.0;
}
inline double plastic_tangent(const PlasticIndentationParams& p, double r_eff, double u) {
  return 3.0 * p.sigma_y * std::sqrt(2.0 * r_eff / u);
}

/// Normal force on the branch selected by the committed u_max (no history change).
inline void normal_force(const PlasticIndentationParams& p, double r_eff, double u_max, double u,
                         double& f, double& k, NormalBranch& branch) {
  if (p.reversible) u_max = 0.0;
  if (u >= u_max && u > 0.0) {  // loading: Eq 2
    f = plastic_force(p, r_eff, u);
    k = plastic_tangent(p, r_eff, u);
    branch = NormalBranch::Plastic;
    return;
  }
  if (u_max > 0.0) {  // elastic un/reloading line through (u_max, F_max), section 3.4
    const double ku = p.unload_ratio * plastic_tangent(p, r_eff, u_max);
    const double fe = plastic_force(p, r_eff, u_max) - ku * (u_max - u);
    if (fe > 0.0) {
      f = fe;
      k = ku;
      branch = NormalBranch::Elastic;
      return;
    }
  }
  f = 0.0;
  k = 0.0;
  branch = NormalBranch::Open;
}

/// Overlap at which a contact with history u_max carries no force (u_max for a fresh contact).
inline double separation_overlap(const PlasticIndentationParams& p, double r_eff, double u_max) {
  if (u_max <= 0.0 || p.reversible) return 0.0;
  return u_max - plastic_force(p, r_eff, u_max) / (p.unload_ratio * plastic_tangent(p, r_eff, u_max));
}

/// Secant normal stiffness over a predicted overlap change u0 -> u1 (exact integral of Eq 2 over
/// the increment). Used instead of the tangent for young contacts, whose tangent is singular at
/// u_N = 0. Returns the tangent at u0 when |u1 - u0| is negligible.
inline double normal_secant(const PlasticIndentationParams& p, double r_eff, double u_max, double u0,
                            double u1) {
  double f0, k0, f1, k1;
  NormalBranch b;
  normal_force(p, r_eff, u_max, u0, f0, k0, b);
  // the end point sees the history the start point leaves behind (u_max >= u0 once committed)
  normal_force(p, r_eff, std::fmax(u_max, u0), u1, f1, k1, b);
  const double du = u1 - u0;
  if (std::fabs(du) <= 1e-14 * (1.0 + std::fabs(u0))) return k0;
  return std::fmax((f1 - f0) / du, 0.0);
}

/// One trial increment in the contact frame: end overlap u_n and slip increment dslip (Eq 5),
/// starting from the committed history. Pure function: the new history is returned, not stored.
inline PlasticIndentationResult evaluate(const PlasticIndentationParams& p,
                                         const PlasticIndentationHistory& h, double r_eff, double u_n,
                                         double dslip) {
  PlasticIndentationResult r;
  normal_force(p, r_eff, h.u_max, u_n, r.f_n, r.k_n, r.branch);
  r.history.u_max = std::fmax(h.u_max, u_n);
  r.area = r.f_n / (3.0 * p.sigma_y);
  if (!p.frictional() || r.branch == NormalBranch::Open) {
    r.history.f_t = 0.0;
    r.history.sliding = 0;
    return r;
  }
  // Eq 6 in rate form: elastic predictor on the shear spring
  const double kt_force = p.shear_stiffness() * r.area;
  const double trial = h.f_t - kt_force * dslip;
  const double limit = p.mu_eff() * r.f_n;  // min(mu F_N, A_c tau_y)
  if (std::fabs(trial) <= limit) {
    r.f_t = trial;
    r.dft_dslip = -kt_force;
    r.dft_dun = -p.shear_stiffness() * (r.k_n / (3.0 * p.sigma_y)) * dslip;
    r.sliding = false;
  } else {  // gross slip, Eq 7: F_T = sgn * mu_eff F_N (return mapping onto the limit)
    const double s = trial > 0.0 ? 1.0 : -1.0;
    r.f_t = s * limit;
    r.dft_dslip = 0.0;
    r.dft_dun = s * p.mu_eff() * r.k_n;
    r.sliding = true;
  }
  r.history.f_t = r.f_t;
  r.history.sliding = r.sliding ? 1 : 0;
  return r;
}

/// Which parts of the element tangent to assemble.
struct TangentOptions {
  bool geometric = false;   ///< add the geometric (rotation-of-the-normal) stiffness
};

/// Contact element: forces on both nodes and the consistent 6x6 tangent K = -d f / d q_end.
struct PairElement {
  PlasticIndentationResult law;
  double dslip = 0.0;
  PairVec force = PairVec::Zero();  ///< generalized forces ON the particles (f_i, M_i, f_j, M_j)
  PairMat stiffness = PairMat::Zero();
};

/// Evaluates the increment from configuration g0 (start, committed) to g1 (trial end) with
/// rotation increments dth_i, dth_j. If `tangent` is non-null the consistent tangent with respect
/// to the end configuration is written there (material part always, geometric part on request).
inline void element(const PlasticIndentationParams& p, const PlasticIndentationHistory& h,
                    const PairGeometry& g0, const PairGeometry& g1, double dth_i, double dth_j,
                    PairElement& e, const TangentOptions* tangent = nullptr) {
  e.dslip = slip_increment(g0, g1, dth_i, dth_j);
  e.law = evaluate(p, h, g1.r_eff, g1.overlap, e.dslip);
  const PairVec bn = normal_gradient(g1);
  const PairVec bt = slip_gradient(g1);
  e.force = -e.law.f_n * bn + e.law.f_t * bt;
  if (!tangent) return;
  // d(slip increment)/d q_end for the objective form of Eq 5 (slip_increment()).
  PairVec btt;  // translational part of b_t (no lever arms)
  btt << -g1.t.x(), -g1.t.y(), 0.0, g1.t.x(), g1.t.y(), 0.0;
  const double dphi = std::atan2(cross(g0.n, g1.n), g0.n.dot(g1.n));
  const double Lm = 0.5 * (g0.L + g1.L);
  PairVec ds = (Lm / g1.L) * btt + (0.5 * (g1.a_i * dth_i + g1.a_j * dth_j) - 0.5 * dphi) * bn;
  ds(2) -= 0.5 * (g0.d_i + g1.d_i);
  ds(5) -= 0.5 * (g0.d_j + g1.d_j);
  e.stiffness.noalias() = e.law.k_n * bn * bn.transpose();
  if (e.law.dft_dun != 0.0 || e.law.dft_dslip != 0.0)
    e.stiffness.noalias() -= bt * (e.law.dft_dun * bn + e.law.dft_dslip * ds).transpose();
  if (tangent->geometric && e.law.branch != NormalBranch::Open) {
    PairVec c = PairVec::Zero();
    c(2) = g1.a_i;
    c(5) = g1.a_j;
    e.stiffness.noalias() -= (e.law.f_n / g1.L) * btt * btt.transpose();
    e.stiffness.noalias() -= (e.law.f_t / g1.L) * bn * btt.transpose();
    e.stiffness.noalias() -= e.law.f_t * c * bn.transpose();
  }
}

}  // namespace netdem::contact
