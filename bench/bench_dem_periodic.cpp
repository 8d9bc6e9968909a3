// bench_dem_periodic: what the periodic cell costs the explicit DEM per particle-step (issue 29,
// "Speed": at most 10 % against the walled DEM). Plain executable, CSV on stdout, own timing loop
// (CPU time of this thread), as bench_dem.
//
//   bench_dem_periodic [--dim 2|3] [--n 4000] [--psteps 2e7] [--min-steps 200] [--reps 3] [--seed 1]
//                      [--mode both|walls|periodic] [--packing-cache FILE]
// (--mode walls or periodic times one mode only: for a profiler's counts of one loop.
// --packing-cache reads the packing from FILE if it exists, else makes it and writes it there:
// the packing route is most of a run's time, and a profile of the timed loop should not see it.)
//
// Scene: one jammed periodic packing of the periodic route (make_periodic_packing: r = R[0.9, 1.1],
// frictionless linear law, p / k_n = 1e-4), particles in the order of its random sequential
// addition (no spatial sort: "deposition order"). The same particles are timed twice, with the
// packing route's linear law (k_n = 1, 0.3 of critical damping) and friction mu = 0.5:
//   walls:    the cell's particles in a box with fixed frictionless walls r_max outside the cell
//             (no particle touches a wall at the start; the contacts across the cell's faces are
//             missing, about 2 sqrt(N) of them);
//   periodic: the same particles in the periodic cell (the contacts across the faces through the
//             images, the branch vectors with the image shift).
// Both are compressed isotropically, untimed over 3 x steps (steps = max(min_steps, psteps / N)) by
// 3 % of strain plus, for the walls, the strain ln((L + 2 r_max) / L) that closes their gap, so
// that both reach the same state of the particles; then by 1 % more over the timed `steps`, at the
// same rate. Each rep times walls and periodic in alternating order (ABBA...), each on a fresh
// solver.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "netdem/dynamic/periodic_packing.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/io.hpp"

using namespace netdem::dem;
namespace packing = netdem::packing;

namespace {

double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Args {
  int dim = 2;
  std::size_t n = 4000;
  double psteps = 2e7;
  int min_steps = 200, reps = 3;
  std::uint64_t seed = 1;
  std::string mode = "both";
  std::string cache;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int k = 1; k < argc; ++k) {
    const std::string o = argv[k];
    if (k + 1 >= argc) throw std::invalid_argument(o + " needs a value");
    const std::string v = argv[++k];
    if (o == "--dim") a.dim = std::stoi(v);
    else if (o == "--n") a.n = std::stoul(v);
    else if (o == "--psteps") a.psteps = std::stod(v);
    else if (o == "--min-steps") a.min_steps = std::stoi(v);
    else if (o == "--reps") a.reps = std::stoi(v);
    else if (o == "--seed") a.seed = std::stoull(v);
    else if (o == "--mode") a.mode = v;
    else if (o == "--packing-cache") a.cache = v;
    else throw std::invalid_argument("unknown option " + o);
  }
  if (a.dim != 2 && a.dim != 3) throw std::invalid_argument("--dim must be 2 or 3");
  if (a.mode != "both" && a.mode != "walls" && a.mode != "periodic")
    throw std::invalid_argument("--mode must be both, walls or periodic");
  if (a.n < 50 || a.reps < 1 || !(a.psteps > 0) || a.min_steps < 1)
    throw std::invalid_argument("need --n >= 50, --reps >= 1, --psteps > 0, --min-steps >= 1");
  return a;
}

template <int D>
LudingParams law(const packing::Packing& pk) {  // the periodic route's law, with friction 0.5
  double r_mean = 0.0;
  for (double r : pk.r) r_mean += r;
  return periodic_packing_law(D, r_mean / static_cast<double>(pk.size()), 0.5);
}

