#pragma once
// Runs indices in worker processes of this executable (worker_pool.cpp): each worker is this
// program started again with its own command line plus the extra arguments of its index; it
// writes a JSON record file and exits 0. At most `jobs` run at a time. Linux/POSIX (posix_spawn
// of /proc/self/exe). Used by `netsolve yield --jobs` (one worker per probe).
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace netdem::app {

/// How a worker ended: its record (ok: it exited 0 and its record file parses) or why not
/// ("crashed: signal N", "failed: exit status N").
struct WorkerResult {
  int index = -1;
  bool ok = false;
  nlohmann::json record;
  std::string failure;
};

struct WorkerPool {
  std::vector<std::string> argv;                                 ///< this program's command line (argv[0] first)
  std::function<std::vector<std::string>(int)> extra_args;       ///< appended for index k, e.g. {"--worker", "k"}
  std::function<std::filesystem::path(int)> record_file;         ///< the JSON file the worker of index k writes
  int jobs = 1;                                                  ///< workers at the same time
};

/// The program a worker starts when it is not this executable (the Python module, whose
/// executable is the interpreter): these words, then the pool's argv (argv[0] the tool's name);
/// words[0] is the program's path. Empty (the default): /proc/self/exe with the pool's argv.
std::vector<std::string>& worker_program();

/// Runs a worker for each of `indices` (in this order, at most pool.jobs at a time) and calls
/// `finished` in the parent as each one ends. Throws std::runtime_error if a worker cannot be
/// started or waiting fails.
void run_in_workers(const WorkerPool& pool, const std::vector<int>& indices, const std::function<void(const WorkerResult&)>& finished);

/// In a worker: the kernel kills it when its parent dies (Linux; elsewhere nothing), so that a
/// killed run leaves no worker running.
void die_with_parent();

}  // namespace netdem::app
