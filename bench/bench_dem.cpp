// bench_dem: particle-steps per CPU-second of netdem::dem::DynamicSolver on a dense, jammed,
// polydisperse, frictional 2D disk packing (issue #4), for the linear spring-dashpot
// specialisation (ContactModel::Linear: Luding law with k1 = k2, k_c = 0, constant T) and the
// full Luding law (ContactModel::Full, Table 1, constant 80 deg C). Plain executable with its own
// timing loop (CPU time of this thread), CSV on stdout. See bench/README.md, docs/performance.md.
//
//   bench_dem [--n 300,3000,30000] [--models linear,full] [--psteps 3e7] [--min-steps 200]
//             [--warmup 1000] [--cache DIR] [--lammps-data DIR] [--seed 1] [--reps 1] [--threads 1]
//
// --threads N: DynamicOptions::threads for the preparation and the timed runs (the same packing
// and results for any N); with N > 1 compare the wall-time rates (psteps_per_wall_s).
// Scene (the same as ../shared/bench/lammps/params.in as far as the solver allows):
//  * radii uniform in a0 [1 - w0, 1 + w0] = [0.5, 1.5] mm, disks of height h = 6 mm, rho = 2000
//    (LMM05 Table 1); k2 = 2e5 N/m, k_t = 0.2 k2, gamma_0 = 0.2 kg/s, gamma_t = 0.05 kg/s,
//    mu = 0.5; walls frictionless (mu_w = 0, Table 1); dt = t_c/50 for a pair of two a0 disks
//    (as params.in: 6.108e-7 s); Verlet skin 0.2 mm (as params.in), rebuilt when a disk moved
//    more than skin/2; a square box with four walls (LMM05 Fig 1).
//  * preparation (untimed, cached in DIR/pack_N<N>_s<seed>.csv, the packing CSV of
//    netdem/packing/io.hpp in metres): all radii drawn first
//    (std::mt19937_64(seed), the platform-independent uniform of demsolve), then random sequential
//    placement without overlap, largest disks first, at solid fraction 0.45, particles renumbered
//    in Morton order of a grid of cell a_max (spatial locality, as LAMMPS's atom sorting); all
//    with the linear law and friction mu = 0.5, walls frictionless:
//    (a) affine compression of the gas (positions and box scaled by 0.998, then 200 steps with
//        fixed walls, velocities zeroed) up to solid fraction 0.70;
//    (b) stress-controlled right and top walls (LMM05 Eq 1, p = 100 N/m, m_w = 0.01 kg,
//        gamma_w = p L / (0.5 m/s), so the walls never move faster than 0.5 m/s at any N), one
//        solver, until after a 2000-step chunk both wall stresses are within 1 % of p, the density
//        changed by less than 2e-5 and the kinetic energy per disk is below 1e-9 J (about 1 % of
//        the elastic energy of a contact at p; at most 100 chunks); the walls are then fixed
//        where they are.
//  * timing: a fresh solver on the cached packing with fixed walls (full law:
//    T_radius_ref = 80 deg C so that Eq 9 keeps the packing's radii at the constant 80 deg C),
//    `warmup` untimed steps (the tangential springs build up), then max(min_steps, psteps/N)
//    timed steps; CPU time of this thread (CLOCK_THREAD_CPUTIME_ID) and wall time.
//
// --dim 3 (issue 16): DynamicSolver3 on spheres (defaults --n 10000,100000 --psteps 2e7
// --warmup 300; CSV columns as 2D with wall_contacts, the contact stress sxx/syy/szz in Pa, the
// kinetic energy at the end, and the solver's heap (memory_use(): per particle, per table row, the
// search's scratch per particle) and the process's resident set after the run). Scene: radii uniform in a0 [0.5, 1.5] mm, m = rho 4/3 pi r^3,
// I = 2/5 m r^2, the same k2, k_t = 0.2 k2, gamma_0, gamma_t, mu = 0.5, frictionless walls, skin
// 0.2 mm, no gravity; dt = t_c/50 of a pair of two a0 SPHERES (2.893e-7 s); a box with six fixed
// walls. Preparation (untimed, cached in DIR/pack3d_N<N>_s<seed>_v2.txt: a box line and x y z r
// per sphere, m, %.17g): a 3D ballistic deposition (ballistic3d.hpp, seed, walls; the first N
// spheres in deposition order, the lid lowered onto the highest), renumbered in 3D Morton order;
// then on spheres of EQUAL mass (that of an a0 sphere) with steps of t_c/7, frictionless (mu = 0,
// so that it compacts quickly) with a global viscous drag 2e3/s: affine isotropic compression at
// 50/s to a mean contact stress > p/4 (p = 4e4 Pa: a mean contact force of ~0.2 N, delta/a0 ~ 1e-3
// as in 2D), stress-controlled right/back/top walls at p (Eq 1, m_w = 0.01 kg, gamma_w = p A /
// (25/s L)) in chunks of 0.29 ms for up to 8.7 ms; friction on (mu = 0.5), 3 more chunks; walls
// fixed, 0.58 ms with and 0.58 ms without the drag (prepare3()). (Before 2026-12-06, night: real
// masses, steps of t_c/50, walls at 5/s, cache pack3d_N<N>_s<seed>.txt; 542-655 s of CPU at N =
// 1e5.)
// Timing: as 2D, on the cached packing at rest (fresh histories).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/ballistic3d.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/random_fill.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;
using netdem::packing::Packing;
using netdem::packing::uniform01;

