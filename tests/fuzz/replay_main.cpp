// Replays fuzz inputs through a fuzz target's LLVMFuzzerTestOneInput in an ordinary build (gcc,
// no libFuzzer): the regression corpus (tests/fuzz/regressions/<target>) and the seed corpus are
// checked by ctest in every build. Usage: replay_<target> DIR_OR_FILE...
// Each file must finish without a crash (the process would die), and within 2 s; the target
// itself treats a std::exception as a clean outcome. Exit status 1 if a file was too slow or an
// argument is missing.
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  constexpr double kLimit = 2.0;  // seconds per input, as libFuzzer's -timeout=2
  std::vector<fs::path> files;
  int status = 0;
  for (int a = 1; a < argc; ++a) {
    const fs::path arg = argv[a];
    if (fs::is_directory(arg)) {
      for (const auto& e : fs::recursive_directory_iterator(arg))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (fs::is_regular_file(arg)) {
      files.push_back(arg);
    } else {
      std::fprintf(stderr, "replay: %s: no such file or directory\n", arg.c_str());
      status = 1;
    }
  }
  std::sort(files.begin(), files.end());
  double worst = 0.0;
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto t0 = std::chrono::steady_clock::now();
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(data.data()), data.size());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    worst = std::max(worst, s);
    if (s > kLimit) {
      std::fprintf(stderr, "replay: %s took %.2f s (limit %.0f s)\n", f.c_str(), s, kLimit);
      status = 1;
    }
  }
  std::printf("replay: %zu inputs, slowest %.3f s%s\n", files.size(), worst, status ? ", FAILED" : "");
  return status;
}
