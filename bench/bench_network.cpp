// One compaction increment of the quasi-static network solver (netdem::qs::NetworkSolver) on
// deposited packings W = 40, 80, 160 R (r in [0.9, 1.1] R, seed 1, lid = centre), default
// SolverOptions = `netsolve compact` defaults (die mode, sticking, max 4 Newton iterations,
// viscosity 0.1), hydrostatic path with the strain increment of a 100-increment run to D = 0.85.
//
// Per benchmark: the solver is constructed and kWarmup increments are run OUTSIDE the timed loop,
// then each timed iteration is ONE increment (fixed kTimed iterations, so every W is measured on
// the same part of the compaction, increments kWarmup+1 .. kWarmup+kTimed of 100). Counters are
// per increment, from the deltas of NetworkSolver::timings() over the timed increments:
//   assemble_ms, analyse_ms, factorise_ms, solve_ms (CHOLMOD split; solve includes GMRES),
//   other_ms = wall - (assemble + analyse + factorise + solve + neighbours), newton_it, gmres_it,
//   wall_ms and cpu_ms (process CPU time; the split above is steady_clock wall time, so on a loaded
//   machine compare wall_ms with cpu_ms before trusting it),
//   converged (fraction of increments whose Newton iteration met the tolerance).
// BM_network_construct times the constructor (neighbour list, pattern, first analysis).
#include <benchmark/benchmark.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <exception>
#include <map>
#include <memory>

#include <Eigen/Core>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"

namespace np = netdem::packing;
namespace qs = netdem::qs;

namespace {

constexpr int kIncrementsToTarget = 100;
constexpr int kWarmup = 5;
constexpr int kTimed = 20;
constexpr double kTarget = 0.85;

const np::Packing& packing(int width) {
  static std::map<int, np::Packing> cache;
  auto it = cache.find(width);
  if (it == cache.end()) {
    np::DepositionOptions o;
    o.width = width;
    o.r_min = 0.9;
    o.r_max = 1.1;
    o.seed = 1;
    o.lid = np::Lid::Centre;
    it = cache.emplace(width, np::ballistic_deposition(o)).first;
  }
  return it->second;
}

Eigen::Matrix2d strain_increment(double d0) {
  const Eigen::Matrix2d rate = qs::StrainPath::hydrostatic().rate();
  return rate * (std::log(d0 / kTarget) / rate.trace()) / kIncrementsToTarget;
}

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void BM_network_construct(benchmark::State& state) {
  const np::Packing& pk = packing(static_cast<int>(state.range(0)));
  const qs::SolverOptions so;
  for (auto _ : state) {
    auto solver = std::make_unique<qs::NetworkSolver>(pk, so);
    benchmark::DoNotOptimize(solver.get());
  }
  state.counters["particles"] = static_cast<double>(pk.size());
}

void BM_network_increment(benchmark::State& state) {
  const np::Packing& pk = packing(static_cast<int>(state.range(0)));
  const qs::SolverOptions so;
  const Eigen::Matrix2d dE = strain_increment(pk.density());
  std::unique_ptr<qs::NetworkSolver> solver;
  try {
    solver = std::make_unique<qs::NetworkSolver>(pk, so);
    for (int k = 0; k < kWarmup; ++k) solver->increment(dE);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const qs::SolverTimings t0 = solver->timings();
  long newton = 0, gmres = 0, converged = 0, n = 0;
  double wall = 0.0;
  const double cpu0 = process_cpu_seconds();
  for (auto _ : state) {
    const auto a = std::chrono::steady_clock::now();
    try {
      const qs::IncrementReport r = solver->increment(dE);
      newton += r.newton_iterations;
      gmres += r.linear_iterations;
      converged += r.converged ? 1 : 0;
    } catch (const std::exception& e) {
      state.SkipWithError(e.what());
      break;
    }
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
    ++n;
  }
  const double cpu = process_cpu_seconds() - cpu0;
  if (n == 0) return;
  const qs::SolverTimings& t1 = solver->timings();
  const double inv = 1.0 / static_cast<double>(n);
  const double asm_s = t1.assemble - t0.assemble, ana = t1.analyse - t0.analyse;
  const double fac = t1.factorise - t0.factorise, sol = t1.solve - t0.solve;
  const double nbr = t1.neighbours - t0.neighbours;
  state.counters["particles"] = static_cast<double>(pk.size());
  state.counters["free_dofs"] = solver->free_dofs();
  state.counters["wall_ms"] = 1e3 * wall * inv;
  state.counters["cpu_ms"] = 1e3 * cpu * inv;
  state.counters["assemble_ms"] = 1e3 * asm_s * inv;
  state.counters["analyse_ms"] = 1e3 * ana * inv;
  state.counters["factorise_ms"] = 1e3 * fac * inv;
  state.counters["solve_ms"] = 1e3 * sol * inv;
  state.counters["neighbours_ms"] = 1e3 * nbr * inv;
  state.counters["other_ms"] = 1e3 * (wall - asm_s - ana - fac - sol - nbr) * inv;
  state.counters["factorisations"] = static_cast<double>(t1.factorisations - t0.factorisations) * inv;
  state.counters["newton_it"] = static_cast<double>(newton) * inv;
  state.counters["gmres_it"] = static_cast<double>(gmres) * inv;
  state.counters["converged"] = static_cast<double>(converged) * inv;
  state.counters["D"] = solver->measures().density;
}

}  // namespace

BENCHMARK(BM_network_construct)->ArgName("W")->Arg(40)->Arg(80)->Arg(160)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_network_increment)
    ->ArgName("W")
    ->Arg(40)
    ->Arg(80)
    ->Arg(160)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(kTimed)
    ->MeasureProcessCPUTime();

BENCHMARK_MAIN();
