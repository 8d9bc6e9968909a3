#pragma once
// Sintering contact law of Luding, Manetsberger & Muellers, "A discrete model for long time
// sintering", J. Mech. Phys. Solids 53 (2005) 455 (cited below as LMM05), sections 2-3.
//
// Parameters, history and evaluation are three things: `LudingParams` (per run, Table 1 defaults),
// `LudingHistory` (per contact, plain data) and the const evaluation `luding_evaluate<F>()`, which
// returns the forces, the tangent and the history to commit; nothing is stored. The temperature
// state k1(T, t) is a material (global) state, advanced once per step by `advance_thermal()`.
//
// Conventions (as kinematics.hpp): overlap delta > 0 when touching (compression positive);
// n from i to j; the normal force f_n is the force ON j along n, f_n > 0 repulsive; the slip xi is
// the tangential displacement of j relative to i along t = perp(n), and f_t is the tangential
// force ON j along t. Units: SI as Table 1 (N/m for stiffnesses of the 2D cylinders, kg/s for
// damping, s, m); temperatures in deg C (only differences enter, in K).
//
// Compile-time specialisation: `luding_evaluate<kLudingLinear>` is a plain linear spring-dashpot
// with a Cundall-Strack tangential spring (no hysteresis, no cohesion, no temperature); it equals
// the full law when k1 = k2, k_c = 0 and the temperature is constant (tested). Use
// `luding_is_linear()` to choose the instantiation once per run.
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "netdem/contact/dim.hpp"
#include "netdem/contact/fminmax.hpp"

namespace netdem::contact {

/// All parameters of LMM05 Table 1, with the paper's values as defaults (SI units).
struct LudingParams {
  // ---- contact law (Table 1) ----
  double k2 = 2.0e5;        ///< particle stiffness k2 [N/m] (un/reloading, Eq 4; cap of Eq 7)
  double k1_ratio = 0.5;    ///< k1/k2: cold loading stiffness (Eq 4)
  double kc_ratio = 0.5;    ///< k_c/k2: cohesion stiffness (Eq 4, 13)
  double alpha = 0.2;       ///< k_t/k2(delta_max): tangential stiffness ratio (Eq 23)
  double gamma_n = 0.2;     ///< normal damping gamma_0 [kg/s] (Eq 5)
  double gamma_t = 0.05;    ///< tangential damping gamma_t [kg/s] (Eq 19)
  double mu = 0.5;          ///< particle-particle friction (Eq 14, 24)
  double mu_wall = 0.0;     ///< particle-wall friction mu_w (see wall_params())
  double T_melt = 120.0;    ///< melting temperature [deg C] (Eq 9, 10)
  double T_var = 10.0;      ///< temperature range of melting [K] (Eq 10)
  double da_T = 1.0e-4;     ///< relative radius change per K, delta a_T [1/K] (Eq 9)
  double delta_fluid_rel = 0.2;  ///< delta_fluid / a0 (section 3.1.3; 0.0477 physically)
  double t0 = 1.0e3;        ///< relaxation time t0 [s] (Eq 11, 12), default
  double t0_sinter = 0.1;   ///< relaxation time during sintering [s] (section 4.1)
  // ---- sample / solver (Table 1), not used by the contact law itself except a0 ----
  double a0 = 1.0e-3;       ///< mean particle radius [m]; scales delta_fluid
  double w0 = 0.5;          ///< relative width of the radius distribution
  double h = 6.0e-3;        ///< particle height [m]
  double rho_p = 2000.0;    ///< particle density [kg/m^3] at the reference temperature
  double m_wall = 0.01;     ///< wall mass (Eq 1)
  double gamma_wall = 0.2;  ///< wall damping (Eq 1)
  /// Temperature [deg C] at which the drawn radii a_i (and rho_p) are given. Default T_melt: the
  /// drawn radius IS a(T_melt) of Eq 9. The mass is computed once at this temperature and kept.
  double T_radius_ref = 120.0;
  // ---- switches (not in the paper) ----
  bool stiffness_growth = true;  ///< Eq 7 on; off: un/reloading stiffness is the constant k2
  bool sliding_breaks_cohesion = true;  ///< footnote 5: f_n >= 0 while sliding
  /// Section 3.3.2 "also the stiffness is increased accordingly": while k1(T, t) rises, delta_max
  /// grows with delta_0 fixed AND the line slope k2' = k2(delta_max) of Eq 7 is re-evaluated at
  /// the new delta_max (so k_c of Eq 13 and k_t of Eq 23 grow too). Off: the old line is kept.
  bool cooling_stiffness_update = true;
  /// Particle-wall contacts sinter: the wall law uses k1(T, t) (Eq 10-12, section 3.3 rules, the
  /// creep of section 3.3.1). Off (default): the wall contacts keep the cold k1, i.e. they are
  /// hysteretic (Eq 4, 7) but do not creep; see docs/luding.md (three-particle control).
  bool wall_sintering = true;