namespace {
int g_threads = 1;  // --threads

constexpr double kPressure = 100.0;    // N/m (LMM05 section 4.1, params.in Pt)
constexpr double kSkin = 0.2e-3;       // m (params.in)
constexpr double kPlaceDensity = 0.45;  // solid fraction of the random placement

double clock_now(clockid_t c) {
  timespec t{};
  clock_gettime(c, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
double cpu_now() { return clock_now(CLOCK_THREAD_CPUTIME_ID); }
double wall_now() { return clock_now(CLOCK_MONOTONIC); }

/// The linear spring-dashpot parameters (k1 = k2, k_c = 0) of the scene.
LudingParams linear_params() {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  return p;  // k2, alpha, gamma_n, gamma_t, mu = 0.5, mu_wall = 0: Table 1
}

/// dt of params.in: t_c/50 of a pair of two a0 disks (LMM05 Eq 6).
double scene_dt(const LudingParams& p) {
  const double m0 = netdem::contact::luding_mass(p, p.a0);
  return contact_duration(p.k2, p.gamma_n, 0.5 * m0) / 50.0;
}

std::uint64_t morton(std::uint32_t a, std::uint32_t b) {
  std::uint64_t m = 0;
  for (int k = 0; k < 32; ++k)
    m |= (static_cast<std::uint64_t>((a >> k) & 1u) << (2 * k)) |
         (static_cast<std::uint64_t>((b >> k) & 1u) << (2 * k + 1));
  return m;
}

/// Random sequential placement without overlap (grid of side 2 a_max for the overlap test).
Packing place(int n, std::uint64_t seed, const LudingParams& lp) {
  std::mt19937_64 rng(seed);
  Packing pk;
  pk.r.resize(static_cast<std::size_t>(n));
  double area = 0.0, rmax = 0.0;
  for (auto& r : pk.r) {
    r = lp.a0 * (1.0 - lp.w0 + 2.0 * lp.w0 * uniform01(rng));
    area += std::numbers::pi * r * r;
    rmax = std::max(rmax, r);
  }
  const double L = std::sqrt(area / kPlaceDensity);
  std::sort(pk.r.begin(), pk.r.end(), std::greater<>());  // largest first: denser placement
  pk = netdem::packing::random_fill(pk.r, {0.0, 0.0, L, L}, rng, 10000000);
  // renumber in Morton order of a grid of side a_max (locality of the particle arrays)
  std::vector<std::pair<std::uint64_t, std::uint32_t>> key(pk.r.size());
  for (std::size_t i = 0; i < key.size(); ++i)
    key[i] = {morton(static_cast<std::uint32_t>(pk.x[i] / rmax),
                     static_cast<std::uint32_t>(pk.y[i] / rmax)),
              static_cast<std::uint32_t>(i)};
  std::sort(key.begin(), key.end());
  Packing s = pk;
  for (std::size_t k = 0; k < key.size(); ++k) {
    s.x[k] = pk.x[key[k].second];
    s.y[k] = pk.y[key[k].second];
    s.r[k] = pk.r[key[k].second];
  }
  return s;
}

struct Stage {
  double nu = 0, sxx = 0, syy = 0, ekin = 0;
};
/// Runs `steps` steps of a solver built on (pk, velocities v) and returns its state in pk, v.
/// Walls: fixed at pk's box, or stress-controlled right/top walls (p, m_w = 0.01 kg, gamma_w).
Stage run_stage(Packing& pk, std::vector<double>& vx, std::vector<double>& vy,
                const LudingParams& lp, std::size_t steps, double gamma_w) {
  Box box(pk.box);
  if (gamma_w > 0.0)
    for (MovingWall* w : {&box.right, &box.top}) {
      w->mode = WallMode::Stress;
      w->pressure = kPressure;
      w->mass = 0.01;
      w->damping = gamma_w;
    }
  DynamicOptions o;
  o.threads = g_threads;
  o.model = ContactModel::Linear;
  o.dt = scene_dt(lp);
  o.skin = kSkin;
  Particles P;
  for (std::size_t i = 0; i < pk.r.size(); ++i) P.add(pk.x[i], pk.y[i], pk.r[i], lp, vx[i], vy[i]);
  DynamicSolver s(std::move(P), lp, box, o);
  s.run(steps);
  const Particles& q = s.particles();
  pk.x = q.axis(0);
  pk.y = q.axis(1);
  for (std::size_t i = 0; i < q.size(); ++i) vx[i] = q.vel[2 * i], vy[i] = q.vel[2 * i + 1];
  pk.box = s.box();
  const Stress2 ws = s.wall_stress(), cs = s.contact_stress();
  Stage st;
  st.nu = s.density();
  st.sxx = gamma_w > 0.0 ? ws.xx : cs.xx;
  st.syy = gamma_w > 0.0 ? ws.yy : cs.yy;
  st.ekin = s.energies().kinetic / static_cast<double>(pk.r.size());
  return st;
}

/// The preparation of the file comment. Prints progress on stderr.
Packing compress(const Packing& start, const LudingParams& lp) {
  Packing pk = start;
  const std::size_t n = pk.r.size();
  std::vector<double> vx(n, 0.0), vy(n, 0.0);
  const double t0 = wall_now();
  double area = 0.0;
  for (double r : pk.r) area += std::numbers::pi * r * r;
  // (a) affine compression of the gas: strain 0.2 % per 200-step chunk, velocities zeroed after
  //     each chunk, up to solid fraction 0.70
  std::size_t steps = 0;
  while (area / (pk.box.x_max * pk.box.y_max) < 0.70) {
    const double f = 0.998;
    for (std::size_t i = 0; i < n; ++i) {
      pk.x[i] *= f;
      pk.y[i] *= f;
    }
    pk.box.x_max *= f;
    pk.box.y_max *= f;
    std::fill(vx.begin(), vx.end(), 0.0);
    std::fill(vy.begin(), vy.end(), 0.0);
    run_stage(pk, vx, vy, lp, 200, 0.0);
    steps += 200;
  }
  std::fprintf(stderr, "  prepare N=%zu: affine compression to nu = %.4f in %zu steps (%.0f s)\n",
               n, area / (pk.box.x_max * pk.box.y_max), steps, wall_now() - t0);
  // (b) stress-controlled right/top walls; gamma_w = p L / (0.5 m/s) keeps the wall speed below
  //     0.5 m/s at every N; one solver, checked every 2000 steps
  Box box(pk.box);
  for (MovingWall* w : {&box.right, &box.top}) {
    w->mode = WallMode::Stress;
    w->pressure = kPressure;
    w->mass = 0.01;
    w->damping = kPressure * pk.box.x_max / 0.5;
  }
  DynamicOptions o;
  o.threads = g_threads;
  o.model = ContactModel::Linear;
  o.dt = scene_dt(lp);
  o.skin = kSkin;
  DynamicSolver s(particles_from(pk, lp), lp, box, o);
  double nu_prev = s.density();
  for (int chunk = 0; chunk < 100; ++chunk) {
    s.run(2000);
    steps += 2000;
    const Stress2 ws = s.wall_stress();
    const double nu = s.density(), ek = s.energies().kinetic / static_cast<double>(n);
    std::fprintf(stderr,
                 "  prepare N=%zu: %zu steps, nu = %.5f, sxx/p = %.4f, syy/p = %.4f, "
                 "Ekin/N = %.2e J (%.0f s)\n",
                 n, steps, nu, ws.xx / kPressure, ws.yy / kPressure, ek, wall_now() - t0);
    const bool done = std::fabs(ws.xx / kPressure - 1.0) < 0.01 &&
                      std::fabs(ws.yy / kPressure - 1.0) < 0.01 &&
                      std::fabs(nu - nu_prev) < 2e-5 && ek < 1e-9;
    nu_prev = nu;
    if (done) break;
  }
  const Particles& q = s.particles();
  pk.x = q.axis(0);
  pk.y = q.axis(1);
  pk.box = s.box();
  return pk;
}

/// LAMMPS data file (atom_style sphere: id type diameter density x y z). The density column is
/// a placeholder: the LAMMPS input sets mass = rho pi r^2 h per atom as params.in/prep.in do.
void write_lammps_data(const fs::path& f, const Packing& pk) {
  std::ofstream o(f);
  char buf[256];
  o << "LAMMPS data file written by netdem bench_dem (walls at the box faces)\n\n";
  o << pk.r.size() << " atoms\n1 atom types\n\n";
  std::snprintf(buf, sizeof buf,
                "%.17g %.17g xlo xhi\n%.17g %.17g ylo yhi\n-0.001 0.001 zlo zhi\n\n"
                "Atoms # sphere\n\n",
                pk.box.x_min, pk.box.x_max, pk.box.y_min, pk.box.y_max);
  o << buf;
  for (std::size_t i = 0; i < pk.r.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%zu 1 %.17g 1.0 %.17g %.17g 0.0\n", i + 1, 2.0 * pk.r[i],
                  pk.x[i], pk.y[i]);
    o << buf;
  }
}

Packing get_packing(int n, std::uint64_t seed, const fs::path& cache) {
  const fs::path f = cache / ("pack_N" + std::to_string(n) + "_s" + std::to_string(seed) + ".csv");
  if (fs::exists(f)) return netdem::packing::read_packing_csv(f);
  Packing pk;
  const LudingParams lp = linear_params();
  const double t0 = cpu_now();
  pk = compress(place(n, seed, lp), lp);
  std::fprintf(stderr, "  prepared N=%d in %.1f s CPU -> %s\n", n, cpu_now() - t0, f.c_str());
  fs::create_directories(cache);
  pk.seed = seed;
  pk.comments = {"bench_dem packing N " + std::to_string(n) + " (SI units, m)"};
  netdem::packing::write_packing_csv(pk, f);
  return pk;
}

struct Row {
  int n = 0;
  std::string model;
  std::size_t steps = 0, rebuilds = 0, table = 0, contacts = 0;
  double cpu = 0, wall = 0, nu = 0, sxx = 0, syy = 0;
};

Row time_model(const Packing& pk, const std::string& model, std::size_t warm, std::size_t steps) {
  LudingParams lp;  // Table 1 (full law)
  DynamicOptions o;
  o.threads = g_threads;
  if (model == "linear") {
    lp = linear_params();
    o.model = ContactModel::Linear;
  } else if (model == "full") {
    o.model = ContactModel::Full;  // Table 1: k1 = k2/2, k_c = k2/2, 80 deg C constant
    lp.T_radius_ref = 80.0;        // the packing's radii are a(80 deg C) (Eq 9): no shrinkage
  } else if (model == "full_linparams") {
    lp = linear_params();
    lp.T_radius_ref = 80.0;
    o.model = ContactModel::Full;  // the general code on the linear parameters (no specialisation)
  } else {
    throw std::invalid_argument("unknown model " + model);
  }
  o.dt = scene_dt(linear_params());
  o.skin = kSkin;
  o.temperature = 80.0;
  DynamicSolver s(particles_from(pk, lp), lp, Box(pk.box), o);
  s.run(warm);
  const std::size_t b0 = s.rebuilds();
  const double c0 = cpu_now(), w0 = wall_now();
  s.run(steps);
  Row r;
  r.cpu = cpu_now() - c0;
  r.wall = wall_now() - w0;
  r.n = static_cast<int>(pk.r.size());
  r.model = model;
  r.steps = steps;
  r.rebuilds = s.rebuilds() - b0;
  r.table = s.table_size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  s.touching_pairs(pairs);
  r.contacts = pairs.size();
  r.nu = s.density();
  const Stress2 cs = s.contact_stress();
  r.sxx = cs.xx;
  r.syy = cs.yy;
  return r;
}

// ---------------------------------------------------------------------------------------------
// 3D (--dim 3, issue 16): DynamicSolver3 on a dense, jammed, polydisperse, frictional packing of
// spheres in a box with six frictionless walls. See the comment at the top of the file.

constexpr double kDeposit3Density = 0.56;  // expected solid fraction of the deposition (box size)
constexpr double kPressure3 = 4.0e4;       // Pa: a mean contact force of ~0.2 N, delta/a0 ~ 1e-3 (as 2D)
constexpr double kRate3 = 50.0;            // 1/s: strain rate of the affine compression
constexpr double kDrag3 = 2.0e3;           // 1/s: global viscous drag of the preparation
constexpr double kWallRate3 = 25.0;        // 1/s: stress-controlled walls: gamma_w = p A / (rate L)
constexpr std::size_t kSettleDragSteps3 = 2000, kSettleFreeSteps3 = 2000;
// The preparation's step: kPrepDtFactor3 x the scene's dt, on spheres of equal mass (below), i.e.
// t_c/7 of every pair's mass; velocity Verlet is stable to about t_c/1.6 for one contact and
// t_c/(1.6 sqrt(z)) for z equal contacts on one sphere. Checked against a floor of 6 steps.
constexpr double kPrepDtFactor3 = 50.0 / 7.0;
constexpr double kPrepMinStepsPerContact = 6.0;

/// The preparation's spheres: every one with the mass of an a0 sphere (rho (a0/r)^3), so that the
/// lightest pair is the pair dt is set for and the preparation's steps can be longer. Only the
/// static end state is kept; the timed runs use m = rho 4/3 pi r^3.
Particles3 equal_mass_spheres(const Packing& pk, const LudingParams& lp) {
  Particles3 P;
  for (std::size_t i = 0; i < pk.size(); ++i) {
    const double s = lp.a0 / pk.r[i];
    P.add_sphere(pk.x[i], pk.y[i], pk.z[i], pk.r[i], lp.rho_p * s * s * s);
  }
  return P;
}

/// dt of the 3D scene: t_c/50 of a pair of two a0 spheres (LMM05 Eq 6 with sphere masses).
double scene_dt3(const LudingParams& p) {
  const double m0 = p.rho_p * (4.0 / 3.0) * std::numbers::pi * p.a0 * p.a0 * p.a0;
  return contact_duration(p.k2, p.gamma_n, 0.5 * m0) / 50.0;
}

std::uint64_t morton3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::uint64_t m = 0;
  for (int k = 0; k < 21; ++k)
    m |= (static_cast<std::uint64_t>((a >> k) & 1u) << (3 * k)) |
         (static_cast<std::uint64_t>((b >> k) & 1u) << (3 * k + 1)) |
         (static_cast<std::uint64_t>((c >> k) & 1u) << (3 * k + 2));
  return m;
}

/// Ballistic deposition (ballistic3d.hpp) of at least n spheres with radii uniform in
/// a0 [1 - w0, 1 + w0], the first n in deposition order, the lid lowered onto the highest one,
/// renumbered in Morton order of a grid of cell a_max. Prints the deposition's CPU time.
Packing deposit3(int n, std::uint64_t seed, const LudingParams& lp) {
  const double r3 = (std::pow(1.0 + lp.w0, 4) - std::pow(1.0 - lp.w0, 4)) / (8.0 * lp.w0);  // <(r/a0)^3>
  const double vol = static_cast<double>(n) * (4.0 / 3.0) * std::numbers::pi * r3 / kDeposit3Density;
  netdem::packing::Deposition3dOptions o;
  o.radius = lp.a0;
  o.r_min = 1.0 - lp.w0;
  o.r_max = 1.0 + lp.w0;
  o.seed = seed;
  o.width = std::cbrt(vol);
  o.height = 1.15 * o.width;
  netdem::packing::Packing dep;
  for (int attempt = 0;; ++attempt) {
    const double c0 = cpu_now();
    dep = netdem::packing::ballistic_deposition_3d(o);
    std::fprintf(stderr, "  prepare N=%d: deposition of %zu spheres (W = %.2f a0, H = %.2f a0) in %.2f s CPU\n", n,
                 dep.size(), o.width, o.box_height(), cpu_now() - c0);
    if (dep.size() >= static_cast<std::size_t>(n)) break;
    if (attempt == 5) throw std::runtime_error("deposit3: too few spheres deposited");
    o.height *= 1.2 * static_cast<double>(n) / static_cast<double>(dep.size());
  }
  const std::size_t m = static_cast<std::size_t>(n);
  double rmax = 0.0, top = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    rmax = std::max(rmax, dep.r[i]);
    top = std::max(top, dep.z[i] + dep.r[i]);
  }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> key(m);
  for (std::size_t i = 0; i < m; ++i)
    key[i] = {morton3(static_cast<std::uint32_t>(dep.x[i] / rmax), static_cast<std::uint32_t>(dep.y[i] / rmax),
                      static_cast<std::uint32_t>(dep.z[i] / rmax)),
              static_cast<std::uint32_t>(i)};
  std::sort(key.begin(), key.end());
  Packing pk;
  pk.dim = 3;
  pk.box = dep.box;
  pk.box.z_max = top;  // the lid on the highest sphere
  for (const auto& [k, i] : key) {
    pk.x.push_back(dep.x[i]);
    pk.y.push_back(dep.y[i]);
    pk.z.push_back(dep.z[i]);
    pk.r.push_back(dep.r[i]);
  }
  return pk;
}

