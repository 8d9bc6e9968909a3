// Ballistic deposition (src/packing, Redanz & Fleck section 2.2) at W = 80, 160, 320, 640 R:
// wall time per deposition and particles/s. Options as `netsolve pack` (r in [0.9, 1.1] R,
// seed 1, lid = centre, max_rejections 1000); square box.
#include <benchmark/benchmark.h>

#include "netdem/packing/ballistic.hpp"

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

BENCHMARK_MAIN();
