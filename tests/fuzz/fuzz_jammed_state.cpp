// libFuzzer target: the jammed-state reader (netdem/system/jammed_state.hpp, the state both solvers
// start from: `netsolve compact --state`, `demsolve compact --state`): the header and dimension,
// then parse_jammed_state<D> with every check of JammedStateT::validate. An accepted state must
// write (format_jammed_state) and read back to the same text: a reader that accepts what the
// writer refuses, or a writer whose text reads differently, is a finding (abort).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <istream>
#include <iterator>
#include <string>

#include "fuzz_input.hpp"
#include "netdem/system/jammed_state.hpp"

namespace {
template <int D>
void round_trip(const std::string& text) {
  const auto s = netdem::sys::parse_jammed_state<D>(text, "input");
  const std::string once = netdem::sys::format_jammed_state(s);
  if (netdem::sys::format_jammed_state(netdem::sys::parse_jammed_state<D>(once, "written")) != once) std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return netdem::fuzz::run(data, size, [](std::istream& in) {
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (netdem::sys::jammed_state_dim(text, "input") == 3) round_trip<3>(text);
    else round_trip<2>(text);
  });
}
