// 3D state files, restarts and contact output of the explicit DEM (DynamicSolver3, issue 16).
#include <gtest/gtest.h>

#include "test_scale.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"

using namespace netdem::dem;
using netdem::contact::LudingParams;

namespace {

using netdem::test::small_scale;

// side^3 spheres on a jittered lattice of pitch 2.05 a0, radii a0 (1 +- 0.3), random velocities
// and spins; density rho_p (Table 1) per volume.
Particles3 dense3(const LudingParams& p, int side, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles3 P;
  const double pitch = 2.05 * p.a0;
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        const double r = p.a0 * (1.0 + 0.3 * u(rng));
        const double g = 0.1 * (pitch - 2 * r);
        const double x = (i + 0.5) * pitch + g * u(rng), y = (j + 0.5) * pitch + g * u(rng),
                     z = (k + 0.5) * pitch + g * u(rng);
        const double vx = 0.02 * u(rng), vy = 0.02 * u(rng), vz = 0.02 * u(rng);
        P.add_sphere(x, y, z, r, p.rho_p, {vx, vy, vz});
      }
  return P;
}

Box stress_box3(int side, const LudingParams& p, double pressure) {
  Box b;
  b.x_min = b.y_min = b.z_min = 0.0;
  b.x_max = b.y_max = b.z_max = side * 2.05 * p.a0;
  for (MovingWall* w : {&b.right, &b.back, &b.top}) {
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->damping = 20.0;
  }
  return b;
}

double schedule(double t, double ramp) { return t < ramp ? 80.0 + 60.0 * t / ramp : 140.0; }

void advance(DynamicSolver3& s, std::size_t steps, double ramp) {
  for (std::size_t k = 0; k < steps; ++k) {
    s.advance_temperature(schedule(s.time() + s.dt(), ramp), s.dt(), 1e-3);
    s.step();
  }
}

}  // namespace

// The full law (friction, cohesion, hysteresis, T(t)) with three stress-controlled walls and
// gravity: a run restarted from the 3D state file ends bit for bit where the uninterrupted run
// ends, and state -> file -> state is the identity.
TEST(DynamicState3D, RestartThroughStateFileIsBitwiseExact) {
  LudingParams p;  // Table 1
  const int side = small_scale() ? 4 : 5;
  DynamicOptions o;
  o.model = ContactModel::Full;
  o.gravity_z = -9.81;
  // 3D pressure [N/m^2]: 100 N/m over 2 a0, the overlap ratio of the 2D runs
  DynamicSolver3 a(dense3(p, side, 3), p, stress_box3(side, p, 100.0 / (2.0 * p.a0)), o);
  const std::size_t n1 = small_scale() ? 600 : 2000, n2 = small_scale() ? 600 : 2000;
  const double ramp = 0.8 * static_cast<double>(n1 + n2) * a.dt();
  advance(a, n1, ramp);
  const std::string text = format_state(a.state());
  ASSERT_NE(text.find("\"dim\":3"), std::string::npos);
  std::istringstream in(text);
  const SolverState parsed = parse_state(in, "mem");
  EXPECT_EQ(parsed.dim(), 3);
  DynamicSolver3 b(parsed, o);
  EXPECT_EQ(format_state(b.state()), text) << "state -> file -> state is not the identity";
  advance(a, n2, ramp);
  advance(b, n2, ramp);
  const Particles3 &A = a.particles(), &B = b.particles();
  std::size_t sliding = 0, cohesive = 0, slipped = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  a.touching_pairs(pairs);
  for (auto [i, j] : pairs) {
    const auto* h = a.history(i, j);
    ASSERT_NE(h, nullptr);
    sliding += h->sliding;
    cohesive += h->delta0 > 0.0;
    slipped += h->xi.norm() > 0.0;
  }
  std::printf("  %zu spheres, %zu + %zu steps, T %.1f C, %zu contacts (%zu sliding, %zu with delta0 > 0, %zu with "
              "a tangential spring), walls at %.6g %.6g %.6g m\n",
              A.size(), n1, n2, a.thermal().T, pairs.size(), sliding, cohesive, slipped, a.box().x_max,
              a.box().y_max, a.box().z_max);
  EXPECT_GT(slipped, 0u) << "the test must exercise the 3D tangential history";
  EXPECT_GT(sliding + cohesive, 0u) << "the test must exercise the history";
  EXPECT_NE(a.box().z_max, stress_box3(side, p, 0.0).z_max) << "the stress walls must have moved";
  for (std::size_t i = 0; i < A.size(); ++i) {
    ASSERT_EQ(A.pos[3 * i], B.pos[3 * i]) << i;
    ASSERT_EQ(A.pos[3 * i + 1], B.pos[3 * i + 1]) << i;
    ASSERT_EQ(A.pos[3 * i + 2], B.pos[3 * i + 2]) << i;
    ASSERT_EQ(A.vel[3 * i + 2], B.vel[3 * i + 2]) << i;
    ASSERT_EQ(A.spin[3 * i], B.spin[3 * i]) << i;
    ASSERT_EQ(A.spin[3 * i + 1], B.spin[3 * i + 1]) << i;
    ASSERT_EQ(A.spin[3 * i + 2], B.spin[3 * i + 2]) << i;
    ASSERT_EQ(A.r[i], B.r[i]) << i;
  }
  EXPECT_EQ(a.box().y_max, b.box().y_max);
  EXPECT_EQ(a.box().z_max, b.box().z_max);
  EXPECT_EQ(a.wall_velocity(1), b.wall_velocity(1));
  EXPECT_EQ(a.wall_velocity(2), b.wall_velocity(2));
  EXPECT_EQ(format_state(a.state()), format_state(b.state()));
  // the in-memory snapshot of the instability checks exists in 3D and restarts
  ASSERT_NE(a.last_good(), nullptr);
  DynamicSolver3 c(*a.last_good(), o);
  EXPECT_LE(c.time(), a.time());
}

