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
//
// Spheres (D = 3; Fleck 1995, the 3D analogue of Eq 2, issue 16): F_N = 3 sigma_y pi a^2 with
// a^2 = 2 R* u_N, i.e. F_N = 6 pi sigma_y R* u_N (linear in u_N); A_c = pi a^2 = F_N / (3 sigma_y)
// as in 2D, so the tangential law (Eq 6 with the area pi a^2, the cap pi a^2 sigma_y / sqrt 3), the
// unloading branch and the first-touch rule (the chord of a linear law is the law) are the same
// code. sigma_y is then a stress and the tangential force a vector in the tangent plane. The
// dimension enters only through the normal force of the loading branch (plastic_force<D>).
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <utility>

#include "netdem/contact/fminmax.hpp"
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
  double mu_eff() const { return fmin_of(mu, 1.0 / (3.0 * std::sqrt(3.0))); }
  bool frictional() const { return mu > 0.0; }
  /// The shear stress per unit slip in absolute units, k_t sigma_y (k_t is given in sigma_y / R,
  /// lengths in R): so that every force, and S / sigma_y unchanged, scales with sigma_y.
  double shear_stiffness() const { return k_t * sigma_y; }
  /// The first-touch chord stiffness 6 sigma_y / sqrt(first_touch) (inf for first_touch = 0): the
  /// largest loading stiffness of any 2D contact, whatever R*.
  double chord_stiffness() const { return 6.0 * sigma_y / std::sqrt(first_touch); }
  /// The loading stiffness of a 3D contact, 6 pi sigma_y R* (its chord and tangent).
  double chord_stiffness_3d(double r_eff) const { return 6.0 * std::numbers::pi * sigma_y * r_eff; }
  bool damped() const { return damping_n > 0.0 || damping_t > 0.0; }
  /// Throws std::invalid_argument with a one-line message for an invalid value.
  void validate() const;
};

template <int D>
struct PlasticIndentationHistoryT {
  using Tan = typename Dim<D>::Tan;
  double u_max = 0.0;     ///< largest overlap reached (plastic flattening); 0 = never touched
  Tan f_t = tan_zero<Tan>();  ///< committed tangential force on j (2D: along t)
  std::uint8_t sliding = 0;  ///< 1 if the last committed increment slid
};
using PlasticIndentationHistory = PlasticIndentationHistoryT<2>;

enum class NormalBranch : std::uint8_t { Open = 0, Plastic = 1, Elastic = 2 };

/// Contact-frame result of one trial increment.
template <int D>
struct PlasticIndentationResultT {
  using Tan = typename Dim<D>::Tan;
  double f_n = 0.0;   ///< normal force, >= 0 (repulsive)
  double k_n = 0.0;   ///< dF_N/du_N on the active branch
  double area = 0.0;  ///< A_c = F_N/(3 sigma_y)
  Tan f_t = tan_zero<Tan>();      ///< tangential force on j (2D: along t)
  Tan dft_dun = tan_zero<Tan>();  ///< dF_T/du_N at the trial state
  typename Dim<D>::TanMat dft_dslip = tan_identity<D>(0.0);  ///< dF_T/d(slip increment)
  NormalBranch branch = NormalBranch::Open;
  bool sliding = false;
  PlasticIndentationHistoryT<D> history;  ///< the history to commit if the increment is accepted
};
using PlasticIndentationResult = PlasticIndentationResultT<2>;

/// Eq 2: plastic-branch force and tangent (D = 3: 3 sigma_y pi a^2, a^2 = 2 R* u).
template <int D = 2>
inline double plastic_force(const PlasticIndentationParams& p, double r_eff, double u) {
  if constexpr (D == 2) {
    return u > 0.0 ? 3.0 * p.sigma_y * std::sqrt(8.0 * u * r_eff) : 0.0;
  } else {
    return u > 0.0 ? p.chord_stiffness_3d(r_eff) * u : 0.0;
  }
}
template <int D = 2>
inline double plastic_tangent(const PlasticIndentationParams& p, double r_eff, double u) {
  if constexpr (D == 2) {
    return 3.0 * p.sigma_y * std::sqrt(2.0 * r_eff / u);
  } else {
    (void)u;
    return p.chord_stiffness_3d(r_eff);
  }
}

