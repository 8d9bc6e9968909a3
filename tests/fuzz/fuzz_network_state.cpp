// libFuzzer target: the network-solver state readers alone, the 2D one (kind "network") and the 3D
// one (kind "network3d"), both on the same input (load_state_text / load_state3_text, the code
// paths of the file readers, including the states' validate()).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <istream>
#include <iterator>
#include <string>

#include "fuzz_input.hpp"
#include "netdem/quasistatic/network_solver.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) {
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    try {
      (void)netdem::qs::load_state_text(text, "input");
    } catch (const std::exception&) {  // a refused input: the 3D reader gets it too
    }
    (void)netdem::qs::load_state3_text(text, "input");
  });
}
