// Tests of the 3D contact element (element.hpp, docs/contact.md "The 3D contact element"): the
// forces and their virtual work, the Jacobians of the 3D increment (kinematics.hpp), the
// consistent 12x12 tangent against central finite differences (frictionless, sticking, sliding,
// random geometries with unequal radii and finite rotations, two laws), the closed form at a zero
// increment, objectivity under finite rigid rotations, and the 2D element reproduced by a 3D pair
// lying in the x-y plane.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "netdem/contact/element.hpp"
#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"

using namespace netdem::contact;

namespace {

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;
using Vec12 = PairVecT<3>;
using Mat12 = PairMatT<3>;
using Law3 = PlasticIndentationLaw3;
using History3 = PlasticIndentationHistoryT<3>;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kStep = 1e-7;   // central differences: lengths ~ 1, rotations ~ 1 rad
constexpr double kFdTol = 1e-6;  // column-wise, relative to the column norm
constexpr double kJacStep = 1e-6;  // the kinematic Jacobians (differences of rotation matrices)

static_assert(Dim<3>::kPairDofs == 12 && Dim<2>::kPairDofs == 6);
static_assert(std::is_same_v<PairVecT<2>, PairVec> && std::is_same_v<PairMatT<2>, PairMat>);
static_assert(std::is_same_v<PairElement<PlasticIndentationLaw>, PairElementT<PlasticIndentationLaw>>);
static_assert(std::is_same_v<PairGeometryT<3>, PairGeometry3> && std::is_same_v<PairGeometryT<2>, PairGeometry>);

// A pair of spheres over one increment: the start centres and the end DOFs
// q = (x_i, dth_i, x_j, dth_j) (end positions and rotation-vector increments).
struct Scene {
  double ri = 1.0, rj = 1.0;
  V3 xi0 = V3::Zero(), xj0 = V3::UnitX();
  Vec12 q = Vec12::Zero();
  PairGeometry3 g0() const { return pair_geometry(xi0, xj0, ri, rj); }
  PairGeometry3 g1(const Vec12& qe) const {
    return pair_geometry(V3(qe.segment<3>(0)), V3(qe.segment<3>(6)), ri, rj);
  }
};

template <class L>
PairElementT<L> element_at(const L& law, const typename L::History& h, const Scene& s, const Vec12& q,
                           bool tangent, bool geometric = true) {
  PairElementT<L> e;
  TangentOptions opt;
  opt.geometric = geometric;
  pair_element(law, h, s.g0(), s.g1(q), V3(q.segment<3>(3)), V3(q.segment<3>(9)), e, tangent ? &opt : nullptr);
  return e;
}

// Central differences of K = -df/dq_end; `same` is false when the law's branch or sliding state
// differs at a perturbed point (the tangent is then not defined there).
template <class L>
Mat12 fd_tangent(const L& law, const typename L::History& h, const Scene& s, bool& same) {
  const PairElementT<L> e0 = element_at(law, h, s, s.q, false);
  Mat12 K;
  same = true;
  for (int c = 0; c < 12; ++c) {
    Vec12 qp = s.q, qm = s.q;
    qp(c) += kStep;
    qm(c) -= kStep;
    const PairElementT<L> ep = element_at(law, h, s, qp, false), em = element_at(law, h, s, qm, false);
    for (const PairElementT<L>* e : {&ep, &em})
      if (e->law.branch != e0.law.branch || e->law.sliding != e0.law.sliding) same = false;
    K.col(c) = -(ep.force - em.force) / (2.0 * kStep);
  }
  return K;
}

// max over columns of |K_c - F_c| / max(|F_c|, 1e-3 max_c |F_c|) (a zero column is checked
// against the largest one).
template <class A, class B>
double column_error(const A& K, const B& F) {
  double big = 0.0;
  for (int c = 0; c < F.cols(); ++c) big = std::fmax(big, F.col(c).norm());
  double err = 0.0;
  for (int c = 0; c < F.cols(); ++c)
    err = std::fmax(err, (K.col(c) - F.col(c)).norm() / std::fmax(F.col(c).norm(), 1e-3 * big));
  return err;
}

V3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> N(0.0, 1.0);
  const double z = N(rng), y = N(rng), x = N(rng);  // GCC's order (a call's arguments: unspecified)
  V3 v(x, y, z);
  return v.normalized();
}
// three draws of U as a vector (GCC's order of the former V3(U(rng), U(rng), U(rng)))
V3 uniform3(std::uniform_real_distribution<double>& U, std::mt19937& rng) {
  const double z = U(rng), y = U(rng), x = U(rng);
  return V3(x, y, z);
}
V3 random_in_plane(const V3& n, std::mt19937& rng) {
  const V3 v = random_unit(rng);
  return (v - n * n.dot(v)).normalized();
}