// contacts() in 3D against closed forms: a sphere resting on the floor and on a second sphere
// along a skew direction, at rest, the linear law (f_n = k2 delta), and a loaded tangential
// spring after a tangential shift (|f_t| = k_t |xi| along -xi's direction on j).
TEST(DynamicState3D, ContactsGiveTheForcesOfTheLawInThreeDimensions) {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.gamma_n = p.gamma_t = 0.0;
  p.mu = 0.5;
  const double a = p.a0, d1 = 1e-4 * a, d2 = 2e-4 * a;  // small: the contact forces barely move the spheres in a step
  const double ux = 2.0 / 3.0, uy = 1.0 / 3.0, uz = 2.0 / 3.0;  // a unit vector
  Particles3 P;
  P.add_sphere(5 * a, 5 * a, a - d1, a, p.rho_p);  // on the floor, overlap d1
  const double L = 2 * a - d2;
  P.add_sphere(5 * a + L * ux, 5 * a + L * uy, a - d1 + L * uz, a, p.rho_p);
  Box box;
  box.x_min = box.y_min = box.z_min = 0.0;
  box.x_max = box.y_max = box.z_max = 20 * a;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  o.steps_per_contact = 200.0;
  DynamicSolver3 s(std::move(P), p, box, o);
  std::vector<ContactInfo> cs;
  s.contacts(cs);
  ASSERT_EQ(cs.size(), 2u);
  const ContactInfo& pair = cs[0];
  const ContactInfo& floor = cs[1];
  EXPECT_EQ(pair.wall, -1);
  EXPECT_NEAR(pair.overlap, d2, 1e-12 * a);
  EXPECT_NEAR(pair.nx, ux, 1e-12);
  EXPECT_NEAR(pair.ny, uy, 1e-12);
  EXPECT_NEAR(pair.nz, uz, 1e-12);
  EXPECT_NEAR(pair.f_n, p.k2 * d2, 1e-9 * p.k2 * d2);
  EXPECT_NEAR(pair.d_i + pair.d_j, L, 1e-12 * a);
  EXPECT_EQ(floor.wall, 4);  // z_min
  EXPECT_EQ(floor.nz, 1.0);
  EXPECT_NEAR(floor.f_n, p.k2 * d1, 1e-9 * p.k2 * d1);
  EXPECT_NEAR(floor.d_i, a - d1, 1e-12 * a);
  EXPECT_EQ(pair.f_t, 0.0);
  // shear: move the upper sphere along a tangent of the pair for some steps, gravity off
  const double tx = -uy / std::hypot(ux, uy), ty = ux / std::hypot(ux, uy);  // in the plane, _|_ u
  double shift = 0.0;
  const double v = 0.02;  // [m/s]
  for (int k = 0; k < 10; ++k) {
    // a prescribed slow tangential motion: set the velocity before each step
    auto& Q = const_cast<Particles3&>(s.particles());
    std::fill(Q.vel.begin(), Q.vel.end(), 0.0);  // (two spheres)
    std::fill(Q.spin.begin(), Q.spin.end(), 0.0);
    Q.vel[3] = v * tx;
    Q.vel[4] = v * ty;
    s.step();
    shift += v * s.dt();
  }
  s.contacts(cs);
  ASSERT_GE(cs.size(), 1u);
  const ContactInfo& c = cs[0];
  ASSERT_EQ(c.wall, -1);
  const double kt = p.alpha * p.k2;  // Eq 23 with k2(delta_max) = k2 (linear)
  ASSERT_LT(kt * shift, p.mu * c.f_n) << "the test must stay inside the Coulomb limit";
  // the spring is the slip, up to the motion the contact forces add within a step (~1e-3)
  EXPECT_NEAR(c.f_t, kt * shift, 5e-3 * kt * shift);
  // the force on j opposes its motion: along -t, in the tangent plane
  EXPECT_LT((c.ftx * tx + c.fty * ty) / c.f_t, -0.999);
  EXPECT_NEAR(c.ftx * c.nx + c.fty * c.ny + c.ftz * c.nz, 0.0, 1e-9 * c.f_t);
}

