// The green-body packing route of Ivannikov et al. (netdem/dynamic/green_body.hpp).
#include "netdem/dynamic/green_body.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/random_fill.hpp"

namespace netdem::dem {

namespace {

constexpr double kPi = std::numbers::pi;

void need(bool ok, const char* name, const char* rule, double v) {
  if (!ok) throw std::invalid_argument(fmt::format("green body: {} must be {}, got {}", name, rule, v));
}

packing::Packing packing_of(const DynamicSolver3& s, std::uint64_t seed) {
  const Particles& P = s.particles();
  packing::Packing p;
  p.dim = 3;
  p.x = P.x;
  p.y = P.y;
  p.z = P.z;
  p.r = P.radius;
  p.box = static_cast<const packing::Box&>(s.box());
  p.seed = seed;
  return p;
}

}  // namespace

void GreenBodyOptions::validate() const {
  const auto fin = [](double v) { return std::isfinite(v); };
  need(n >= 1 && n <= 10000000, "the number of spheres", "in [1, 1e7]", static_cast<double>(n));
  need(fin(mean_radius) && mean_radius > 0.0, "the mean radius", "positive and finite", mean_radius);
  need(fin(dispersion) && dispersion >= 0.0 && dispersion < 1.0, "the dispersion", "in [0, 1)", dispersion);
  need(fin(solid_density) && solid_density > 0.0, "the solid density", "positive and finite", solid_density);
  need(fin(target_density) && target_density > 0.0 && target_density <= 0.74, "the target density", "in (0, 0.74]",
       target_density);
  need(fin(aspect) && aspect >= 0.1 && aspect <= 10.0, "the aspect (height / width)", "in [0.1, 10]", aspect);
  need(fin(cloud_fraction) && cloud_fraction > 0.0 && cloud_fraction <= packing::kMaxCloudFraction,
       "the cloud fraction", "in (0, 0.30]", cloud_fraction);
  need(fin(settled_guess) && settled_guess > cloud_fraction && settled_guess < 0.74, "the settled-density guess",
       "in (cloud fraction, 0.74)", settled_guess);
  need(fin(gravity) && gravity >= 1e-6 && gravity <= 1e4, "the gravity", "in [1e-6, 1e4] m/s^2", gravity);
  need(fin(stiffness_number) && stiffness_number >= 10.0 && stiffness_number <= 1e9, "the stiffness number kappa",
       "in [10, 1e9]", stiffness_number);
  need(fin(restitution) && restitution > 0.0 && restitution <= 1.0, "the restitution", "in (0, 1]", restitution);
  need(fin(mu_settle) && mu_settle >= 0.0, "the settling friction", ">= 0 and finite", mu_settle);
  need(fin(mu_compress) && mu_compress >= 0.0, "the compression friction", ">= 0 and finite", mu_compress);
  need(fin(mu_final) && mu_final >= 0.0, "the final friction", ">= 0 and finite", mu_final);
  need(fin(mu_wall) && mu_wall >= 0.0, "the wall friction", ">= 0 and finite", mu_wall);
  need(fin(steps_per_contact) && steps_per_contact >= 15.0, "the steps per contact", ">= 15", steps_per_contact);
  need(fin(wall_speed) && wall_speed > 0.0 && wall_speed <= 1.0, "the wall speed / sqrt(g r)", "in (0, 1]", wall_speed);
  need(fin(rest_energy) && rest_energy > 0.0, "the rest energy", "positive and finite", rest_energy);
  need(fin(max_mean_overlap) && max_mean_overlap > 0.0 && max_mean_overlap < 0.5, "the largest mean overlap / r",
       "in (0, 0.5)", max_mean_overlap);
  need(fin(max_phase_time) && max_phase_time > 0.0, "the phase-time cap", "positive and finite", max_phase_time);
  need(check_every >= 1, "check_every", ">= 1", static_cast<double>(check_every));
}

packing::RandomFill3dOptions green_body_cloud_options(const GreenBodyOptions& o) {
  o.validate();
  const double r = o.mean_radius;
  const double vs_expected =
      static_cast<double>(o.n) * 4.0 / 3.0 * kPi * r * r * r * (1.0 + o.dispersion * o.dispersion);
  // width L0: the settled box (density settled_guess) has the intended aspect; the cloud does not
  // depend on the target, so one seed settles the same way for every target
  const double L0 = std::cbrt(vs_expected / (o.settled_guess * o.aspect));
  const double H_cloud = vs_expected / (o.cloud_fraction * L0 * L0);
  packing::RandomFill3dOptions fo;
  fo.n = o.n;
  fo.mean_radius = r;
  fo.dispersion = o.dispersion;
  fo.seed = o.seed;
  fo.box = packing::Box{0.0, 0.0, L0, L0, 0.0, H_cloud};
  return fo;
}

GreenBodyResult make_green_body(const GreenBodyOptions& o, const GreenBodyObserver& observer) {
  o.validate();
  using clock = std::chrono::steady_clock;
  GreenBodyResult res;
  const double r = o.mean_radius, g = o.gravity;
  const double m = o.solid_density * 4.0 / 3.0 * kPi * r * r * r;  // the mean sphere
  const double mgr = m * g * r;
  res.mean_mass = m;
  res.time_unit = std::sqrt(r / g);
  res.stiffness = o.stiffness_number * m * g / r;
  // the restitution e of a mean pair (m12 = m / 2): e = exp(-eta t_c), t_c = pi / sqrt(k / m12 - eta^2)
  const double m12 = 0.5 * m, le = std::log(o.restitution);
  const double eta = -le * std::sqrt(res.stiffness / m12) / std::sqrt(kPi * kPi + le * le);
  res.gamma_n = 2.0 * m12 * eta;
  const double alpha = 2.0 / 7.0;  // k_t / k_n: the tangential and normal periods of a sphere pair match
  res.gamma_t = alpha * res.gamma_n;

  // 1. the cloud
  const packing::RandomFill3dOptions fo = green_body_cloud_options(o);
  res.cloud_box = fo.box;
  const packing::Packing cloud = packing::random_fill_3d(fo);
  const double vs = cloud.solid_volume();

  LudingParams lp;
  lp.k2 = res.stiffness;
  lp.k1_ratio = 1.0;
  lp.kc_ratio = 0.0;
  lp.alpha = alpha;
  lp.gamma_n = res.gamma_n;
  lp.gamma_t = res.gamma_t;
  lp.mu = o.mu_settle;
  lp.mu_wall = o.mu_wall;
  lp.a0 = r;
  lp.rho_p = o.solid_density;
  Particles P;
  P.dim = 3;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    P.add_sphere(cloud.x[i], cloud.y[i], cloud.z[i], cloud.r[i], o.solid_density);
  Box box(fo.box);
  DynamicOptions dopt;
  dopt.model = ContactModel::Linear;
  dopt.rule = TimeStepRule::MeanPair;
  dopt.steps_per_contact = o.steps_per_contact;
  dopt.gravity_z = -g;
  DynamicSolver3 s(std::move(P), lp, box, dopt);
  res.dt = s.dt();
  res.contact_time = s.time_step().tc_mean;
  const double dt = s.dt();
  const double n_sph = static_cast<double>(o.n);
  // translational kinetic energy per sphere / (m g r): a sphere spinning in place (e.g. touching
  // frictionless walls only, which cannot stop its spin) does not move the packing
  const auto kinetic = [&] {
    const Particles& Q = s.particles();
    double e = 0.0;
    for (std::size_t i = 0; i < Q.size(); ++i) e += Q.mass[i] * (Q.vx[i] * Q.vx[i] + Q.vy[i] * Q.vy[i] + Q.vz[i] * Q.vz[i]);
    return 0.5 * e / n_sph / mgr;
  };

  auto report = [&](const char* phase, std::int64_t steps, double ke, double fraction) {
    if (!observer) return;
    GreenBodyProgress pr;
    pr.phase = phase;
    pr.steps = steps;
    pr.time = s.time();
    pr.density = s.density();
    pr.kinetic = ke;
    pr.fraction = fraction;
    observer(pr);
  };
  // runs until the rest criterion holds at 3 checks in a row (after min_time), or the cap
  auto run_to_rest = [&](const char* name, double min_time) {
    GreenBodyPhase ph;
    ph.name = name;
    const auto w0 = clock::now();
    const double t0 = s.time(), cap = o.max_phase_time * res.time_unit;
    int calm = 0;
    double ke = kinetic();
    while (true) {
      s.run(static_cast<std::size_t>(o.check_every));
      ph.steps += o.check_every;
      ke = kinetic();
      calm = ke < o.rest_energy && s.time() - t0 >= min_time ? calm + 1 : 0;
      report(name, ph.steps, ke, -1.0);
      if (calm >= 3) {
        ph.at_rest = true;
        break;
      }
      if (s.time() - t0 >= cap) break;
    }
    ph.time = s.time() - t0;
    ph.wall_seconds = std::chrono::duration<double>(clock::now() - w0).count();
    ph.density = s.density();
    ph.kinetic = ke;
    return ph;
  };
  auto not_ok = [&](const std::string& status, const std::string& why) {
    if (res.status == "ok") {
      res.status = status;
      res.reason = why;
    } else if (status == "unreachable" && res.status != "unreachable") {  // the stronger verdict first
      res.reason = why + "; " + res.status + ": " + res.reason;
      res.status = status;
    } else {
      res.reason += "; " + why;
    }
  };

  // 2. settle under gravity (at least the free-fall time over the cloud's empty height)
  const double L0 = fo.box.x_max - fo.box.x_min, H_cloud = fo.box.z_max - fo.box.z_min;  // green_body_cloud_options
  const double vs_expected = static_cast<double>(o.n) * 4.0 / 3.0 * kPi * r * r * r * (1.0 + o.dispersion * o.dispersion);
  const double fall = std::sqrt(2.0 * std::max(0.0, H_cloud - vs_expected / (o.settled_guess * L0 * L0)) / g);
  res.phases.push_back(run_to_rest("settle", fall));
  if (!res.phases.back().at_rest)
    not_ok("unconverged", fmt::format("the settling did not come to rest in {:g} sqrt(r/g) (kinetic energy {:.3g} m g r "
                                      "per sphere, criterion {:.3g})",
                                      o.max_phase_time, res.phases.back().kinetic, o.rest_energy));

  // 3. the lid onto the uppermost sphere: the z_max wall moves down at 0.05 r_min per step
  {
    GreenBodyPhase ph;
    ph.name = "lid";
    const auto w0 = clock::now();
    const double t0 = s.time();
    const Particles& Q = s.particles();
    double top = 0.0, rmin = Q.radius[0];
    for (std::size_t i = 0; i < Q.size(); ++i) {
      top = std::max(top, Q.z[i] + Q.radius[i]);
      rmin = std::min(rmin, Q.radius[i]);
    }
    const double travel = s.box().z_max - top;
    if (travel > 0.0) {
      const auto steps = static_cast<std::int64_t>(std::ceil(travel / (0.05 * rmin)));
      MovingWall fixed, lid;
      lid.mode = WallMode::Strain;
      lid.velocity = -travel / (static_cast<double>(steps) * dt);
      s.set_walls(fixed, fixed, lid);
      s.run(static_cast<std::size_t>(steps));
      s.set_walls(fixed, fixed, fixed);
      ph.steps = steps;
    }
    ph.time = s.time() - t0;
    ph.wall_seconds = std::chrono::duration<double>(clock::now() - w0).count();
    ph.density = s.density();
    ph.kinetic = kinetic();
    res.phases.push_back(ph);
  }
  res.settled_box = static_cast<const packing::Box&>(s.box());
  res.settled_density = s.density();

  // 4. compress: the three walls reach the scaled box at the same time, the fastest at wall_speed
  // the target box: width L* = (V / (target aspect))^(1/3) (x = y), height aspect L*, if every wall
  // then moves inward; else the settled box scaled by s = (settled density / target)^(1/3)
  res.scale = std::cbrt(res.settled_density / o.target_density);
  const packing::Box& b1 = res.settled_box;
  res.target_box = b1;
  const double Ls = std::cbrt(vs / (o.target_density * o.aspect)), Hs = o.aspect * Ls;
  if (res.scale < 1.0) {
    res.exact_aspect = Ls <= b1.width() && Ls <= b1.height() && Hs <= b1.depth();
    res.target_box.x_max = b1.x_min + (res.exact_aspect ? Ls : res.scale * b1.width());
    res.target_box.y_max = b1.y_min + (res.exact_aspect ? Ls : res.scale * b1.height());
    res.target_box.z_max = b1.z_min + (res.exact_aspect ? Hs : res.scale * b1.depth());
    GreenBodyPhase ph;
    ph.name = "compress";
    const auto w0 = clock::now();
    const double t0 = s.time();
    const double travel[3] = {b1.width() - res.target_box.width(), b1.height() - res.target_box.height(),
                              b1.depth() - res.target_box.depth()};
    const double tmax = std::max({travel[0], travel[1], travel[2]});
    const double vmax = o.wall_speed * std::sqrt(g * r);
    const auto steps = static_cast<std::int64_t>(std::ceil(tmax / (vmax * dt)));
    const double T = static_cast<double>(steps) * dt;
    MovingWall w[3];
    for (int a = 0; a < 3; ++a) {
      w[a].mode = WallMode::Strain;
      w[a].velocity = -travel[a] / T;
      res.wall_velocity[a] = w[a].velocity;
    }
    const double Lmax = std::max({b1.width(), b1.height(), b1.depth()});
    res.strain_rate = vmax / Lmax;
    const double p_g = o.solid_density * res.settled_density * g * b1.depth() / 2.0;
    res.inertial_number = res.strain_rate * 2.0 * r * std::sqrt(o.solid_density / p_g);
    LudingParams lc = lp;
    lc.mu = o.mu_compress;
    s.set_params(lc);
    s.set_walls(w[0], w[1], w[2]);
    std::int64_t done = 0;
    bool aborted = false;
    while (done < steps) {
      const std::int64_t chunk = std::min<std::int64_t>(o.check_every, steps - done);
      s.run(static_cast<std::size_t>(chunk));
      done += chunk;
      const packing::OverlapStats ov = packing::overlap_stats(packing_of(s, o.seed));
      res.compress_max_mean_overlap = std::max(res.compress_max_mean_overlap, ov.pair_mean);
      if (res.limit_density == 0.0 && ov.pair_mean > o.max_mean_overlap) res.limit_density = s.density();
      report("compress", done, kinetic(), static_cast<double>(done) / static_cast<double>(steps));
      if (ov.pair_mean > 3.0 * o.max_mean_overlap) {
        aborted = true;
        not_ok("unreachable",
               fmt::format("the compression was stopped at density {:.4f}: the mean overlap reached {:.3g} r, 3 times the "
                           "limit {:.3g} r, before the target {:.4f} (it passed the limit at density {:.4f})",
                           s.density(), ov.pair_mean, o.max_mean_overlap, o.target_density, res.limit_density));
        break;
      }
    }
    MovingWall fixed;
    s.set_walls(fixed, fixed, fixed);
    (void)aborted;
    ph.steps = done;
    ph.time = s.time() - t0;
    ph.wall_seconds = std::chrono::duration<double>(clock::now() - w0).count();
    ph.density = s.density();
    ph.kinetic = kinetic();
    res.phases.push_back(ph);
  }

  // 5. rest with the final friction
  {
    LudingParams lf = lp;
    lf.mu = o.mu_final;
    s.set_params(lf);
    res.phases.push_back(run_to_rest("rest", 0.0));
    if (!res.phases.back().at_rest)
      not_ok("unconverged", fmt::format("the final rest was not reached in {:g} sqrt(r/g) (kinetic energy {:.3g} m g r "
                                        "per sphere, criterion {:.3g})",
                                        o.max_phase_time, res.phases.back().kinetic, o.rest_energy));
  }
  res.packing = packing_of(s, o.seed);
  res.overlaps = packing::overlap_stats(res.packing);
  const Stress3 ws = s.wall_stress();
  for (int a = 0; a < 3; ++a) res.wall_stress[a] = ws.s[a][a];
  if (res.overlaps.pair_mean > o.max_mean_overlap && res.status != "unreachable")
    not_ok("unreachable",
           fmt::format("at rest at density {:.4f} the mean overlap is {:.3g} r, above the limit {:.3g} r: the springs, not "
                       "the packing, hold the target {:.4f}{}",
                       s.density(), res.overlaps.pair_mean, o.max_mean_overlap, o.target_density,
                       res.limit_density > 0.0
                           ? fmt::format(" (the compression passed the limit at density {:.4f})", res.limit_density)
                           : std::string()));
  (void)vs;
  return res;
}

}  // namespace netdem::dem
