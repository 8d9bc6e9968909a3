#pragma once
// The sintering law of Luding, Manetsberger & Muellers (luding.hpp) behind the contact-law
// interface (law.hpp). `LudingLaw<F>` is one compile-time feature set of the law (LudingFeatures)
// with its parameters and the material state k1(T, t) of the current step.
#include <cmath>
#include <cstdint>

#include "netdem/contact/law.hpp"
#include "netdem/contact/luding.hpp"

namespace netdem::contact {

/// D = 3: the spring is a vector in the tangent plane, carried into the current plane by the
/// step's Transport (LMM05 Eq 16 generalised to a rotation, law.hpp) before the step.
template <LudingFeatures F = kLudingFull, int D = 2>
class LudingLaw {
 public:
  static constexpr int kDim = D;
  using Params = LudingParams;
  using History = LudingHistoryT<D>;
  using Response = ContactResponse<History, D>;
  using Kin = Kinematics<D>;
  using Tan = typename Dim<D>::Tan;
  /// The history is reset on separation (docs/luding.md).
  static constexpr bool kHistoryOutlivesSeparation = false;

  /// The law with parameters p (held by reference: p must outlive the law) at the material state
  /// k1(T, t) = k1_Tt (ignored without F.thermal).
  LudingLaw(const Params& p, double k1_Tt) : p_(&p), k1_Tt_(k1_Tt), s_(luding_step<F>(p, k1_Tt)) {}
  /// The law without a temperature (feature sets without F.thermal), as an implicit solver
  /// builds it from its options (held by reference as above).
  explicit LudingLaw(const Params& p)
    requires(!F.thermal)
      : LudingLaw(p, 0.0) {}
  LudingLaw() = default;  ///< no parameters: assign a law before evaluating
  const Params& params() const { return *p_; }
  double k1_Tt() const { return k1_Tt_; }
  bool has_history(const History& h) const { return !h.fresh(); }
  /// k2 delta^2 / 2: the unloading spring's energy (exact for the linear law).
  double elastic_energy(const Kin& k) const { return 0.5 * p_->k2 * k.overlap * k.overlap; }

  LudingInputT<D> input(const Kin& k) const {
    LudingInputT<D> in;
    in.delta = k.overlap;
    in.delta_dot = k.v_n;
    in.dxi = k.dslip;
    in.xi_dot = k.v_t;
    in.k1_Tt = k1_Tt_;
    return in;
  }

  /// The history in the current tangent plane (2D: h itself).
  static const History& transported(const History& h, const Kin& k, History& buf) {
    if constexpr (D == 2) {
      (void)k;
      (void)buf;
      return h;
    } else {
      buf = h;
      buf.xi = k.transport.apply(h.xi);
      return buf;
    }
  }

  Response evaluate(const History& h, const Kin& k, Tangent<D>* t) const {
    History buf;
    const LudingResultT<D> r = luding_evaluate<F>(*p_, s_, transported(h, k, buf), input(k));
    Response out;
    out.f_n = r.f_n;
    out.f_t = r.f_t;
    out.loaded = r.branch != LudingBranch::Open;
    out.sliding = r.sliding;
    out.branch = static_cast<std::uint8_t>(r.branch);
    out.history = r.history;
    if (t) {
      t->dfn_dun = r.dfn_ddelta;
      t->dfn_dslip = r.dfn_dxi;
      t->dft_dun = r.dft_ddelta;
      t->dft_dslip = r.dft_dxi;
    }
    return out;
  }

  /// The un/reloading line k2(delta_max) <= k2 (Eq 7) bounds every branch; k_t = alpha k2 (Eq 23).
  StiffnessBound stiffness_bound(const History&, const Kin&) const {
    StiffnessBound s;
    s.k_n = p_->k2;
    s.k_t = F.friction ? p_->alpha * p_->k2 : 0.0;
    return s;
  }

  /// The explicit time step (law.hpp kHasExplicitBound): every contact's normal stiffness is at
  /// most k2, with the dashpot gamma_0 of Eq 5 (Eq 6 takes the damped period); the tangential
  /// spring alpha k2 (Eq 23). Eq 6 may take the mean pair (kMeanPairTimeStep). r_eff is not used.
  StiffnessBound stiffness_bound(double /*r_eff*/) const {
    StiffnessBound s = stiffness_bound(History{}, Kin{});
    s.gamma_n = p_->gamma_n;
    return s;
  }
  static constexpr bool kMeanPairTimeStep = true;