// Bad 3D state files: one line naming the problem; a 3D state refused by a 2D solver.
TEST(DynamicState3D, BadStateFilesGiveOneLineErrors) {
  LudingParams p;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  DynamicSolver3 a(dense3(p, 2, 1), p, stress_box3(2, p, 1000.0), o);
  for (int k = 0; k < 50; ++k) a.step();
  const std::string good = format_state(a.state());
  auto refuse = [&](const std::string& text, const std::string& what) {
    std::istringstream in(text);
    try {
      (void)parse_state(in, "s3");
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_NE(m.find(what), std::string::npos) << m;
    }
  };
  auto replace = [&](std::string s, const std::string& from, const std::string& to) {
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  refuse(replace(good, "\"dim\":3", "\"dim\":4"), "/dim: 4 is outside [2, 3]");
  refuse(replace(good, "\"moving_walls\":[{", "\"moving_walls\":[{},{"), "/moving_walls: expected 3 elements, found 4");
  refuse(good.substr(0, good.size() - 4), "syntax error at byte");
  {  // a centre outside the box (z above z_max)
    std::istringstream in(good);
    SolverState st = parse_state(in, "s3");
    st.particles_of<3>().pos[2] = st.box.z_max + 0.5 * st.particles_of<3>().r[0];
    refuse(format_state(st), "outside the box");
  }
  {  // a torque of 1e300 about x (campaign of issue 27: accepted before, inf in the outputs)
    std::istringstream in(good);
    SolverState st = parse_state(in, "s3");
    st.particles_of<3>().torque[3] = 1e300;  // (tx of particle 1)
    refuse(format_state(st), "/particles/tx/1: particle 1: torque");
  }
  {  // a Luding history's delta0 against the contact's geometry (campaign of issue 27: delta0 = 1e300
     // was accepted and gave f_min = -inf in contacts_*.csv)
    std::istringstream in(good);
    const SolverState st0 = parse_state(in, "s3");
    using H3 = netdem::contact::LudingHistoryT<3>;
    ASSERT_FALSE(st0.histories_of<H3>().pair.empty());
    SolverState st = st0;
    st.histories_of<H3>().pair[0].delta0 = 1e300;
    refuse(format_state(st), "/pairs/history/0/delta0: the force-free overlap 1e+300 m is outside [0, ");
    st = st0;
    st.histories_of<H3>().pair.back().delta0 = -1e-9;
    refuse(format_state(st), "/delta0: the force-free overlap -1e-09 m is outside");
    st = st0;
    std::size_t w = 0;
    auto& wh = st.histories_of<H3>().wall;
    while (w < wh.size() && wh[w].fresh()) ++w;
    ASSERT_LT(w, wh.size());
    wh[w].delta0 = 1e300;
    refuse(format_state(st), "/wall_contacts/history/0/delta0: the force-free overlap 1e+300 m");
  }
  {  // a stress-controlled wall's pressure is held to --pressure's range (campaign of issue 27: 4.9e-324
     // was accepted and gave inf in timeseries.csv, the stresses over p)
    std::istringstream in(good);
    SolverState st = parse_state(in, "s3");
    ASSERT_EQ(st.box.top.mode, WallMode::Stress);
    st.box.top.pressure = 4.9e-324;
    refuse(format_state(st), "/moving_walls/2/pressure: pressure 4.94066e-324 gives the loading ratio 4 p a0/k2 = 0, below 1e-09");
    st.box.top.pressure = 0.0;
    refuse(format_state(st), "/pressure: pressure 0 gives the loading ratio");
  }
  {  // the 2D solver refuses a sphere state
    std::istringstream in(good);
    const SolverState st = parse_state(in, "s3");
    EXPECT_THROW(DynamicSolver b(st, o), std::invalid_argument);
  }
}