/// The 3D preparation (prints progress on stderr): the deposition, then with the linear law
/// (walls frictionless) and a global viscous drag -c m v, -c I w (c = kDrag3), on spheres of equal
/// mass (equal_mass_spheres) with kPrepDtFactor3 x the scene's step (only the static end state is
/// kept: the path need not be the real masses' dynamics), FRICTIONLESS first (mu = 0: the packing
/// reaches a dense jammed state quickly). The stages' lengths are physical times (chunk_steps:
/// the time of 1000 scene steps):
/// (a) affine isotropic compression at the strain rate kRate3 (right, back and top walls Affine)
///     until the mean contact stress exceeds p/4 (p = kPressure3) at nu > 0.58, or nu >= 0.68;
/// (b) stress-controlled right, back and top walls (Eq 1, p, m_w = 0.01 kg, gamma_w = p A /
///     (kWallRate3 L), L the cube root of the box volume: the walls move at most at a strain rate
///     of kWallRate3) in chunks until the three wall stresses are within 5 % of p and the density
///     changed by < 2e-4 over a chunk (at most the time of 30 chunks of 1000 scene steps);
/// (c) friction on (mu = 0.5), 3 more chunks of (b);
/// (d) the walls fixed where they are, kSettleDragSteps3 scene steps' time with the drag,
///     kSettleFreeSteps3 without.
Packing prepare3(int n, std::uint64_t seed, const LudingParams& lp) {
  Packing pk = deposit3(n, seed, lp);
  DynamicOptions o;
  o.threads = g_threads;
  o.model = ContactModel::Linear;
  o.dt = kPrepDtFactor3 * scene_dt3(lp);
  o.skin = kSkin;
  o.affine_drag = kDrag3;
  o.min_steps_per_contact = kPrepMinStepsPerContact;
  Box box(pk.box);
  for (MovingWall* w : {&box.right, &box.back, &box.top}) w->mode = WallMode::Affine;
  const double c0 = cpu_now();
  LudingParams lp0 = lp;
  lp0.mu = 0.0;
  DynamicSolver3 s(equal_mass_spheres(pk, lp), lp0, box, o);
  std::size_t steps = 0;
  auto report = [&](const char* what) {
    const Stress3 cs = s.contact_stress(), ws = s.wall_stress();
    std::fprintf(stderr,
                 "  prepare N=%d: %s, %zu steps: nu = %.5f, contact stress %.4g Pa, walls/p %.4f %.4f %.4f, "
                 "Ekin/N = %.2e J (%.0f s CPU)\n",
                 n, what, steps, s.density(), (cs.s[0][0] + cs.s[1][1] + cs.s[2][2]) / 3.0, ws.s[0][0] / kPressure3,
                 ws.s[1][1] / kPressure3, ws.s[2][2] / kPressure3, s.energies().kinetic / static_cast<double>(n),
                 cpu_now() - c0);
  };
  // (a)
  s.set_strain_rate3(-kRate3, -kRate3, -kRate3);
  const auto probe_steps = static_cast<std::size_t>(std::lround(200.0 / kPrepDtFactor3));
  for (int chunk = 0;; ++chunk) {
    s.run(probe_steps);
    steps += probe_steps;
    const Stress3 cs = s.contact_stress();
    const double pc = (cs.s[0][0] + cs.s[1][1] + cs.s[2][2]) / 3.0;
    if (chunk % 10 == 9) report("affine compression");
    if ((pc > 0.25 * kPressure3 && s.density() > 0.58) || s.density() >= 0.68) break;
    if (chunk > 2000) throw std::runtime_error("prepare3: the affine compression did not jam");
  }
  report("affine compression done");
  // (b)
  s.set_strain_rate3(0.0, 0.0, 0.0);
  const Box& bx = s.box();
  const double ex = bx.x_max - bx.x_min, ey = bx.y_max - bx.y_min, ez = bx.z_max - bx.z_min;
  MovingWall w[3];
  const double area[3] = {ey * ez, ex * ez, ex * ey};
  for (int a = 0; a < 3; ++a) {
    w[a].mode = WallMode::Stress;
    w[a].pressure = kPressure3;
    w[a].mass = 0.01;
    w[a].damping = kPressure3 * area[a] / (kWallRate3 * std::cbrt(ex * ey * ez));
  }
  s.set_walls(w[0], w[1], w[2]);
  double nu_prev = s.density();
  const auto chunk_steps = static_cast<std::size_t>(std::lround(1000.0 / kPrepDtFactor3));
  for (int chunk = 0; chunk < 30 * kPrepDtFactor3; ++chunk) {
    s.run(chunk_steps);
    steps += chunk_steps;
    report("stress-controlled walls, mu = 0");
    const Stress3 ws = s.wall_stress();
    const double nu = s.density();
    bool done = std::fabs(nu - nu_prev) < 2e-4;
    for (int a = 0; a < 3; ++a) done = done && std::fabs(ws.s[a][a] / kPressure3 - 1.0) < 0.05;
    nu_prev = nu;
    if (done) break;
  }
  // (c)
  s.set_params(lp);
  for (int chunk = 0; chunk < 3; ++chunk) {
    s.run(chunk_steps);
    steps += chunk_steps;
    report("stress-controlled walls, mu = 0.5");
  }
  // (d)
  const MovingWall fixed;
  s.set_walls(fixed, fixed, fixed);
  s.run(kSettleDragSteps3 * chunk_steps / 1000);
  steps += kSettleDragSteps3 * chunk_steps / 1000;
  report("walls fixed, drag");
  s.set_affine_drag(0.0);
  s.run(kSettleFreeSteps3 * chunk_steps / 1000);
  steps += kSettleFreeSteps3 * chunk_steps / 1000;
  report("settled (walls fixed, no drag)");
  const Particles3& q = s.particles();
  pk.x = q.axis(0);
  pk.y = q.axis(1);
  pk.z = q.axis(2);
  pk.box = s.box();
  return pk;
}