  double k1() const { return k1_ratio * k2; }
  double kc() const { return kc_ratio * k2; }
  double delta_fluid() const { return delta_fluid_rel * a0; }
  /// delta_max^fluid = k2 delta_fluid / (k2 - k1) (section 3.1.3); inf when k1 = k2.
  double delta_max_fluid() const {
    return k1_ratio < 1.0 ? delta_fluid() / (1.0 - k1_ratio)
                          : std::numeric_limits<double>::infinity();
  }
  /// The parameters for a particle-wall contact (not in the paper; our choice, docs/luding.md):
  /// the same law with the wall as a flat of infinite radius and mass, mu = mu_w, and no cohesion
  /// (the tooling does not sinter to the powder).
  LudingParams wall_params() const {
    LudingParams w = *this;
    w.mu = mu_wall;
    w.kc_ratio = 0.0;
    w.frozen_k1 = !wall_sintering;
    return w;
  }
  /// Set by wall_params() (not a user parameter): evaluate with the cold k1 whatever k1(T, t) is.
  bool frozen_k1 = false;
  /// Throws std::invalid_argument with a one-line message for an invalid value.
  void validate() const;
  bool frictional() const { return mu > 0.0; }
};

/// Compile-time feature flags of the evaluation.
struct LudingFeatures {
  bool hysteresis = true;  ///< Eq 4 with k1 < k2 and Eq 7; off: f = k2 delta
  bool cohesion = true;    ///< -k_c delta branch, Eq 13-15; off: k_c = 0, f_min = 0
  bool thermal = true;     ///< k1(T, t), Eq 10-13, 24 and the delta rules of section 3.3
  bool friction = true;    ///< tangential spring, Eq 14-24; off: f_t = 0, no tangential work
                           ///< (identical to mu = 0, where the spring is released every step)
};
inline constexpr LudingFeatures kLudingFull{true, true, true, true};
inline constexpr LudingFeatures kLudingLinear{false, false, false, true};

/// True when the full law reduces to a linear spring-dashpot (k1 = k2, k_c = 0, constant T).
inline bool luding_is_linear(const LudingParams& p, bool constant_temperature) {
  return p.k1_ratio == 1.0 && p.kc_ratio == 0.0 && constant_temperature;
}

/// Per-contact history (plain data). Lifecycle: created zero on first touch; reset (returned as a
/// fresh history) on separation, delta <= 0; for a pair-order flip negate xi. In 3D xi is a vector
/// in the tangent plane (global axes), carried into the current plane each step (LMM05 Eq 16; the
/// law interface's Transport, law.hpp); in 2D it is the component along t.
template <int D>
struct LudingHistoryT {
  using Tan = typename Dim<D>::Tan;
  double delta_max = 0.0;  ///< delta_max (Fig 2); 0 = fresh contact
  double delta0 = 0.0;     ///< force-free overlap delta_0 of the un/reloading line
  double k2_line = 0.0;    ///< slope k2' = k2(delta_max) of the un/reloading line (Eq 7)
  double k1_seen = 0.0;    ///< k1(T, t) at which (delta_max, delta0) were last made consistent
  Tan xi = tan_zero<Tan>();  ///< tangential spring (Eq 16-21)
  std::uint8_t fluid = 0;  ///< 1 once delta_0 reached delta_fluid (fluid limit, frozen delta_0)
  std::uint8_t sliding = 0;  ///< 1 if the committed step slid
  /// True for the zero history of a pair that has not touched (or was reset on separation).
  bool fresh() const {
    return delta_max == 0.0 && delta0 == 0.0 && k2_line == 0.0 && k1_seen == 0.0 && tan_is_zero(xi) &&
           fluid == 0 && sliding == 0;
  }
};
using LudingHistory = LudingHistoryT<2>;

/// Kinematic input of one step (contact frame; 3D: the tangential vectors in the current plane).
template <int D>
struct LudingInputT {
  using Tan = typename Dim<D>::Tan;
  double delta = 0.0;      ///< overlap at the end of the step [m]
  double delta_dot = 0.0;  ///< d delta / dt (> 0 approaching) [m/s]
  Tan dxi = tan_zero<Tan>();     ///< slip increment over the step [m]
  Tan xi_dot = tan_zero<Tan>();  ///< slip rate v_t [m/s]
  double k1_Tt = 0.0;      ///< k1(T, t) of the material [N/m] (ignored without F.thermal)
};
using LudingInput = LudingInputT<2>;

enum class LudingBranch : std::uint8_t { Open = 0, Loading = 1, Line = 2, Cohesive = 3, Fluid = 4 };

template <int D>
struct LudingResultT {
  using Tan = typename Dim<D>::Tan;
  using TanMat = typename Dim<D>::TanMat;
  double f_n = 0.0;     ///< normal force on j along n (spring + Eq 5 damping), > 0 repulsive
  Tan f_t = tan_zero<Tan>();     ///< tangential force on j
  Tan m_roll = tan_zero<Tan>();  ///< rolling moment: not in the paper (section 5), always 0 (hook)
  double f_min = 0.0;   ///< Eq 15 for the committed state (<= 0)
  double k_c = 0.0;     ///< Eq 13
  double k_t = 0.0;     ///< Eq 23
  double mu = 0.0;      ///< Eq 24
  // tangent (rates held fixed): derivatives with respect to delta and dxi
  double dfn_ddelta = 0.0;
  Tan dfn_dxi = tan_zero<Tan>();
  Tan dft_ddelta = tan_zero<Tan>();
  TanMat dft_dxi = tan_identity<D>(0.0);
  LudingBranch branch = LudingBranch::Open;
  bool sliding = false;
  LudingHistoryT<D> history;  ///< the history to commit if the step is accepted
};
using LudingResult = LudingResultT<2>;

/// The constants of one step of the law: functions of the parameters and of the material state
/// k1(T, t) only. luding_evaluate(p, h, in) computes them per call; a force loop computes them once
/// per step (LudingLaw) and passes them in, with the same operations, so that both give the same
/// results to the last bit (tests/contact/test_law_conformance.cpp) without a division per contact
/// for what is the same for every contact (docs/performance.md "Issue 31").
struct LudingStep {
  double k1c = 0.0;      ///< the cold k1 (Eq 4)
  double k1 = 0.0;       ///< k1(T, t) the step evaluates with (Eq 11-12; the cold k1 without F.thermal)
  double k2 = 0.0;       ///< k2
  double k2_k1c = 0.0;   ///< k2 - k1 (cold), Eq 7
  double dmf = 0.0;      ///< delta_max^fluid (section 3.1.3)
  double dk2 = 0.0;      ///< dk2/d delta_max of Eq 7 below delta_max^fluid
  double dfluid = 0.0;   ///< delta_fluid
  double c = 0.0;        ///< k_c / k2' (Eq 13)
  double mu = 0.0;       ///< Eq 24
};

/// The step constants of feature set F at the material state k1_Tt.
template <LudingFeatures F>
inline LudingStep luding_step(const LudingParams& p, double k1_Tt) {
  LudingStep s;
  s.k1c = p.k1();
  s.k1 = F.thermal && !p.frozen_k1 ? k1_Tt : s.k1c;  // k1(T, t), Eq 11-12
  s.k2 = p.k2;
  s.k2_k1c = p.k2 - p.k1();
  s.dmf = p.delta_max_fluid();
  s.dk2 = s.k2_k1c / s.dmf;
  s.dfluid = p.delta_fluid();
  if constexpr (F.cohesion) s.c = (s.k1 / s.k1c) * p.kc() / p.k2;  // k_c = c k2', LMM05 Eq 13
  s.mu = F.thermal ? (s.k1 / s.k1c) * p.mu : p.mu;                 // LMM05 Eq 24
  return s;
}

// ---------------------------------------------------------------------------------------------
// Temperature (sections 3.2-3.4)

/// Eq 10: k1(T) = k1/2 [1 + tanh((T_melt - T)/T_var)].
inline double luding_k1_of_T(const LudingParams& p, double T) {
  return 0.5 * p.k1() * (1.0 + std::tanh((p.T_melt - T) / p.T_var));  // LMM05 Eq 10
}

/// Eq 9 with constant mass: radius at T of a particle drawn with radius a_ref at T_radius_ref.
inline double luding_radius(const LudingParams& p, double a_ref, double T) {
  // LMM05 Eq 9: a(T) = a(T_melt) [1 - da_T (T_melt - T)], referred to a_ref = a(T_radius_ref)
  return a_ref * (1.0 - p.da_T * (p.T_melt - T)) / (1.0 - p.da_T * (p.T_melt - p.T_radius_ref));
}
/// Constant particle mass rho_p pi a_ref^2 h (Eq 8: the density follows the radius).
inline double luding_mass(const LudingParams& p, double a_ref) {
  return p.rho_p * std::numbers::pi * a_ref * a_ref * p.h;
}

/// Eq 11 literally (falling k1, k1_T0 > k1_T): k1(T, t) after time t at constant T.
inline double luding_k1_eq11(double k1_T, double k1_T0, double t, double t0) {
  return k1_T * (1.0 - 1.0 / (1.0 / (1.0 - k1_T0 / k1_T) - t / t0));  // LMM05 Eq 11
}

/// Exact solution over dt of Eq 12 with the sign of footnote 3, dk/dt = y|y|/(k1_T t0),
/// y = k1_T - k, from k_prev = k1(T, t - dt) at constant T: y(dt) = y0 / (1 + |y0| dt/(k1_T t0)).
/// For falling k1 this is Eq 11; for rising k1 it is Eq 11 with the sign of t/t0 flipped.
/// Never overshoots k1_T, for any dt.
inline double luding_relax_k1(double k_prev, double k1_T, double dt, double t0) {
  const double y0 = k1_T - k_prev;
  if (k1_T <= 0.0) return k1_T;
  return k1_T - y0 / (1.0 + std::fabs(y0) * dt / (k1_T * t0));  // LMM05 Eq 11/12, footnote 3
}

/// Material temperature state: T and k1(T, t).
struct LudingThermalState {
  double T = 80.0;     ///< [deg C]
  double k1_Tt = 0.0;  ///< k1(T, t) [N/m]
};
/// Cold start: k1(T, t) = k1(T) (equilibrated at T).
inline LudingThermalState luding_thermal_start(const LudingParams& p, double T) {
  return {T, luding_k1_of_T(p, T)};
}
/// Advances (T, k1(T, t)) to T_new over dt with relaxation time t0 (p.t0 or p.t0_sinter).
/// Section 3.4 exception: if the temperature falls and k1(T) > k1(T, t - dt), the contact freezes
/// at once, k1(T, t) = k1(T). Otherwise the exact step of Eq 12 from k1(T, t - dt) (footnote 3).
inline LudingThermalState luding_advance_thermal(const LudingParams& p, const LudingThermalState& s,
                                                 double T_new, double dt, double t0) {
  const double k1T = luding_k1_of_T(p, T_new);  // LMM05 Eq 10
  if (T_new < s.T && k1T > s.k1_Tt) return {T_new, k1T};  // LMM05 section 3.4: freezing
  return {T_new, luding_relax_k1(s.k1_Tt, k1T, dt, t0)};  // LMM05 Eq 12 (footnote 3)
}

// ---------------------------------------------------------------------------------------------
// Normal and tangential law

/// Eq 7: k2(delta_max), using the constant cold k1 (section 3.3), capped at k2 (s: the step's
/// constants, luding_step).
inline double luding_k2_of(const LudingParams& p, const LudingStep& s, double delta_max) {
  if (!p.stiffness_growth) return s.k2;
  if (!(delta_max < s.dmf)) return s.k2;                                 // LMM05 Eq 7, fluid
  return s.k1c + s.k2_k1c * delta_max / s.dmf;                          // LMM05 Eq 7
}
inline double luding_k2_of(const LudingParams& p, double delta_max) {
  return luding_k2_of(p, luding_step<kLudingFull>(p, p.k1()), delta_max);
}
/// dk2(delta_max)/d delta_max of Eq 7.
inline double luding_dk2_of(const LudingParams& p, const LudingStep& s, double delta_max) {
  if (!p.stiffness_growth) return 0.0;
  return delta_max < s.dmf ? s.dk2 : 0.0;
}

/// Section 3.3.2 with Eq 7: the delta_max that solves delta_max (1 - k1_Tt / k2(delta_max)) =
/// delta_0 (delta_0 fixed, k2(.) of Eq 7 evaluated at the solution). Below delta_max^fluid Eq 7 is
/// k2(d) = A + B d (A = cold k1, B = (k2 - k1)/delta_max^fluid), so B d^2 + (A - k - B delta_0) d
/// - A delta_0 = 0; beyond it k2(d) = k2 and d = k2 delta_0 / (k2 - k). Needs k1_Tt < k2.
inline double luding_delta_max_cooling(const LudingParams& p, const LudingStep& s, double delta0,
                                        double k1_Tt) {
  const double A = s.k1c, dmf = s.dmf;
  if (!p.stiffness_growth || !(dmf < std::numeric_limits<double>::infinity()))
    return p.k2 * delta0 / (p.k2 - k1_Tt);
  const double B = s.dk2;
  const double b = A - k1_Tt - B * delta0, c4 = 4.0 * B * A * delta0;
  const double root = std::sqrt(b * b + c4);
  // the positive root, written without cancellation for either sign of b
  const double d = b > 0.0 ? 2.0 * A * delta0 / (b + root) : (root - b) / (2.0 * B);
  if (d < dmf) return d;
  return p.k2 * delta0 / (p.k2 - k1_Tt);  // LMM05 Eq 7 capped: k2(d) = k2
}
inline double luding_delta_max_cooling(const LudingParams& p, double delta0, double k1_Tt) {
  return luding_delta_max_cooling(p, luding_step<kLudingFull>(p, k1_Tt), delta0, k1_Tt);
}

/// Section 3.3 delta rules, keyed on k1(T, t) (not on dT/dt), on the history h in place: while
/// k1(T, t) falls, delta_max stays and delta_0 grows (Fig 5 left), frozen at delta_fluid (fluid
/// limit); while it rises, delta_0 stays and delta_max grows on the same k2' line (Fig 5 right).
template <int D>
inline void luding_thermal_update(const LudingParams& p, const LudingStep& s, LudingHistoryT<D>& h,
                                  double k1_Tt) {
  const double seen = h.k1_seen;
  h.k1_seen = k1_Tt;
  if (h.delta_max <= 0.0 || h.fluid) return;  // fresh contact, or fluid: delta_0 frozen
  const double k2l = h.k2_line;
  if (k1_Tt < seen) {
    h.delta0 = (1.0 - k1_Tt / k2l) * h.delta_max;  // LMM05 section 3.3.1: delta_0^+(T)
    if (h.delta0 >= s.dfluid) {                     // LMM05 section 3.1.3: fluid limit
      h.delta0 = s.dfluid;
      h.fluid = 1;
    }
  } else if (k1_Tt > seen && h.delta0 > 0.0) {
    if (p.cooling_stiffness_update && p.stiffness_growth) {
      if (k1_Tt < p.k2) {  // (k1 = k2: no plastic range left, delta_max stays)
        // LMM05 section 3.3.2 with Eq 7 re-evaluated: delta_max^- = delta_0 / (1 - k1(T)/k2(dmax^-))
        h.delta_max = fmax_of(h.delta_max, luding_delta_max_cooling(p, s, h.delta0, k1_Tt));
        h.k2_line = luding_k2_of(p, s, h.delta_max);  // "also the stiffness is increased accordingly"
      }
    } else if (k1_Tt < k2l) {
      h.delta_max = k2l * h.delta0 / (k2l - k1_Tt);  // LMM05 section 3.3.2: delta_max^-(T)
    }
  }
}

/// The normal spring of luding_update (Eq 4 with Fig 2/3, Eq 7, the fluid limit of section 3.1.3)
/// on the history h in place: the spring force f, its slope kn and the branch; Tangent: also
/// d(delta_0)/d delta and d(k2')/d delta on the loading branch.
template <LudingFeatures F, bool Tangent, int D>
inline void luding_normal_spring(const LudingParams& p, const LudingStep& s, LudingHistoryT<D>& h, double delta,
                                 double& f, double& kn, double& ddelta0, double& dk2l, LudingBranch& branch) {
  (void)p;  // (read on the hysteretic branches only)
  const double k1 = s.k1;
  if constexpr (!F.hysteresis) {
    f = s.k2 * delta;  // LMM05 Eq 4 with k1 = k2: linear spring
    kn = s.k2;
    h.delta_max = fmax_of(h.delta_max, delta);
    h.k2_line = s.k2;
  } else {
    if (h.fluid) {
      h.delta_max = fmax_of(h.delta_max, delta);
      f = h.k2_line * (delta - h.delta0);  // LMM05 Fig 3: liquid branch, slope k2, delta_0 fixed
      kn = h.k2_line;
      branch = LudingBranch::Fluid;
    } else if (delta >= h.delta_max) {  // loading on k1
      h.delta_max = delta;
      h.k2_line = luding_k2_of(p, s, delta);              // LMM05 Eq 7
      h.delta0 = (1.0 - k1 / h.k2_line) * delta;          // LMM05 Eq 4: delta_0
      if constexpr (Tangent) {
        dk2l = luding_dk2_of(p, s, delta);
        ddelta0 = (1.0 - k1 / h.k2_line) + delta * k1 * dk2l / (h.k2_line * h.k2_line);
      }
      if (h.delta0 >= s.dfluid) {                         // LMM05 section 3.1.3: fluid limit
        // The liquid branch (Fig 3) starts through the current loading point, so the force stays
        // continuous: slope k1 delta/(delta - delta_fluid) <= k2(delta_max) <= k2 (our choice;
        // = k2 when the limit is met exactly at delta_max^fluid with the cold k1).
        const double df = s.dfluid;
        h.delta0 = df;
        h.fluid = 1;
        h.k2_line = k1 * delta / (delta - df);
        if constexpr (Tangent) {
          dk2l = -k1 * df / ((delta - df) * (delta - df));
          ddelta0 = 0.0;
        }
        f = k1 * delta;                                   // = k2' (delta - delta_fluid)
        kn = k1;
        branch = LudingBranch::Fluid;
      } else {
        f = k1 * delta;                                   // LMM05 Eq 4: loading
        kn = k1;
        branch = LudingBranch::Loading;
      }
    } else {
      f = h.k2_line * (delta - h.delta0);                 // LMM05 Eq 4: un/reloading
      kn = h.k2_line;
    }
  }
}

/// One step of the law (see LudingInput) on the history h in place (h becomes the history to
/// commit), with the step's constants s = luding_step<F>(p, in.k1_Tt) (in.k1_Tt itself is not
/// read): the forces in f_n_out and f_t_out. Tangent: also the tangent and the state of the step
/// in *r (luding_evaluate); without it nothing but the forces and the history is computed (the
/// force loops). In 3D the history's spring must already be in the current tangent plane.
template <LudingFeatures F, bool Tangent, int D>
inline void luding_update(const LudingParams& p, const LudingStep& s, LudingHistoryT<D>& h,
                          const LudingInputT<D>& in, double& f_n_out, typename Dim<D>::Tan& f_t_out,
                          LudingResultT<D>* r) {
  using Tan = typename Dim<D>::Tan;
  const double delta = in.delta;
  if (!(delta > 0.0)) {  // open: no force; the history is reset (docs/luding.md)
    h = LudingHistoryT<D>{};
    f_n_out = 0.0;
    f_t_out = tan_zero<Tan>();
    if constexpr (Tangent) *r = LudingResultT<D>{};
    return;
  }
  const double k1 = s.k1;  // k1(T, t), Eq 11-12
  if constexpr (F.thermal && F.hysteresis) {
    luding_thermal_update(p, s, h, k1);
  } else {
    h.k1_seen = k1;
  }

  // ---- normal spring, Eq 4 with Fig 2/3 ----
  double f = 0.0, kn = 0.0;
  double ddelta0 = 0.0, dk2l = 0.0;  // d(delta_0)/d delta, d(k2')/d delta (loading only)
  LudingBranch branch = LudingBranch::Line;
  luding_normal_spring<F, Tangent>(p, s, h, delta, f, kn, ddelta0, dk2l, branch);

  // ---- cohesion, Eq 13 and 15 ----
  double kc = 0.0, fmin = 0.0, dfmin = 0.0;
  double c = 0.0;
  if constexpr (F.cohesion) {
    c = s.c;  // k_c = c k2', LMM05 Eq 13
    kc = c * h.k2_line;
  }
  if constexpr (F.hysteresis) {
    if (f < -kc * delta) {  // LMM05 Eq 4: attractive limit -k_c delta (0 without cohesion)
      f = -kc * delta;
      kn = -kc;
      dk2l = 0.0;
      branch = LudingBranch::Cohesive;
    }
  }
  if constexpr (F.cohesion) {
    if (kc > 0.0) {
      // f_min = -k_c delta_min, the line/limit intersection; = Eq 15 when delta_0 = (1-k1/k2')dmax
      fmin = -kc * h.k2_line * h.delta0 / (h.k2_line + kc);  // LMM05 Eq 15
      // d f_min / d delta on the loading branch (k2' and delta_0 move with delta_max = delta)
      if (Tangent && (dk2l != 0.0 || ddelta0 != 0.0)) {
        const double g = h.delta0 / (1.0 + c);  // = delta_min, since k_c = c k2'
        dfmin = -(c * dk2l * g + kc * ddelta0 / (1.0 + c));
      }
    }
  }

  // ---- damping, Eq 5 ----
  double fn = f + p.gamma_n * in.delta_dot;  // LMM05 Eq 5
  double dfn = kn;

  // ---- tangential, Eq 14, 16-24 (2D: xi is a scalar along t, Eq 16 is implicit; 3D: vectors in
  // the tangent plane, Eq 16 applied to the history before the call) ----
  const double mu = s.mu;                                  // LMM05 Eq 24
  const double kt = p.alpha * h.k2_line;                   // LMM05 Eq 23
  const double dkt = p.alpha * dk2l;
  const double fc = F.friction ? mu * (fn - fmin) : 0.0;  // LMM05 Eq 14: f_C = mu (f_n - f_min)
  Tan ft = tan_zero<Tan>();
  bool sliding = false;
  if (F.friction && fc > 0.0) {
    const Tan xi_trial = h.xi + in.dxi;                     // LMM05 Eq 20
    const Tan ft0 = -kt * xi_trial - p.gamma_t * in.xi_dot;  // LMM05 Eq 19
    const double ft0_norm = tan_norm(ft0);
    if (ft0_norm <= fc) {                                   // static friction
      ft = ft0;
      h.xi = xi_trial;
      if constexpr (Tangent) {
        r->dft_dxi = tan_identity<D>(-kt);
        r->dft_ddelta = -dkt * xi_trial;
      }
    } else {                                                   // sliding friction
      const Tan sd = tan_direction(ft0);
      ft = sd * fc;                                            // LMM05 Eq 22
      h.xi = -(fc * sd + p.gamma_t * in.xi_dot) / kt;          // LMM05 Eq 21
      if constexpr (Tangent) {
        r->dft_ddelta = sd * mu * (dfn - dfmin);
        if constexpr (D == 3) {  // the direction sd = ft0/|ft0| turns with ft0
          const Eigen::Matrix3d P = (fc / ft0_norm) * (Eigen::Matrix3d::Identity() - sd * sd.transpose());
          r->dft_dxi = -kt * P;
          r->dft_ddelta += P * (-dkt * xi_trial);
        } else {
          r->dft_dxi = 0.0;
        }
      }
      sliding = true;
      if (p.sliding_breaks_cohesion && fn < 0.0) {             // LMM05 footnote 5: f_n >= 0
        fn = 0.0;
        dfn = 0.0;
      }
    }
  } else {  // f_n <= f_min: no tangential force, the spring is released
    h.xi = tan_zero<Tan>();
    if constexpr (Tangent) {
      r->dft_dxi = tan_identity<D>(0.0);
      r->dft_ddelta = tan_zero<Tan>();
    }
  }
  h.sliding = sliding ? 1 : 0;
  f_n_out = fn;
  f_t_out = ft;
  if constexpr (Tangent) {
    r->f_n = fn;
    r->f_t = ft;
    r->m_roll = tan_zero<Tan>();  // rolling resistance (not in LMM05): none is modelled
    r->f_min = fmin;
    r->k_c = kc;
    r->k_t = kt;
    r->mu = mu;
    r->dfn_ddelta = dfn;
    r->dfn_dxi = tan_zero<Tan>();
    r->branch = branch;
    r->sliding = sliding;
    r->history = h;
  }
}

/// One step of the law (see LudingInput) with the step's constants s = luding_step<F>(p,
/// in.k1_Tt). Pure: the new history is returned, not stored. In 3D the history's spring must
/// already be in the current tangent plane (LudingLaw does that).
template <LudingFeatures F = kLudingFull, int D>
inline LudingResultT<D> luding_evaluate(const LudingParams& p, const LudingStep& s, const LudingHistoryT<D>& h0,
                                        const LudingInputT<D>& in) {
  LudingResultT<D> r;
  LudingHistoryT<D> h = h0;
  double fn;
  typename Dim<D>::Tan ft;
  luding_update<F, true, D>(p, s, h, in, fn, ft, &r);
  return r;
}
/// One step of the law at the material state in.k1_Tt (the step's constants computed here).
template <LudingFeatures F = kLudingFull, int D>
inline LudingResultT<D> luding_evaluate(const LudingParams& p, const LudingHistoryT<D>& h0,
                                        const LudingInputT<D>& in) {
  return luding_evaluate<F>(p, luding_step<F>(p, in.k1_Tt), h0, in);
}

}  // namespace netdem::contact
