// The sintering protocol as library functions (netdem/dynamic/protocol.hpp, docs/sintering.md).
#include "netdem/dynamic/protocol.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "netdem/field_error.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/random_fill.hpp"

namespace netdem::dem {

using packing::uniform01;

Particles place_sample(const SampleSpec& a, const LudingParams& lp, Box& box) {
  if (a.n < 1 || a.n > 1000000) throw FieldError("n", fmt::format("the number of particles n must be in [1, 1e6], got {}", a.n));
  if (!(a.initial_density > 0.0 && a.initial_density < 0.6))
    throw std::invalid_argument(fmt::format("initial density must be in (0, 0.6), got {}", a.initial_density));
  Particles P;
  if (a.arrangement != "random") {  // LMM05 section 4.1.3 control: three equal disks
    if (a.n != 3) throw FieldError("n", "the triangle and line arrangements (LMM05 4.1.3) are three disks: n must be 3");
    const double r = lp.a0;
    if (a.arrangement == "line") {
      box.x_min = box.y_min = 0.0;
      box.x_max = 6.0 * r;
      box.y_max = 2.0 * r;
      for (int k = 0; k < 3; ++k) P.add((1.0 + 2.0 * k) * r, r, r, lp);
    } else if (a.arrangement == "triangle") {
      // two on the floor, one on top; the box closes around them
      const double h = std::sqrt(3.0) * r;
      box.x_min = box.y_min = 0.0;
      box.x_max = 4.0 * r;
      box.y_max = 2.0 * r + h;
      P.add(r, r, r, lp);
      P.add(3.0 * r, r, r, lp);
      P.add(2.0 * r, r + h, r, lp);
    } else {
      throw FieldError("arrangement", "the arrangement must be random, triangle or line, got '" + a.arrangement + "'");
    }
    return P;
  }
  std::mt19937_64 rng(a.seed);
  std::vector<double> r(static_cast<std::size_t>(a.n));
  double area = 0.0;
  for (auto& ri : r) {  // draw order: all radii first, then positions, then velocities
    ri = lp.a0 * (1.0 - lp.w0 + 2.0 * lp.w0 * uniform01(rng));
    area += std::numbers::pi * ri * ri;
  }
  const double L = std::sqrt(area / a.initial_density);
  box.x_min = box.y_min = 0.0;
  box.x_max = box.y_max = L;
  netdem::packing::Packing placed;
  try {
    placed = netdem::packing::random_fill(r, {0.0, 0.0, L, L}, rng);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("{} at density {}", e.what(), a.initial_density));
  }
  for (std::size_t i = 0; i < r.size(); ++i) P.add(placed.x[i], placed.y[i], r[i], lp);
  const double v0 = 0.01;  // [m/s]
  for (std::size_t i = 0; i < r.size(); ++i) {
    P.vel[2 * i] = v0 * (2.0 * uniform01(rng) - 1.0);
    P.vel[2 * i + 1] = v0 * (2.0 * uniform01(rng) - 1.0);
  }
  return P;
}

double packing_length_unit(const packing::Packing& p, const LudingParams& lp, double length_unit) {
  if (!(std::isfinite(length_unit) && length_unit >= 0.0))
    throw FieldError("length_unit", fmt::format("the length unit must be a number of metres >= 0 (0: from the radii), got {}", length_unit));
  if (length_unit > 0.0) return length_unit;
  double mean = 0.0;
  for (double r : p.r) mean += r;
  mean /= static_cast<double>(std::max<std::size_t>(1, p.size()));
  if (!(mean > 0.0)) throw std::invalid_argument("the packing has no disks");
  return lp.a0 / mean;
}

