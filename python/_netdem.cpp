// _netdem: the extension of the Python package netdem (python/netdem/, README.md "From Python").
//
// run() runs a subcommand of netsolve or demsolve in this process through the same command line
// the executables run (apps/*/command.cpp, libraries netdem_netsolve_cli and netdem_demsolve_cli),
// so that a keyword argument is the long option of the same name, with its default, its checks and
// its one-line messages. The run releases the GIL; the progress hook of the apps (output.hpp)
// calls back into Python at most every 50 ms and checks for Ctrl-C there. The packing reader and
// writer of src/packing are bound directly, as numpy arrays.
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "demsolve/command.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netsolve/command.hpp"
#include "output.hpp"
#include "run_status.hpp"
#include "worker_pool.hpp"

namespace py = pybind11;

namespace {

/// Thrown by the progress hook when Python has an error pending (Ctrl-C, an exception of the
/// callback): not a std::exception, so that the command's error handler lets it through.
struct PythonError {};

/// One run at a time: the command lines keep their run state in process-wide variables.
std::mutex g_run_mutex;

/// Sets the apps' error and summary sinks and progress hook for one run and clears them after it.
class RunHooks {
 public:
  RunHooks(std::vector<std::string>& lines, std::vector<std::string>& summary, const py::object& progress)
      : progress_(progress) {
    netdem::app::error_sink() = [&lines](const std::string& line) { lines.push_back(line); };
    netdem::app::summary_sink() = [&summary](const std::string& line) { summary.push_back(line); };
    netdem::app::progress_hook() = [this](double fraction) { call(fraction); };
  }
  ~RunHooks() {
    netdem::app::error_sink() = nullptr;
    netdem::app::summary_sink() = nullptr;
    netdem::app::progress_hook() = nullptr;
  }
  RunHooks(const RunHooks&) = delete;
  RunHooks& operator=(const RunHooks&) = delete;

  /// Re-raises the Python error the hook stopped the run with (the GIL held).
  [[noreturn]] void raise() {
    PyErr_Restore(type_, value_, traceback_);
    type_ = value_ = traceback_ = nullptr;
    throw py::error_already_set();
  }

 private:
  /// Only on the thread of the run (the caller's): a protocol that reports progress from its worker
  /// threads (demsolve yield's probes) must not throw there, nor call Python from them.
  void call(double fraction) {
    if (std::this_thread::get_id() != owner_) return;
    const auto now = std::chrono::steady_clock::now();
    if (fraction < 1.0 && started_ && now - last_ < std::chrono::milliseconds(50)) return;
    started_ = true;
    last_ = now;
    py::gil_scoped_acquire gil;
    bool failed = PyErr_CheckSignals() != 0;  // Ctrl-C: KeyboardInterrupt set
    if (!failed && !progress_.is_none()) {
      try {
        progress_(fraction);
      } catch (py::error_already_set& e) {
        e.restore();
        failed = true;
      }
    }
    if (!failed) return;
    PyErr_Fetch(&type_, &value_, &traceback_);
    throw PythonError{};
  }

  const py::object& progress_;
  const std::thread::id owner_ = std::this_thread::get_id();
  std::chrono::steady_clock::time_point last_;
  bool started_ = false;
  PyObject* type_ = nullptr;
  PyObject* value_ = nullptr;
  PyObject* traceback_ = nullptr;
};

/// Runs `tool args...` (tool "netsolve" or "demsolve") in process; returns the exit status, the
/// error lines and the closing summary lines the command would have printed (without the GIL during
/// the run; nothing goes to the process's stdout).
py::tuple run(const std::string& tool, const std::vector<std::string>& args, const py::object& progress) {
  if (tool != "netsolve" && tool != "demsolve") throw py::value_error("tool must be 'netsolve' or 'demsolve', not '" + tool + "'");
  std::vector<std::string> words{tool};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  const int argc = static_cast<int>(words.size());
  std::vector<std::string> lines, summary;
  int code = 0;
  bool stopped = false;
  RunHooks hooks(lines, summary, progress);
  {
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(g_run_mutex);
    try {
      code = tool == "netsolve" ? netsolve_command(argc, argv.data()) : demsolve_command(argc, argv.data());
    } catch (const PythonError&) {
      stopped = true;
    }
  }
  if (stopped) hooks.raise();
  return py::make_tuple(code, lines, summary);
}

py::array_t<double> array(const std::vector<double>& v) { return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data()); }

