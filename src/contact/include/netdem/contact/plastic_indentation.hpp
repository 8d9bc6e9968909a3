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
// First touch: Eq 2 has an infinite stiffness at u_N = 0. Below u_c = first_touch * 2R* (= first_touch
// R for equal radii R) the loading branch is the chord F = F_2(u_c) u_N / u_c: the force is
// continuous, the stiffness bounded (by 6 sigma_y / sqrt(first_touch), whatever R*), so that an
// explicit solver has a time step; first_touch = 0 is Eq 2 down to u_N = 0.
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
#include "netdem/contact/law.hpp"

namespace netdem::contact {

struct PlasticIndentationParams {
  double sigma_y = 1.0;  ///< yield stress of the solid (force per unit depth / length)
  double mu = std::numeric_limits<double>::infinity();  ///< Coulomb coefficient; inf = sticking
  double k_t = 1.0e3;         ///< tau = k_t u_T: shear stress per unit slip [sigma_y / R]
  double unload_ratio = 1.0e3;  ///< elastic un/reloading stiffness / loading tangent at u_max
  /// true: no elastic unloading branch, unloading follows Eq 2 back (nonlinear elastic normal law,
  /// the incremental Eq 3 read literally); false: the section 3.4 unloading branch
  bool reversible = false;
  /// First-touch overlap u_c / (2 R*): below u_c the loading branch is linear (see above); 0: none
  double first_touch = 1.0e-5;
  /// Contact dashpots for an explicit solver, as fractions of critical damping of the first-touch
  /// chord stiffness k_c = 6 sigma_y / sqrt(first_touch): gamma_n = 2 damping_n sqrt(k_c m*),
  /// gamma_t = 2 damping_t sqrt(k_c m*/3) (m*/3: the tangential effective mass of two equal disks,
  /// rotation included). Constant per pair, so the tangent (rates held) is the undamped one.
  /// 0 (quasi-static): none. Needs first_touch > 0.
  double damping_n = 0.0, damping_t = 0.0;

