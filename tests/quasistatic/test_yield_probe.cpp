// Tests of the yield-surface probing (src/quasistatic/yield_probe.cpp): the yield-point
// definitions on synthetic reloading curves whose answer is known, and a physical check on a
// small affine packing (the probe along the loading direction yields at the loading point).
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/yield_probe.hpp"

using namespace netdem;

namespace {

// Samples as the probe takes them: 20 equal fine steps h, then each step 1.2x larger (cap 50 h).
std::vector<double> probe_strains(double h, double x_max) {
  std::vector<double> x{0.0};
  double step = h;
  for (int k = 1; x.back() < x_max; ++k) {
    if (k > 20) step = std::min(50 * h, step * 1.2);
    x.push_back(x.back() + step);
  }
  return x;
}

// W = 20R packing (seed 3), affine frictionless hydrostatic compaction to D = 0.85 in 20 increments.
struct AffineCase {
  packing::Packing pk;
  qs::SolverOptions so;
  qs::CompactionOptions co;
};
AffineCase affine_case() {
  AffineCase c;
  packing::DepositionOptions d;
  d.width = 20;
  d.seed = 3;
  c.pk = packing::ballistic_deposition(d);
  c.so.mode = qs::BoundaryMode::Affine;
  c.so.law.mu = 0.0;
  c.co.target_density = 0.85;
  c.co.increments = 20;
  return c;
}

// The columns of a reloading curve: strain, stress, S11, S22.
struct Columns {
  std::vector<double> x, y, s11, s22;
};
Columns columns(const qs::ProbeCurve& c) {
  Columns r;
  for (const auto& p : c.samples) {
    r.x.push_back(p.strain);
    r.y.push_back(p.stress);
    r.s11.push_back(p.S11);
    r.s22.push_back(p.S22);
  }
  return r;
}

// Bilinear elastic-plastic curve: slope k up to the kink (xk, k xk), then slope hp.
double bilinear(double x, double k, double xk, double hp) { return x <= xk ? k * x : k * xk + hp * (x - xk); }

}  // namespace

TEST(YieldProbe, ElasticFitIsLeastSquares) {
  const std::vector<double> x{0, 1, 2, 3, 4, 5, 6}, y{0.5, 2.5, 4.5, 6.5, 8.5, 0, 0};
  const auto f = qs::elastic_fit(x, y, 4);
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(f.slope, 2.0, 1e-12);
  EXPECT_NEAR(f.y0, 0.5, 1e-12);
  EXPECT_NEAR(qs::interpolate_at(y, 1.25), 3.0, 1e-12);
}

// The kink of a bilinear curve is the curvature point (to a fraction of the sample spacing
// there); the offset point is the exact intersection of the plastic line with the offset line.
TEST(YieldProbe, BilinearKink) {
  const double k = 1e4, hp = 50.0, offset = 1e-3;
  for (double xk : {5e-5, 6.3e-5, 1.1e-4, 3e-4}) {
    const auto x = probe_strains(1e-5, 3e-3);
    std::vector<double> y;
    for (double v : x) y.push_back(bilinear(v, k, xk, hp));
    qs::YieldOptions o;
    o.offset = offset;
    const auto c = qs::yield_by_curvature(x, y, o);
    ASSERT_TRUE(c.found) << c.reason;
    // spacing of the samples around the kink
    std::size_t i = 0;
    while (x[i + 1] < xk) ++i;
    const double dx = x[i + 1] - x[i];
    EXPECT_NEAR(c.strain, xk, 0.5 * dx + 1e-12) << "xk = " << xk;
    // the samples cut the corner: the point lies on the chord between the two samples around the kink
    const double chord = y[i] + (y[i + 1] - y[i]) * (xk - x[i]) / dx;
    EXPECT_NEAR(c.stress, k * xk, (k * xk - chord) + 1e-3 * k * xk) << "xk = " << xk;
    const auto f = qs::yield_by_offset(x, y, o);
    ASSERT_TRUE(f.found) << f.reason;
    const double x_off = (k * xk - hp * xk + k * offset) / (k - hp);
    EXPECT_NEAR(f.strain, x_off, 1e-9);
    EXPECT_NEAR(f.stress, k * (x_off - offset), 1e-9 * k * xk);
  }
}

// A kink that falls on a sample is found exactly; with a softening branch after it too.
TEST(YieldProbe, KinkOnSampleAndSoftening) {
  std::vector<double> x, y;
  for (int i = 0; i <= 100; ++i) {
    x.push_back(1e-5 * i);
    y.push_back(i <= 30 ? 0.01 * i : 0.3 - 0.002 * (i - 30));
  }
  const auto c = qs::yield_by_curvature(x, y, {});
  ASSERT_TRUE(c.found) << c.reason;
  EXPECT_NEAR(c.position, 30.0, 1e-6);
  EXPECT_NEAR(c.stress, 0.3, 1e-9);
}

