#pragma once
// The contact element of any law (law.hpp) in global axes: from the pair's start and end
// configurations, the generalized forces on both particles and the consistent 6x6 tangent
// K = -d f / d q_end. Law-agnostic: the law sees only ContactKinematics and returns contact-frame
// forces and derivatives; the chain rule through the pair kinematics (kinematics.hpp) is here.
#include <cmath>

#include "netdem/contact/kinematics.hpp"
#include "netdem/contact/law.hpp"

namespace netdem::contact {

/// Which parts of the element tangent to assemble.
struct TangentOptions {
  bool geometric = false;  ///< add the geometric (rotation-of-the-normal) stiffness
};

/// Contact element: the law's response, forces on both nodes and the tangent.
template <ContactLaw L>
struct PairElement {
  ContactResponse<typename L::History> law;
  ContactTangent tangent;  ///< contact-frame tangent (written when the element tangent is asked)
  ContactKinematics kin;   ///< the kinematics the law was evaluated with
  double dslip = 0.0;
  PairVec force = PairVec::Zero();  ///< generalized forces ON the particles (f_i, M_i, f_j, M_j)
  PairMat stiffness = PairMat::Zero();
};

/// The quasi-static kinematics of the increment g0 -> g1 with rotation increments dth_i, dth_j
/// (no rates, no time step).
inline ContactKinematics increment_kinematics(const PairGeometry& g0, const PairGeometry& g1,
                                              double dth_i, double dth_j) {
  ContactKinematics k;
  k.overlap = g1.overlap;
  k.overlap_start = g0.overlap;
  k.dslip = slip_increment(g0, g1, dth_i, dth_j);
  k.r_eff = g1.r_eff;
  return k;
}

/// Evaluates the increment from configuration g0 (start, committed) to g1 (trial end) with
/// rotation increments dth_i, dth_j. If `tangent` is non-null the consistent tangent with respect
/// to the end configuration is written to e.stiffness (material part always, geometric part on
/// request).
template <ContactLaw L>
inline void pair_element(const L& law, const typename L::History& h, const PairGeometry& g0,
                         const PairGeometry& g1, double dth_i, double dth_j, PairElement<L>& e,
                         const TangentOptions* tangent = nullptr) {
  e.kin = increment_kinematics(g0, g1, dth_i, dth_j);
  e.dslip = e.kin.dslip;
  e.law = law.evaluate(h, e.kin, tangent ? &e.tangent : nullptr);
  const PairVec bn = normal_gradient(g1);
  const PairVec bt = slip_gradient(g1);
  e.force = -e.law.f_n * bn + e.law.f_t * bt;
  if (!tangent) return;
  const ContactTangent& t = e.tangent;
  // d(slip increment)/d q_end for the objective form of Eq 5 (slip_increment()).
  PairVec btt;  // translational part of b_t (no lever arms)
  btt << -g1.t.x(), -g1.t.y(), 0.0, g1.t.x(), g1.t.y(), 0.0;
  const double dphi = std::atan2(cross(g0.n, g1.n), g0.n.dot(g1.n));
  const double Lm = 0.5 * (g0.L + g1.L);
  PairVec ds = (Lm / g1.L) * btt + (0.5 * (g1.a_i * dth_i + g1.a_j * dth_j) - 0.5 * dphi) * bn;
  ds(2) -= 0.5 * (g0.d_i + g1.d_i);
  ds(5) -= 0.5 * (g0.d_j + g1.d_j);
  // K = b_n (dF_N/dq)^T - b_t (dF_T/dq)^T with dF/dq = dF/du_N b_n + dF/dslip ds
  if (t.dfn_dslip == 0.0)
    e.stiffness.noalias() = t.dfn_dun * bn * bn.transpose();
  else
    e.stiffness.noalias() = bn * (t.dfn_dun * bn + t.dfn_dslip * ds).transpose();
  if (t.dft_dun != 0.0 || t.dft_dslip != 0.0)
    e.stiffness.noalias() -= bt * (t.dft_dun * bn + t.dft_dslip * ds).transpose();
  if (tangent->geometric && e.law.loaded) {
    PairVec c = PairVec::Zero();
    c(2) = g1.a_i;
    c(5) = g1.a_j;
    e.stiffness.noalias() -= (e.law.f_n / g1.L) * btt * btt.transpose();
    e.stiffness.noalias() -= (e.law.f_t / g1.L) * bn * btt.transpose();
    e.stiffness.noalias() -= e.law.f_t * c * bn.transpose();
  }
}

}  // namespace netdem::contact
