// libFuzzer target: the temperature-profile reader (netdem::contact::sinter::TemperatureProfile::
// parse_csv, the code path of `netsolve sinter --profile FILE` and `sinter-pair --profile FILE`),
// then the profile evaluated around its breakpoints (issue 27). An accepted profile must give a
// temperature in (0, 1e4) K everywhere; a message longer than 400 characters is a finding (a bad
// input is quoted to at most 80 characters).
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
    const sp::TemperatureProfile p = sp::TemperatureProfile::parse_csv(text, "fuzz.csv");
    for (double t : p.times())
      for (double s : {t - 1.0, t, t + 0.5, std::nextafter(t, -INFINITY), std::nextafter(t, INFINITY)}) {
        const double T = p(s);
        if (!(T > 0.0 && T < sp::kMaxTemperature)) std::abort();
      }
  } catch (const std::invalid_argument& e) {
    if (std::strlen(e.what()) > 400) std::abort();  // the quoting rule
  }
  return 0;
}
