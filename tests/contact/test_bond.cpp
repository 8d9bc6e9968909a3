// The bond element of Ivannikov et al. (Eqs 25-40; netdem/contact/bond.hpp): each stiffness of
// Eqs 34-36 by a deformation that excites it alone, rigid-body motions, moment balance, symmetry and
// rank of K_e, the scaling with E, and the printed Eq 37 against H^T.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include <Eigen/Eigenvalues>

#include "netdem/contact/bond.hpp"

using namespace netdem::contact;
using V3 = Eigen::Vector3d;

namespace {
constexpr double kPi = std::numbers::pi;
// a skew pair of unequal copper-like spheres (SI units): R_A = 24 um, R_B = 27 um, 2 % overlap
struct Pair {
  V3 xA{1.0e-4, -2.0e-5, 3.0e-5};
  V3 dir = V3(0.3, -0.7, 0.5).normalized();
  double RA = 24e-6, RB = 27e-6;
  double L = 0.98 * (24e-6 + 27e-6);
  V3 xB() const { return xA + L * dir; }
  double lA() const { return 0.47 * L; }
  BondElement bond() const { return make_bond(xA, xB(), lA(), L - lA(), RA, RB); }
};
const BondMaterial kCu{120e9, 0.34};

BondVec12 nodal(const V3& uA, const V3& tA, const V3& uB, const V3& tB) {
  BondVec12 y;
  y << uA, tA, uB, tB;
  return y;
}
V3 seg(const BondVec12& P, int k) { return P.segment<3>(3 * k); }  // 0 F_A, 1 M_A, 2 F_B, 3 M_B
}  // namespace

TEST(Bond, FrameAndLengths) {
  const Pair p;
  const BondElement b = p.bond();
  EXPECT_NEAR((b.e3 - p.dir).norm(), 0.0, 1e-15);
  EXPECT_NEAR(b.e1.dot(b.e3), 0.0, 1e-15);
  EXPECT_NEAR(b.e2.dot(b.e3), 0.0, 1e-15);
  EXPECT_NEAR(b.e1.cross(b.e2).dot(b.e3), 1.0, 1e-15);
  EXPECT_NEAR(b.L0(), p.L, 1e-15 * p.L);
  EXPECT_DOUBLE_EQ(b.Rm, 0.5 * (p.RA + p.RB));  // Eq 16
  EXPECT_THROW(make_bond(p.xA, p.xA, 1e-6, 1e-6, p.RA, p.RB), std::invalid_argument);
  EXPECT_THROW(make_bond(p.xA, p.xB(), p.lA(), 1.01 * (p.L - p.lA()), p.RA, p.RB), std::invalid_argument);
  EXPECT_THROW(make_bond(p.xA, p.xB(), -1e-6, p.L + 1e-6, p.RA, p.RB), std::invalid_argument);
  EXPECT_THROW(make_bond(p.xA, p.xB(), p.lA(), p.L - p.lA(), 0.0, p.RB), std::invalid_argument);
}

// Eq 34a/36a: an axial stretch d of B along e3 needs EA/L0 d at B (and the opposite at A), with
// no moment (the force acts along the arms).
TEST(Bond, AxialStiffnessEAOverL0) {
  const Pair p;
  const BondElement b = p.bond();
  const double d = 1e-9, A = kPi * b.Rm * b.Rm, k = kCu.E * A / b.L0();
  const BondVec12 P = bond_forces(b, kCu, nodal(V3::Zero(), V3::Zero(), d * b.e3, V3::Zero()));
  EXPECT_NEAR(seg(P, 2).dot(b.e3) / (k * d), 1.0, 1e-12);
  EXPECT_NEAR((seg(P, 2) - k * d * b.e3).norm(), 0.0, 1e-12 * k * d);
  EXPECT_NEAR((seg(P, 0) + seg(P, 2)).norm(), 0.0, 1e-12 * k * d);
  EXPECT_LT(seg(P, 1).norm() + seg(P, 3).norm(), 1e-12 * k * d * b.L0());
}

