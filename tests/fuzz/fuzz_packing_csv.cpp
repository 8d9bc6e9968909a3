// libFuzzer target: the packing CSV reader alone (netdem::packing::read_packing_csv on a stream,
// the code path of the file reader: parsing, the valid ranges, find_close_pair, validate).
#include <cstddef>
#include <cstdint>
#include <istream>

#include "fuzz_input.hpp"
#include "netdem/packing/io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) { (void)netdem::packing::read_packing_csv(in, "input"); });
}