// How the pair moves over the increment: start overlap u0; a rigid rotation of angle `turn` about
// a random axis through the centre of i with a translation, both spheres turned with it; then an
// approach du along the end normal, a slip of j of length `slip` in a random direction of the plane
// and random rotation increments of size `spin` on each sphere.
struct Motion {
  double u0 = 0.01, du = 0.002, slip = 0.0, spin = 0.0, turn = 0.0;
};

Scene random_scene(std::mt19937& rng, const Motion& m) {
  std::uniform_real_distribution<double> U(-1.0, 1.0), R(0.6, 1.4);
  Scene s;
  s.ri = R(rng);
  s.rj = R(rng);
  const V3 n0 = random_unit(rng);
  s.xi0 = uniform3(U, rng);
  s.xj0 = s.xi0 + (s.ri + s.rj - m.u0) * n0;
  const V3 w = m.turn * random_unit(rng);
  const V3 n1 = rotation_of(w) * n0;
  const V3 xi1 = s.xi0 + 0.3 * uniform3(U, rng);
  const V3 xj1 = xi1 + (s.ri + s.rj - m.u0 - m.du) * n1 + m.slip * random_in_plane(n1, rng);
  const V3 ti = w + m.spin * random_unit(rng), tj = w + m.spin * random_unit(rng);
  s.q << xi1, ti, xj1, tj;
  return s;
}

// A loaded plastic history at the start: u_max = u0, a tangential force of `frac` of the friction
// limit in a random direction of the start plane.
History3 plastic_history(const PlasticIndentationParams& p, const Scene& s, double frac, std::mt19937& rng) {
  const PairGeometry3 g = s.g0();
  History3 h;
  h.u_max = g.overlap;
  if (p.frictional())
    h.f_t = frac * p.mu_eff() * loading_force<3>(p, g.r_eff, g.overlap) * random_in_plane(g.n, rng);
  return h;
}

PlasticIndentationParams plastic_params(double mu) {
  PlasticIndentationParams p;
  p.mu = mu;
  return p;
}

// The FD check of one state; returns the column error (and the error of the material part alone
// in `material_err`), or -1 when the regime changes within the difference step.
template <class L>
double tangent_error(const L& law, const typename L::History& h, const Scene& s, double* material_err = nullptr) {
  bool same = false;
  const Mat12 Kfd = fd_tangent(law, h, s, same);
  if (!same) return -1.0;
  const PairElementT<L> e = element_at(law, h, s, s.q, true, true);
  if (material_err) *material_err = column_error(element_at(law, h, s, s.q, true, false).stiffness, Kfd);
  return column_error(e.stiffness, Kfd);
}

}  // namespace

// ---- kinematics -----------------------------------------------------------------------------

