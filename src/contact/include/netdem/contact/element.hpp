#pragma once
// The contact element of any law (law.hpp) in global axes: from the pair's start and end
// configurations, the generalized forces on both particles and the consistent tangent
// K = -d f / d q_end, 6x6 for disks and 12x12 for spheres (docs/contact.md "The 3D contact
// element"). Law-agnostic: the law sees only its Kinematics<D> and returns contact-frame forces and
// derivatives; the chain rule through the pair kinematics (kinematics.hpp) is here. One element
// type PairElementT<L> for both dimensions and one name pair_element() (the overload is chosen by
// the geometry, PairGeometryT<L::kDim>); the 2D function is the code from before the 3D element,
// unchanged, so the 2D network solver's results are bit for bit the same.
#include <cmath>

#include "netdem/contact/kinematics.hpp"
#include "netdem/contact/law.hpp"

namespace netdem::contact {

/// Which parts of the element tangent to assemble.
struct TangentOptions {
  bool geometric = false;  ///< add the geometric (rotation-of-the-normal) stiffness
};

/// Contact element: the law's response, forces on both nodes and the tangent, in the dimension of
/// the law (2D: 6 DOF (x, y, theta) per pair; 3D: 12, (u_i, rotation vector of i, u_j, rotation
/// vector of j)).
template <ContactLaw L>
struct PairElementT {
  static constexpr int kDim = L::kDim;
  using Tan = typename Dim<kDim>::Tan;
  ContactResponse<typename L::History, kDim> law;
  Tangent<kDim> tangent;  ///< contact-frame tangent (written when the element tangent is asked)
  Kinematics<kDim> kin;   ///< the kinematics the law was evaluated with
  Tan dslip = tan_zero<Tan>();
  PairVecT<kDim> force = PairVecT<kDim>::Zero();  ///< generalized forces ON the particles (f_i, M_i, f_j, M_j)
  PairMatT<kDim> stiffness = PairMatT<kDim>::Zero();
};
/// The name from before the 3D element (any dimension).
template <ContactLaw L>
using PairElement = PairElementT<L>;

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
  requires(L::kDim == 2)
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

/// The 3D element (spheres) of the increment g0 -> g1 with rotation-vector increments dth_i,
/// dth_j (pair_increment()). Forces ON the particles, with F = f_n n + f_t the force on j:
///   f_i = -F, M_i = -d_i n x f_t, f_j = F, M_j = -d_j n x f_t
/// (the moments of -F and F about the centres from the contact plane; their virtual work is
/// -f_n du_N + f_t . dxi with dxi = slip_gradient(g1) dq, the derivative of pair_increment()'s
/// slip at a zero increment). If `tangent` is non-null, the consistent tangent K = -d f / d q_end
/// (q_end = (x_i, dth_i, x_j, dth_j)) is written to e.stiffness: the material part always, the
/// geometric part on request (TangentOptions::geometric). Derivation (docs/contact.md): the law's
/// response is isotropic in its vectors (the slip and the transported history), so its variation
/// is the contact-frame tangent applied to the co-rotational slip variation Dc = d dslip - dw x
/// dslip (dw: the spin of the Transport, increment_jacobian()) plus the rotation dw x f_t of the
/// force with the pair:
///   d f_n = k_nn du_N + k_ns . Dc,  d f_t = k_tn du_N + K_ts Dc [+ dw x f_t]
/// material: the forces' directions and lever arms held (n, d_i, d_j of g1);
/// geometric: dw x f_t, f_n dn, and in the moments the change of d (dd/dL = 1 - d/L) and of n.
/// With the pair in the x-y plane and in-plane motion, the in-plane rows and columns are the 2D
/// element's (both parts; tests/contact/test_element3d.cpp).
template <ContactLaw L>
  requires(L::kDim == 3)
inline void pair_element(const L& law, const typename L::History& h, const PairGeometry3& g0,
                         const PairGeometry3& g1, const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j,
                         PairElementT<L>& e, const TangentOptions* tangent = nullptr) {
  using V3 = Eigen::Vector3d;
  using M3 = Eigen::Matrix3d;
  using M312 = Eigen::Matrix<double, 3, 12>;
  using R12 = Eigen::Matrix<double, 1, 12>;
  e.kin = increment_kinematics(g0, g1, dth_i, dth_j);
  e.dslip = e.kin.dslip;
  e.law = law.evaluate(h, e.kin, tangent ? &e.tangent : nullptr);
  const V3& n = g1.n;
  const V3 fj = e.law.f_n * n + e.law.f_t;
  const V3 nft = n.cross(e.law.f_t);
  e.force << -fj, -g1.d_i * nft, fj, -g1.d_j * nft;
  if (!tangent) return;
  const Tangent<3>& t = e.tangent;
  const IncrementJacobian3 J = increment_jacobian(g0, g1, dth_i, dth_j);
  const R12 bn = normal_gradient(g1).transpose();               // d u_N / d q
  const M312 Dc = J.dslip + skew<double>(e.dslip) * J.spin;     // co-rotational slip variation
  const R12 dfn = t.dfn_dun * bn + t.dfn_dslip.transpose() * Dc;
  M312 dft = t.dft_dun * bn + t.dft_dslip * Dc;
  const bool geometric = tangent->geometric && e.law.loaded;
  if (geometric) dft -= skew<double>(e.law.f_t) * J.spin;       // f_t turns with the pair
  M312 dfj = n * dfn + dft;
  const M3 N = skew<double>(n);
  M312 dMi = (-g1.d_i) * N * dft;
  M312 dMj = (-g1.d_j) * N * dft;
  if (geometric) {
    dfj += e.law.f_n * J.dn;
    const M312 dn_x_ft = -skew<double>(e.law.f_t) * J.dn;       // d(n) x f_t
    const R12 dL = -bn;
    dMi -= (1.0 - g1.d_i / g1.L) * nft * dL + g1.d_i * dn_x_ft;
    dMj -= (1.0 - g1.d_j / g1.L) * nft * dL + g1.d_j * dn_x_ft;
  }
  e.stiffness.template block<3, 12>(0, 0) = dfj;
  e.stiffness.template block<3, 12>(3, 0) = -dMi;
  e.stiffness.template block<3, 12>(6, 0) = -dfj;
  e.stiffness.template block<3, 12>(9, 0) = -dMj;
}

}  // namespace netdem::contact
