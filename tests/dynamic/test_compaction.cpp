// The DEM compaction protocol of the library (netdem/dynamic/compaction.hpp) and the Eq 16
// measures (netdem/system/affine_deviation.hpp), disks and spheres, against closed forms:
//  * Eq 16 for one contact: u_N^a = -n.dE.n (r_i + r_j), |u_T^a| = |dE n - (n.dE.n) n| (r_i + r_j);
//    the same contact in 2D and in the x-y plane in 3D gives the same numbers, and an isotropic dE
//    no tangential part (exactly, in 2D);
//  * a square (cubic) lattice in affine hydrostatic compaction: the overlaps follow
//    u = R_sum - L_0 exp(e t), so the Eq 16 deviation of every contact is the second-order strain
//    term: |u - u^a| / u^a = (exp(e t) - 1 - e t) / |e t| ~ |e t| / 2; Z = 3 (square), 4 (cubic);
//    the run ends at the target density D = D_0 exp(-tr E);
//  * the Figs 7-8 tangential deviation (2D): a rigid rotation of the lattice moves the centres by
//    L alpha across every contact and slips no contact point; turning every disk by beta slips
//    each contact point by L beta;
//  * the strain paths and the protocol's options, refused with the field they name.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "netdem/dynamic/compaction.hpp"
#include "netdem/field_error.hpp"
#include "netdem/system/affine_deviation.hpp"
#include "test_scale.hpp"

using namespace netdem::dem;
namespace sys = netdem::sys;