// Eq 34a: a lateral offset d of B along e1 needs GA/L0 d (a zero-length spring on rigid arms, not
// the 12 EI/L^3 of a beam), and the moments of that force about the centres, l x F.
TEST(Bond, LateralStiffnessGAOverL0) {
  const Pair p;
  const BondElement b = p.bond();
  const double d = 1e-9, A = kPi * b.Rm * b.Rm, k = kCu.G() * A / b.L0();
  for (const V3& e : {b.e1, b.e2}) {
    const BondVec12 P = bond_forces(b, kCu, nodal(V3::Zero(), V3::Zero(), d * e, V3::Zero()));
    EXPECT_NEAR((seg(P, 2) - k * d * e).norm(), 0.0, 1e-12 * k * d);
    const double Ib = 0.25 * kPi * std::pow(b.Rm, 4);
    EXPECT_GT(std::fabs(seg(P, 2).dot(e) / (12.0 * kCu.E * Ib / std::pow(b.L0(), 3) * d) - 1.0), 0.5);  // not a beam
    // M_A = l_A0 x F_link, M_B = -l_B0 x F_link with F_link = -F_B (Eq 39 with H^T)
    const V3 F = -seg(P, 2);
    EXPECT_NEAR((seg(P, 1) - (b.lA0 * b.e3).cross(F)).norm(), 0.0, 1e-12 * k * d * b.L0());
    EXPECT_NEAR((seg(P, 3) + (-b.lB0 * b.e3).cross(F)).norm(), 0.0, 1e-12 * k * d * b.L0());
  }
}

// Eq 34b/36b-c: a relative rotation of B about the grain-boundary centre (theta_B with the
// displacement that keeps B's bond point in place, so eps = 0) needs EI/L0 phi about e1, e2 and
// GJ/L0 phi about e3, and no force.
TEST(Bond, BendingEIAndTorsionGJOverL0) {
  const Pair p;
  const BondElement b = p.bond();
  const double phi = 1e-6, Ib = 0.25 * kPi * std::pow(b.Rm, 4), J = 0.5 * kPi * std::pow(b.Rm, 4);
  const double kb = kCu.E * Ib / b.L0(), kt = kCu.G() * J / b.L0();
  for (int a = 0; a < 3; ++a) {
    const V3 e = a == 0 ? b.e1 : a == 1 ? b.e2 : b.e3;
    const V3 tB = phi * e;
    const V3 uB = (-b.lB0 * b.e3).cross(tB);  // B turns about its bond point: eps = 0 (Eq 25)
    const BondVec12 y = nodal(V3::Zero(), V3::Zero(), uB, tB);
    EXPECT_LT(bond_deformation(b, y).head<3>().norm(), 1e-15 * phi * b.L0());
    const BondVec12 P = bond_forces(b, kCu, y);
    const double k = a < 2 ? kb : kt;
    EXPECT_NEAR((seg(P, 3) - k * phi * e).norm(), 0.0, 1e-12 * k * phi) << "axis " << a;
    EXPECT_NEAR((seg(P, 1) + k * phi * e).norm(), 0.0, 1e-12 * k * phi) << "axis " << a;
    EXPECT_LT(seg(P, 0).norm() + seg(P, 2).norm(), 1e-9 * k * phi / b.L0()) << "axis " << a;
  }
  EXPECT_NEAR(kt / kb, 2.0 * kCu.G() / kCu.E, 1e-15);  // J = 2 I
}