Particles particles_from_packing(const packing::Packing& p, const LudingParams& lp, double length_unit, Box& box) {
  packing::validate(p);
  const double s = packing_length_unit(p, lp, length_unit);
  packing::Packing q = p;
  for (std::size_t i = 0; i < q.size(); ++i) {
    q.x[i] *= s;
    q.y[i] *= s;
    q.r[i] *= s;
  }
  box.x_min = s * p.box.x_min;
  box.y_min = s * p.box.y_min;
  box.x_max = s * p.box.x_max;
  box.y_max = s * p.box.y_max;
  // the lid of a packing is open (netsolve's default deposition lets the top layer stick out by
  // less than a radius): the top wall starts at the highest disk top if that is above the lid
  for (std::size_t i = 0; i < q.size(); ++i) box.y_max = std::max(box.y_max, q.y[i] + q.r[i]);
  for (std::size_t i = 0; i < q.size(); ++i) {
    const double x = q.x[i], y = q.y[i], r = q.r[i], tol = 1e-9 * r;
    if (!(r >= 0.01 * lp.a0 && r <= 100.0 * lp.a0))
      throw std::invalid_argument(fmt::format(
          "disk {} has radius {} m after the unit conversion ({} m per file unit), outside [a0 / 100, 100 a0] = "
          "[{}, {}] m: check the length unit",
          i, r, s, 0.01 * lp.a0, 100.0 * lp.a0));
    if (x - r < box.x_min - tol || x + r > box.x_max + tol || y - r < box.y_min - tol)
      throw std::invalid_argument(fmt::format(
          "disk {} (centre ({}, {}), r = {} in file units) reaches through a side wall or the floor of the box", i,
          p.x[i], p.y[i], p.r[i]));
  }
  return particles_from(q, lp);
}

Particles3 place_sample3(const SampleSpec& a, const LudingParams& lp, Box& box) {
  if (a.n < 1 || a.n > 1000000) throw FieldError("n", fmt::format("the number of particles n must be in [1, 1e6], got {}", a.n));
  if (a.arrangement != "random")
    throw FieldError("arrangement", "the triangle and line arrangements are the 2D three-disk control of LMM05 4.1.3 (disks, not spheres)");
  // the cube whose region of the centres, (L - 2 a0)^3, holds the expected solid volume (E[a^3] of
  // the uniform radii) at kInitialDensity3 (a small box's walls would otherwise crowd the cloud)
  const double w = lp.w0, a0 = lp.a0;
  const double mean_r3 = a0 * a0 * a0 * (1.0 + w * w);  // E[(1 + w (2U - 1))^3] = 1 + w^2
  const double L = 2.0 * a0 * (1.0 + w) +
                   std::cbrt(static_cast<double>(a.n) * 4.0 / 3.0 * std::numbers::pi * mean_r3 / kInitialDensity3);
  packing::RandomFill3dOptions o;
  o.n = static_cast<std::size_t>(a.n);
  o.mean_radius = a0;
  o.dispersion = w;
  o.box = packing::Box{0.0, 0.0, L, L, 0.0, L};
  o.seed = a.seed;
  const packing::Packing placed = packing::random_fill_3d(o);
  box.x_min = box.y_min = box.z_min = 0.0;
  box.x_max = box.y_max = box.z_max = L;
  Particles3 P;
  std::mt19937_64 rng(a.seed + 1);
  const double v0 = 0.01;  // [m/s]
  for (std::size_t i = 0; i < placed.size(); ++i) {
    const double vx = v0 * (2.0 * uniform01(rng) - 1.0), vy = v0 * (2.0 * uniform01(rng) - 1.0),
                 vz = v0 * (2.0 * uniform01(rng) - 1.0);
    P.add_sphere(placed.x[i], placed.y[i], placed.z[i], placed.r[i], lp.rho_p, {vx, vy, vz});
  }
  return P;
}

