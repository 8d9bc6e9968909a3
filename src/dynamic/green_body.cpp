// The green-body packing route of Ivannikov et al. (netdem/dynamic/green_body.hpp).
#include "netdem/dynamic/green_body.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
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
  packing::Packing p = to_packing(s.particles(), s.box());
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

namespace {

/// The mean sphere's mass m, the stiffness k = kappa m g / r and the damping rate eta of a mean
/// pair (m12 = m / 2) with restitution e = exp(-eta t_c), t_c = pi / sqrt(k / m12 - eta^2).
struct MeanPair {
  double m, k, m12, eta;
};
MeanPair mean_pair(const GreenBodyOptions& o) {
  const double r = o.mean_radius;
  MeanPair p{};
  p.m = o.solid_density * 4.0 / 3.0 * kPi * r * r * r;
  p.k = o.stiffness_number * p.m * o.gravity / r;
  p.m12 = 0.5 * p.m;
  const double le = std::log(o.restitution);
  p.eta = -le * std::sqrt(p.k / p.m12) / std::sqrt(kPi * kPi + le * le);
  return p;
}

}  // namespace

double green_body_min_steps(const GreenBodyOptions& o) {
  const packing::RandomFill3dOptions fo = green_body_cloud_options(o);
  const double r = o.mean_radius, g = o.gravity;
  // the mean pair's time step, as make_green_body sets the law (material()) and the MeanPair rule
  const MeanPair mp = mean_pair(o);
  const double dt = kPi / std::sqrt(mp.k / mp.m12 - mp.eta * mp.eta) / o.steps_per_contact;
  const double vs = static_cast<double>(o.n) * 4.0 / 3.0 * kPi * r * r * r * (1.0 + o.dispersion * o.dispersion);
  const double L0 = fo.box.x_max, H_cloud = fo.box.z_max;
  const double fall = std::sqrt(2.0 * std::max(0.0, H_cloud - vs / (o.settled_guess * L0 * L0)) / g);
  // the expected settled box (density settled_guess, aspect) scaled to the target
  const double scale = std::cbrt(o.settled_guess / o.target_density);
  const double travel = scale < 1.0 ? (1.0 - scale) * std::max(L0, o.aspect * L0) : 0.0;
  const double compress = travel / (o.wall_speed * std::sqrt(g * r));
  return (fall + compress) / dt;
}

double green_body_lightest_steps_per_contact(const GreenBodyOptions& o, const packing::Packing& cloud) {
  if (cloud.size() == 0) throw std::invalid_argument("green body: the cloud has no spheres");
  const MeanPair mp = mean_pair(o);  // the law of material(); the masses as add_sphere's
  double mean = 0.0, lo = HUGE_VAL, lo2 = HUGE_VAL;
  for (double r : cloud.r) {
    const double m = o.solid_density * (4.0 / 3.0) * kPi * r * r * r;
    mean += m;
    if (m < lo) {
      lo2 = lo;
      lo = m;
    } else if (m < lo2) {
      lo2 = m;
    }
  }
  mean /= static_cast<double>(cloud.size());
  if (cloud.size() < 2) lo2 = lo;
  const double gamma_n = 2.0 * mp.m12 * mp.eta;
  return o.steps_per_contact * contact_duration(mp.k, gamma_n, lo * lo2 / (lo + lo2)) /
         contact_duration(mp.k, gamma_n, 0.5 * mean);
}

namespace {

/// The phases of make_green_body, in order (the numbers are the comments' of the route).
class GreenBodyRoute {
  using clock = std::chrono::steady_clock;

 public:
  GreenBodyRoute(const GreenBodyOptions& o, const GreenBodyObserver& observer) : o_(o), observer_(observer) {}

  GreenBodyResult run() {
    material();
    make_cloud();  // 1.
    settle();      // 2.
    lid();         // 3.
    res_.settled_box = static_cast<const packing::Box&>(s_->box());
    res_.settled_density = s_->density();
    compress();    // 4.
    rest();        // 5.
    finish();
    return std::move(res_);
  }

