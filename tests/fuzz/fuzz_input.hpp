#pragma once
// The common body of the fuzz targets: the input as a stream, a std::exception counted as the
// expected outcome (a one-line error); anything else (a crash, another exception, a hang, UB, a
// leak) is a finding (tests/fuzz/README.md).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>

namespace netdem::fuzz {

template <class F>
int run(const std::uint8_t* data, std::size_t size, F&& body) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    body(in);
  } catch (const std::exception&) {
  }
  return 0;
}

}  // namespace netdem::fuzz