Particles3 make_sample3(const SampleSpec& spec, const LudingParams& lp, Box& box, double* length_unit) {
  if (spec.packing_file.empty()) return place_sample3(spec, lp, box);
  const packing::Packing p = packing::read_packing_csv(spec.packing_file);
  if (p.dim != 3) throw std::invalid_argument(fmt::format("{} is a 2D packing; a sample of spheres needs a 3D one (# dim 3)", spec.packing_file));
  if (p.periodic)
    throw std::invalid_argument(fmt::format("{} is a periodic packing ('# periodic'): the sample's box has walls, which would "
                                            "cut its contacts across the faces", spec.packing_file));
  packing::validate(p);
  const double s = packing_length_unit(p, lp, spec.length_unit);
  if (length_unit) *length_unit = s;
  box.x_min = s * p.box.x_min;
  box.y_min = s * p.box.y_min;
  box.z_min = s * p.box.z_min;
  box.x_max = s * p.box.x_max;
  box.y_max = s * p.box.y_max;
  box.z_max = s * p.box.z_max;
  for (std::size_t i = 0; i < p.size(); ++i) box.z_max = std::max(box.z_max, s * (p.z[i] + p.r[i]));
  Particles3 P;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double x = s * p.x[i], y = s * p.y[i], z = s * p.z[i], r = s * p.r[i], tol = 1e-9 * r;
    if (!(r >= 0.01 * lp.a0 && r <= 100.0 * lp.a0))
      throw std::invalid_argument(fmt::format(
          "sphere {} has radius {} m after the unit conversion ({} m per file unit), outside [a0 / 100, 100 a0] = "
          "[{}, {}] m: check the length unit",
          i, r, s, 0.01 * lp.a0, 100.0 * lp.a0));
    if (x - r < box.x_min - tol || x + r > box.x_max + tol || y - r < box.y_min - tol || y + r > box.y_max + tol ||
        z - r < box.z_min - tol)
      throw std::invalid_argument(fmt::format(
          "sphere {} (centre ({}, {}, {}), r = {} in file units) reaches through a side wall or the floor of the box (a "
          "periodic deposition? demsolve's box has walls)",
          i, p.x[i], p.y[i], p.z[i], p.r[i]));
    P.add_sphere(x, y, z, r, lp.rho_p);
  }
  return P;
}

Particles make_sample(const SampleSpec& spec, const LudingParams& lp, Box& box, double* length_unit) {
  if (spec.packing_file.empty()) return place_sample(spec, lp, box);
  const packing::Packing p = packing::read_packing_csv(spec.packing_file);
  if (p.dim != 2) throw std::invalid_argument(fmt::format("{} is a 3D packing (# dim 3): its spheres need the 3D solver", spec.packing_file));
  if (p.periodic)
    throw std::invalid_argument(fmt::format("{} is a periodic packing ('# periodic'): the sample's box has walls, which would "
                                            "cut its contacts across the faces", spec.packing_file));
  const double unit = packing_length_unit(p, lp, spec.length_unit);
  if (length_unit) *length_unit = unit;
  return particles_from_packing(p, lp, unit, box);
}

void set_stress_walls(Box& box, double pressure, const LudingParams& lp, int dim) {
  for (MovingWall* w : {&box.right, &box.top, &box.back}) {
    if (w == &box.back && dim != 3) continue;
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->mass = lp.m_wall;
    w->damping = lp.gamma_wall;
  }
}

template <int D>
ContactCounts count_contacts(const DynamicSolverT<D>& s, std::vector<std::pair<std::uint32_t, std::uint32_t>>& buffer) {
  s.touching_pairs(buffer);
  return {buffer.size(), s.wall_contacts()};
}

template <int D>
void particle_stress(const ParticlesT<D>& P, const std::vector<ContactInfo>& cs, std::vector<double>& p,
                     std::vector<double>& z) {
  p.assign(P.size(), 0.0);
  z.assign(P.size(), 0.0);
  for (const auto& c : cs) {
    p[c.i] += c.f_n * c.d_i;
    z[c.i] += 1.0;
    if (c.wall < 0) {
      p[c.j] += c.f_n * c.d_j;
      z[c.j] += 1.0;
    }
  }
  if (D == 3)
    for (std::size_t i = 0; i < P.size(); ++i) p[i] /= 4.0 * std::numbers::pi * P.r[i] * P.r[i] * P.r[i];
  else
    for (std::size_t i = 0; i < P.size(); ++i) p[i] /= 2.0 * std::numbers::pi * P.r[i] * P.r[i];
}
template void particle_stress(const Particles&, const std::vector<ContactInfo>&, std::vector<double>&,
                              std::vector<double>&);
