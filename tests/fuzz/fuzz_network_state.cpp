// libFuzzer target: the network-solver state reader alone (netdem::qs::load_state on a stream, the
// code path of the file reader, including NetworkState::validate).
#include <cstddef>
#include <cstdint>
#include <istream>

#include "fuzz_input.hpp"
#include "netdem/quasistatic/network_solver.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) { (void)netdem::qs::load_state(in, "input"); });
}
