// libFuzzer target: the packing CSV reader alone (netdem::packing::read_packing_csv on a stream,
// the code path of the file reader). A std::exception is an expected outcome (a one-line error);
// a crash, a hang, undefined behaviour or a leak is a finding (tests/fuzz/README.md).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>

#include "netdem/packing/io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const netdem::packing::Packing p = netdem::packing::read_packing_csv(in, "input");
    (void)p;
  } catch (const std::exception&) {
  }
  return 0;
}