template void particle_stress(const Particles3&, const std::vector<ContactInfo>&, std::vector<double>&,
                              std::vector<double>&);

namespace {
/// The step at whose end time t lies (t / dt rounded up, 1e-6 steps of slack for rounding).
std::int64_t step_of(double t, double dt) { return static_cast<std::int64_t>(std::ceil(t / dt - 1e-6)); }
template <int D>
std::int64_t first_step(const DynamicSolverT<D>& s) { return static_cast<std::int64_t>(std::llround(s.time() / s.dt())); }
}  // namespace

template <int D>
std::int64_t steps_to_end(const DynamicSolverT<D>& s, const std::vector<SinterPhase>& phases) {
  return std::max<std::int64_t>(0, step_of(phase_end(phases, phases.size() - 1), s.dt()) - first_step(s));
}

template <int D>
PhaseRun run_phases(DynamicSolverT<D>& s, const std::vector<SinterPhase>& phases, const PhaseFriction& fr,
                    std::int64_t samples, PhaseObserverT<D>& obs) {
  const double dt = s.dt();
  const std::int64_t k0 = first_step(s);
  const std::int64_t K = step_of(phase_end(phases, phases.size() - 1), dt);
  std::vector<std::int64_t> ends;
  for (std::size_t p = 0; p < phases.size(); ++p) ends.push_back(step_of(phase_end(phases, p), dt));
  const std::int64_t total = steps_to_end(s, phases);
  PhaseRun run;
  run.sample_every = std::max<std::int64_t>(1, total / std::max<std::int64_t>(1, samples));
  const LudingParams base = s.params();
  std::size_t cur_phase = schedule_at(phases, s.time()).phase;
  obs.sample(s, cur_phase, 0);
  bool friction_known = false, friction = false;
  const double t_final = phase_end(phases, phases.size() - 1);
  for (std::int64_t k = k0 + 1; k <= K; ++k) {
    // the last step may end a fraction of dt past the protocol: it still belongs to the last
    // phase of non-zero length (zero-length trailing phases must not change T)
    const double t = std::min(static_cast<double>(k) * dt, t_final);
    const ScheduleAt at = schedule_at(phases, t);
    cur_phase = at.phase;
    if (!friction_known || at.friction != friction) {  // LMM05 4.1: mu on and mu_w off at t_heat
      LudingParams q = base;
      q.mu = at.friction ? fr.mu : fr.mu_prepare;
      q.mu_wall = at.friction ? 0.0 : fr.mu_wall_prepare;
      s.set_params(q);
      friction = at.friction;
      friction_known = true;
    }
    s.advance_temperature(at.T, dt, at.t0);
    s.step();
    ++run.steps;
    if ((k - k0) % run.sample_every == 0) obs.sample(s, cur_phase, run.steps);
    for (std::size_t p = 0; p < phases.size(); ++p)
      if (ends[p] == k) obs.phase_end(s, p);
  }
  if ((K - k0) % run.sample_every != 0 || total == 0) obs.sample(s, cur_phase, run.steps);
  return run;
}

template ContactCounts count_contacts<2>(const DynamicSolverT<2>&, std::vector<std::pair<std::uint32_t, std::uint32_t>>&);
template ContactCounts count_contacts<3>(const DynamicSolverT<3>&, std::vector<std::pair<std::uint32_t, std::uint32_t>>&);
template std::int64_t steps_to_end<2>(const DynamicSolverT<2>&, const std::vector<SinterPhase>&);
template std::int64_t steps_to_end<3>(const DynamicSolverT<3>&, const std::vector<SinterPhase>&);
template PhaseRun run_phases<2>(DynamicSolverT<2>&, const std::vector<SinterPhase>&, const PhaseFriction&, std::int64_t,
                                PhaseObserverT<2>&);
template PhaseRun run_phases<3>(DynamicSolverT<3>&, const std::vector<SinterPhase>&, const PhaseFriction&, std::int64_t,
                                PhaseObserverT<3>&);

}  // namespace netdem::dem