std::vector<double> vector(const py::handle& a) {
  const auto arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!arr || arr.ndim() != 1) throw py::value_error("a packing's x, y, z and r must be one-dimensional arrays of numbers");
  return std::vector<double>(arr.data(), arr.data() + arr.size());
}

/// A packing file as a dict of numpy arrays and its header fields (packing.py makes the Packing).
py::dict read_packing(const std::string& path) {
  netdem::packing::Packing p;
  try {
    p = netdem::packing::read_packing_csv(path);
  } catch (const std::exception& e) {
    throw py::value_error(e.what());
  }
  py::dict d;
  d["x"] = array(p.x);
  d["y"] = array(p.y);
  d["z"] = p.dim == 3 ? py::object(array(p.z)) : py::object(py::none());
  d["r"] = array(p.r);
  d["dim"] = p.dim;
  const auto& b = p.box;
  d["box"] = p.dim == 3 ? py::make_tuple(b.x_min, b.y_min, b.z_min, b.x_max, b.y_max, b.z_max)
                        : py::make_tuple(b.x_min, b.y_min, b.x_max, b.y_max);
  d["seed"] = p.seed;
  d["comments"] = p.comments;
  d["periodic"] = p.periodic;
  d["cell"] = array(p.cell);
  return d;
}

/// Writes the packing of dict `d` (the keys of read_packing) to `path` with the library's writer.
void write_packing(const py::dict& d, const std::string& path) {
  netdem::packing::Packing p;
  p.dim = d["dim"].cast<int>();
  if (p.dim != 2 && p.dim != 3) throw py::value_error("a packing's dim must be 2 or 3");
  p.x = vector(d["x"]);
  p.y = vector(d["y"]);
  p.r = vector(d["r"]);
  if (p.dim == 3) p.z = vector(d["z"]);
  const std::size_t n = p.x.size();
  if (p.y.size() != n || p.r.size() != n || (p.dim == 3 && p.z.size() != n))
    throw py::value_error("a packing's x, y" + std::string(p.dim == 3 ? ", z" : "") + " and r must have the same length");
  const auto box = d["box"].cast<std::vector<double>>();
  if (box.size() != static_cast<std::size_t>(2 * p.dim))
    throw py::value_error("a packing's box must be (x_min, y_min" + std::string(p.dim == 3 ? ", z_min" : "") + ", x_max, y_max" +
                          std::string(p.dim == 3 ? ", z_max)" : ")"));
  auto& b = p.box;
  if (p.dim == 3) {
    b = {box[0], box[1], box[3], box[4], box[2], box[5]};
  } else {
    b = {box[0], box[1], box[2], box[3], 0.0, 0.0};
  }
  p.seed = d["seed"].cast<std::uint64_t>();
  p.comments = d["comments"].cast<std::vector<std::string>>();
  p.periodic = d["periodic"].cast<bool>();
  p.cell = vector(d["cell"]);
  try {
    netdem::packing::write_packing_csv(p, path);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}

}  // namespace

PYBIND11_MODULE(_netdem, m) {
  m.doc() = "netdem's extension: the command lines' subcommands in process, the packing files (use the package netdem)";
  m.def("run", &run, py::arg("tool"), py::arg("args"), py::arg("progress") = py::none(),
        "Runs `tool args...` in this process (the GIL released); returns (exit status, error lines).");
  m.def(
      "set_worker_program", [](const std::vector<std::string>& words) { netdem::app::worker_program() = words; },
      py::arg("words"), "The program worker processes start (netsolve yield --jobs): words, then the tool's argv.");
  m.def("read_packing", &read_packing, py::arg("path"), "A packing CSV file as a dict of numpy arrays.");
  m.def("write_packing", &write_packing, py::arg("packing"), py::arg("path"), "Writes a dict of read_packing's keys.");
}