/// The 3D cache file: "# box x_min y_min z_min x_max y_max z_max", then "x y z r" per sphere (m, %.17g).
void write_cache3(const fs::path& f, const Packing& pk) {
  const fs::path tmp = f.string() + ".tmp";
  {
    std::ofstream o(tmp);
    char buf[256];
    std::snprintf(buf, sizeof buf, "# box %.17g %.17g %.17g %.17g %.17g %.17g\n", pk.box.x_min, pk.box.y_min,
                  pk.box.z_min, pk.box.x_max, pk.box.y_max, pk.box.z_max);
    o << "# bench_dem 3D packing (SI units, m): x y z r\n" << buf;
    for (std::size_t i = 0; i < pk.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g %.17g\n", pk.x[i], pk.y[i], pk.z[i], pk.r[i]);
      o << buf;
    }
    if (!o) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, f);
}

Packing read_cache3(const fs::path& f) {
  std::ifstream in(f);
  Packing pk;
  pk.dim = 3;
  std::string line;
  bool box = false;
  while (std::getline(in, line)) {
    if (line.rfind("# box ", 0) == 0) {
      std::istringstream s(line.substr(6));
      s >> pk.box.x_min >> pk.box.y_min >> pk.box.z_min >> pk.box.x_max >> pk.box.y_max >> pk.box.z_max;
      box = static_cast<bool>(s);
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    double x, y, z, r;
    if (!(s >> x >> y >> z >> r) || !std::isfinite(x + y + z + r) || !(r > 0.0))
      throw std::runtime_error(f.string() + ": bad sphere line: " + line.substr(0, 80));
    pk.x.push_back(x);
    pk.y.push_back(y);
    pk.z.push_back(z);
    pk.r.push_back(r);
  }
  if (!box || pk.size() == 0) throw std::runtime_error(f.string() + ": no box line or no spheres");
  return pk;
}

Packing get_packing3(int n, std::uint64_t seed, const fs::path& cache) {
  const fs::path f = cache / ("pack3d_N" + std::to_string(n) + "_s" + std::to_string(seed) + "_v2.txt");
  if (fs::exists(f)) return read_cache3(f);
  const double t0 = cpu_now();
  const Packing pk = prepare3(n, seed, linear_params());
  std::fprintf(stderr, "  prepared N=%d in %.1f s CPU -> %s\n", n, cpu_now() - t0, f.c_str());
  fs::create_directories(cache);
  write_cache3(f, pk);
  return pk;
}

/// LAMMPS data file, 3D (atom_style sphere: id type diameter density x y z; the LAMMPS input sets
/// mass = rho 4/3 pi r^3 with `set density`).
void write_lammps_data3(const fs::path& f, const Packing& pk) {
  std::ofstream o(f);
  char buf[256];
  o << "LAMMPS data file written by netdem bench_dem --dim 3 (walls at the box faces)\n\n";
  o << pk.r.size() << " atoms\n1 atom types\n\n";
  std::snprintf(buf, sizeof buf, "%.17g %.17g xlo xhi\n%.17g %.17g ylo yhi\n%.17g %.17g zlo zhi\n\nAtoms # sphere\n\n",
                pk.box.x_min, pk.box.x_max, pk.box.y_min, pk.box.y_max, pk.box.z_min, pk.box.z_max);
  o << buf;
  for (std::size_t i = 0; i < pk.r.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%zu 1 %.17g 2000.0 %.17g %.17g %.17g\n", i + 1, 2.0 * pk.r[i], pk.x[i],
                  pk.y[i], pk.z[i]);
    o << buf;
  }
}