// increment_jacobian(): d dslip / d q_end and the spin of the Transport (dR R^T = [spin dq]x)
// against central differences of pair_increment(), at finite increments (step 1e-6: the
// differences of R, entries ~ 1, carry 1e-16 / step of rounding).
TEST(Element3D, IncrementJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  double worst_slip = 0.0, worst_spin = 0.0;
  for (int k = 0; k < 20; ++k) {
    Motion m;
    m.turn = 1.5 * k / 19.0;
    m.slip = 0.05;
    m.spin = 0.2;
    m.du = 0.01;
    const Scene s = random_scene(rng, m);
    const PairGeometry3 g0 = s.g0();
    auto inc = [&](const Vec12& q) {
      return pair_increment(g0, s.g1(q), V3(q.segment<3>(3)), V3(q.segment<3>(9)));
    };
    Eigen::Matrix<double, 3, 12> dslip, spin, dn;
    const M3 R0 = inc(s.q).transport.R();
    for (int c = 0; c < 12; ++c) {
      Vec12 qp = s.q, qm = s.q;
      qp(c) += kJacStep;
      qm(c) -= kJacStep;
      const PairIncrement3 ip = inc(qp), im = inc(qm);
      dslip.col(c) = (ip.dslip - im.dslip) / (2.0 * kJacStep);
      const M3 W = (ip.transport.R() - im.transport.R()) / (2.0 * kJacStep) * R0.transpose();
      spin.col(c) = 0.5 * V3(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
      EXPECT_LT((W + W.transpose()).norm(), 1e-6) << "dR R^T is skew";
      dn.col(c) = (s.g1(qp).n - s.g1(qm).n) / (2.0 * kJacStep);
    }
    const IncrementJacobian3 J = increment_jacobian(g0, s.g1(s.q), V3(s.q.segment<3>(3)), V3(s.q.segment<3>(9)));
    worst_slip = std::fmax(worst_slip, column_error(J.dslip, dslip));
    worst_spin = std::fmax(worst_spin, column_error(J.spin, spin));
    EXPECT_LT(column_error(J.dn, dn), kFdTol);
  }
  std::printf("increment Jacobian vs FD: dslip %.2e, spin %.2e\n", worst_slip, worst_spin);
  EXPECT_LT(worst_slip, kFdTol);
  EXPECT_LT(worst_spin, kFdTol);
}

// slip_gradient(g) is the derivative of pair_increment()'s slip at a zero increment, and the
// element's forces do the virtual work -f_n du_N + f_t . dxi: f = -f_n b_n + B_t^T f_t.
TEST(Element3D, ForcesAreTheVirtualWorkOfNormalForceAndSlip) {
  std::mt19937 rng(5);
  const Law3 law(plastic_params(kInf));
  for (int k = 0; k < 10; ++k) {
    Motion m;
    m.turn = 0.7;
    m.slip = 1e-4;
    m.spin = 1e-4;
    const Scene s = random_scene(rng, m);
    const History3 h = plastic_history(law.params(), s, 0.6, rng);
    const PairElementT<Law3> e = element_at(law, h, s, s.q, false);
    ASSERT_TRUE(e.law.loaded);
    ASSERT_GT(e.law.f_t.norm(), 0.0);
    const PairGeometry3 g = s.g1(s.q);
    EXPECT_NEAR(e.law.f_t.dot(g.n), 0.0, 1e-14 * e.law.f_n) << "f_t in the tangent plane";
    const Vec12 f = -e.law.f_n * normal_gradient(g) + slip_gradient(g).transpose() * e.law.f_t;
    EXPECT_LT((e.force - f).norm(), 1e-14 * e.force.norm());
    // moment balance about the centre of i: M_i + M_j + (x_j - x_i) x f_j = 0
    const V3 Mtot = e.force.segment<3>(3) + e.force.segment<3>(9) + g.L * g.n.cross(V3(e.force.segment<3>(6)));
    EXPECT_LT(Mtot.norm(), 1e-14 * e.force.norm());
    // B_t = d dslip / dq at the zero increment from g
    Scene z = s;
    z.xi0 = s.q.segment<3>(0);
    z.xj0 = s.q.segment<3>(6);
    Eigen::Matrix<double, 3, 12> Bfd;
    for (int c = 0; c < 12; ++c) {
      Vec12 qp = Vec12::Zero(), qm = Vec12::Zero();
      qp << z.xi0, V3::Zero(), z.xj0, V3::Zero();
      qm = qp;
      qp(c) += kStep;
      qm(c) -= kStep;
      auto slip = [&](const Vec12& q) {
        return pair_increment(z.g0(), z.g1(q), V3(q.segment<3>(3)), V3(q.segment<3>(9))).dslip;
      };
      Bfd.col(c) = (slip(qp) - slip(qm)) / (2.0 * kStep);
    }
    EXPECT_LT(column_error(slip_gradient(g), Bfd), kFdTol);
  }
}

// ---- the consistent tangent -------------------------------------------------------------------

// A frictionless loaded contact: K = k_n b_n b_n^T + the geometric f_n d n / dq; random
// geometries, finite rotations (which must not matter: no moments).
TEST(Element3D, TangentFrictionlessMatchesFiniteDifferences) {
  std::mt19937 rng(1);
  const Law3 law(plastic_params(0.0));
  double worst = 0.0, worst_material = kInf;
  for (int k = 0; k < 10; ++k) {
    Motion m;
    m.turn = 0.9;
    m.slip = 0.004;
    m.spin = 0.05;
    const Scene s = random_scene(rng, m);
    const History3 h = plastic_history(law.params(), s, 0.0, rng);
    ASSERT_TRUE(element_at(law, h, s, s.q, false).law.loaded);
    double mat = 0.0;
    const double err = tangent_error(law, h, s, &mat);
    ASSERT_GE(err, 0.0);
    worst = std::fmax(worst, err);
    worst_material = std::fmin(worst_material, mat);
  }
  std::printf("frictionless: FD error %.2e (material part alone: >= %.2e)\n", worst, worst_material);
  EXPECT_LT(worst, kFdTol);
  EXPECT_GT(worst_material, 1e-4) << "the geometric part is resolved by the differences";
}

// A sticking frictional contact (plastic law, k_t > 0, mu = inf i.e. mu_eff = 1/(3 sqrt 3)) with a
// tangential force carried from the start plane, finite rigid rotations and twists.
TEST(Element3D, TangentStickingMatchesFiniteDifferences) {
  std::mt19937 rng(2);
  const Law3 law(plastic_params(kInf));
  double worst = 0.0, worst_material = kInf;
  for (int k = 0; k < 10; ++k) {
    Motion m;
    m.turn = 0.2 + 0.15 * k;
    m.slip = 1e-4;
    m.spin = 1e-4;
    const Scene s = random_scene(rng, m);
    const History3 h = plastic_history(law.params(), s, 0.5, rng);
    const PairElementT<Law3> e = element_at(law, h, s, s.q, false);
    ASSERT_TRUE(e.law.loaded);
    ASSERT_FALSE(e.law.sliding);
    double mat = 0.0;
    const double err = tangent_error(law, h, s, &mat);
    ASSERT_GE(err, 0.0);
    worst = std::fmax(worst, err);
    worst_material = std::fmin(worst_material, mat);
  }
  std::printf("sticking: FD error %.2e (material part alone: >= %.2e)\n", worst, worst_material);
  EXPECT_LT(worst, kFdTol);
  EXPECT_GT(worst_material, 1e-4);
}

// A sliding contact (mu = 0.1, the trial force well outside the cone): the direction of the force
// turns with the trial force (the law's 3D gross-slip tangent).
TEST(Element3D, TangentSlidingMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  const Law3 law(plastic_params(0.1));
  double worst = 0.0;
  for (int k = 0; k < 10; ++k) {
    Motion m;
    m.turn = 0.1 * k;
    m.slip = 0.003;
    m.spin = 0.003;
    const Scene s = random_scene(rng, m);
    const History3 h = plastic_history(law.params(), s, 0.9, rng);
    const PairElementT<Law3> e = element_at(law, h, s, s.q, false);
    ASSERT_TRUE(e.law.sliding);
    const double err = tangent_error(law, h, s);
    ASSERT_GE(err, 0.0);
    worst = std::fmax(worst, err);
  }
  std::printf("sliding: FD error %.2e\n", worst);
  EXPECT_LT(worst, kFdTol);
}

// Random states of both laws: random radii, overlaps, histories, rigid rotations up to 1.5 rad,
// slips and rotation increments over four decades; plastic (mu = inf and 0.1) and Luding's linear
// spring with Coulomb friction. Stick and slip must both be visited.
TEST(Element3D, TangentMatchesFiniteDifferencesOnRandomStates) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  LudingParams lp;
  lp.k2 = 100.0;
  lp.k1_ratio = 1.0;
  lp.kc_ratio = 0.0;
  lp.alpha = 0.3;
  lp.mu = 0.4;
  const LudingLaw<kLudingLinear, 3> luding(lp, 0.0);
  int tested = 0, skipped = 0, stick = 0, slide = 0;
  double worst_plastic = 0.0, worst_luding = 0.0;
  for (int k = 0; k < 60; ++k) {
    Motion m;
    m.u0 = 0.005 + 0.03 * U(rng);
    m.du = (U(rng) - 0.3) * 0.5 * m.u0;
    m.turn = 1.5 * U(rng);
    m.slip = std::pow(10.0, -5.0 + 3.0 * U(rng));
    m.spin = std::pow(10.0, -5.0 + 3.0 * U(rng));
    const Scene s = random_scene(rng, m);
    double err = -1.0;
    bool sliding = false;
    if (k % 3 != 2) {
      const Law3 law(plastic_params(k % 3 == 0 ? kInf : 0.1));
      const History3 h = plastic_history(law.params(), s, U(rng), rng);
      const PairElementT<Law3> e = element_at(law, h, s, s.q, false);
      if (!e.law.loaded) continue;
      sliding = e.law.sliding;
      err = tangent_error(law, h, s);
      if (err >= 0.0) worst_plastic = std::fmax(worst_plastic, err);
    } else {
      LudingHistoryT<3> h;
      const PairGeometry3 g = s.g0();
      const V3 dir = random_in_plane(g.n, rng);  // (GCC's order: the operands' order is unspecified)
      const double a = U(rng);
      h.xi = -a * lp.mu * lp.k2 * g.overlap / (lp.alpha * lp.k2) * dir;
      const PairElementT<LudingLaw<kLudingLinear, 3>> e = element_at(luding, h, s, s.q, false);
      if (!e.law.loaded) continue;
      sliding = e.law.sliding;
      err = tangent_error(luding, h, s);
      if (err >= 0.0) worst_luding = std::fmax(worst_luding, err);
    }
    if (err < 0.0) {
      ++skipped;
      continue;
    }
    ++tested;
    (sliding ? slide : stick) += 1;
    EXPECT_LT(err, kFdTol) << "state " << k;
  }
  std::printf("random states: %d tested (%d stick, %d slide), %d skipped (regime change); FD error plastic %.2e, "
              "Luding %.2e\n", tested, stick, slide, skipped, worst_plastic, worst_luding);
  EXPECT_GE(tested, 40);
  EXPECT_GE(stick, 10);
  EXPECT_GE(slide, 10);
}

