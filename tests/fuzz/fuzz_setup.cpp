// libFuzzer target: read + validate + set-up. A packing file is read, validated, turned into a
// NetworkSolver with the compaction preset (peripheral_layer, the neighbour build, the sparsity
// pattern and CHOLMOD's analysis) and one hydrostatic increment is run. Inputs of more than
// kMaxDisks disks are skipped so that one run stays well below the 2 s timeout.
#include <cstddef>
#include <cstdint>
#include <istream>

#include <Eigen/Core>

#include "fuzz_input.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/solver_options.hpp"

namespace {
constexpr std::size_t kMaxDisks = 200;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) {
    const netdem::packing::Packing p = netdem::packing::read_packing_csv(in, "input");
    if (p.size() > kMaxDisks) return;
    netdem::packing::validate(p);
    netdem::qs::NetworkSolver solver(p, netdem::qs::SolverOptions::compact());
    Eigen::Matrix2d dE;
    dE << -2e-3, 0.0, 0.0, -2e-3;
    (void)solver.increment(dE);
    (void)solver.measures();
  });
}
