// libFuzzer target: the staggered sintering state reader (netdem::qs::staggered::Staggered::load,
// the path of netsolve sinter --restart: the archive's field checks, then the set-up of the
// material, the particles, the contacts and the saved factor).
#include <cstddef>
#include <cstdint>
#include <istream>
#include <iterator>
#include <string>

#include "fuzz_input.hpp"
#include "netdem/quasistatic/staggered.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) {
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    (void)netdem::qs::staggered::Staggered::load(text, "input");
  });
}