struct Row3 {
  int n = 0;
  std::string model;
  std::size_t steps = 0, rebuilds = 0, table = 0, contacts = 0, wall_contacts = 0;
  double cpu = 0, wall = 0, nu = 0, s[3] = {0, 0, 0}, ekin = 0;
  DynamicSolver3::MemoryUse mem;
  double rss_mb = 0;
};

/// The resident set of this process [MB] (/proc/self/status VmRSS; 0 where unavailable).
double rss_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  return 0.0;
}

Row3 time_model3(const Packing& pk, const std::string& model, std::size_t warm, std::size_t steps) {
  LudingParams lp;  // Table 1 (full law)
  DynamicOptions o;
  o.threads = g_threads;
  if (model == "linear") {
    lp = linear_params();
    o.model = ContactModel::Linear;
  } else if (model == "full") {
    o.model = ContactModel::Full;  // Table 1: k1 = k2/2, k_c = k2/2, 80 deg C constant
    lp.T_radius_ref = 80.0;
  } else if (model == "full_linparams") {
    lp = linear_params();
    lp.T_radius_ref = 80.0;
    o.model = ContactModel::Full;
  } else {
    throw std::invalid_argument("unknown model " + model);
  }
  o.dt = scene_dt3(linear_params());
  o.skin = kSkin;
  o.temperature = 80.0;
  DynamicSolver3 s(spheres_from(pk, lp.rho_p), lp, Box(pk.box), o);
  s.run(warm);
  const std::size_t b0 = s.rebuilds();
  const double c0 = cpu_now(), w0 = wall_now();
  s.run(steps);
  Row3 r;
  r.cpu = cpu_now() - c0;
  r.wall = wall_now() - w0;
  r.n = static_cast<int>(pk.r.size());
  r.model = model;
  r.steps = steps;
  r.rebuilds = s.rebuilds() - b0;
  r.table = s.table_size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  s.touching_pairs(pairs);
  r.contacts = pairs.size();
  r.wall_contacts = s.wall_contacts();
  r.nu = s.density();
  const Stress3 cs = s.contact_stress();
  for (int a = 0; a < 3; ++a) r.s[a] = cs.s[a][a];
  r.ekin = s.energies().kinetic;
  r.mem = s.memory_use();
  r.rss_mb = rss_mb();
  return r;
}