 private:
  // the mean sphere, the stiffness and the damping of a mean pair
  void material() {
    const double r = o_.mean_radius, g = o_.gravity;
    const MeanPair mp = mean_pair(o_);
    m_ = mp.m;  // the mean sphere
    mgr_ = m_ * g * r;
    res_.mean_mass = m_;
    res_.time_unit = std::sqrt(r / g);
    res_.stiffness = mp.k;
    res_.gamma_n = 2.0 * mp.m12 * mp.eta;
    const double alpha = 2.0 / 7.0;  // k_t / k_n: the tangential and normal periods of a sphere pair match
    res_.gamma_t = alpha * res_.gamma_n;
    lp_.k2 = res_.stiffness;
    lp_.k1_ratio = 1.0;
    lp_.kc_ratio = 0.0;
    lp_.alpha = alpha;
    lp_.gamma_n = res_.gamma_n;
    lp_.gamma_t = res_.gamma_t;
    lp_.mu = o_.mu_settle;
    lp_.mu_wall = o_.mu_wall;
    lp_.a0 = r;
    lp_.rho_p = o_.solid_density;
  }

  // 1. the cloud, and the solver on it
  void make_cloud() {
    const double r = o_.mean_radius;
    const packing::RandomFill3dOptions fo = green_body_cloud_options(o_);
    vs_expected_ = static_cast<double>(o_.n) * 4.0 / 3.0 * kPi * r * r * r * (1.0 + o_.dispersion * o_.dispersion);
    L0_ = fo.box.x_max - fo.box.x_min;
    H_cloud_ = fo.box.z_max - fo.box.z_min;
    res_.cloud_box = fo.box;
    const packing::Packing cloud = packing::random_fill_3d(fo);
    vs_ = cloud.solid_volume();
    Particles3 P;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      P.add_sphere(cloud.x[i], cloud.y[i], cloud.z[i], cloud.r[i], o_.solid_density);
    Box box(fo.box);
    DynamicOptions dopt;
    dopt.model = ContactModel::Linear;
    dopt.rule = TimeStepRule::MeanPair;
    dopt.steps_per_contact = o_.steps_per_contact;
    dopt.gravity_z = -o_.gravity;
    s_ = std::make_unique<DynamicSolver3>(std::move(P), lp_, box, dopt);
    res_.dt = s_->dt();
    res_.contact_time = s_->time_step().tc_mean;
  }

