// Worker processes of this executable (worker_pool.hpp).
#include "worker_pool.hpp"

#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

extern char** environ;

namespace netdem::app {

namespace {

/// The result of the worker of `index` that ended with wait status `st`.
WorkerResult collect(int index, int st, const std::filesystem::path& record_file) {
  WorkerResult r;
  r.index = index;
  if (WIFEXITED(st) && WEXITSTATUS(st) == 0 && std::filesystem::exists(record_file)) {
    std::ifstream in(record_file);
    try {
      in >> r.record;
      r.ok = true;
    } catch (const std::exception&) {
    }
  }
  if (!r.ok)
    r.failure = WIFSIGNALED(st) ? fmt::format("crashed: signal {}", WTERMSIG(st))
                                : fmt::format("failed: exit status {}", WIFEXITED(st) ? WEXITSTATUS(st) : -1);
  return r;
}

pid_t spawn(const WorkerPool& pool, int index) {
  std::vector<std::string> args = worker_program();
  args.insert(args.end(), pool.argv.begin(), pool.argv.end());
  for (auto& s : pool.extra_args(index)) args.push_back(std::move(s));
  std::vector<char*> cargs;
  for (auto& s : args) cargs.push_back(s.data());
  cargs.push_back(nullptr);
  pid_t pid = 0;
  const char* program = worker_program().empty() ? "/proc/self/exe" : worker_program().front().c_str();
  const int rc = ::posix_spawn(&pid, program, nullptr, nullptr, cargs.data(), environ);
  if (rc != 0) throw std::runtime_error(fmt::format("cannot start a worker process: {}", std::strerror(rc)));
  return pid;
}

}  // namespace

std::vector<std::string>& worker_program() {
  static std::vector<std::string> words;
  return words;
}

void run_in_workers(const WorkerPool& pool, const std::vector<int>& indices, const std::function<void(const WorkerResult&)>& finished) {
  std::fflush(stdout);
  std::fflush(stderr);
  std::map<pid_t, int> running;
  std::size_t next = 0;
  while (next < indices.size() || !running.empty()) {
    if (next < indices.size() && static_cast<int>(running.size()) < pool.jobs) {
      const int idx = indices[next++];
      running[spawn(pool, idx)] = idx;
      continue;
    }
    int st = 0;
    const pid_t pid = ::waitpid(-1, &st, 0);
    if (pid <= 0) throw std::runtime_error("waitpid failed while worker processes were running");
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const int idx = it->second;
    running.erase(it);
    finished(collect(idx, st, pool.record_file(idx)));
  }
}

void die_with_parent() {
#ifdef __linux__
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
}

}  // namespace netdem::app