// At a zero increment the sticking element's material tangent is the closed form
// k_n b_n b_n^T + k_t A_c B_t^T B_t (k_n = 6 pi sigma_y R*, A_c = F_N / (3 sigma_y)): symmetric,
// rank 3, the six rigid modes and the three rolling/twisting modes in its null space.
TEST(Element3D, StickingTangentAtZeroIncrementIsTheClosedForm) {
  std::mt19937 rng(6);
  const Law3 law(plastic_params(kInf));
  for (int k = 0; k < 5; ++k) {
    Motion m;
    Scene s = random_scene(rng, m);
    s.q << s.xi0, V3::Zero(), s.xj0, V3::Zero();
    const History3 h = plastic_history(law.params(), s, 0.5, rng);
    const PairElementT<Law3> e = element_at(law, h, s, s.q, true, false);
    ASSERT_FALSE(e.law.sliding);
    const PairGeometry3 g = s.g0();
    const double kn = 6.0 * std::numbers::pi * law.params().sigma_y * g.r_eff;
    const double kta = law.params().shear_stiffness() * e.law.f_n / (3.0 * law.params().sigma_y);
    const Vec12 bn = normal_gradient(g);
    const Eigen::Matrix<double, 3, 12> Bt = slip_gradient(g);
    const Mat12 K = kn * bn * bn.transpose() + kta * Bt.transpose() * Bt;
    EXPECT_LT((e.stiffness - K).norm(), 1e-13 * K.norm());
    EXPECT_LT((e.stiffness - e.stiffness.transpose()).norm(), 1e-13 * K.norm());
    Eigen::SelfAdjointEigenSolver<Mat12> es(0.5 * (e.stiffness + e.stiffness.transpose()));
    for (int i = 0; i < 9; ++i) EXPECT_LT(std::fabs(es.eigenvalues()(i)), 1e-12 * K.norm());
    for (int i = 9; i < 12; ++i) EXPECT_GT(es.eigenvalues()(i), 1e-3 * K.norm());
    for (int a = 0; a < 3; ++a) {  // rigid translation and rotation about a far point
      Vec12 t = Vec12::Zero(), r = Vec12::Zero();
      t(a) = t(6 + a) = 1.0;
      const V3 w = V3::Unit(a), p(5.0, -3.0, 2.0);
      r << w.cross(s.xi0 - p), w, w.cross(s.xj0 - p), w;
      EXPECT_LT((e.stiffness * t).norm(), 1e-13 * K.norm());
      EXPECT_LT((e.stiffness * r).norm(), 1e-13 * K.norm() * r.norm());
    }
  }
}

