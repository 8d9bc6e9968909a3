// libFuzzer target: the network-solver state reader alone (netdem::qs::load_state on a stream, the
// code path of the file reader, including NetworkState::validate). A std::exception is an expected
// outcome; a crash, a hang, undefined behaviour or a leak is a finding (tests/fuzz/README.md).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>

#include "netdem/quasistatic/network_solver.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const netdem::qs::NetworkState s = netdem::qs::load_state(in, "input");
    (void)s;
  } catch (const std::exception&) {
  }
  return 0;
}
