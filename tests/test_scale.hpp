#pragma once
// NETDEM_TEST_SCALE=small (set by run-tests.sh --sanitize) shrinks the heavy tests' systems.
#include <cstdlib>
#include <cstring>

namespace netdem::test {
inline bool small_scale() {
  const char* s = std::getenv("NETDEM_TEST_SCALE");
  return s != nullptr && std::strcmp(s, "small") == 0;
}
}  // namespace netdem::test