/// The loading branch with the first-touch rule: Eq 2 above u_c, the chord F_2(u_c) u/u_c below.
inline double first_touch_overlap(const PlasticIndentationParams& p, double r_eff) {
  return p.first_touch * 2.0 * r_eff;
}
template <int D = 2>
inline double loading_force(const PlasticIndentationParams& p, double r_eff, double u) {
  const double uc = first_touch_overlap(p, r_eff);
  if (u < uc) return u > 0.0 ? plastic_force<D>(p, r_eff, uc) * (u / uc) : 0.0;
  return plastic_force<D>(p, r_eff, u);
}
template <int D = 2>
inline double loading_tangent(const PlasticIndentationParams& p, double r_eff, double u) {
  const double uc = first_touch_overlap(p, r_eff);
  if (u < uc) return plastic_force<D>(p, r_eff, uc) / uc;
  return plastic_tangent<D>(p, r_eff, u);
}

/// Normal force on the branch selected by the committed u_max (no history change).
template <int D = 2>
inline void normal_force(const PlasticIndentationParams& p, double r_eff, double u_max, double u,
                         double& f, double& k, NormalBranch& branch) {
  if (p.reversible) u_max = 0.0;
  if (u >= u_max && u > 0.0) {  // loading: Eq 2
    f = loading_force<D>(p, r_eff, u);
    k = loading_tangent<D>(p, r_eff, u);
    branch = NormalBranch::Plastic;
    return;
  }
  if (u_max > 0.0) {  // elastic un/reloading line through (u_max, F_max), section 3.4
    const double ku = p.unload_ratio * loading_tangent<D>(p, r_eff, u_max);
    const double fe = loading_force<D>(p, r_eff, u_max) - ku * (u_max - u);
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
template <int D = 2>
inline double separation_overlap(const PlasticIndentationParams& p, double r_eff, double u_max) {
  if (u_max <= 0.0 || p.reversible) return 0.0;
  return u_max - loading_force<D>(p, r_eff, u_max) / (p.unload_ratio * loading_tangent<D>(p, r_eff, u_max));
}

/// The work of the loading branch (Eq 2 with the first-touch chord) from u = 0 to u: the
/// integral of loading_force (2D: 2 sigma_y sqrt(8 R*) u^{3/2} above u_c; 3D: k_c u^2 / 2).
template <int D = 2>
inline double loading_work(const PlasticIndentationParams& p, double r_eff, double u) {
  if (u <= 0.0) return 0.0;
  const double uc = first_touch_overlap(p, r_eff);
  const double fc = plastic_force<D>(p, r_eff, uc);
  if (u < uc) return 0.5 * fc * u * u / uc;
  const double w_chord = 0.5 * fc * uc;
  if constexpr (D == 2) {
    return w_chord + 2.0 * p.sigma_y * std::sqrt(8.0 * r_eff) * (u * std::sqrt(u) - uc * std::sqrt(uc));
  } else {
    return w_chord + 0.5 * p.chord_stiffness_3d(r_eff) * (u * u - uc * uc);
  }
}

/// The normal force's potential at fixed history: the integral of normal_force (the branch the
/// committed u_max selects, no history change) from the force-free overlap up to u. Its
/// derivative in u is the force normal_force returns, on every branch, so a frictionless step of
/// the quasi-static solver is the minimisation of the sum of these over the contacts.
template <int D = 2>
inline double normal_work(const PlasticIndentationParams& p, double r_eff, double u_max, double u) {
  if (p.reversible || u_max <= 0.0) return loading_work<D>(p, r_eff, u);
  const double ku = p.unload_ratio * loading_tangent<D>(p, r_eff, u_max);
  const double fm = loading_force<D>(p, r_eff, u_max);
  if (u >= u_max) return 0.5 * fm * fm / ku + loading_work<D>(p, r_eff, u) - loading_work<D>(p, r_eff, u_max);
  const double fe = fm - ku * (u_max - u);
  return fe > 0.0 ? 0.5 * fe * fe / ku : 0.0;
}

/// The tangential force's potential over a slip increment dslip at a frozen spring stiffness
/// kt_force (force per unit slip, k_t sigma_y A_c) and a frozen limit (mu_eff F_N): the spring
/// starts at the committed f_t and caps at the limit, so -d/d dslip of this is the tangential
/// force evaluate() returns when its area and limit are those. With them frozen at a state (the
/// normal force of that state), a frictional step of the quasi-static solver is the minimisation
/// of an incremental potential whose gradient at that state is the law's force (an elastic-
/// perfectly-plastic spring: quadratic in the trial force inside the limit, linear outside).
template <int D = 2>
inline double tangential_work(const typename Dim<D>::Tan& f_t_committed, double kt_force, double limit,
                              const typename Dim<D>::Tan& dslip) {
  if (!(limit > 0.0)) return 0.0;
  if (!(kt_force > 0.0)) {  // no spring: the committed force (within the limit) does the work
    const double m = tan_norm(f_t_committed);
    if (!(m > 0.0)) return 0.0;
    return -tan_dot(f_t_committed, dslip) * fmin_of(1.0, limit / m);
  }
  const typename Dim<D>::Tan y = f_t_committed - kt_force * dslip;
  const double m = tan_norm(y);
  const double w = m <= limit ? 0.5 * m * m : limit * m - 0.5 * limit * limit;
  return w / kt_force;
}

/// Secant normal stiffness over a predicted overlap change u0 -> u1 (exact integral of Eq 2 over
/// the increment). Used instead of the tangent for young contacts, whose tangent is singular at
/// u_N = 0. Returns the tangent at u0 when |u1 - u0| is negligible.
template <int D = 2>
inline double normal_secant(const PlasticIndentationParams& p, double r_eff, double u_max, double u0,
                            double u1) {
  double f0, k0, f1, k1;
  NormalBranch b;
  normal_force<D>(p, r_eff, u_max, u0, f0, k0, b);
  // the end point sees the history the start point leaves behind (u_max >= u0 once committed)
  normal_force<D>(p, r_eff, fmax_of(u_max, u0), u1, f1, k1, b);
  const double du = u1 - u0;
  if (std::fabs(du) <= 1e-14 * (1.0 + std::fabs(u0))) return k0;
  return fmax_of((f1 - f0) / du, 0.0);
}

/// One trial increment in the contact frame: end overlap u_n and slip increment dslip (Eq 5),
/// starting from the committed history (3D: its f_t already in the current tangent plane). Pure
/// function: the new history is returned, not stored.
template <int D>
inline PlasticIndentationResultT<D> evaluate(const PlasticIndentationParams& p,
                                             const PlasticIndentationHistoryT<D>& h, double r_eff,
                                             double u_n, const typename Dim<D>::Tan& dslip) {
  using Tan = typename Dim<D>::Tan;
  PlasticIndentationResultT<D> r;
  normal_force<D>(p, r_eff, h.u_max, u_n, r.f_n, r.k_n, r.branch);
  r.history.u_max = fmax_of(h.u_max, u_n);
  r.area = r.f_n / (3.0 * p.sigma_y);
  if (!p.frictional() || r.branch == NormalBranch::Open) {
    r.history.f_t = tan_zero<Tan>();
    r.history.sliding = 0;
    return r;
  }
  // Eq 6 in rate form: elastic predictor on the shear spring
  const double kt_force = p.shear_stiffness() * r.area;
  const Tan trial = h.f_t - kt_force * dslip;
  const double limit = p.mu_eff() * r.f_n;  // min(mu F_N, A_c tau_y)
  const double trial_norm = tan_norm(trial);
  if (trial_norm <= limit) {
    r.f_t = trial;
    r.dft_dslip = tan_identity<D>(-kt_force);
    r.dft_dun = -p.shear_stiffness() * (r.k_n / (3.0 * p.sigma_y)) * dslip;
    r.sliding = false;
  } else {  // gross slip, Eq 7: F_T = sgn * mu_eff F_N (return mapping onto the limit)
    const Tan s = tan_direction(trial);
    r.f_t = s * limit;
    r.dft_dun = s * p.mu_eff() * r.k_n;
    if constexpr (D == 3) {  // the direction turns with the trial force
      const Eigen::Matrix3d P = (limit / trial_norm) * (Eigen::Matrix3d::Identity() - s * s.transpose());
      const Tan dtrial_dun = -p.shear_stiffness() * (r.k_n / (3.0 * p.sigma_y)) * dslip;
      r.dft_dslip = -kt_force * P;
      r.dft_dun += P * dtrial_dun;
    } else {
      r.dft_dslip = 0.0;
    }
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
template <int D>
inline PlasticIndentationResultT<D> evaluate_damped(const PlasticIndentationParams& p,
                                                    const PlasticIndentationHistoryT<D>& h, double r_eff,
                                                    double u_n, const typename Dim<D>::Tan& dslip,
                                                    double fd_n, const typename Dim<D>::Tan& fd_t) {
  using Tan = typename Dim<D>::Tan;
  PlasticIndentationResultT<D> r;
  normal_force<D>(p, r_eff, h.u_max, u_n, r.f_n, r.k_n, r.branch);
  r.history.u_max = fmax_of(h.u_max, u_n);
  r.area = r.f_n / (3.0 * p.sigma_y);
  if (r.branch == NormalBranch::Open) {
    r.history.f_t = tan_zero<Tan>();
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
    r.history.f_t = tan_zero<Tan>();
    r.history.sliding = 0;
    return r;
  }
  const double kt_force = p.shear_stiffness() * r.area;
  const Tan spring = h.f_t - kt_force * dslip;
  const Tan trial = spring + fd_t;
  const double cap = r.area * p.sigma_y / std::sqrt(3.0);  // A_c tau_y
  const bool coulomb = !std::isinf(p.mu) && p.mu * r.f_n < cap;
  const double limit = coulomb ? p.mu * r.f_n : cap;
  const double trial_norm = tan_norm(trial);
  if (trial_norm <= limit) {
    r.f_t = trial;
    r.history.f_t = spring;
    r.dft_dslip = tan_identity<D>(-kt_force);
    r.dft_dun = -p.shear_stiffness() * (k_spring / (3.0 * p.sigma_y)) * dslip;
    r.sliding = false;
  } else {
    const Tan s = tan_direction(trial);
    r.f_t = s * limit;
    r.history.f_t = s * limit - fd_t;
    r.dft_dun = s * (coulomb ? p.mu * r.k_n : k_spring / (3.0 * std::sqrt(3.0)));
    if constexpr (D == 3) {
      const Eigen::Matrix3d P = (limit / trial_norm) * (Eigen::Matrix3d::Identity() - s * s.transpose());
      const Tan dtrial_dun = -p.shear_stiffness() * (k_spring / (3.0 * p.sigma_y)) * dslip;
      r.dft_dslip = -kt_force * P;
      r.dft_dun += P * dtrial_dun;
    } else {
      r.dft_dslip = 0.0;
    }
    r.sliding = true;
  }
  r.history.sliding = r.sliding ? 1 : 0;
  return r;
}

/// The plastic-indentation law behind the contact-law interface (law.hpp). Holds its parameters
/// by value; a solver builds it once per run (or per parameter change). D = 3: spheres (the
/// tangential force a vector, carried into the current plane by the step's Transport).
template <int D>
class PlasticIndentationLawT {
 public:
  static constexpr int kDim = D;
  using Params = PlasticIndentationParams;
  using History = PlasticIndentationHistoryT<D>;
  using Response = ContactResponse<History, D>;
  using Kin = Kinematics<D>;
  using Tan = typename Dim<D>::Tan;
  /// u_max outlives separation: a separated contact reloads elastically from its flattening.
  static constexpr bool kHistoryOutlivesSeparation = true;
  /// The branch needs the start overlap and R*, the dashpots m* (law.hpp kReadsPairProperties).
  static constexpr bool kReadsPairProperties = true;

  PlasticIndentationLawT() = default;
  explicit PlasticIndentationLawT(const Params& p)
      : p_(p), damped_(p.damped()), k_chord_(p.damped() && D == 2 ? p.chord_stiffness() : 0.0) {}
  const Params& params() const { return p_; }
  bool has_history(const History& h) const { return h.u_max > 0.0; }
  /// The potential of the normal force at fixed history h (normal_work): d/du of it is the
  /// normal force of evaluate() at overlap u.
  double normal_work(const History& h, double r_eff, double u) const {
    return contact::normal_work<D>(p_, r_eff, h.u_max, u);
  }
  /// The tangential spring's force stiffness k_t sigma_y A_c and limit mu_eff F_N at the normal
  /// force f_n (0 and 0 without friction), the two that tangential_work freezes.
  std::pair<double, double> tangential_frozen(double f_n) const {
    if (!p_.frictional() || !(f_n > 0.0)) return {0.0, 0.0};
    return {p_.shear_stiffness() * contact_area(f_n), p_.mu_eff() * f_n};
  }
  /// The potential of the tangential force over the slip increment dslip from the committed
  /// history h (its f_t in the current tangent plane) at a frozen stiffness and limit
  /// (tangential_work): -d/d dslip of it is the force of evaluate() with that area and limit.
  double tangential_work(const History& h, double kt_force, double limit, const Tan& dslip) const {
    return contact::tangential_work<D>(h.f_t, kt_force, limit, dslip);
  }
  /// The scales of law.hpp kHasReferenceScales: the force sigma_y r (2D, per unit depth; 3D
  /// sigma_y r^2), the stiffness sigma_y (3D: sigma_y r), the force at the first-touch overlap.
  double reference_force(double r) const { return D == 2 ? p_.sigma_y * r : p_.sigma_y * r * r; }
  double reference_stiffness(double r) const { return D == 2 ? p_.sigma_y : p_.sigma_y * r; }
  double first_touch_force(double r_eff) const {
    return loading_force<D>(p_, r_eff, first_touch_overlap(p_, r_eff));
  }
  /// The contact area (2D: width per unit depth) of a normal force at the mean contact pressure
  /// 3 sigma_y (Eq 2); it scales the tangential spring k_t sigma_y A_c.
  double contact_area(double f_n) const { return f_n / (3.0 * p_.sigma_y); }

  /// The history in the current tangent plane (2D: h itself).
  static const History& transported(const History& h, const Kin& k, History& buf) {
    if constexpr (D == 2) {
      (void)k;
      (void)buf;
      return h;
    } else {
      buf = h;
      buf.f_t = k.transport.apply(h.f_t);
      return buf;
    }
  }

  Response evaluate(const History& h0, const Kin& k, Tangent<D>* t) const {
    PlasticIndentationResultT<D> r;
    History buf;
    const History& h = transported(h0, k, buf);
    if (!damped_) {
      r = contact::evaluate<D>(p_, h, k.r_eff, k.overlap, k.dslip);
    } else if constexpr (D == 2) {
      const double gn = 2.0 * p_.damping_n * std::sqrt(k_chord_ * k.m_eff);
      const double gt = 2.0 * p_.damping_t * std::sqrt(k_chord_ * k.m_eff / 3.0);
      r = evaluate_damped<D>(p_, h, k.r_eff, k.overlap, k.dslip, gn * k.v_n, -gt * k.v_t);
    } else {  // the 3D loading stiffness 6 pi sigma_y R*; the sphere's tangential mass 2/7
      const double kc = p_.chord_stiffness_3d(k.r_eff);
      const double gn = 2.0 * p_.damping_n * std::sqrt(kc * k.m_eff);
      const double gt = 2.0 * p_.damping_t * std::sqrt(kc * k.m_eff * kTangentialMassRatio<3>);
      const Tan fd_t = -gt * k.v_t;
      r = evaluate_damped<D>(p_, h, k.r_eff, k.overlap, k.dslip, gn * k.v_n, fd_t);
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
      t->dfn_dslip = tan_zero<Tan>();
      t->dft_dun = r.dft_dun;
      t->dft_dslip = r.dft_dslip;
    }
    return out;
  }

  /// Normal: the tangent of the active branch at the end of the step, or the elastic
  /// un/reloading stiffness of the history when that is larger (it is the stiffest branch the
  /// contact can reach in a step). Tangential: k_t A_c at the end force.
  StiffnessBound stiffness_bound(const History& h, const Kin& k) const {
    double f, kn;
    NormalBranch b;
    normal_force<D>(p_, k.r_eff, h.u_max, k.overlap, f, kn, b);
    const double u_max = p_.reversible ? 0.0 : fmax_of(h.u_max, k.overlap);
    if (u_max > 0.0) kn = fmax_of(kn, p_.unload_ratio * loading_tangent<D>(p_, k.r_eff, u_max));
    StiffnessBound s;
    s.k_n = kn;
    s.k_t = p_.frictional() ? p_.shear_stiffness() * f / (3.0 * p_.sigma_y) : 0.0;
    return s;
  }

  /// The explicit time step (law.hpp kHasExplicitBound): the stiffest normal branch of any contact
  /// of effective radius up to r_eff is the first-touch chord 6 sigma_y / sqrt(first_touch) (2D,
  /// whatever R*; 3D: the loading stiffness 6 pi sigma_y R*), times unload_ratio with the elastic
  /// unloading branch; infinite for first_touch = 0 (Eq 2 at first touch). The tangential spring
  /// k_t sigma_y A_c grows with the contact area: k_t_area = k_t sigma_y. No dashpot is counted
  /// (the undamped period: stricter).
  StiffnessBound stiffness_bound(double r_eff) const {
    StiffnessBound s;
    s.k_n = (D == 3 ? p_.chord_stiffness_3d(r_eff) : p_.chord_stiffness()) * (p_.reversible ? 1.0 : p_.unload_ratio);
    s.k_t_area = p_.frictional() ? p_.shear_stiffness() : 0.0;
    return s;
  }

  /// Eq 2 is concave with a tangent that is singular at first touch, and Newton on the tangent
  /// overshoots into separation: on the plastic branch the normal stiffness is raised to the secant
  /// of Eq 2 over the step (from the start overlap, or from the force-free overlap) when that is
  /// stiffer. The tangential stiffness is the shear spring k_t A_c, also while sliding.
  IterationStiffness iteration_stiffness(const History& h, const Kin& k, const Response& r) const {
    IterationStiffness s;
    if (r.branch == static_cast<std::uint8_t>(NormalBranch::Plastic)) {
      const double u_sep = separation_overlap<D>(p_, k.r_eff, h.u_max);
      const double u_from = fmax_of(k.overlap_start, u_sep);
      if (k.overlap > u_from) {
        const double ksec = normal_secant<D>(p_, k.r_eff, h.u_max, u_from, k.overlap);
        const double kn = loading_tangent<D>(p_, k.r_eff, k.overlap);
        s.k_n_add = fmax_of(0.0, ksec - kn);
      }
    }
    double f_spring = r.f_n;  // the contact width comes from the spring force (no dashpot)
    if (damped_) {
      double kn;
      NormalBranch b;
      normal_force<D>(p_, k.r_eff, h.u_max, k.overlap, f_spring, kn, b);
    }
    s.k_t = p_.frictional() ? p_.shear_stiffness() * (f_spring / (3.0 * p_.sigma_y)) : 0.0;
    return s;
  }

  /// The history with which a contact continues when the elastic unloading branch is switched on
  /// (reversible -> elastic, section 3.4) at overlap u: u_max := u (no force jump); a separated
  /// contact loses its tangential force.
  static History start_unloading_branch(const History& h, double u) {
    History r = h;
    r.u_max = fmax_of(u, 0.0);
    if (u <= 0.0) {
      r.f_t = tan_zero<Tan>();
      r.sliding = 0;
    }
    return r;
  }

 private:
  Params p_;
  bool damped_ = false;
  double k_chord_ = 0.0;
};
using PlasticIndentationLaw = PlasticIndentationLawT<2>;
using PlasticIndentationLaw3 = PlasticIndentationLawT<3>;
static_assert(ContactLaw<PlasticIndentationLaw>);
static_assert(ContactLaw<PlasticIndentationLaw3>);

}  // namespace netdem::contact
