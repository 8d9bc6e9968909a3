// Ballistic deposition (src/packing, Redanz & Fleck section 2.2) at W = 80, 160, 320, 640 R:
// wall time per deposition and particles/s. Options as `netsolve pack` (r in [0.9, 1.1] R,
// seed 1, lid = centre, max_rejections 1000); square box.
// 3D (issue 16, ballistic3d.hpp): about 10^4 spheres in a cube W = H (walls, seed 1,
// max_rejections 1000), r in [0.9, 1.1] R (W = 43 R) and in [0.5, 1.5] R (W = 46 R, the radii of
// bench_dem --dim 3); time per deposition (process CPU) and spheres/s.
#include <benchmark/benchmark.h>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/ballistic3d.hpp"

namespace np = netdem::packing;

static void BM_ballistic_deposition(benchmark::State& state) {
  np::DepositionOptions o;
  o.width = static_cast<double>(state.range(0));
  o.r_min = 0.9;
  o.r_max = 1.1;
  o.seed = 1;
  o.lid = np::Lid::Centre;
  std::size_t n = 0;
  double density = 0.0;
  for (auto _ : state) {
    np::Packing pk = np::ballistic_deposition(o);
    n = pk.size();
    density = pk.density();
    benchmark::DoNotOptimize(pk.x.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
  state.counters["particles"] = static_cast<double>(n);
  state.counters["D0"] = density;
}

BENCHMARK(BM_ballistic_deposition)
    ->ArgName("W")
    ->Arg(80)
    ->Arg(160)
    ->Arg(320)
    ->Arg(640)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime();

static void BM_ballistic_deposition_3d(benchmark::State& state) {
  np::Deposition3dOptions o;
  o.width = static_cast<double>(state.range(0));
  o.r_min = 1.0 - 0.1 * static_cast<double>(state.range(1));
  o.r_max = 1.0 + 0.1 * static_cast<double>(state.range(1));
  o.seed = 1;
  std::size_t n = 0;
  double density = 0.0;
  for (auto _ : state) {
    np::Packing pk = np::ballistic_deposition_3d(o);
    n = pk.size();
    density = pk.density();
    benchmark::DoNotOptimize(pk.x.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
  state.counters["particles"] = static_cast<double>(n);
  state.counters["D0"] = density;
}

// args: W / R, half-width of the radius range in tenths of R (1: [0.9, 1.1]; 5: [0.5, 1.5])
BENCHMARK(BM_ballistic_deposition_3d)
    ->ArgNames({"W", "w10"})
    ->Args({43, 1})
    ->Args({46, 5})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime();

BENCHMARK_MAIN();