  /// min(mu, 1/(3 sqrt 3)): the Coulomb limit and the shear cap tau_y = sigma_y/sqrt(3) combined.
  double mu_eff() const { return std::fmin(mu, 1.0 / (3.0 * std::sqrt(3.0))); }
  bool frictional() const { return mu > 0.0; }
  /// The shear stress per unit slip in absolute units, k_t sigma_y (k_t is given in sigma_y / R,
  /// lengths in R): so that every force, and S / sigma_y unchanged, scales with sigma_y.
  double shear_stiffness() const { return k_t * sigma_y; }
  /// The first-touch chord stiffness 6 sigma_y / sqrt(first_touch) (inf for first_touch = 0): the
  /// largest loading stiffness of any contact, whatever R*.
  double chord_stiffness() const { return 6.0 * sigma_y / std::sqrt(first_touch); }
  bool damped() const { return damping_n > 0.0 || damping_t > 0.0; }
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

/// The loading branch with the first-touch rule: Eq 2 above u_c, the chord F_2(u_c) u/u_c below.
inline double first_touch_overlap(const PlasticIndentationParams& p, double r_eff) {
  return p.first_touch * 2.0 * r_eff;
}
inline double loading_force(const PlasticIndentationParams& p, double r_eff, double u) {
  const double uc = first_touch_overlap(p, r_eff);
  if (u < uc) return u > 0.0 ? plastic_force(p, r_eff, uc) * (u / uc) : 0.0;
  return plastic_force(p, r_eff, u);
}
inline double loading_tangent(const PlasticIndentationParams& p, double r_eff, double u) {
  const double uc = first_touch_overlap(p, r_eff);
  if (u < uc) return plastic_force(p, r_eff, uc) / uc;
  return plastic_tangent(p, r_eff, u);
}

/// Normal force on the branch selected by the committed u_max (no history change).
inline void normal_force(const PlasticIndentationParams& p, double r_eff, double u_max, double u,
                         double& f, double& k, NormalBranch& branch) {
  if (p.reversible) u_max = 0.0;
  if (u >= u_max && u > 0.0) {  // loading: Eq 2
    f = loading_force(p, r_eff, u);
    k = loading_tangent(p, r_eff, u);
    branch = NormalBranch::Plastic;
    return;
  }
  if (u_max > 0.0) {  // elastic un/reloading line through (u_max, F_max), section 3.4
    const double ku = p.unload_ratio * loading_tangent(p, r_eff, u_max);
    const double fe = loading_force(p, r_eff, u_max) - ku * (u_max - u);
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
  return u_max - loading_force(p, r_eff, u_max) / (p.unload_ratio * loading_tangent(p, r_eff, u_max));
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

/// evaluate() with contact dashpots (explicit dynamics): the normal force F_N = max(0, F_spring +
/// fd_n) is never attractive; the tangential dashpot force fd_t acts inside the Coulomb limit
/// min(mu F_N, A_c tau_y) (the spring is reset so that spring + dashpot sits on the limit while
/// sliding, as LMM05 Eq 21); the contact width A_c = F_spring/(3 sigma_y) comes from the spring.
/// fd_n = gamma_n d(overlap)/dt, fd_t = -gamma_t d(slip)/dt.
inline PlasticIndentationResult evaluate_damped(const PlasticIndentationParams& p,
                                                const PlasticIndentationHistory& h, double r_eff,
                                                double u_n, double dslip, double fd_n, double fd_t) {
  PlasticIndentationResult r;
  normal_force(p, r_eff, h.u_max, u_n, r.f_n, r.k_n, r.branch);
  r.history.u_max = std::fmax(h.u_max, u_n);
  r.area = r.f_n / (3.0 * p.sigma_y);
  if (r.branch == NormalBranch::Open) {
    r.history.f_t = 0.0;
    r.history.sliding = 0;
    return r;
  }
  const double k_spring = r.k_n;
  r.f_n += fd_n;
  if (!(r.f_n > 0.0)) {  // F_N >= 0: the dashpot does not pull
    r.f_n = 0.0;
    r.k_n = 0.0;
  }
  if (!p.frictional()) {
    r.history.f_t = 0.0;
    r.history.sliding = 0;
    return r;
  }
  const double kt_force = p.shear_stiffness() * r.area;
  const double spring = h.f_t - kt_force * dslip;
  const double trial = spring + fd_t;
  const double cap = r.area * p.sigma_y / std::sqrt(3.0);  // A_c tau_y
  const bool coulomb = !std::isinf(p.mu) && p.mu * r.f_n < cap;
  const double limit = coulomb ? p.mu * r.f_n : cap;
  if (std::fabs(trial) <= limit) {
    r.f_t = trial;
    r.history.f_t = spring;
    r.dft_dslip = -kt_force;
    r.dft_dun = -p.shear_stiffness() * (k_spring / (3.0 * p.sigma_y)) * dslip;
    r.sliding = false;
  } else {
    const double s = trial > 0.0 ? 1.0 : -1.0;
    r.f_t = s * limit;
    r.history.f_t = s * limit - fd_t;
    r.dft_dslip = 0.0;
    r.dft_dun = s * (coulomb ? p.mu * r.k_n : k_spring / (3.0 * std::sqrt(3.0)));
    r.sliding = true;
  }
  r.history.sliding = r.sliding ? 1 : 0;
  return r;
}

/// The plastic-indentation law behind the contact-law interface (law.hpp). Holds its parameters
/// by value; a solver builds it once per run (or per parameter change).
class PlasticIndentationLaw {
 public:
  using Params = PlasticIndentationParams;
  using History = PlasticIndentationHistory;
  using Response = ContactResponse<History>;
  /// u_max outlives separation: a separated contact reloads elastically from its flattening.
  static constexpr bool kHistoryOutlivesSeparation = true;

  PlasticIndentationLaw() = default;
  explicit PlasticIndentationLaw(const Params& p)
      : p_(p), damped_(p.damped()), k_chord_(p.damped() ? p.chord_stiffness() : 0.0) {}
  const Params& params() const { return p_; }
  bool has_history(const History& h) const { return h.u_max > 0.0; }

  Response evaluate(const History& h, const ContactKinematics& k, ContactTangent* t) const {
    PlasticIndentationResult r;
    if (!damped_) {
      r = contact::evaluate(p_, h, k.r_eff, k.overlap, k.dslip);
    } else {
      const double gn = 2.0 * p_.damping_n * std::sqrt(k_chord_ * k.m_eff);
      const double gt = 2.0 * p_.damping_t * std::sqrt(k_chord_ * k.m_eff / 3.0);
      r = evaluate_damped(p_, h, k.r_eff, k.overlap, k.dslip, gn * k.v_n, -gt * k.v_t);
    }
    Response out;
    out.f_n = r.f_n;
    out.f_t = r.f_t;
    out.loaded = r.branch != NormalBranch::Open;
    out.sliding = r.sliding;
    out.branch = static_cast<std::uint8_t>(r.branch);
    out.history = r.history;
    if (t) {
      t->dfn_dun = r.k_n;
      t->dfn_dslip = 0.0;
      t->dft_dun = r.dft_dun;
      t->dft_dslip = r.dft_dslip;
    }
    return out;
  }

  /// Normal: the tangent of the active branch at the end of the step, or the elastic
  /// un/reloading stiffness of the history when that is larger (it is the stiffest branch the
  /// contact can reach in a step). Tangential: k_t A_c at the end force.
  StiffnessBound stiffness_bound(const History& h, const ContactKinematics& k) const {
    double f, kn;
    NormalBranch b;
    normal_force(p_, k.r_eff, h.u_max, k.overlap, f, kn, b);
    const double u_max = p_.reversible ? 0.0 : std::fmax(h.u_max, k.overlap);
    if (u_max > 0.0) kn = std::fmax(kn, p_.unload_ratio * loading_tangent(p_, k.r_eff, u_max));
    StiffnessBound s;
    s.k_n = kn;
    s.k_t = p_.frictional() ? p_.shear_stiffness() * f / (3.0 * p_.sigma_y) : 0.0;
    return s;
  }

  /// Eq 2 is concave with a tangent that is singular at first touch, and Newton on the tangent
  /// overshoots into separation: on the plastic branch the normal stiffness is raised to the secant
  /// of Eq 2 over the step (from the start overlap, or from the force-free overlap) when that is
  /// stiffer. The tangential stiffness is the shear spring k_t A_c, also while sliding.
  IterationStiffness iteration_stiffness(const History& h, const ContactKinematics& k,
                                         const Response& r) const {
    IterationStiffness s;
    if (r.branch == static_cast<std::uint8_t>(NormalBranch::Plastic)) {
      const double u_sep = separation_overlap(p_, k.r_eff, h.u_max);
      const double u_from = std::fmax(k.overlap_start, u_sep);
      if (k.overlap > u_from) {
        const double ksec = normal_secant(p_, k.r_eff, h.u_max, u_from, k.overlap);
        const double kn = loading_tangent(p_, k.r_eff, k.overlap);
        s.k_n_add = std::fmax(0.0, ksec - kn);
      }
    }
    double f_spring = r.f_n;  // the contact width comes from the spring force (no dashpot)
    if (damped_) {
      double kn;
      NormalBranch b;
      normal_force(p_, k.r_eff, h.u_max, k.overlap, f_spring, kn, b);
    }
    s.k_t = p_.frictional() ? p_.shear_stiffness() * (f_spring / (3.0 * p_.sigma_y)) : 0.0;
    return s;
  }

  /// The history with which a contact continues when the elastic unloading branch is switched on
  /// (reversible -> elastic, section 3.4) at overlap u: u_max := u (no force jump); a separated
  /// contact loses its tangential force.
  static History start_unloading_branch(const History& h, double u) {
    History r = h;
    r.u_max = std::fmax(u, 0.0);
    if (u <= 0.0) {
      r.f_t = 0.0;
      r.sliding = 0;
    }
    return r;
  }

 private:
  Params p_;
  bool damped_ = false;
  double k_chord_ = 0.0;
};
static_assert(ContactLaw<PlasticIndentationLaw>);

}  // namespace netdem::contact