namespace {

TEST(AffineApproach, ClosedFormAndDimensionConsistency) {
  const double th = 0.3, a = -0.02, b = 0.01, c = 0.005, Rsum = 2.5;
  const Eigen::Vector2d n2(std::cos(th), std::sin(th));
  Eigen::Matrix2d E2;
  E2 << a, c, c, b;
  const auto r2 = sys::affine_approach<2>(n2, E2, Rsum);
  const double cs = std::cos(th), sn = std::sin(th);
  EXPECT_NEAR(r2.normal, -(a * cs * cs + b * sn * sn + 2 * c * sn * cs) * Rsum, 1e-15);
  EXPECT_NEAR(r2.tangential, ((b - a) * sn * cs + c * (cs * cs - sn * sn)) * Rsum, 1e-15);
  // the same contact in the x-y plane of a 3D sample: the same normal part and |tangential part|
  const Eigen::Vector3d n3(cs, sn, 0.0);
  Eigen::Matrix3d E3 = Eigen::Matrix3d::Zero();
  E3.topLeftCorner<2, 2>() = E2;
  E3(2, 2) = 0.7;  // a strain along z moves nothing in this contact
  const auto r3 = sys::affine_approach<3>(n3, E3, Rsum);
  EXPECT_NEAR(r3.normal, r2.normal, 1e-15);
  EXPECT_NEAR(r3.tangential_norm(), std::fabs(r2.tangential), 1e-15);
  EXPECT_NEAR(r3.tangential.dot(n3), 0.0, 1e-15);  // in the tangent plane
  // isotropic: no tangential part, exactly in 2D
  const auto iso = sys::affine_approach<2>(n2, Eigen::Matrix2d::Identity() * -0.01, Rsum);
  EXPECT_EQ(iso.tangential, 0.0);
  EXPECT_NEAR(iso.normal, 0.01 * Rsum, 1e-15);
}

TEST(StrainPath, ParsesBothDimensionsAndNamesTheField) {
  const auto h2 = sys::StrainPathT<2>::parse("hydrostatic");
  EXPECT_EQ(h2.E, (sys::Voigt<2>{-1, -1, 0}));
  const auto d3 = sys::StrainPathT<3>::parse("closed-die");  // along z, the gravity axis
  EXPECT_EQ(d3.E, (sys::Voigt<3>{0, 0, -1, 0, 0, 0}));
  const auto g3 = sys::StrainPathT<3>::parse("-1,-1,-1,0.5,0,0");
  EXPECT_TRUE(g3.shear());
  EXPECT_DOUBLE_EQ(g3.norm(), std::sqrt(3.0 + 2 * 0.25));
  EXPECT_DOUBLE_EQ(g3.trace(), -3.0);
  for (const char* bad : {"", "1,2", "1,2,3,4", "a,b,c", "0,0,0", "1,nan,0", "1,2,3,"}) {
    try {
      (void)sys::StrainPathT<2>::parse(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const netdem::FieldError& e) {
      EXPECT_EQ(e.field(), "path") << bad;
    }
  }
  EXPECT_THROW((void)sys::StrainPathT<3>::parse("1,2,3,4,5"), netdem::FieldError);
}

/// A square (D = 2) or cubic (D = 3) lattice of m^D unit particles at spacing 2 - u0 in a box
/// touching the outer ones.
template <int D>
netdem::packing::Packing lattice(int m, double u0) {
  netdem::packing::Packing p;
  p.dim = D;
  const double h = 2.0 - u0;
  const int mz = D == 3 ? m : 1;
  for (int k = 0; k < mz; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        p.x.push_back(1.0 + i * h);
        p.y.push_back(1.0 + j * h);
        if (D == 3) p.z.push_back(1.0 + k * h);
        p.r.push_back(1.0);
      }
  const double L = 2.0 + (m - 1) * h;
  p.box.x_max = p.box.y_max = L;
  if (D == 3) p.box.z_max = L;
  return p;
}

template <int D>
class Rows : public CompactionObserverT<D> {
 public:
  void row(const CompactionRowT<D>& r) override { rows.push_back(r); }
  std::vector<CompactionRowT<D>> rows;
};

template <int D>
void affine_lattice_compaction() {
  // (the sanitizer build: 3^3 spheres instead of 4^3; every check below holds for any m >= 3)
  const int m = D == 3 && netdem::test::small_scale() ? 3 : 4;
  const double u0 = 1e-9;
  const auto pk = lattice<D>(m, u0);
  ParticlesT<D> P = particles_at_rest<D>(pk, 1.0);
  Box box(pk.box);
  box.contact_walls = false;  // the box follows the affine field (as demsolve compact --affine)
  box.right.mode = box.top.mode = WallMode::Affine;
  if constexpr (D == 3) box.back.mode = WallMode::Affine;
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.sigma_y = 1.0;
  o.plastic.mu = 0.0;
  o.plastic.first_touch = 1e-4;
  o.plastic.damping_n = o.plastic.damping_t = 0.5;
  DynamicSolverT<D> s(std::move(P), o.plastic, box, o);
  const double D0 = pk.density();
  CompactionOptions co;
  co.target_density = D0 * std::exp(0.06);  // tr E = -0.06
  co.inertial_number = 1e-3;
  co.increments = 6;
  const auto path = sys::StrainPathT<D>::parse("hydrostatic");
  co.validate(path, D0);
  const auto rate = compaction_rate(path, co.inertial_number, D0, co.target_density);
  // |E'| (Frobenius) = gamma' = I / 2 (d = 2, rho = sigma_y = 1)
  EXPECT_NEAR(std::sqrt(D * rate.rate[0] * rate.rate[0]), co.inertial_number / 2.0, 1e-15);
  set_strain_rate(s, rate.rate);
  s.set_affine_velocities();
  std::vector<std::uint32_t> all;
  for (std::uint32_t p = 0; p < s.particles().size(); ++p) all.push_back(p);
  s.set_prescribed(all, false);
  Rows<D> obs;
  const auto sum = run_compaction(s, rate, co, obs);
  ASSERT_TRUE(sum.ok()) << sum.reason;
  ASSERT_EQ(obs.rows.size(), 7u);
  // the target density, within the last step's overshoot
  const double overshoot = std::fabs(D * rate.rate[0]) * s.dt();
  EXPECT_GE(s.density(), co.target_density * (1.0 - 1e-12));
  EXPECT_LE(s.density(), co.target_density * (1.0 + 1.01 * overshoot));
  // every lattice bond loaded, no other contact: Z = 2 D (m - 1) / m
  const auto& last = obs.rows.back();
  EXPECT_EQ(last.mean.Z, 2.0 * D * (m - 1) / m);
  EXPECT_EQ(last.outside, 0);
  // Eq 16 in affine motion. Along each axis x = -e t > 0 and L = L_0 exp(-x), so with L_0 = R_sum -
  // u_0: u - u^a = u_0 exp(-x) - R_sum (exp(-x) - 1 + x), u^a = x R_sum, and every contact's
  // |u - u^a| / u^a = f(x) = (exp(-x) - 1 + x) / x = x/2 - x^2/6 + ... (u_0 adds ~1e-8).
  auto f = [](double x) { return (std::expm1(-x) + x) / x; };
  const double x_end = -last.E[0], x_prev = -obs.rows[obs.rows.size() - 2].E[0];
  {  // at one instant: a fresh meter (every contact first seen now, formed at E = 0)
    CompactionMeterT<D> meter(false, 1.0);
    const auto now = meter.measure(s, last.E);
    EXPECT_NEAR(now.dev_ratio_of_means, f(x_end), 1e-6);
    EXPECT_NEAR(now.dev_mean_ratio, f(x_end), 1e-6);
    EXPECT_EQ(now.Z, last.mean.Z);
  }
  // the row: the mean over the samples of its window, between the window's ends
  EXPECT_GT(last.mean.dev_ratio_of_means, f(x_prev));
  EXPECT_LT(last.mean.dev_ratio_of_means, f(x_end) + 1e-6);
  EXPECT_LT(last.mean.affine_ut, 1e-12);  // hydrostatic: no tangential affine motion
  // the compression stress: every bond carries the same force, so Eq 13 from the contacts is
  // isotropic
  EXPECT_LT(last.mean.Sc[0], 0.0);
  EXPECT_NEAR(last.mean.Sc[1], last.mean.Sc[0], 1e-9 * std::fabs(last.mean.Sc[0]));
}

TEST(DemCompaction, AffineSquareLatticeMatchesEq16Disks) { affine_lattice_compaction<2>(); }
TEST(DemCompaction, AffineCubicLatticeMatchesEq16Spheres) { affine_lattice_compaction<3>(); }

/// The Figs 7-8 bookkeeping of the meter (2D), on a square lattice of 4 x 4 unit disks with the
/// overlap u0, measured in three states at the same macroscopic strain E (hydrostatic, so u_T^a = 0
/// and u_N^a = x R_sum, x = -E11, for every contact):
///  * a rigid rotation of the whole lattice by alpha, centres and angles: each contact's centres
///    move by L alpha across it, and its contact points do not slip (Eq 5 is objective);
///  * then every disk turned by beta more, the centres held: each contact point slips by
///    -(d_i + d_j) beta = -L beta, the centres do not move.
TEST(DemCompaction, TangentialDeviationIsObjectiveAndCountsTheRolling) {
  const int m = 4;
  const double u0 = 1e-3, alpha = 0.02, beta = -0.005, x = 0.01;
  const auto pk = lattice<2>(m, u0);
  const double cx = 0.5 * (pk.box.x_min + pk.box.x_max), cy = 0.5 * (pk.box.y_min + pk.box.y_max);
  auto solver_at = [&](double rot, double spin) {
    ParticlesT<2> P = particles_at_rest<2>(pk, 1.0);
    const double c = std::cos(rot), s = std::sin(rot);
    for (std::size_t p = 0; p < P.size(); ++p) {
      const double dx = P.pos[2 * p] - cx, dy = P.pos[2 * p + 1] - cy;
      P.pos[2 * p] = cx + c * dx - s * dy;
      P.pos[2 * p + 1] = cy + s * dx + c * dy;
      P.rot[p] = rot + spin;
    }
    Box box(pk.box);
    box.x_min -= 1.0, box.y_min -= 1.0, box.x_max += 1.0, box.y_max += 1.0;  // room for the turned corners
    box.contact_walls = false;
    DynamicOptions o;
    o.model = ContactModel::PlasticIndentation;
    o.plastic.sigma_y = 1.0;
    o.plastic.mu = 0.0;
    return DynamicSolverT<2>(std::move(P), o.plastic, box, o);
  };
  const Voigt<2> E{-x, -x, 0.0};
  CompactionMeterT<2> meter(false, 1.0);
  const auto first = meter.measure(solver_at(0.0, 0.0), E);  // every contact first seen: nothing accumulated
  ASSERT_EQ(first.contacts, 2 * m * (m - 1));
  EXPECT_EQ(first.dev_ut_centres, 0.0);
  EXPECT_EQ(first.dev_ut_rotations, 0.0);
  // (E_form = 0 for every contact: the strain before the first sample)
  const double L = 2.0 - u0, una = x * 2.0;
  const auto turned = meter.measure(solver_at(alpha, 0.0), E);
  ASSERT_EQ(turned.contacts, first.contacts);
  EXPECT_NEAR(turned.dev_ut_centres, L * alpha / una, 1e-12);
  EXPECT_NEAR(turned.dev_ut_rotations, 0.0, 1e-12);
  const auto rolled = meter.measure(solver_at(alpha, beta), E);
  EXPECT_NEAR(rolled.dev_ut_centres, L * alpha / una, 1e-12);  // the centres did not move
  EXPECT_NEAR(rolled.dev_ut_rotations, L * std::fabs(beta) / una, 1e-12);
  // the Eq 16 normal measure is the same in every state (the overlaps are)
  EXPECT_NEAR(rolled.dev_ratio_of_means, first.dev_ratio_of_means, 1e-12);
}

TEST(DemCompaction, OptionsNameTheirField) {
  const auto path = sys::StrainPathT<2>::parse("hydrostatic");
  auto field_of = [&](const CompactionOptions& o, double D0) {
    try {
      o.validate(path, D0);
    } catch (const netdem::FieldError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  CompactionOptions o;
  EXPECT_EQ(field_of(o, 0.8), "accepted");
  EXPECT_EQ(field_of(o, 0.9), "to_density");  // impossible: the target is below the start
  CompactionOptions bad = o;
  bad.inertial_number = std::nan("");
  EXPECT_EQ(field_of(bad, 0.8), "inertial_number");
  bad = o;
  bad.increments = 0;
  EXPECT_EQ(field_of(bad, 0.8), "increments");
  bad = o;
  bad.walls = true;
  EXPECT_EQ(field_of(bad, 0.8), "accepted");
  try {
    bad.validate(sys::StrainPathT<2>::parse("-1,-1,0.5"), 0.8);  // walls stay axis-aligned
    ADD_FAILURE();
  } catch (const netdem::FieldError& e) {
    EXPECT_EQ(e.field(), "path");
    EXPECT_NE(std::string(e.what()).find("E12 = 0"), std::string::npos);
  }
  try {
    o.validate(sys::StrainPathT<2>::parse("1,0,0"), 0.8);  // dilates: never reaches the target
    ADD_FAILURE();
  } catch (const netdem::FieldError& e) {
    EXPECT_EQ(e.field(), "path");
  }
  // a strain target: any direction (pure shear keeps the volume), in [1e-9, 1], ending below D = 1
  const auto shear = sys::StrainPathT<2>::parse("1,-1,0");
  auto field_along = [&](const CompactionOptions& q, const sys::StrainPathT<2>& p, double D0) {
    try {
      q.validate(p, D0);
    } catch (const netdem::FieldError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  CompactionOptions st = o;
  st.target_strain = 0.02;
  EXPECT_EQ(field_along(st, shear, 0.8), "accepted");
  EXPECT_EQ(field_along(st, path, 0.98), "to_strain");  // hydrostatic |E| = 0.02 from 0.98 passes D = 1
  st.target_strain = 2.0;
  EXPECT_EQ(field_along(st, shear, 0.8), "to_strain");
  // the precompaction: above the start, below 1; the path's target from the precompaction density
  CompactionOptions pre = o;
  pre.precompact_density = 0.83;
  EXPECT_EQ(field_along(pre, path, 0.8), "accepted");                  // to 0.85 after 0.83
  EXPECT_EQ(field_along(pre, path, 0.83), "precompact_density");       // not above the start
  pre.precompact_density = 0.86;
  EXPECT_EQ(field_along(pre, path, 0.8), "to_density");                // 0.85 is below 0.86
  pre.precompact_density = 1.0;
  EXPECT_EQ(field_along(pre, path, 0.8), "precompact_density");
  pre.precompact_density = 0.83;
  pre.precompact_increments = 0;
  EXPECT_EQ(field_along(pre, path, 0.8), "precompact_increments");
  pre.precompact_increments = 20;
  pre.target_strain = 0.02;
  EXPECT_EQ(field_along(pre, shear, 0.8), "accepted");
  const auto legs = compaction_legs(shear, pre, 0.8);
  ASSERT_EQ(legs.size(), 2u);
  EXPECT_EQ(legs[0].target_density, 0.83);
  EXPECT_EQ(legs[0].increments, 20);
  EXPECT_EQ(legs[1].target_strain, 0.02);
  EXPECT_NEAR(legs[1].rate.t_end * legs[1].rate.gamma_dot, 0.02, 1e-15) << "|E'| = gamma' along pure shear too";
  EXPECT_NEAR(legs[1].rate.rate[0], legs[1].rate.gamma_dot / std::sqrt(2.0), 1e-15);
  EXPECT_TRUE(legs[0].exact_end && legs[1].exact_end);
  const auto one = compaction_legs(path, o, 0.8);  // the default: one leg to the density, as before
  ASSERT_EQ(one.size(), 1u);
  EXPECT_FALSE(one[0].exact_end);
  EXPECT_EQ(one[0].rate.t_end, compaction_rate(path, o.inertial_number, 0.8, o.target_density).t_end);
}

// A change of the strain rate between steps: shift_affine_velocities keeps the motion relative to
// the affine field (walled box: the velocities are absolute), and step_to ends a step at a given
// time without changing the rule's time step.
TEST(DemCompaction, RateChangeKeepsTheFluctuationsAndStepToEndsOnTime) {
  const auto pk = lattice<2>(3, 1e-3);
  Box box(pk.box);
  box.contact_walls = false;
  box.right.mode = box.top.mode = WallMode::Affine;
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.damping_n = o.plastic.damping_t = 0.5;
  DynamicSolver s(particles_from(pk, 1.0), o.plastic, box, o);
  s.set_strain_rate(-0.01, -0.01, 0.0);
  s.set_affine_velocities();
  s.run(3);
  std::vector<double> wx, wy;  // the velocities relative to the affine field
  for (std::size_t i = 0; i < s.particles().size(); ++i) {
    wx.push_back(s.particles().vel[2 * i] + 0.01 * (s.particles().pos[2 * i] - s.box().x_min));
    wy.push_back(s.particles().vel[2 * i + 1] + 0.01 * (s.particles().pos[2 * i + 1] - s.box().y_min));
  }
  s.set_strain_rate(0.02, -0.03, 0.005);
  Eigen::Matrix2d dL;
  dL << 0.03, 0.005, 0.005, -0.02;
  s.shift_affine_velocities(dL);
  for (std::size_t i = 0; i < s.particles().size(); ++i) {
    const double dx = s.particles().pos[2 * i] - s.box().x_min, dy = s.particles().pos[2 * i + 1] - s.box().y_min;
    EXPECT_NEAR(s.particles().vel[2 * i] - 0.02 * dx - 0.005 * dy, wx[i], 1e-15);
    EXPECT_NEAR(s.particles().vel[2 * i + 1] + 0.03 * dy - 0.005 * dx, wy[i], 1e-15);
  }
  const double dt = s.dt(), t = s.time() + 0.4 * dt;
  s.step_to(t);
  EXPECT_NEAR(s.time(), t, 1e-15);
  EXPECT_EQ(s.dt(), dt) << "the rule's time step stays";
  s.step_to(t + 3 * dt);  // a full step when the time is further than one
  EXPECT_NEAR(s.time(), t + dt, 1e-15);
  EXPECT_THROW(s.step_to(s.time()), std::invalid_argument);
}

}  // namespace