// Smooth knee: the hyperbola (Y - y)(k x - y) = eps Y^2 with asymptotes y = k x and y = Y. In the
// normalised coordinates (X = k x / Y, y / Y) it is symmetric about its axis, so the maximum
// curvature is at its vertex, the point closest to the asymptotes' intersection (1, 1).
TEST(YieldProbe, SmoothHyperbolicKnee) {
  const double k = 2e4, Y = 0.6, eps = 0.003;
  auto curve = [&](double xx) {  // smaller root of (Y - y)(k x - y) = eps Y^2
    const double b = Y + k * xx, c = Y * k * xx - eps * Y * Y;
    return 0.5 * (b - std::sqrt(b * b - 4 * c));
  };
  // vertex: minimise (v - u)^2 + u^2 over u > 0 with v = eps / u (u = 1 - y/Y, v = X - y/Y)
  double lo = 1e-4, hi = 1.0;
  auto f = [&](double u) { return std::pow(eps / u - u, 2) + u * u; };
  for (int it = 0; it < 200; ++it) {
    const double a = lo + (hi - lo) * 0.382, b = lo + (hi - lo) * 0.618;
    (f(a) < f(b) ? hi : lo) = (f(a) < f(b) ? b : a);
  }
  const double u = 0.5 * (lo + hi), v = eps / u;
  const double x_vertex = (1.0 + v - u) * Y / k;
  const auto x = probe_strains(3e-6, 2e-3);
  std::vector<double> y;
  for (double v2 : x) y.push_back(curve(v2));
  const auto c = qs::yield_by_curvature(x, y, {});
  ASSERT_TRUE(c.found) << c.reason;
  EXPECT_NEAR(c.strain, x_vertex, 0.03 * x_vertex);
  EXPECT_NEAR(c.stress, curve(x_vertex), 0.01 * Y);
}

// A toe (gaps closing first: the slope grows from 0 to k) is skipped by the elastic line, so the
// offset point is where it is on the toe-compensated curve (xk + offset for a flat plateau).
TEST(YieldProbe, ToeIsCompensated) {
  const double k = 1e4, xt = 3e-5, xk = 1e-4, offset = 1e-3;  // the kink on sample 20
  const auto x = probe_strains(5e-6, 3e-3);
  std::vector<double> y;
  for (double v : x) y.push_back(v < xt ? 0.5 * k * v * v / xt : 0.5 * k * xt + k * (std::min(v, xk) - xt));
  const auto fit = qs::elastic_fit(x, y, 4);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.slope, k, 1e-9 * k);
  EXPECT_NEAR(fit.y0, -0.5 * k * xt, 1e-9);
  const auto f = qs::yield_by_offset(x, y, {});
  ASSERT_TRUE(f.found) << f.reason;
  EXPECT_NEAR(f.strain, xk + offset, 1e-9);
  const auto c = qs::yield_by_curvature(x, y, {});
  ASSERT_TRUE(c.found) << c.reason;
  EXPECT_NEAR(c.stress, k * (xk - 0.5 * xt), 0.01 * k * xk);
}

// Noise of 0.3% of the yield stress: the smoothing window keeps the knee.
TEST(YieldProbe, NoisyBilinear) {
  const double k = 1e4, hp = 30.0, xk = 8e-5;
  const auto x = probe_strains(8e-6, 3e-3);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.003 * k * xk);
  int worst_fails = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> y;
    for (double v : x) y.push_back(bilinear(v, k, xk, hp) + noise(rng));
    const auto c = qs::yield_by_curvature(x, y, {});
    const auto f = qs::yield_by_offset(x, y, {});
    ASSERT_TRUE(c.found && f.found);
    worst_fails += std::fabs(c.strain - xk) > 0.1 * xk;
    EXPECT_NEAR(c.stress, k * xk, 0.03 * k * xk);
    const double x_off = (k * xk - hp * xk + k * 1e-3) / (k - hp);
    EXPECT_NEAR(f.strain, x_off, 0.05 * x_off);
  }
  EXPECT_EQ(worst_fails, 0);
}

// No yield point is made up: a curve that never rises, a falling one and a straight line.
TEST(YieldProbe, NoYieldPointWithoutKnee) {
  std::vector<double> x, flat, falling, line;
  for (int i = 0; i <= 60; ++i) {
    x.push_back(1e-5 * i);
    flat.push_back(-1e-3 * std::exp(-i / 3.0));  // residual compression vanishing on a tensile probe
    falling.push_back(-0.01 * i);
    line.push_back(100.0 * x.back());
  }
  qs::YieldOptions o;
  o.min_rise = 0.01;
  for (const auto* y : {&flat, &falling}) {
    EXPECT_FALSE(qs::yield_by_curvature(x, *y, o).found);
    EXPECT_FALSE(qs::yield_by_offset(x, *y, o).found);
    EXPECT_FALSE(qs::yield_by_offset(x, *y, o).reason.empty());
  }
  EXPECT_FALSE(qs::yield_by_offset(x, line, o).found);
  EXPECT_FALSE(qs::yield_by_curvature(x, line, o).found);
  EXPECT_FALSE(qs::yield_by_curvature({0.0, 1.0}, {0.0, 1.0}, o).found);
}