// A rigid translation and a small rigid rotation about any point (theta_A = theta_B = w,
// u = w x (x - c)) give y_link = 0 and no force; K_e is symmetric, positive semi-definite, and has
// exactly these six motions as its null space (rank 6).
TEST(Bond, RigidBodyMotionsGiveNoForce) {
  const Pair p;
  const BondElement b = p.bond();
  const BondMat12 K = bond_stiffness(b, kCu);
  const double kscale = K.cwiseAbs().maxCoeff();
  const V3 c(3e-5, 1e-5, -2e-5), w(2e-4, -1e-4, 3e-4), t(1e-8, -2e-8, 5e-9);
  const BondVec12 yt = nodal(t, V3::Zero(), t, V3::Zero());
  const BondVec12 yr = nodal(w.cross(p.xA - c), w, w.cross(p.xB() - c), w);
  EXPECT_LT(bond_forces(b, kCu, yt).norm(), 1e-13 * kscale * t.norm());
  EXPECT_LT(bond_deformation(b, yr).norm(), 1e-15 * w.norm() * p.L);
  EXPECT_LT(bond_forces(b, kCu, yr).norm(), 1e-13 * kscale * w.norm() * p.L);
  EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-15 * kscale);
  // rotations scaled by L0 (all entries in N/m), so that the rotational stiffnesses EI/L0^3 are not
  // lost against EA/L0 in the rank count
  BondVec12 sc;
  for (int i = 0; i < 12; ++i) sc(i) = i % 6 < 3 ? 1.0 : 1.0 / b.L0();
  const BondMat12 Ks = sc.asDiagonal() * K * sc.asDiagonal();
  Eigen::SelfAdjointEigenSolver<BondMat12> es(0.5 * (Ks + Ks.transpose()));
  const auto ev = es.eigenvalues();
  int zero = 0;
  for (int i = 0; i < 12; ++i) {
    EXPECT_GT(ev(i), -1e-12 * ev(11));
    zero += std::fabs(ev(i)) < 1e-10 * ev(11) ? 1 : 0;
  }
  EXPECT_EQ(zero, 6);
}

// Force and moment balance of the element for random y: F_A + F_B = 0 and, about the origin,
// M_A + M_B + x_A x F_A + x_B x F_B = 0 (Eq 40 with H^T). The printed Eq 37b/d instead leave the
// net moment -2 d e3 x F_link, which this test shows as well.
TEST(Bond, MomentBalanceAndPrintedEq37) {
  const Pair p;
  const BondElement b = p.bond();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    BondVec12 y;
    for (int i = 0; i < 12; ++i) y(i) = (i % 6 < 3 ? 1e-9 : 1e-5) * u(rng);
    const BondVec12 P = bond_forces(b, kCu, y);
    const double fs = seg(P, 0).norm() + seg(P, 2).norm(), ms = seg(P, 1).norm() + seg(P, 3).norm() + fs * p.L;
    EXPECT_LT((seg(P, 0) + seg(P, 2)).norm(), 1e-12 * fs);
    const V3 net = seg(P, 1) + seg(P, 3) + p.xA.cross(seg(P, 0)) + p.xB().cross(seg(P, 2));
    EXPECT_LT(net.norm(), 1e-11 * ms) << "trial " << trial;
    // Eq 37 as printed, from the same link forces P_link = K_link H y
    const BondVec6 Pl = bond_K_link(b, kCu) * bond_deformation(b, y);
    const V3 F = Pl.head<3>(), M = Pl.tail<3>();
    const V3 lA0 = b.lA0 * b.e3, lB0 = -b.lB0 * b.e3;
    const V3 MA37 = M - lA0.cross(F), MB37 = -M + lB0.cross(F);  // Eq 37b, 37d as printed
    const V3 net37 = MA37 + MB37 + p.xA.cross(F) + p.xB().cross(-F);
    EXPECT_LT((net37 + 2.0 * b.L0() * b.e3.cross(F)).norm(), 1e-11 * ms);
    EXPECT_GT(net37.norm(), 0.1 * b.L0() * F.cross(b.e3).norm());
    // and H^T: M_A = M + l_A0 x F, M_B = -M - l_B0 x F
    EXPECT_LT((seg(P, 1) - (M + lA0.cross(F))).norm(), 1e-12 * ms);
    EXPECT_LT((seg(P, 3) - (-M - lB0.cross(F))).norm(), 1e-12 * ms);
  }
}

