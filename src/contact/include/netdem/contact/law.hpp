#pragma once
// The contact-law interface: what a solver needs from a law, and nothing else (docs/contact.md
// "The law interface").
//
// A law is three things:
//  * a parameter type `L::Params` (per run, held by the law object);
//  * a per-contact history `L::History` (plain struct, value-initialised = a pair that has never
//    touched);
//  * one const evaluation `law.evaluate(history, kinematics, tangent)`, which returns the normal
//    and tangential forces and the history to commit, and writes the consistent tangent only when
//    `tangent` is non-null. The moments on the particles are the lever-arm moments -d F_T of the
//    contact geometry (kinematics.hpp; pair_element() returns them); none of the toolkit's laws
//    has a rolling moment of its own (a rolling law would add one to the response). Nothing is stored: a rejected Newton iteration or a repeated step costs nothing.
//
// The interface states what the solvers need from a law, so that no solver reads a law's internals:
//  * `law.stiffness_bound(history, kinematics)`: the largest normal and tangential stiffnesses the
//    contact can show over the step, for an explicit time step;
//  * `law.iteration_stiffness(history, kinematics, response)`: symmetric, non-negative normal and
//    tangential stiffnesses for Newton's iteration matrix (the law's answer to a tangent that is
//    singular, negative or zero where the solver needs a positive one);
//  * `L::kHistoryOutlivesSeparation`: whether a separated pair keeps its history (a solver must
//    then keep the pair in its table and evaluate it while it is apart);
//  * `law.has_history(history)`: false for the history of a pair that has never touched (or has
//    lost its history); such a pair that is apart costs a solver nothing.
//
// Solvers are written against this interface with the law chosen at compile time (templates; no
// virtual call per contact). `ContactLaw` checks a law type against it.
//
// Kinematics come from a solver in the contact frame of kinematics.hpp: overlap > 0 touching,
// the slip is j's contact point relative to i's (2D: along t = perp(n); 3D: a vector in the
// tangent plane), forces are on j. A law has a dimension `L::kDim` (2 or 3): the same law
// template is instantiated for both (dim.hpp).
#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>

#include <Eigen/Core>

#include "netdem/contact/dim.hpp"