  /// The scales of law.hpp kHasReferenceScales: k2 r, k2 and no first-touch force (the spring
  /// starts at zero overlap).
  double reference_force(double r) const { return p_->k2 * r; }
  double reference_stiffness(double /*r*/) const { return p_->k2; }
  double first_touch_force(double /*r_eff*/) const { return 0.0; }

  /// Newton needs a non-negative normal stiffness: on the attractive branch (tangent -k_c, Eq 4)
  /// the iteration matrix gets k_c added (zero normal stiffness). The tangential spring is k_t of
  /// Eq 23 (re-evaluates the law for its tangent; the network solver runs the linear feature set,
  /// NetworkSolverLinear).
  IterationStiffness iteration_stiffness(const History& h, const Kin& k, const Response& r) const {
    IterationStiffness s;
    if (!r.loaded) return s;
    Tangent<D> t;
    (void)evaluate(h, k, &t);
    s.k_n_add = t.dfn_dun < 0.0 ? -t.dfn_dun : 0.0;
    s.k_t = F.friction ? p_->alpha * r.history.k2_line : 0.0;
    return s;
  }

  /// In-place form of evaluate() for a hot loop (law.hpp update_contact): the same forces and
  /// history to the last bit (tests/contact/test_law_conformance.cpp). For the linear feature sets
  /// (no hysteresis, cohesion or temperature) it is luding_evaluate<F> written out for the linear
  /// spring-dashpot with the Cundall-Strack spring, operation for operation; otherwise it is
  /// luding_update<F> without the tangent on the table's history. Neither builds the result struct
  /// (3D: the spring transported first, as evaluate()).
  void update(History& h, const Kin& k, double& f_n, Tan& f_t) const {
    const Params& p = *p_;
    if constexpr (!F.hysteresis && !F.cohesion && !F.thermal) {
      const double delta = k.overlap;
      if (!(delta > 0.0)) {  // open (rounding at L = a_i + a_j): no force, history reset
        h = History{};
        f_n = 0.0;
        f_t = tan_zero<Tan>();
        return;
      }
      h.k1_seen = p.k1();
      h.delta_max = h.delta_max < delta ? delta : h.delta_max;  // fmax (both finite, >= 0)
      h.k2_line = p.k2;
      double fn = p.k2 * delta + p.gamma_n * k.v_n;  // LMM05 Eq 4 (k1 = k2) and Eq 5
      Tan ft = tan_zero<Tan>();
      std::uint8_t sliding = 0;
      if constexpr (F.friction) {
        const double fc = p.mu * (fn - 0.0);  // LMM05 Eq 14 with f_min = 0
        if (fc > 0.0) {
          const double kt = p.alpha * p.k2;  // LMM05 Eq 23
          Tan xi_trial;                      // LMM05 Eq 16 (3D: transported), Eq 20
          if constexpr (D == 2) {
            xi_trial = h.xi + k.dslip;
          } else {
            xi_trial = k.transport.apply(h.xi) + k.dslip;
          }
          const Tan ft0 = -kt * xi_trial - p.gamma_t * k.v_t;  // LMM05 Eq 19
          const double ft0_norm = tan_norm(ft0);
          if (ft0_norm <= fc) {
            ft = ft0;
            h.xi = xi_trial;
          } else {
            const Tan sg = tan_direction(ft0);
            ft = sg * fc;                                // LMM05 Eq 22
            h.xi = -(fc * sg + p.gamma_t * k.v_t) / kt;  // LMM05 Eq 21
            sliding = 1;
            if (p.sliding_breaks_cohesion && fn < 0.0) fn = 0.0;
          }
        } else {
          h.xi = tan_zero<Tan>();
        }
      } else {
        h.xi = tan_zero<Tan>();
      }
      h.sliding = sliding;
      f_n = fn;
      f_t = ft;
    } else {  // the law on the table's history in place, without the tangent (luding_update)
      if constexpr (D == 3) h.xi = k.transport.apply(h.xi);
      luding_update<F, false, D>(p, s_, h, input(k), f_n, f_t, nullptr);
    }
  }

 private:
  const Params* p_ = nullptr;
  double k1_Tt_ = 0.0;
  LudingStep s_;  ///< the constants of the step at k1_Tt_ (luding_step)
};
static_assert(ContactLaw<LudingLaw<kLudingFull>>);
static_assert(ContactLaw<LudingLaw<kLudingLinear>>);
static_assert(ContactLaw<LudingLaw<kLudingFull, 3>>);
static_assert(ContactLaw<LudingLaw<kLudingLinear, 3>>);

}  // namespace netdem::contact