int run3(const std::vector<int>& ns, const std::vector<std::string>& models, double psteps, std::size_t min_steps,
         std::size_t warm, int reps, std::uint64_t seed, const fs::path& cache, const fs::path& lammps_dir) {
  std::printf(
      "N,model,rep,steps,cpu_s,wall_s,psteps_per_cpu_s,psteps_per_wall_s,rebuilds,"
      "table_per_particle,contacts_per_particle,wall_contacts,nu,sxx_Pa,syy_Pa,szz_Pa,ekin_J,"
      "heap_B_per_particle,heap_B_per_row,search_B_per_particle,rss_MB\n");
  std::fflush(stdout);
  for (int n : ns) {
    const Packing pk = get_packing3(n, seed, cache);
    if (!lammps_dir.empty()) {
      fs::create_directories(lammps_dir);
      write_lammps_data3(lammps_dir / ("pack3d_N" + std::to_string(n) + ".data"), pk);
    }
    const std::size_t steps = std::max(min_steps, static_cast<std::size_t>(psteps / static_cast<double>(n)));
    for (int rep = 1; rep <= reps; ++rep)
      for (const auto& m : models) {
        if (m == "none") continue;
        const Row3 r = time_model3(pk, m, warm, steps);
        const double ps = static_cast<double>(r.n) * static_cast<double>(r.steps);
        const double nd = r.n;
        std::printf("%d,%s,%d,%zu,%.4f,%.4f,%.6g,%.6g,%zu,%.4f,%.4f,%zu,%.5f,%.6g,%.6g,%.6g,%.4g,%.1f,%.1f,%.1f,%.1f\n",
                    r.n, r.model.c_str(), rep, r.steps, r.cpu, r.wall, ps / r.cpu, ps / r.wall, r.rebuilds,
                    static_cast<double>(r.table) / nd, 2.0 * static_cast<double>(r.contacts) / nd, r.wall_contacts,
                    r.nu, r.s[0], r.s[1], r.s[2], r.ekin, static_cast<double>(r.mem.particles) / nd,
                    static_cast<double>(r.mem.rows) / static_cast<double>(r.table),
                    static_cast<double>(r.mem.search) / nd, r.rss_mb);
        std::fflush(stdout);
      }
  }
  return 0;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> v;
  std::stringstream ss(s);
  std::string t;
  while (std::getline(ss, t, ','))
    if (!t.empty()) v.push_back(t);
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> ns = {300, 3000, 30000};
  std::vector<std::string> models = {"linear", "full"};
  double psteps = 3e7;
  std::size_t min_steps = 200, warm = 1000;
  int reps = 1;
  std::uint64_t seed = 1;
  fs::path cache = "dem_packings", lammps_dir;
  int dim = 2;
  bool ns_given = false, psteps_given = false, warm_given = false;
  try {
    for (int k = 1; k < argc; ++k) {
      const std::string a = argv[k];
      auto val = [&]() -> std::string {
        if (k + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++k];
      };
      if (a == "--dim") {
        dim = std::stoi(val());
        if (dim != 2 && dim != 3) throw std::invalid_argument("--dim must be 2 or 3");
      } else if (a == "--n") {
        ns_given = true;
        ns.clear();
        for (const auto& t : split(val())) ns.push_back(std::stoi(t));
      } else if (a == "--models") {
        models = split(val());
      } else if (a == "--psteps") {
        psteps = std::stod(val());
        psteps_given = true;
      } else if (a == "--min-steps") {
        min_steps = std::stoul(val());
      } else if (a == "--warmup") {
        warm = std::stoul(val());
        warm_given = true;
      } else if (a == "--reps") {
        reps = std::stoi(val());
      } else if (a == "--seed") {
        seed = std::stoull(val());
      } else if (a == "--threads") {
        g_threads = std::stoi(val());
      } else if (a == "--cache") {
        cache = val();
      } else if (a == "--lammps-data") {
        lammps_dir = val();
      } else if (a == "--help" || a == "-h") {
        std::printf(
            "bench_dem [--dim 2|3] [--n 300,3000,30000] [--models linear,full[,full_linparams]]\n"
            "          [--psteps 3e7] [--min-steps 200] [--warmup 1000] [--reps 1] [--seed 1]\n"
            "          [--cache DIR] [--lammps-data DIR] [--threads 1]\n"
            "--dim 3: spheres; defaults --n 10000,100000 --psteps 2e7 --warmup 300\n"
            "(see the comment at the top of bench/bench_dem.cpp)\n");
        return 0;
      } else {
        throw std::invalid_argument("unknown option " + a);
      }
    }
    if (dim == 3) {
      if (!ns_given) ns = {10000, 100000};
      if (!psteps_given) psteps = 2e7;
      if (!warm_given) warm = 300;
      return run3(ns, models, psteps, min_steps, warm, reps, seed, cache, lammps_dir);
    }
    std::printf(
        "N,model,rep,steps,cpu_s,wall_s,psteps_per_cpu_s,psteps_per_wall_s,rebuilds,"
        "table_per_particle,contacts_per_particle,nu,sxx_N_per_m,syy_N_per_m\n");
    std::fflush(stdout);
    for (int n : ns) {
      const Packing pk = get_packing(n, seed, cache);
      if (!lammps_dir.empty()) {
        fs::create_directories(lammps_dir);
        write_lammps_data(lammps_dir / ("pack_N" + std::to_string(n) + ".data"), pk);
      }
      const std::size_t steps =
          std::max(min_steps, static_cast<std::size_t>(psteps / static_cast<double>(n)));
      for (int rep = 1; rep <= reps; ++rep)
        for (const auto& m : models) {
          if (m == "none") continue;
          const Row r = time_model(pk, m, warm, steps);
          const double ps = static_cast<double>(r.n) * static_cast<double>(r.steps);
          std::printf("%d,%s,%d,%zu,%.4f,%.4f,%.6g,%.6g,%zu,%.4f,%.4f,%.5f,%.4f,%.4f\n", r.n,
                      r.model.c_str(), rep, r.steps, r.cpu, r.wall, ps / r.cpu, ps / r.wall,
                      r.rebuilds, static_cast<double>(r.table) / r.n,
                      2.0 * static_cast<double>(r.contacts) / r.n, r.nu, r.sxx, r.syy);
          std::fflush(stdout);
        }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_dem: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