// Forces and stiffness scale with E: 8 E gives exactly 8 P (a power of two: bit for bit), so a
// solver built on the element has no absolute tolerance or penalty in it (issue 17, "E drops out").
TEST(Bond, ScalesExactlyWithE) {
  const Pair p;
  const BondElement b = p.bond();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  BondVec12 y;
  for (int i = 0; i < 12; ++i) y(i) = (i % 6 < 3 ? 1e-9 : 1e-5) * u(rng);
  const BondMaterial m8{8.0 * kCu.E, kCu.nu};
  const BondVec12 P1 = bond_forces(b, kCu, y), P8 = bond_forces(b, m8, y);
  const BondVec12 P18 = 8.0 * P1;
  EXPECT_EQ(std::memcmp(P18.data(), P8.data(), sizeof(double) * 12), 0);
}

// ---- the finite-rotation form (Eq 20, Euler-Rodrigues Eqs 23-24) ---------------------------------

// Eq 23-24 against Eigen's AngleAxis, across the series boundary |theta|^2 = 1e-4 and at 0.
TEST(BondFinite, RodriguesIsTheRotation) {
  for (double t : {0.0, 1e-9, 1e-5, 9.99e-3, 1.001e-2, 0.3, 1.5, 3.0}) {
    const V3 axis = V3(0.2, -0.9, 0.4).normalized(), th = t * axis;
    const Eigen::Matrix3d Q = rotation_rodrigues<double>(th);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(t, axis).toRotationMatrix();
    EXPECT_LT((Q - R).cwiseAbs().maxCoeff(), 2e-16 * 8) << "theta " << t;
    // the left Jacobian: Q(theta + h d) l - Q(theta - h d) l = 2h (J_l d) x (Q l) + O(h^3)
    const V3 l(0.3, 0.1, -0.7), d = V3(0.5, 0.5, -0.2).normalized();
    const double h = 1e-6;
    const V3 fd = (rotation_rodrigues<double>(V3(th + h * d)) * l - rotation_rodrigues<double>(V3(th - h * d)) * l) / (2 * h);
    const V3 an = (left_jacobian<double>(th) * d).cross(Q * l);
    EXPECT_LT((fd - an).norm(), 1e-9) << "theta " << t;
  }
}

namespace {
BondVec12 finite_state(const Pair& p, double rot, double stretch) {
  // finite rotations of both nodes (different), a stretch and a lateral offset of B
  const BondElement b = p.bond();
  return nodal(V3(1e-8, -2e-8, 0.5e-8), rot * V3(0.3, -0.2, 0.5), stretch * b.e3 + 0.3 * stretch * b.e1 + V3(1e-8, -2e-8, 0.5e-8),
               rot * V3(-0.1, 0.4, 0.2));
}
}  // namespace

// A rigid motion of any angle (0.5 rad) gives no force in the finite form; Eq 40 gives one of order
// |w|^2 EA/L0 L0 there. At small y both forms agree to O(|theta|).
TEST(BondFinite, RigidFiniteRotationAndTheSmallLimit) {
  const Pair p;
  const BondElement b = p.bond();
  const V3 w(0.3, -0.25, 0.3), c(3e-5, 1e-5, -2e-5), t(1e-7, 0.0, -3e-8);
  const Eigen::Matrix3d Q = rotation_rodrigues<double>(w);
  const BondVec12 y = nodal((Q - Eigen::Matrix3d::Identity()) * (p.xA - c) + t, w,
                            (Q - Eigen::Matrix3d::Identity()) * (p.xB() - c) + t, w);
  const double fscale = kCu.E * kPi * b.Rm * b.Rm / b.L0() * p.L;  // EA/L0 times L
  EXPECT_LT(bond_deformation_finite<double>(b, y).head<3>().norm(), 1e-15 * p.L);
  EXPECT_LT(bond_forces_finite(b, kCu, y).norm(), 1e-13 * fscale);
  EXPECT_GT(bond_forces(b, kCu, y).norm(), 1e-3 * fscale);  // the small-rotation form is not objective
  for (double sc : {1e-3, 1e-4}) {
    const BondVec12 ys = finite_state(p, sc, 1e-9 * sc / 1e-3);
    const BondVec12 Pf = bond_forces_finite(b, kCu, ys), Pl = bond_forces(b, kCu, ys);
    const double rel = (Pf - Pl).norm() / Pl.norm();
    std::printf("  |theta| ~ %.0e: |P_finite - P_Eq40| / |P| = %.2e\n", sc, rel);
    EXPECT_LT(rel, 3.0 * sc);
  }
}