// ---- objectivity ------------------------------------------------------------------------------

// A loaded pair with a tangential force, moved rigidly: rotated by S = exp(w) about a far point and
// translated, both spheres turned by the same w. No slip; the forces are the reference forces
// rotated; and the tangent is the reference tangent rotated, K = S_b K_ref T with
// T = blockdiag(S^T, S^T J_l(w), S^T, S^T J_l(w)) (a rotation increment dth at w is the spatial
// rotation J_l(w) dth).
TEST(Element3D, ObjectiveUnderFiniteRigidRotations) {
  std::mt19937 rng(7);
  const Law3 law(plastic_params(kInf));
  Motion m;
  Scene ref = random_scene(rng, m);
  ref.q << ref.xi0, V3::Zero(), ref.xj0, V3::Zero();
  History3 h = plastic_history(law.params(), ref, 0.7, rng);
  h.u_max *= 0.9;  // on the loading branch, away from its kink at u_max (rounding would pick a side)
  const PairElementT<Law3> e0 = element_at(law, h, ref, ref.q, true, true);
  ASSERT_GT(e0.law.f_t.norm(), 0.1 * e0.law.f_n * law.params().mu_eff());
  const V3 n0 = ref.g0().n;
  const V3 pivot(-3.0, 5.0, 1.0), shift(7.0, -2.0, 4.0);
  int cases = 0;
  double worst_slip = 0.0, worst_f = 0.0, worst_k = 0.0;
  for (const V3& axis : {random_unit(rng), n0, random_in_plane(n0, rng), V3(V3::UnitZ())}) {
    for (double ang : {1e-3, 0.1, 0.7, 2.5, -1.2}) {
      const V3 w = ang * axis;
      const M3 S = rotation_of(w);
      Scene s = ref;
      s.q << pivot + S * (ref.xi0 - pivot) + shift, w, pivot + S * (ref.xj0 - pivot) + shift, w;
      const PairElementT<Law3> e = element_at(law, h, s, s.q, true, true);
      // rounding: the centres (|x| ~ 10) carry 1e-15, the overlap 0.01 then 1e-13 relative
      EXPECT_LT(e.dslip.norm(), 1e-12 * m.u0) << "angle " << ang;
      EXPECT_NEAR(e.law.f_n, e0.law.f_n, 1e-11 * e0.law.f_n);
      Mat12 Sb = Mat12::Zero(), T = Mat12::Zero();
      const M3 J = left_jacobian<double>(w);
      for (int b = 0; b < 4; ++b) {
        Sb.block<3, 3>(3 * b, 3 * b) = S;
        T.block<3, 3>(3 * b, 3 * b) = (b % 2 == 0) ? M3(S.transpose()) : M3(S.transpose() * J);
      }
      const double ef = (e.force - Sb * e0.force).norm() / e0.force.norm();
      const double ek = (e.stiffness - Sb * e0.stiffness * T).norm() / e0.stiffness.norm();
      EXPECT_LT(ef, 1e-11) << "angle " << ang;
      EXPECT_LT(ek, 1e-10) << "angle " << ang;
      worst_slip = std::fmax(worst_slip, e.dslip.norm() / m.u0);
      worst_f = std::fmax(worst_f, ef);
      worst_k = std::fmax(worst_k, ek);
      ++cases;
    }
  }
  std::printf("rigid rotations: |dslip|/u0 %.1e, forces %.1e, tangent %.1e\n", worst_slip, worst_f, worst_k);
  EXPECT_EQ(cases, 20);
}