  // translational kinetic energy per sphere / (m g r): a sphere spinning in place (e.g. touching
  // frictionless walls only, which cannot stop its spin) does not move the packing
  double kinetic() const {
    const Particles3& Q = s_->particles();
    double e = 0.0;
    for (std::size_t i = 0; i < Q.size(); ++i) {
      const double* const v = &Q.vel[3 * i];
      e += Q.mass[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    }
    return 0.5 * e / static_cast<double>(o_.n) / mgr_;
  }

  void report(const char* phase, std::int64_t steps, double ke, double fraction) const {
    if (!observer_) return;
    GreenBodyProgress pr;
    pr.phase = phase;
    pr.steps = steps;
    pr.time = s_->time();
    pr.density = s_->density();
    pr.kinetic = ke;
    pr.fraction = fraction;
    observer_(pr);
  }

  // runs until the rest criterion holds at 3 checks in a row (after min_time), or the cap
  GreenBodyPhase run_to_rest(const char* name, double min_time) {
    GreenBodyPhase ph;
    ph.name = name;
    const auto w0 = clock::now();
    const double t0 = s_->time(), cap = o_.max_phase_time * res_.time_unit;
    int calm = 0;
    double ke = kinetic();
    while (true) {
      s_->run(static_cast<std::size_t>(o_.check_every));
      ph.steps += o_.check_every;
      ke = kinetic();
      calm = ke < o_.rest_energy && s_->time() - t0 >= min_time ? calm + 1 : 0;
      report(name, ph.steps, ke, -1.0);
      if (calm >= 3) {
        ph.at_rest = true;
        break;
      }
      if (s_->time() - t0 >= cap) break;
    }
    close_phase(ph, t0, w0, ke);
    return ph;
  }

  void close_phase(GreenBodyPhase& ph, double t0, clock::time_point w0, double ke) const {
    ph.time = s_->time() - t0;
    ph.wall_seconds = std::chrono::duration<double>(clock::now() - w0).count();
    ph.density = s_->density();
    ph.kinetic = ke;
  }

  void not_ok(const std::string& status, const std::string& why) {
    if (res_.status == "ok") {
      res_.status = status;
      res_.reason = why;
    } else if (status == "unreachable" && res_.status != "unreachable") {  // the stronger verdict first
      res_.reason = why + "; " + res_.status + ": " + res_.reason;
      res_.status = status;
    } else {
      res_.reason += "; " + why;
    }
  }

  // 2. settle under gravity (at least the free-fall time over the cloud's empty height)
  void settle() {
    const double fall =
        std::sqrt(2.0 * std::max(0.0, H_cloud_ - vs_expected_ / (o_.settled_guess * L0_ * L0_)) / o_.gravity);
    res_.phases.push_back(run_to_rest("settle", fall));
    if (!res_.phases.back().at_rest)
      not_ok("unconverged", fmt::format("the settling did not come to rest in {:g} sqrt(r/g) (kinetic energy {:.3g} m g r "
                                        "per sphere, criterion {:.3g})",
                                        o_.max_phase_time, res_.phases.back().kinetic, o_.rest_energy));
  }

  // 3. the lid onto the uppermost sphere: the z_max wall moves down at 0.05 r_min per step
  void lid() {
    DynamicSolver3& s = *s_;
    GreenBodyPhase ph;
    ph.name = "lid";
    const auto w0 = clock::now();
    const double t0 = s.time();
    const Particles3& Q = s.particles();
    double top = 0.0, rmin = Q.r[0];
    for (std::size_t i = 0; i < Q.size(); ++i) {
      top = std::max(top, Q.coord(i, 2) + Q.r[i]);
      rmin = std::min(rmin, Q.r[i]);
    }
    const double travel = s.box().z_max - top;
    if (travel > 0.0) {
      const auto steps = static_cast<std::int64_t>(std::ceil(travel / (0.05 * rmin)));
      MovingWall fixed, lid;
      lid.mode = WallMode::Strain;
      lid.velocity = -travel / (static_cast<double>(steps) * s.dt());
      s.set_walls(fixed, fixed, lid);
      s.run(static_cast<std::size_t>(steps));
      s.set_walls(fixed, fixed, fixed);
      ph.steps = steps;
    }
    close_phase(ph, t0, w0, kinetic());
    res_.phases.push_back(ph);
  }

  // 4. compress: the three walls reach the scaled box at the same time, the fastest at wall_speed
  // the target box: width L* = (V / (target aspect))^(1/3) (x = y), height aspect L*, if every wall
  // then moves inward; else the settled box scaled by s = (settled density / target)^(1/3)
  void compress() {
    res_.scale = std::cbrt(res_.settled_density / o_.target_density);
    const packing::Box& b1 = res_.settled_box;
    res_.target_box = b1;
    const double Ls = std::cbrt(vs_ / (o_.target_density * o_.aspect)), Hs = o_.aspect * Ls;
    if (!(res_.scale < 1.0)) return;
    res_.exact_aspect = Ls <= b1.width() && Ls <= b1.height() && Hs <= b1.depth();
    res_.target_box.x_max = b1.x_min + (res_.exact_aspect ? Ls : res_.scale * b1.width());
    res_.target_box.y_max = b1.y_min + (res_.exact_aspect ? Ls : res_.scale * b1.height());
    res_.target_box.z_max = b1.z_min + (res_.exact_aspect ? Hs : res_.scale * b1.depth());
    DynamicSolver3& s = *s_;
    GreenBodyPhase ph;
    ph.name = "compress";
    const auto w0 = clock::now();
    const double t0 = s.time();
    const double travel[3] = {b1.width() - res_.target_box.width(), b1.height() - res_.target_box.height(),
                              b1.depth() - res_.target_box.depth()};
    const double tmax = std::max({travel[0], travel[1], travel[2]});
    const double vmax = o_.wall_speed * std::sqrt(o_.gravity * o_.mean_radius);
    const auto steps = static_cast<std::int64_t>(std::ceil(tmax / (vmax * s.dt())));
    const double T = static_cast<double>(steps) * s.dt();
    MovingWall w[3];
    for (int a = 0; a < 3; ++a) {
      w[a].mode = WallMode::Strain;
      w[a].velocity = -travel[a] / T;
      res_.wall_velocity[a] = w[a].velocity;
    }
    const double Lmax = std::max({b1.width(), b1.height(), b1.depth()});
    res_.strain_rate = vmax / Lmax;
    const double p_g = o_.solid_density * res_.settled_density * o_.gravity * b1.depth() / 2.0;
    res_.inertial_number = res_.strain_rate * 2.0 * o_.mean_radius * std::sqrt(o_.solid_density / p_g);
    LudingParams lc = lp_;
    lc.mu = o_.mu_compress;
    s.set_params(lc);
    s.set_walls(w[0], w[1], w[2]);
    ph.steps = compress_steps(steps);
    MovingWall fixed;
    s.set_walls(fixed, fixed, fixed);
    close_phase(ph, t0, w0, kinetic());
    res_.phases.push_back(ph);
  }

  // the walls' run in chunks, stopped when the mean overlap passes 3 x the limit; the steps done
  std::int64_t compress_steps(std::int64_t steps) {
    DynamicSolver3& s = *s_;
    std::int64_t done = 0;
    while (done < steps) {
      const std::int64_t chunk = std::min<std::int64_t>(o_.check_every, steps - done);
      s.run(static_cast<std::size_t>(chunk));
      done += chunk;
      const packing::OverlapStats ov = packing::overlap_stats(packing_of(s, o_.seed));
      res_.compress_max_mean_overlap = std::max(res_.compress_max_mean_overlap, ov.pair_mean);
      if (res_.limit_density == 0.0 && ov.pair_mean > o_.max_mean_overlap) res_.limit_density = s.density();
      report("compress", done, kinetic(), static_cast<double>(done) / static_cast<double>(steps));
      if (ov.pair_mean > 3.0 * o_.max_mean_overlap) {
        not_ok("unreachable",
               fmt::format("the compression was stopped at density {:.4f}: the mean overlap reached {:.3g} r, 3 times the "
                           "limit {:.3g} r, before the target {:.4f} (it passed the limit at density {:.4f})",
                           s.density(), ov.pair_mean, o_.max_mean_overlap, o_.target_density, res_.limit_density));
        break;
      }
    }
    return done;
  }

  // 5. rest with the final friction
  void rest() {
    LudingParams lf = lp_;
    lf.mu = o_.mu_final;
    s_->set_params(lf);
    res_.phases.push_back(run_to_rest("rest", 0.0));
    if (!res_.phases.back().at_rest)
      not_ok("unconverged", fmt::format("the final rest was not reached in {:g} sqrt(r/g) (kinetic energy {:.3g} m g r "
                                        "per sphere, criterion {:.3g})",
                                        o_.max_phase_time, res_.phases.back().kinetic, o_.rest_energy));
  }

  // the packing, its overlaps and wall stresses, the verdict on the overlaps at rest
  void finish() {
    const DynamicSolver3& s = *s_;
    res_.packing = packing_of(s, o_.seed);
    res_.overlaps = packing::overlap_stats(res_.packing);
    const Stress3 ws = s.wall_stress();
    for (int a = 0; a < 3; ++a) res_.wall_stress[a] = ws.s[a][a];
    if (res_.overlaps.pair_mean > o_.max_mean_overlap && res_.status != "unreachable")
      not_ok("unreachable",
             fmt::format("at rest at density {:.4f} the mean overlap is {:.3g} r, above the limit {:.3g} r: the springs, not "
                         "the packing, hold the target {:.4f}{}",
                         s.density(), res_.overlaps.pair_mean, o_.max_mean_overlap, o_.target_density,
                         res_.limit_density > 0.0
                             ? fmt::format(" (the compression passed the limit at density {:.4f})", res_.limit_density)
                             : std::string()));
  }

  const GreenBodyOptions& o_;
  const GreenBodyObserver& observer_;
  GreenBodyResult res_;
  LudingParams lp_;
  std::unique_ptr<DynamicSolver3> s_;
  double m_ = 0.0, mgr_ = 0.0;
  double vs_expected_ = 0.0, L0_ = 0.0, H_cloud_ = 0.0, vs_ = 0.0;
};

}  // namespace

GreenBodyResult make_green_body(const GreenBodyOptions& o, const GreenBodyObserver& observer) {
  o.validate();
  return GreenBodyRoute(o, observer).run();
}

}  // namespace netdem::dem