// Physical check: a small random packing compacted hydrostatically with affine motion
// (frictionless), unloaded to |Sigma| < 1e-3 sigma_y, then reloaded along the loading direction
// (theta = 225 deg) and along a tensile direction (45 deg).
TEST(YieldProbe, AffineProbeAlongLoadingDirectionYieldsAtLoadingPoint) {
  const auto [pk, so, co] = affine_case();
  qs::StateMeasures loaded;
  // compact, remember the loaded state, unload (each probe needs its own copy: netsolve forks)
  // (init-captures: clang 14, the sanitizer build's compiler, cannot capture structured bindings)
  auto prepare = [&co = co, &so = so, &loaded](qs::NetworkSolver& s) {
    qs::run_compaction(s, co, [](const qs::CompactionRow&) {});
    loaded = s.measures();
    return qs::unload(s, co.path.rate(), 1.0, so.law.unload_ratio);
  };
  qs::NetworkSolver s(pk, so);
  const auto un = prepare(s);
  ASSERT_TRUE(un.converged) << un.message;
  EXPECT_LT(un.stress_norm, 1e-3);
  EXPECT_LT(un.path.size(), 8u);
  // affine unloading is linear: every contact gives back 2 u_max / unload_ratio of overlap
  const double e = std::hypot(loaded.E11, loaded.E22);
  EXPECT_NEAR(un.strain, 2 * e / so.law.unload_ratio, 0.2 * 2 * e / so.law.unload_ratio);

  qs::ProbeOptions po;
  po.first_step = un.strain / 10;
  const auto c = qs::probe(s, 1.25 * std::numbers::pi, 1.0, po);
  ASSERT_GT(c.samples.size(), 25u) << c.end;
  EXPECT_EQ(c.end, "past offset");
  const auto [x, y, s11, s22] = columns(c);
  qs::YieldOptions yo;
  yo.min_rise = 0.02 * un.loading_norm;
  const auto yc = qs::yield_by_curvature(x, y, yo);
  ASSERT_TRUE(yc.found) << yc.reason;
  const double r_load = std::hypot(loaded.S11, loaded.S22);
  const double S11 = qs::interpolate_at(s11, yc.position), S22 = qs::interpolate_at(s22, yc.position);
  EXPECT_NEAR(std::hypot(S11 - loaded.S11, S22 - loaded.S22) / r_load, 0.0, 0.02);
  const auto yf = qs::yield_by_offset(x, y, yo);
  ASSERT_TRUE(yf.found) << yf.reason;
  EXPECT_NEAR(qs::interpolate_at(s22, yf.position) / loaded.S22, 1.0, 0.05);  // hardening past the knee

  qs::NetworkSolver s2(pk, so);
  ASSERT_TRUE(prepare(s2).converged);
  const auto t = qs::probe(s2, 0.25 * std::numbers::pi, 1.0, po);
  std::vector<double> xt, yt;
  for (const auto& p : t.samples) {
    xt.push_back(p.strain);
    yt.push_back(p.stress);
  }
  EXPECT_FALSE(qs::yield_by_curvature(xt, yt, yo).found);
  EXPECT_FALSE(qs::yield_by_offset(xt, yt, yo).found);
}

// Die (local relaxation) boundary conditions, frictionless: unloading converges, a tensile probe
// ends with a recorded reason and no yield point, never with an exception; the probe along the
// loading direction finds a knee below the loading stress (no vertex: the paper's rounding).
TEST(YieldProbe, DieProbesEndWithReasonNotException) {
  packing::DepositionOptions d;
  d.width = 20;
  d.seed = 3;
  const auto pk = packing::ballistic_deposition(d);
  qs::SolverOptions so;
  so.law.mu = 0.0;
  qs::CompactionOptions co;
  co.target_density = 0.85;
  co.increments = 20;
  for (double theta : {0.25 * std::numbers::pi, 1.25 * std::numbers::pi}) {
    qs::NetworkSolver s(pk, so);
    qs::run_compaction(s, co, [](const qs::CompactionRow&) {});
    const auto loaded = s.measures();
    const auto un = qs::unload(s, co.path.rate(), 1.0, so.law.unload_ratio);
    ASSERT_TRUE(un.converged) << un.message;
    qs::ProbeOptions po;
    po.first_step = un.strain / 10;
    qs::ProbeCurve c;
    ASSERT_NO_THROW(c = qs::probe(s, theta, 1.0, po));
    EXPECT_FALSE(c.end.empty());
    std::vector<double> x, y;
    for (const auto& p : c.samples) {
      x.push_back(p.strain);
      y.push_back(p.stress);
    }
    qs::YieldOptions yo;
    yo.min_rise = 0.02 * un.loading_norm;
    const auto yc = qs::yield_by_curvature(x, y, yo);
    if (theta < 1.0) {
      EXPECT_FALSE(yc.found);
      EXPECT_FALSE(yc.reason.empty());
    } else {
      ASSERT_TRUE(yc.found) << yc.reason;
      const double load = -(loaded.S11 + loaded.S22) / std::sqrt(2.0);  // Sigma : E_hat at the loading point
      EXPECT_GT(yc.stress, 0.2 * load);
      EXPECT_LT(yc.stress, 1.05 * load);
    }
  }
}

