// libFuzzer target: the sintering material reader (netdem::contact::sinter::parse_sinter_material,
// the code path of `netsolve sinter --material FILE`, `sinter-pair --material FILE` and --set),
// then the diffusivities of an accepted material at a few temperatures (issue 27). A message
// longer than 400 characters is a finding too: a bad input is quoted to at most 80 characters.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include "netdem/contact/sintering_pair.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace sp = netdem::contact::sinter;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const sp::SinterMaterial m = sp::parse_sinter_material(text, "fuzz.txt");
    for (double T : {300.0, 1273.15, 9999.0}) {
      const sp::Diffusivities d = sp::diffusivities(m, T);
      if (std::isnan(d.kT)) std::abort();
    }
  } catch (const std::invalid_argument& e) {
    if (std::strlen(e.what()) > 400) std::abort();  // the quoting rule
  }
  return 0;
}