// ---- the 2D element as a special case ---------------------------------------------------------

// A 3D pair in the x-y plane moving in the plane (rotations about e3) is the 2D element: the same
// slip along t, forces, and the same in-plane block of the tangent (material and geometric parts);
// the out-of-plane forces vanish and the in-plane and out-of-plane DOFs are uncoupled (mirror
// symmetry z -> -z). The law: Luding's linear spring with Coulomb friction, the same in 2D and 3D.
TEST(Element3D, PlanarPairReproducesThe2DElement) {
  LudingParams lp;
  lp.k2 = 100.0;
  lp.k1_ratio = 1.0;
  lp.kc_ratio = 0.0;
  lp.alpha = 0.3;
  lp.mu = 0.4;
  const LudingLaw<kLudingLinear, 2> law2(lp, 0.0);
  const LudingLaw<kLudingLinear, 3> law3(lp, 0.0);
  const int in[6] = {0, 1, 5, 6, 7, 11}, out[6] = {2, 3, 4, 8, 9, 10};
  int stick = 0, slide = 0;
  for (double slip : {2e-4, 2e-2}) {
    for (double ang : {0.0, 0.3, -2.0}) {
      const double ri = 1.1, rj = 0.8, u0 = 0.01;
      const Vec xi0(0.3, -0.2), n0(std::cos(0.4), std::sin(0.4));
      const Vec xj0 = xi0 + (ri + rj - u0) * n0;
      const Eigen::Rotation2Dd R(ang);
      const Vec n1 = R * n0;
      const Vec xi1 = xi0 + Vec(0.05, 0.02);
      const Vec xj1 = xi1 + (ri + rj - u0 - 0.002) * n1 + slip * perp(n1);
      const double thi = ang + 0.5 * slip, thj = ang - 0.7 * slip;
      LudingHistoryT<2> h2;
      h2.xi = 0.5 * lp.mu * u0 / lp.alpha;  // half the friction limit at the start
      LudingHistoryT<3> h3;
      h3.xi = h2.xi * V3(-n0.y(), n0.x(), 0.0);
      const PairGeometry a0 = pair_geometry(xi0, xj0, ri, rj), a1 = pair_geometry(xi1, xj1, ri, rj);
      const PairGeometry3 b0 = pair_geometry(V3(xi0.x(), xi0.y(), 0.0), V3(xj0.x(), xj0.y(), 0.0), ri, rj);
      const PairGeometry3 b1 = pair_geometry(V3(xi1.x(), xi1.y(), 0.0), V3(xj1.x(), xj1.y(), 0.0), ri, rj);
      for (bool geometric : {false, true}) {
        TangentOptions opt;
        opt.geometric = geometric;
        PairElementT<LudingLaw<kLudingLinear, 2>> e2;
        PairElementT<LudingLaw<kLudingLinear, 3>> e3;
        pair_element(law2, h2, a0, a1, thi, thj, e2, &opt);
        pair_element(law3, h3, b0, b1, V3(0.0, 0.0, thi), V3(0.0, 0.0, thj), e3, &opt);
        ASSERT_TRUE(e2.law.loaded);
        EXPECT_EQ(e2.law.sliding, e3.law.sliding);
        (e2.law.sliding ? slide : stick) += geometric ? 1 : 0;
        const V3 t1(-a1.n.y(), a1.n.x(), 0.0);
        EXPECT_LT((e3.dslip - e2.dslip * t1).norm(), 1e-14) << "angle " << ang;
        EXPECT_NEAR(e3.law.f_n, e2.law.f_n, 1e-13 * e2.law.f_n);
        Eigen::Matrix<double, 6, 6> Kin, Kio, Koi;
        for (int r = 0; r < 6; ++r) {
          EXPECT_NEAR(e3.force(in[r]), e2.force(r), 1e-13 * e2.force.norm()) << "row " << r;
          EXPECT_EQ(e3.force(out[r]), 0.0) << "row " << out[r];
          for (int c = 0; c < 6; ++c) {
            Kin(r, c) = e3.stiffness(in[r], in[c]);
            Kio(r, c) = e3.stiffness(in[r], out[c]);
            Koi(r, c) = e3.stiffness(out[r], in[c]);
          }
        }
        std::printf("planar (slip %.0e, angle %.1f, geometric %d): |K3 - K2| / |K2| = %.2e\n", slip, ang,
                    int(geometric), (Kin - e2.stiffness).norm() / e2.stiffness.norm());
        EXPECT_LT((Kin - e2.stiffness).norm(), 1e-12 * e2.stiffness.norm());
        EXPECT_LT(Kio.norm(), 1e-13 * e2.stiffness.norm());
        EXPECT_LT(Koi.norm(), 1e-13 * e2.stiffness.norm());
      }
    }
  }
  EXPECT_EQ(stick, 3);
  EXPECT_EQ(slide, 3);
}