// P is the gradient of the link energy W, and the AD tangent is the Hessian of W: both against
// central finite differences at a state with 0.2 rad rotations and a stretched link, where the
// geometric part of the tangent matters (the Gauss-Newton part B^T K B alone misses it).
TEST(BondFinite, ForcesAndTangentAgainstFiniteDifferences) {
  const Pair p;
  const BondElement b = p.bond();
  const BondVec12 y = finite_state(p, 0.4, 2e-7);
  const BondVec12 P = bond_forces_finite(b, kCu, y);
  const BondMat12 Kt = bond_tangent_finite(b, kCu, y);
  BondVec12 scale;  // per DOF: a length for displacements, 1 for rotations
  for (int i = 0; i < 12; ++i) scale(i) = i % 6 < 3 ? p.L : 1.0;
  double errP = 0.0, errK = 0.0, errGN = 0.0;
  const double Pn = P.cwiseProduct(scale).cwiseAbs().maxCoeff();
  BondMat12 Kfd;
  for (int i = 0; i < 12; ++i) {
    const double h = 1e-6 * scale(i);
    BondVec12 yp = y, ym = y;
    yp(i) += h;
    ym(i) -= h;
    const double dW = (bond_energy_finite(b, kCu, yp) - bond_energy_finite(b, kCu, ym)) / (2 * h);
    errP = std::fmax(errP, std::fabs(dW - P(i)) * scale(i) / Pn);
    Kfd.col(i) = (bond_forces_finite(b, kCu, yp) - bond_forces_finite(b, kCu, ym)) / (2 * h);
  }
  // the Gauss-Newton tangent B^T K B, B = d y_link / d y by differences of the deformation
  Eigen::Matrix<double, 6, 12> B;
  for (int i = 0; i < 12; ++i) {
    const double h = 1e-6 * scale(i);
    BondVec12 yp = y, ym = y;
    yp(i) += h;
    ym(i) -= h;
    B.col(i) = (bond_deformation_finite<double>(b, yp) - bond_deformation_finite<double>(b, ym)) / (2 * h);
  }
  const BondMat12 KGN = B.transpose() * bond_K_link(b, kCu) * B;
  const BondMat12 S = scale.asDiagonal();
  const double Kn = (S * Kt * S).cwiseAbs().maxCoeff();
  errK = (S * (Kt - Kfd) * S).cwiseAbs().maxCoeff() / Kn;
  errGN = (S * (KGN - Kfd) * S).cwiseAbs().maxCoeff() / Kn;
  std::printf("  P vs dW/dy: %.2e; tangent vs dP/dy: %.2e; Gauss-Newton part alone: %.2e\n", errP, errK, errGN);
  EXPECT_LT(errP, 1e-7);
  EXPECT_LT(errK, 1e-7);
  EXPECT_GT(errGN, 100.0 * errK);  // the geometric stiffness is there and is right
  EXPECT_LT((S * (Kt - Kt.transpose()) * S).cwiseAbs().maxCoeff(), 1e-12 * Kn);  // a Hessian
  // at y = 0 the finite form's tangent is K_e of Eq 40
  const BondMat12 K0 = bond_tangent_finite(b, kCu, BondVec12::Zero()), Ke = bond_stiffness(b, kCu);
  EXPECT_LT((S * (K0 - Ke) * S).cwiseAbs().maxCoeff(), 1e-13 * (S * Ke * S).cwiseAbs().maxCoeff());
}
