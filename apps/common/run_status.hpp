#pragma once
// The status of a run and the exit codes of the command-line tools (README.md "Exit status"):
// RunStatus (summary.json "status", "status_reason", exit 0 or 3), and guarded(), which maps the
// exceptions of a run to one line on stderr and exit 1 or 2. netsolve uses them; demsolve can.
#include <cstdarg>
#include <cstdio>
#include <exception>
#include <functional>
#include <new>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/field_error.hpp"
#include "output.hpp"

namespace netdem::app {

/// The status of a run, written to summary.json as "status" and "status_reason".
///   ok           finished, every criterion met
///   unconverged  finished, but an iteration did not converge well enough (netsolve's criteria:
///                docs/quasistatic.md "Run status"; yield: also a failed unloading)
///   unstable     the state failed (netsolve: centres left the box, Z < 2) or the run was stopped
///                (non-finite values, a residual that grows); the rows written so far are kept
///   incomplete   stopped early at a documented, expected limit; the rows written are valid
/// Exit: 0 for ok and incomplete, 3 for unconverged and unstable (0 with --allow-unconverged).
struct RunStatus {
  std::string status = "ok";
  std::vector<std::string> reasons;

  /// Adds a reason; `worse` replaces the status if it ranks higher (ok < incomplete < unconverged < unstable).
  void add(const std::string& worse, const std::string& reason) {
    auto rank = [](const std::string& s) { return s == "unstable" ? 3 : s == "unconverged" ? 2 : s == "incomplete" ? 1 : 0; };
    if (rank(worse) > rank(status)) status = worse;
    reasons.push_back(reason);
  }
  bool ok() const { return status == "ok"; }
  std::string reason() const {
    if (reasons.empty()) return "every criterion met";
    std::string s;
    for (const auto& r : reasons) s += (s.empty() ? "" : "; ") + r;
    return s;
  }
  /// 0 for ok and incomplete, 3 otherwise, 0 again with --allow-unconverged.
  int exit_code(bool allow_unconverged) const {
    if (status == "ok" || status == "incomplete" || allow_unconverged) return exit_code::ok;
    return exit_code::untrustworthy;
  }
  void write(nlohmann::json& j) const {
    j["status"] = status;
    j["status_reason"] = reason();
  }
};

/// Where the one-line errors of a command go: stderr, or, when set (the Python module), this sink,
/// which receives the line without its newline.
inline std::function<void(const std::string&)>& error_sink() {
  static std::function<void(const std::string&)> sink;
  return sink;
}

/// Writes one error line ("netsolve: error: ...") to the sink if there is one, else to stderr.
inline void print_error_line(const std::string& line) {
  if (error_sink()) {
    error_sink()(line);
  } else {
    std::fprintf(stderr, "%s\n", line.c_str());
  }
}

/// Where a command's closing summary line goes ("D = 0.8500: ... -> DIR"): stdout, or, when set (the
/// Python module, which returns it instead), this sink, which receives the line without its newline.
inline std::function<void(const std::string&)>& summary_sink() {
  static std::function<void(const std::string&)> sink;
  return sink;
}

/// printf for the closing summary line of a command: to the summary sink if there is one, else to
/// stdout, formatted exactly as std::printf would.
__attribute__((format(printf, 1, 2))) inline void summary_printf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string line(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(line.data(), line.size() + 1, format, args);
  va_end(args);
  if (summary_sink()) {
    if (!line.empty() && line.back() == '\n') line.pop_back();
    summary_sink()(line);
  } else {
    std::fputs(line.c_str(), stdout);
  }
}

/// What the program was doing, for "out of memory while ..." (set before each big step).
inline std::string& activity() {
  static std::string s = "starting";
  return s;
}

/// Runs `body` and maps its exceptions to a one-line error and an exit code: a refused command
/// line (UsageError, or any error before the output folder was opened) 2, out of memory and
/// every other error 1. `prefix` starts the message ("netsolve", "netsolve yield").
template <class F>
int guarded(const std::string& prefix, F&& body) {
  auto line = [&](const std::string& msg) {
    std::string m = msg;
    for (char& c : m)  // one line: every control character becomes a space
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
    print_error_line(prefix + ": error: " + m);
  };
  try {
    return body();
  } catch (const std::bad_alloc&) {
    line(fmt::format("out of memory while {}", activity()));
    return exit_code::run_error;
  } catch (const UsageError& e) {
    line(e.what());
    return exit_code::usage;
  } catch (const FieldError& e) {  // a library's bad field: named by its option
    std::string option = "--" + e.field();
    for (char& c : option)
      if (c == '_') c = '-';
    line(option + ": " + e.what());
    return run_dir_opened() ? exit_code::run_error : exit_code::usage;
  } catch (const std::exception& e) {
    line(e.what());
    return run_dir_opened() ? exit_code::run_error : exit_code::usage;
  }
}

}  // namespace netdem::app