// Fabric-resolved affine bound: along a fully compressive direction every contact counts, so it is
// the Love-Weber stress of the loaded state; along a dilatant one nothing; for every direction it
// maximises the dissipation Sigma : Edot over the points of all other directions (normality); and
// an affine-affine frictionless probe reaches it at the offset point.
TEST(YieldProbe, FabricAffineBound) {
  const auto [pk, so, co] = affine_case();
  qs::NetworkSolver s(pk, so);
  qs::run_compaction(s, co, [](const qs::CompactionRow&) {});
  const auto loaded = s.measures();
  const double pi = std::numbers::pi;
  const auto h = qs::fabric_affine_point(s, 1.25 * pi, 1.0);
  EXPECT_NEAR(h.S11, loaded.S11_contacts, 1e-9 * std::fabs(loaded.S11_contacts));
  EXPECT_NEAR(h.S22, loaded.S22_contacts, 1e-9 * std::fabs(loaded.S22_contacts));
  const auto t = qs::fabric_affine_point(s, 0.25 * pi, 1.0);
  EXPECT_EQ(t.S11, 0.0);
  EXPECT_EQ(t.S22, 0.0);
  std::vector<qs::YieldPoint> pts;
  const int n = 72;
  for (int k = 0; k < n; ++k) pts.push_back(qs::fabric_affine_point(s, 2 * pi * k / n, 1.0));
  const double scale = std::hypot(h.S11, h.S22);
  for (int k = 0; k < n; ++k) {
    const double c = std::cos(2 * pi * k / n), sn = std::sin(2 * pi * k / n);
    const double own = pts[k].S11 * c + pts[k].S22 * sn;
    EXPECT_GE(own, -1e-14 * scale);
    for (int m = 0; m < n; ++m) EXPECT_GE(own, pts[m].S11 * c + pts[m].S22 * sn - 1e-12 * scale) << k << " " << m;
  }
  EXPECT_THROW(qs::fabric_affine_point(s, std::nan(""), 1.0), std::invalid_argument);

  // an affine probe at 150 degrees (E11dot = -0.87, E22dot = 0.5: part of the contacts open)
  const auto un = qs::unload(s, co.path.rate(), 1.0, so.law.unload_ratio);
  ASSERT_TRUE(un.converged) << un.message;
  qs::ProbeOptions po;
  po.first_step = un.strain / 10;
  const double theta = 150.0 / 180.0 * pi;
  const auto bound = qs::fabric_affine_point(s, theta, 1.0);  // the unloaded state has other forces
  const auto at_load = pts[30];                                // 150 degrees at the loading point
  EXPECT_NE(bound.S11, at_load.S11);
  const auto c = qs::probe(s, theta, 1.0, po);
  const auto [x, y, s11, s22] = columns(c);
  qs::YieldOptions yo;
  yo.min_rise = 0.02 * un.loading_norm;
  const auto yf = qs::yield_by_offset(x, y, yo);
  ASSERT_TRUE(yf.found) << yf.reason;
  const double S11 = qs::interpolate_at(s11, yf.position), S22 = qs::interpolate_at(s22, yf.position);
  std::printf("150 deg: offset point (%.4f, %.4f), fabric bound at the loading point (%.4f, %.4f)\n", S11, S22,
              at_load.S11, at_load.S22);
  // within the validation's 10 % bar, and from below: contacts that the probe compresses only
  // slowly have not re-yielded at the offset strain (the hardening of Eq 2 over that strain is ~2 %)
  const double r_bound = std::hypot(at_load.S11, at_load.S22);
  EXPECT_LT(std::hypot(S11 - at_load.S11, S22 - at_load.S22) / r_bound, 0.10);
  EXPECT_LT(std::hypot(S11, S22), 1.02 * r_bound);
}
