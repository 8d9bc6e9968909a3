// libFuzzer target: the DEM state reader alone (netdem::dem::read_state on a stream, the code
// path of demsolve's --state, including its limits; issue 13 item 5).
#include <cstddef>
#include <cstdint>
#include <istream>

#include "fuzz_input.hpp"
#include "netdem/dynamic/state.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) { (void)netdem::dem::read_state(in); });
}