namespace netdem::contact {

/// The rotation that carries a law's stored tangential vectors (a spring, a force) from the
/// tangent plane of the last step into the current one (kinematics.hpp computes it). 2D: nothing
/// to do (a tangential quantity is the component along t, which rotates with n).
template <int D>
struct Transport {
  double apply(double v) const { return v; }
};
/// 3D: the rigid rotation of the pair over the step (the lever-arm weighted mean rotation of the
/// two particles, then the rotation of the normal relative to it), followed by the projection onto
/// the current tangent plane (LMM05 Eq 16), which only removes rounding.
///  * a quasi-static increment (pair_increment(), finite rotations): the matrix R;
///  * an explicit step (step_transport(), `small` = true): the rotation vector theta of the step,
///    applied as exp([theta]x) to second order, v + theta x v + (theta x (theta x v))/2, which
///    keeps |v| to O(theta^4) (no rescale), then projected (transport_small()).
template <>
struct Transport<3> {
  // (the initialisers from scalars: Eigen's Identity() and Zero() expressions are chains of calls
  // in a build that does not inline them, and the explicit loops construct a Transport per contact
  // and step: half of the run time of a 3D DEM test under the sanitizers. R is a plain array: the
  // nested-list constructor of an Eigen matrix is a loop over the rows even at -O3, 10 % of the 3D
  // periodic force loop's samples; docs/performance.md "Transport's R")
  double r[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};  ///< R, column-major
  Eigen::Vector3d n{0.0, 0.0, 1.0};      ///< the current normal
  Eigen::Vector3d theta{0.0, 0.0, 0.0};  ///< the rotation vector of one step (small = true)
  bool small = false;
  /// The finite rotation (small = false); the identity by default.
  Eigen::Map<const Eigen::Matrix3d> R() const { return Eigen::Map<const Eigen::Matrix3d>(r); }
  void set_R(const Eigen::Matrix3d& m) { std::copy(m.data(), m.data() + 9, r); }
  Eigen::Vector3d apply(const Eigen::Vector3d& v) const;
};

/// The explicit step's transport of a tangential vector v (in the last tangent plane) by the small
/// rotation theta into the plane of the unit normal n, in place, in scalars: w = v + theta x v +
/// theta x (theta x v) / 2 (exp([theta]x) to second order: |w| = |v| (1 + O(theta^4))), then
/// w - n (n . w). A rigid rotation at rate w_r carries a spring with the pair to O((w_r dt)^3)
/// per step.
inline void transport_small(double th0, double th1, double th2, double n0, double n1, double n2, double& v0,
                            double& v1, double& v2) {
  const double c0 = th1 * v2 - th2 * v1, c1 = th2 * v0 - th0 * v2, c2 = th0 * v1 - th1 * v0;  // theta x v
  const double d0 = th1 * c2 - th2 * c1, d1 = th2 * c0 - th0 * c2, d2 = th0 * c1 - th1 * c0;  // theta x (theta x v)
  const double w0 = v0 + c0 + 0.5 * d0, w1 = v1 + c1 + 0.5 * d1, w2 = v2 + c2 + 0.5 * d2;
  const double a = n0 * w0 + n1 * w1 + n2 * w2;
  v0 = w0 - n0 * a;
  v1 = w1 - n1 * a;
  v2 = w2 - n2 * a;
}

inline Eigen::Vector3d Transport<3>::apply(const Eigen::Vector3d& v) const {
  if (small) {
    double w0 = v.x(), w1 = v.y(), w2 = v.z();
    transport_small(theta.x(), theta.y(), theta.z(), n.x(), n.y(), n.z(), w0, w1, w2);
    return Eigen::Vector3d(w0, w1, w2);
  }
  Eigen::Vector3d w = R() * v;
  w -= n * n.dot(w);
  return w;
}

/// One contact over one step (explicit) or one increment (quasi-static), in the contact frame.
/// Tangential quantities are `Dim<D>::Tan`: the component along t in 2D, a vector in the current
/// tangent plane in 3D.
template <int D>
struct Kinematics {
  using Tan = typename Dim<D>::Tan;
  double overlap = 0.0;    ///< u_N at the end of the step (> 0: touching)
  double overlap_start = 0.0;  ///< u_N at the start of the step
  Tan dslip = tan_zero<Tan>();  ///< slip increment over the step (kinematics.hpp, Redanz & Fleck Eq 5)
  double v_n = 0.0;        ///< d overlap / dt (> 0 approaching); 0 in a quasi-static increment
  Tan v_t = tan_zero<Tan>();  ///< slip rate; 0 in a quasi-static increment
  double r_eff = 0.0;      ///< R* = r_i r_j / (r_i + r_j) (r_i for a flat wall)
  double m_eff = 0.0;      ///< m_i m_j / (m_i + m_j) (m_i for a wall); 0 when unknown
  double dt = 0.0;         ///< the step; 0 in a quasi-static increment
  [[no_unique_address]] Transport<D> transport;  ///< carries the stored tangential history into the current plane
};
using ContactKinematics = Kinematics<2>;

/// Consistent tangent in the contact frame: derivatives of the end forces with respect to the end
/// overlap and the slip increment, the rates v_n, v_t held fixed. 3D: dfn_dslip is the gradient,
/// dft_dun the derivative vector, dft_dslip the 3x3 matrix d f_t / d dslip (in-plane block used).
template <int D>
struct Tangent {
  using Tan = typename Dim<D>::Tan;
  using TanMat = typename Dim<D>::TanMat;
  double dfn_dun = 0.0;
  Tan dfn_dslip = tan_zero<Tan>();
  Tan dft_dun = tan_zero<Tan>();
  TanMat dft_dslip = tan_identity<D>(0.0);
};
using ContactTangent = Tangent<2>;

/// What one evaluation returns.
template <class History, int D = 2>
struct ContactResponse {
  double f_n = 0.0;   ///< normal force on j along n (> 0 repulsive)
  typename Dim<D>::Tan f_t = tan_zero<typename Dim<D>::Tan>();  ///< tangential force on j
  bool loaded = false;   ///< the contact is closed (not on its open branch): it carries the forces
  bool sliding = false;  ///< the tangential force is on its limit
  std::uint8_t branch = 0;  ///< the law's branch code, for diagnostics; 0 = open for every law
  History history;          ///< the history to commit if the step is accepted
};

/// Stiffness bounds for an explicit time step: normal and tangential, force per length.
struct StiffnessBound {
  double k_n = 0.0, k_t = 0.0;
  /// The a-priori bound (`stiffness_bound(r_eff)`, kHasExplicitBound) of a law whose tangential
  /// spring grows with its contact area (the plastic law: k_t sigma_y A_c): the tangential
  /// stiffness per unit contact area (2D: width); a solver adds k_t_area times the largest area
  /// it sees to k_t. 0 for a per-contact bound.
  double k_t_area = 0.0;
  /// The normal dashpot [force / velocity] by which a period of the normal spring may be taken
  /// damped (LMM05 Eq 6: omega = sqrt(k_n/m - (gamma_n/2m)^2)); 0: the undamped period (stricter).
  double gamma_n = 0.0;
};

/// What an implicit solver's iteration matrix takes from the law beyond the consistent tangent.
struct IterationStiffness {
  /// Normal stiffness (>= 0) added to the consistent normal tangent where Newton needs a stiffer
  /// one (the secant of a concave law); the symmetric iteration matrix uses tangent + k_n_add.
  double k_n_add = 0.0;
  double k_t = 0.0;  ///< the tangential spring (also while sliding, where the tangent has none)
};

template <class L>
concept ContactLaw = requires(const L& law, const typename L::History& h,
                              const Kinematics<L::kDim>& k, Tangent<L::kDim>* t,
                              const ContactResponse<typename L::History, L::kDim>& r) {
  typename L::Params;
  typename L::History;
  { L::kDim } -> std::convertible_to<int>;
  { law.params() } -> std::convertible_to<const typename L::Params&>;
  { law.evaluate(h, k, t) } -> std::same_as<ContactResponse<typename L::History, L::kDim>>;
  { law.stiffness_bound(h, k) } -> std::same_as<StiffnessBound>;
  { law.iteration_stiffness(h, k, r) } -> std::same_as<IterationStiffness>;
  { law.has_history(h) } -> std::same_as<bool>;
  { L::kHistoryOutlivesSeparation } -> std::convertible_to<bool>;
};

// ---- what a law offers beyond the concept: a solver asks, it never tests which law it has ------
/// The law reads the pair's properties in Kinematics (overlap_start, r_eff, m_eff: the plastic law's
/// branch and dashpots); a hot loop may leave them unset for a law that does not (the Luding law
/// reads only overlaps, rates and slips).
template <class L>
inline constexpr bool kReadsPairProperties = requires { requires L::kReadsPairProperties; };
/// The law knows the elastic energy stored at a contact: `elastic_energy(k)` (a function of the
/// kinematics the step ended with).
template <class L>
inline constexpr bool kHasElasticEnergy = requires(const L& law, const Kinematics<L::kDim>& k) {
  { law.elastic_energy(k) } -> std::convertible_to<double>;
};
/// The law's contact area (2D: width) follows from its normal force: `contact_area(f_n)` (the
/// plastic law: the mean contact pressure 3 sigma_y), which bounds its tangential stiffness.
template <class L>
inline constexpr bool kHasContactArea = requires(const L& law, double f_n) {
  { law.contact_area(f_n) } -> std::convertible_to<double>;
};

/// The law bounds every contact it can form, before the contacts are known: `stiffness_bound(r_eff)`
/// returns the largest normal stiffness of any contact of effective radius up to r_eff, over every
/// history and overlap, and the tangential bound (k_t, plus k_t_area per unit contact area). An
/// explicit solver takes its time step from it (docs/dynamic.md "Time step"), so that a new law
/// needs no solver edit.
template <class L>
inline constexpr bool kHasExplicitBound = requires(const L& law, double r_eff) {
  { law.stiffness_bound(r_eff) } -> std::same_as<StiffnessBound>;
};
/// The law's explicit time step may be taken from the contact duration of the mean pair when the
/// solver's rule says so (LMM05 Eq 6 and section 3.1.2, the Luding law); a law without it bounds
/// the lightest pair whatever the rule.
template <class L>
inline constexpr bool kMeanPairTimeStep = requires { requires L::kMeanPairTimeStep; };

/// The law gives the scales an implicit solver measures its residual against where no contact
/// carries a force yet (the network solver, NetworkSolverT<D, Law>): `reference_force(r)` and
/// `reference_stiffness(r)` for particles of radius r, and `first_touch_force(r_eff)`, the force
/// at the smallest overlap the law resolves (0 for a law whose force starts at zero overlap).
template <class L>
inline constexpr bool kHasReferenceScales = requires(const L& law, double r) {
  { law.reference_force(r) } -> std::convertible_to<double>;
  { law.reference_stiffness(r) } -> std::convertible_to<double>;
  { law.first_touch_force(r) } -> std::convertible_to<double>;
};
/// The law's normal force has a potential at fixed history, `normal_work(h, r_eff, u)` (d/du of
/// it is the normal force), and its tangential force one at a frozen stiffness and limit
/// (`tangential_frozen(f_n)`, `tangential_work(h, k_t, limit, dslip)`): the network solver's
/// trust region on the contact energy needs them.
template <class L>
inline constexpr bool kHasPotential = requires(const L& law, const typename L::History& h, double u,
                                               const typename Dim<L::kDim>::Tan& s) {
  { law.normal_work(h, u, u) } -> std::convertible_to<double>;
  { law.tangential_frozen(u) };
  { law.tangential_work(h, u, u, s) } -> std::convertible_to<double>;
};

/// The step of a solver's hot loop: evaluates the law and commits its history in place, returning
/// the forces. A law may provide `update(History&, const ContactKinematics&, double& f_n,
/// double& f_t)`, an in-place form of `evaluate` for a hot loop; it must give the same forces and
/// history to the last bit (the conformance suite checks every law that has one, and
/// Dynamic.InPlaceUpdateIsBitIdentical a whole run). InPlace = false: always `evaluate`.
template <bool InPlace = true, ContactLaw L>
inline void update_contact(const L& law, typename L::History& h, const Kinematics<L::kDim>& k,
                           double& f_n, typename Dim<L::kDim>::Tan& f_t) {
  if constexpr (InPlace && requires { law.update(h, k, f_n, f_t); }) {
    law.update(h, k, f_n, f_t);
  } else {
    const ContactResponse<typename L::History, L::kDim> r = law.evaluate(h, k, nullptr);
    h = r.history;
    f_n = r.f_n;
    f_t = r.f_t;
  }
}

}  // namespace netdem::contact