template <int D>
DynamicSolverT<D> make_solver(const packing::Packing& pk, bool periodic) {
  DynamicOptions opt;
  opt.model = ContactModel::Linear;
  opt.steps_per_contact = 25.0;
  if (periodic) return DynamicSolverT<D>(periodic_particles_from<D>(pk, 1.0), law<D>(pk), packing::periodic_cell<D>(pk), opt);
  packing::Packing w = pk;  // the same particles, not periodic, in a box r_max wider on every side
  w.periodic = false;
  w.cell.clear();
  const double rm = *std::max_element(pk.r.begin(), pk.r.end());
  w.box.x_min -= rm, w.box.y_min -= rm, w.box.x_max += rm, w.box.y_max += rm;
  if constexpr (D == 3) w.box.z_min -= rm, w.box.z_max += rm;
  ParticlesT<D> P = particles_at_rest<D>(w, 1.0);
  Box box(w.box);
  box.contact_walls = true;
  box.right.mode = box.top.mode = WallMode::Affine;
  if constexpr (D == 3) box.back.mode = WallMode::Affine;
  return DynamicSolverT<D>(std::move(P), law<D>(pk), box, opt);
}

template <int D>
void run(const Args& a) {
  PeriodicPackOptions po;
  po.n = a.n;
  po.seed = a.seed;
  PeriodicPackSummary ps;
  const bool cached = !a.cache.empty() && std::filesystem::exists(a.cache);
  const packing::Packing pk = cached ? packing::read_packing_csv(a.cache) : make_periodic_packing(D, po, ps, {});
  if (cached) {  // (a packing of another --dim or --n is refused; its density is the file's)
    if (pk.size() != a.n || pk.dim != D)
      throw std::invalid_argument("--packing-cache " + a.cache + " holds another packing (not " +
                                  std::to_string(D) + "D with " + std::to_string(a.n) + " particles)");
    ps.status = "cached";
    ps.density = pk.density();
  } else if (!a.cache.empty()) {
    packing::write_packing_csv(pk, a.cache);
  }
  const long steps = std::max<long>(a.min_steps, static_cast<long>(a.psteps / static_cast<double>(a.n)));
  std::printf(
      "dim,n,rep,mode,steps,cpu_s,particle_steps_per_cpu_s,contacts,table_builds,packing_density,packing_status\n");
  for (int rep = 0; rep < a.reps; ++rep) {
    for (int k = 0; k < 2; ++k) {
      const bool periodic = (k == 1) != (rep % 2 == 1);  // walls first in even reps
      if (a.mode != "both" && periodic != (a.mode == "periodic")) continue;
      DynamicSolverT<D> s = make_solver<D>(pk, periodic);
      auto set_rate = [&](double e) {
        if constexpr (D == 2)
          s.set_strain_rate(e, e);
        else
          s.set_strain_rate3(e, e, e);
      };
      const double L = pk.box.x_max - pk.box.x_min, rm = *std::max_element(pk.r.begin(), pk.r.end());
      const double pre = std::log(1.03) + (periodic ? 0.0 : std::log((L + 2.0 * rm) / L));
      set_rate(-pre / (3.0 * static_cast<double>(steps) * s.dt()));
      s.set_affine_velocities();
      for (long w = 0; w < 3 * steps; ++w) s.step();
      set_rate(-std::log(1.01) / (static_cast<double>(steps) * s.dt()));
      const std::size_t builds0 = s.rebuilds();
      const double t0 = cpu_now();
      for (long w = 0; w < steps; ++w) s.step();
      const double cpu = cpu_now() - t0;
      const std::size_t builds = s.rebuilds() - builds0;
      std::vector<ContactInfo> cs;
      s.contacts(cs);
      std::printf("%d,%zu,%d,%s,%ld,%.4f,%.5g,%zu,%zu,%.5f,%s\n", D, a.n, rep, periodic ? "periodic" : "walls", steps,
                  cpu, static_cast<double>(steps) * static_cast<double>(a.n) / cpu, cs.size(), builds, ps.density,
                  ps.status.c_str());
      std::fflush(stdout);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    if (a.dim == 2)
      run<2>(a);
    else
      run<3>(a);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_dem_periodic: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
