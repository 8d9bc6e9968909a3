// netsolve yield / yield-merge: yield surfaces of a precompacted network (issue #3; Redanz & Fleck,
// Acta Mater. 49 (2001) 4325, section 3.4, Figs 9-10). Algorithm and outputs: docs/yield.md.
//
//   netsolve yield [--precompact hydrostatic|closed-die] [--to-density 0.85] [--friction MU|inf]
//                  [--compact-bc affine|die|walls|periodic] [--probe-bc ...] [--directions N]
//                  [--probe i/N | --probes LIST] [--jobs J] [--out DIR]
//   netsolve yield-merge DIR... [--out DIR]
//
// The command compacts (or restores a compacted state, --from-state), unloads, then runs the
// probes, each on its own solver restored from the unloaded state (qs::run_probes,
// src/quasistatic/yield_driver.hpp): in this process for --jobs 1, otherwise in --jobs worker
// processes of this program (apps/common/worker_pool.hpp); each finished probe writes
// probes/probe_NNN.csv and .json atomically, and yield_points.csv is assembled from the records
// (yield_records.cpp, which also holds yield-merge). The physics lives in the library
// (compaction, switch_boundary_mode, unload, run_probes); this file parses and runs the phases.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/analytic_yield.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/yield_driver.hpp"
#include "netdem/quasistatic/yield_probe.hpp"
#include "compact.hpp"
#include "compact_common.hpp"
#include "output.hpp"
#include "parse.hpp"
#include "scene_file.hpp"
#include "setup.hpp"
#include "status.hpp"
#include "worker_pool.hpp"
#include "yield_records.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
namespace qs = netdem::qs;

int run_yield_command(int argc, char** argv);

namespace {

using netdem::app::netsolve::non_empty_file;
using netdem::app::netsolve::parse_int;
using netdem::app::netsolve::yield::Analytic;
using netdem::app::netsolve::yield::from_json;
using netdem::app::netsolve::yield::jnum;

using Clock = std::chrono::steady_clock;
constexpr double kPi = std::numbers::pi;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct YieldArgs {
  // packing
  netdem::app::netsolve::PackArgs pack;  // a new deposition (lid: centre)
  std::string packing_file, from_state, state_file;  // state_file: a jammed state (--state)
  // precompaction
  std::string precompact = "hydrostatic", compact_bc = "die", probe_bc;
  double to_density = 0.85;
  int increments = 100;
  // contact law and solver (--normal-unloading: the law during the precompaction)
  netdem::app::netsolve::LawArgs law;
  // probing
  int directions = 24;
  std::string probe_slice;
  std::vector<int> probe_list;  ///< --probes: a set of indices (empty: every direction)
  int jobs = 0;
  double offset = 1e-3, max_strain = 4e-3, window = 0.1, unload_tol = 1e-3, growth = 1.2;
  /// elastic un/reloading stiffness over the loading tangent at u_max (section 3.4), the law's default
  double unload_ratio = netdem::contact::PlasticIndentationParams{}.unload_ratio;
  int fine = 20;
  bool quiet = false, overwrite = false, allow_unconverged = false;
  std::string out = "results/yield";
  int probe_worker = -1;          ///< hidden: run probe k from out/probes/unloaded_state.txt (a worker process)
  std::vector<std::string> argv;  ///< the command line, to start the workers
};


qs::BoundaryMode parse_bc(const std::string& s, const char* opt) {
  if (s == "affine") return qs::BoundaryMode::Affine;
  if (s == "die" || s == "lr" || s == "l.r.") return qs::BoundaryMode::Die;
  if (s == "periodic") return qs::BoundaryMode::Periodic;
  if (s == "walls") return qs::BoundaryMode::Walls;
  throw std::invalid_argument(
      fmt::format("{} '{}' is not 'affine', 'die' (local relaxation), 'walls' or 'periodic'", opt, s));
}

const char* bc_name(qs::BoundaryMode m) {
  return m == qs::BoundaryMode::Affine     ? "affine"
         : m == qs::BoundaryMode::Periodic ? "periodic"
         : m == qs::BoundaryMode::Walls    ? "walls"
                                           : "die";
}

/// Probe indices of this run: all, a job-array slice "i/N" (indices k with k mod N == i) or a list.
std::vector<int> select_probes(const YieldArgs& a) {
  if (a.directions < 1 || a.directions > 100000)
    throw std::invalid_argument(fmt::format("--directions must be in [1, 100000], got {}", a.directions));
  if (!a.probe_slice.empty() && !a.probe_list.empty())
    throw std::invalid_argument("--probe and --probes exclude each other");
  std::vector<int> sel;
  if (!a.probe_slice.empty()) {
    const auto slash = a.probe_slice.find('/');
    long i = -1, n = -1;
    if (slash == std::string::npos || !parse_int(a.probe_slice.substr(0, slash), i) ||
        !parse_int(a.probe_slice.substr(slash + 1), n) || n < 1 || i < 0 || i >= n)
      throw std::invalid_argument(
          fmt::format("--probe '{}' is not a slice i/N with 0 <= i < N (probes k with k mod N == i)", a.probe_slice));
    for (int k = 0; k < a.directions; ++k)
      if (k % n == i) sel.push_back(k);
    if (sel.empty())
      throw std::invalid_argument(fmt::format("--probe {} selects no probe of --directions {}", a.probe_slice, a.directions));
    return sel;
  }
  if (!a.probe_list.empty()) {
    std::set<int> s;  // a set: sorted, each index once
    for (int v : a.probe_list) {
      if (v < 0 || v >= a.directions)
        throw std::invalid_argument(
            fmt::format("--probes: '{}' is not a probe index in [0, {}) (--directions {})", v, a.directions, a.directions));
      s.insert(v);
    }
    return {s.begin(), s.end()};
  }
  for (int k = 0; k < a.directions; ++k) sel.push_back(k);
  return sel;
}

// ---------------------------------------------------------------------------------------------
/// The solver options of the two phases: the precompaction preset with the command's law and
/// Newton options, and the probe preset with the same law (docs/quasistatic.md "Presets").
void yield_options(const YieldArgs& a, qs::SolverOptions& pre, qs::SolverOptions& probe) {
  pre = qs::SolverOptions::yield_precompaction();
  pre.mode = parse_bc(a.compact_bc, "--compact-bc");
  const qs::BoundaryMode probe_mode = parse_bc(a.probe_bc.empty() ? a.compact_bc : a.probe_bc, "--probe-bc");
  // the iteration covers both phases: its default depends on both boundary modes
  netdem::app::netsolve::apply_law_args(a.law, pre, probe_mode);
  if (!(a.unload_ratio >= 1.0 && a.unload_ratio <= 1e8))
    throw std::invalid_argument(fmt::format("--unload-ratio must lie in [1, 1e8] (the un/reloading stiffness over the "
                                            "loading tangent), got {}", a.unload_ratio));
  pre.law.unload_ratio = a.unload_ratio;
  pre.validate();
  probe = netdem::app::netsolve::yield_probe_options(pre, probe_mode);
  if ((pre.mode == qs::BoundaryMode::Periodic) != (probe.mode == qs::BoundaryMode::Periodic))
    throw std::invalid_argument("--compact-bc and --probe-bc: a periodic cell is probed periodic or affine (--probe-bc "
                                "periodic or affine with --compact-bc periodic, neither without)");
  if (probe.mode == qs::BoundaryMode::Walls && pre.mode != qs::BoundaryMode::Walls)
    throw std::invalid_argument("--compact-bc and --probe-bc: walls probe a state compacted between the same walls "
                                "(--probe-bc walls needs --compact-bc walls)");
  if (pre.mode == qs::BoundaryMode::Walls && probe.mode == qs::BoundaryMode::Die)
    throw std::invalid_argument("--compact-bc and --probe-bc: a state compacted between walls is probed between them or "
                                "affine (--probe-bc walls or affine)");
}

/// The compacted state of --from-state; its strain must lie along --precompact's path.
std::unique_ptr<qs::NetworkSolver> restore_compacted(const YieldArgs& a, const qs::StrainPath& path,
                                                     const qs::SolverOptions& pre) {
  const qs::NetworkState st = qs::load_state(a.from_state);
  const bool walls = pre.mode == qs::BoundaryMode::Walls;
  if (st.wall_history.empty() == walls)
    throw std::invalid_argument(fmt::format("--from-state {}: the state has {}wall contacts: run it {} --compact-bc walls",
                                            a.from_state, walls ? "no " : "", walls ? "without" : "with"));
  const Eigen::Matrix2d E = st.strain, R = path.rate();
  const double cosine = (E.array() * R.array()).sum() / (E.norm() * R.norm());
  if (!(E.norm() > 0.0) || !(cosine > 1.0 - 1e-9))
    throw std::invalid_argument(fmt::format("--from-state {}: its strain (E11, E22, E12) = ({:.4g}, {:.4g}, {:.4g}) does not "
                                            "lie along --precompact {}",
                                            a.from_state, E(0, 0), E(1, 1), E(0, 1), path.name));
  return std::make_unique<qs::NetworkSolver>(st, pre);
}

/// The density at zero strain, D exp(E11 + E22) (the box area scales with det exp(E)), where the
/// solver's own initial density is not (a run from a jammed state starts at the jammed density but
/// carries the strain that led there); else the solver's initial density, bit for bit.
double density_at_zero_strain(const qs::StateMeasures& m, double initial_density) {
  const double d0 = m.density * std::exp(m.E11 + m.E22);
  return std::fabs(d0 - initial_density) > 1e-9 * initial_density ? d0 : initial_density;
}

/// The probe settings of the command line, with the fine step and the loading stress of the run.
qs::ProbeSettings probe_settings(const YieldArgs& a, double first_step, double loading_norm, double sigma_y) {
  return netdem::app::netsolve::yield_probe_settings(a, a.directions, first_step, loading_norm, sigma_y);
}


namespace yr = netdem::app::netsolve::yield;

/// Worker process: probe k from the unloaded state of the run folder, written as probe files.
int run_probe_worker(const YieldArgs& a) {
  netdem::app::die_with_parent();  // a killed run leaves no probe running
  qs::SolverOptions so, po;
  yield_options(a, so, po);
  po.law.reversible = false;  // the state was saved on the elastic branch
  const fs::path out = a.out;
  const auto state = qs::load_state((out / "probes" / "unloaded_state.txt").string());
  json w;
  {
    std::ifstream in(out / "probes" / "worker.json");
    if (!in) throw std::runtime_error(fmt::format("probe worker: {} is missing", (out / "probes" / "worker.json").string()));
    in >> w;
  }
  const json setup = w.at("setup");
  const Analytic an = yr::make_analytic(setup.at("analytic"));
  const qs::ProbeSettings ps =
      probe_settings(a, w.at("first_step").get<double>(), w.at("loading_norm").get<double>(), so.law.sigma_y);
  qs::run_probes(state, po, {a.probe_worker}, ps,
                 [&](const qs::ProbeResult& p) { yr::write_probe(p, a.directions, an, setup, out); });
  return 0;
}

/// One `netsolve yield` run in its phases: the checks before the output folder exists, the input
/// and the folder, the precompaction, the setup record, the boundary handover, the unloading, the
/// probes and the summary. Each phase reads what the earlier ones left in the members.
class YieldRun {
 public:
  YieldRun(const YieldArgs& a, const std::string& command) : a_(a), command_(command) {}

  int run() {
    t_start_ = Clock::now();
    validate();
    open_input();
    if (!precompact()) return netdem::app::exit_code::untrustworthy;
    make_setup();
    hand_over();
    unload_phase();
    probe_phase();
    return finish();
  }

 private:
  void validate();
  void open_input();
  bool precompact();
  void make_setup();
  void hand_over();
  void unload_phase();
  void probe_phase();
  int finish();
  void stopped_summary(const std::string& stopped, int done);

  const YieldArgs& a_;
  const std::string& command_;
  Clock::time_point t_start_;
  qs::SolverOptions so_, po_;
  qs::CompactionOptions co_;
  std::vector<int> selection_;
  int jobs_ = 1;
  std::string source_;
  netdem::packing::Packing pk_;
  std::optional<netdem::sys::JammedStateT<2>> jammed_;  ///< --state: the precompaction starts from it
  std::unique_ptr<qs::NetworkSolver> solver_;
  fs::path out_;
  double sy_ = 0.0;
  // precompaction
  int unconverged_ = 0;
  qs::StateMeasures loaded_;
  netdem::app::netsolve::ConvergenceRecord conv_;
  double t_compact_ = 0.0, D0_ = 0.0;
  // setup, handover, unloading
  json setup_, handover_ = nullptr;
  Analytic an_;
  qs::UnloadResult un_;
  double t_unload_ = 0.0, first_step_ = 0.0, loading_norm_ = 0.0;
  // probes
  std::map<int, json> records_;
  double t_probes_ = 0.0;
};

/// Everything checked before the output folder exists (a refused command is exit 2, nothing touched).
void YieldRun::validate() {
  using namespace netdem;
  const YieldArgs& a = a_;
  yield_options(a, so_, po_);
  if (so_.mode != po_.mode && so_.law.mu != 0.0)
    throw std::invalid_argument(
        "--compact-bc differs from --probe-bc: only frictionless runs (--friction 0) can switch, the solver is rebuilt "
        "from the compacted state and would lose the tangential contact forces");
  if (a.precompact != "hydrostatic" && a.precompact != "closed-die")
    throw std::invalid_argument(fmt::format("--precompact '{}' is not 'hydrostatic' or 'closed-die'", a.precompact));
  co_.path = qs::StrainPath::parse(a.precompact);
  co_.target_density = a.to_density;
  co_.increments = a.increments;
  selection_ = select_probes(a);
  if (!(a.offset > 0.0) || !(a.max_strain > a.offset) || !(a.window > 0.0) || !(a.unload_tol > 0.0) || !(a.growth >= 1.0) ||
      a.fine < 5 || !std::isfinite(a.max_strain) || !std::isfinite(a.window) || !std::isfinite(a.unload_tol) ||
      !std::isfinite(a.growth))
    throw std::invalid_argument(
        "probe options: need finite --offset > 0, --max-strain > --offset, --window > 0, --unload-tol > 0, --growth >= 1, "
        "and --fine >= 5");
  jobs_ = a.jobs > 0 ? a.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (a.jobs < 0) throw std::invalid_argument(fmt::format("--jobs must be >= 1 (0: number of cores), got {}", a.jobs));
  if (!a.from_state.empty() && !a.packing_file.empty()) throw std::invalid_argument("--from-state and --packing exclude each other");
  if (!a.from_state.empty() && !a.state_file.empty()) throw std::invalid_argument("--from-state and --state exclude each other");
  if (!a.state_file.empty() && so_.mode == qs::BoundaryMode::Periodic)
    throw std::invalid_argument("--state: a jammed state has walls or a layer, not a periodic cell (--compact-bc periodic)");
  app::RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  rdo.inputs = {a.packing_file, a.from_state, a.state_file};
  app::check_run_dir(a.out, rdo);  // before any work: a refused folder is exit 2, nothing touched
  if (!a.from_state.empty() && fs::is_directory(a.from_state))
    throw app::UsageError(fmt::format("--from-state '{}' is a folder, not a state file (netsolve compact --save-state writes "
                                      "DIR/state.txt)", a.from_state.substr(0, 80)));
}

/// The packing (a deposition, a file) or the restored state; the output folder, the packing file
/// and the line on stderr.
void YieldRun::open_input() {
  using namespace netdem;
  const YieldArgs& a = a_;
  // a jammed state: the precompaction starts from it (at rest: its box is the run's initial box)
  jammed_ = app::netsolve::jammed_input(a.state_file, a.packing_file, so_, "netsolve yield", "--compact-bc walls");
  if (jammed_) {
    pk_ = jammed_->packing();
    source_ = "jammed state " + a.state_file;
    co_.validate(pk_.density());
  } else if (a.from_state.empty()) {
    if (a.packing_file.empty()) app::netsolve::check_deposition_size(a.pack, true);
    app::netsolve::activity() = a.packing_file.empty() ? "building the ballistic deposition" : "reading the packing " + a.packing_file;
    pk_ = app::netsolve::input_packing(a.packing_file, a.pack, source_, "netsolve yield",
                                       so_.mode == qs::BoundaryMode::Periodic ? app::netsolve::PeriodicInput::Require
                                                                              : app::netsolve::PeriodicInput::Refuse,
                                       "--compact-bc periodic");
    // the walls enclose every disk at the start (as in netsolve compact --boundary walls)
    if (so_.mode == qs::BoundaryMode::Walls) pk_.box = app::netsolve::walls_box(pk_);
    co_.validate(pk_.density());
  } else {
    solver_ = restore_compacted(a, co_.path, so_);
    source_ = "state " + a.from_state;
  }
  out_ = a.out;
  app::RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  rdo.inputs = {a.packing_file, a.from_state, a.state_file};
  app::open_run_dir(out_, command_, rdo);
  app::make_output_dir(out_ / "probes");
  // probe files of an earlier run in this folder would mix into yield-merge: remove them
  for (const auto& e : fs::directory_iterator(out_ / "probes")) {
    const auto name = e.path().filename().string();
    if (name.rfind("probe_", 0) == 0 && (e.path().extension() == ".csv" || e.path().extension() == ".json"))
      fs::remove(e.path());
  }
  if (!solver_) packing::write_packing_csv(pk_, out_ / "packing.csv");
  sy_ = so_.law.sigma_y;
  if (!a.quiet)
    std::fprintf(stderr, "netsolve yield: %zu particles, D0 = %.4f (%s); %s %s-%s, friction %s, %zu of %d probes, %d jobs\n",
                 solver_ ? solver_->size() : pk_.size(), solver_ ? solver_->initial_density() : pk_.density(), source_.c_str(),
                 a.precompact.c_str(), bc_name(so_.mode), po_.affine_centres ? "affine" : bc_name(po_.mode),
                 a.law.friction.c_str(), selection_.size(),
                 a.directions, jobs_);
}

/// The precompaction and history.csv (or the measures of the restored state); false when it was
/// stopped (its summary written: no unloading or probes from a diverged precompaction).
bool YieldRun::precompact() {
  using namespace netdem;
  const auto t0 = Clock::now();
  conv_.tol = so_.residual_tol;
  if (so_.iteration == qs::Iteration::PseudoTransient) conv_.max_unconverged_fraction = 0.0;
  app::netsolve::activity() = "precompacting";
  if (solver_) {
    loaded_ = solver_->measures();
    D0_ = density_at_zero_strain(loaded_, solver_->initial_density());
    t_compact_ = seconds_since(t0);
    return true;
  }
  solver_ = jammed_ ? std::make_unique<qs::NetworkSolver>(*jammed_, so_) : std::make_unique<qs::NetworkSolver>(pk_, so_);
  const double sy = sy_;
  std::string hist = "increment,E11,E22,D,S11,S22,S12,Z,contacts,residual,newton,converged,net_force_ratio,eq13_vs_contacts\n";
  app::Progress progress("precompact", co_.increments, a_.quiet);
  app::netsolve::ResidualGrowth growth;  // the stop rule of `compact` (docs/quasistatic.md "Run status")
  growth.tol = so_.residual_tol;
  std::string stopped;
  int done = 0;
  const auto on_row = [&](const qs::CompactionRow& row) {
    const auto& m = row.state;
    hist += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{:.3e},{},{},{:.3e},{:.3e}\n", row.increment, m.E11,
                        m.E22, m.density, m.S11 / sy, m.S22 / sy, m.S12 / sy, m.Z, m.contacts, row.report.residual,
                        row.report.newton_iterations, row.report.converged ? 1 : 0, m.net_force_ratio,
                        m.eq13_vs_contacts);
    if (row.increment > 0) {
      unconverged_ += !row.report.converged;
      conv_.add(row.increment, row.report.converged, row.report.newton_residual);
    }
    done = row.increment;
    progress.update(row.increment);
    loaded_ = m;
    if (row.increment > 0 && growth.add(row.increment, row.report.newton_residual))
      throw app::netsolve::StopRun{growth.message(row.increment, row.report.newton_residual)};
  };
  try {
    qs::run_compaction(*solver_, co_, on_row);
  } catch (const app::netsolve::StopRun& s) {
    stopped = s.reason;
  } catch (const qs::DivergedError& e) {
    stopped = fmt::format("increment {}: {}", done + 1, e.what());
  }
  progress.finish();
  if (!stopped.empty()) hist += "# stopped: " + stopped + "\n";
  app::write_file_atomic(out_ / "history.csv", hist);
  if (!stopped.empty()) {
    stopped_summary(stopped, done);
    return false;
  }
  D0_ = density_at_zero_strain(loaded_, solver_->initial_density());
  t_compact_ = seconds_since(t0);
  return true;
}

/// summary.json of a stopped precompaction, and its line on stderr.
void YieldRun::stopped_summary(const std::string& stopped, int done) {
  using namespace netdem;
  app::netsolve::RunStatus st;
  st.add("unstable", "precompaction stopped: " + stopped);
  conv_.judge(st, "precompaction");
  json j;
  j["command"] = command_;
  st.write(j);
  j["allow_unconverged"] = a_.allow_unconverged;
  j["precompaction"] = {{"increments_done", done}, {"increments", co_.increments}, {"unconverged_increments", unconverged_},
                        {"max_newton_residual", conv_.max_newton_residual}, {"D", loaded_.density}, {"Z", loaded_.Z}};
  if (!a_.state_file.empty()) j["precompaction"]["jammed_state"] = a_.state_file;
  app::write_file_atomic(out_ / "summary.json", j.dump(2) + "\n");
  app::close_run_dir(out_);
  std::fprintf(stderr, "netsolve yield: error: unstable: precompaction: %s (history.csv keeps increments 0..%d)\n",
               stopped.c_str(), done);
}

/// The run's setup record (in summary.json and every probe record) and its analytic surface.
void YieldRun::make_setup() {
  const YieldArgs& a = a_;
  const double sy = sy_;
  json& setup = setup_;
  setup["precompact"] = a.precompact;
  setup["to_density"] = a.from_state.empty() ? a.to_density : loaded_.density;
  setup["friction"] = a.law.friction;
  setup["normal_unloading"] = a.law.normal_unloading;
  setup["first_touch"] = a.law.first_touch;
  setup["unload_ratio"] = a.unload_ratio;
  setup["compact_bc"] = bc_name(so_.mode);
  setup["probe_bc"] = po_.affine_centres ? "affine" : bc_name(po_.mode);
  // the resolved iteration: yield-merge refuses to mix the legacy drag's points with undragged ones
  setup["iteration"] = netdem::app::netsolve::iteration_name(so_.iteration);
  setup["directions"] = a.directions;
  setup["packing"] = source_;
  setup["particles"] = solver_->size();
  setup["sigma_y"] = sy;
  setup["offset"] = a.offset;
  setup["window"] = a.window;
  setup["analytic"] = {{"D0", D0_},       {"D", loaded_.density},      {"Z0", loaded_.Z},
                       {"sigma_y", sy},  {"dir11", co_.path.E11},     {"dir22", co_.path.E22}};
  setup["loading"] = {{"S11", loaded_.S11 / sy}, {"S22", loaded_.S22 / sy}, {"S12", loaded_.S12 / sy}};
  {  // fabric-resolved affine bound at the loading point, one point per probe direction
    json f11 = json::array(), f22 = json::array();
    for (int k = 0; k < a.directions; ++k) {
      const auto p = qs::fabric_affine_point(*solver_, 2 * kPi * k / a.directions, sy);
      f11.push_back(jnum(p.S11));
      f22.push_back(jnum(p.S22));
    }
    setup["fabric"] = {{"S11", f11}, {"S22", f22}};
  }
  an_ = yr::make_analytic(setup["analytic"]);
}

/// The probe phase's solver; a switch of boundary mode rebuilds it (frictionless only).
void YieldRun::hand_over() {
  if (po_.mode != so_.mode) {
    qs::HandoverReport h;
    solver_ = qs::switch_boundary_mode(*solver_, solver_->initial_box(), solver_->seed(), po_, h);
    handover_ = {{"contacts", h.contacts},
                 {"contacts_unloaded_before_handover", h.contacts_unloaded},
                 {"S11_before", h.S11_before}, {"S22_before", h.S22_before},
                 {"S11_after", h.S11_after},   {"S22_after", h.S22_after},
                 {"zero_strain_increments", h.zero_strain_increments}, {"unconverged", h.unconverged},
                 {"centres_outside_box", h.centres_outside_box}, {"box_area_growth", h.box_area_growth}};
    netdem::packing::write_packing_csv(h.compacted, out_ / "packing_compacted.csv");
  } else {
    solver_ = std::make_unique<qs::NetworkSolver>(solver_->state(), po_);
  }
}

/// The unloading and unload.csv: from here on the section 3.4 elastic un/reloading branch, every
/// contact starting at its current overlap.
void YieldRun::unload_phase() {
  const double sy = sy_;
  solver_->set_reversible_normal(false);
  const auto t0 = Clock::now();
  qs::UnloadOptions uo;
  uo.tol = a_.unload_tol;
  uo.first_step = 0.2 * 2.0 * std::hypot(loaded_.E11, loaded_.E22) / so_.law.unload_ratio;
  un_ = qs::unload(*solver_, co_.path.rate(), sy, so_.law.unload_ratio, uo);
  const auto& un = un_;
  std::string ucsv = "increment,strain,S11,S22,S12,D,Z,contacts,newton,converged\n";
  for (std::size_t k = 0; k < un.path.size(); ++k) {
    const auto& m = un.path[k].state;
    ucsv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{}\n", k, un.path[k].strain, m.S11 / sy,
                        m.S22 / sy, m.S12 / sy, m.density, m.Z, m.contacts, un.path[k].report.newton_iterations,
                        k == 0 || un.path[k].report.converged ? 1 : 0);
  }
  netdem::app::write_file_atomic(out_ / "unload.csv", ucsv);
  t_unload_ = seconds_since(t0);
  if (!a_.quiet && !un.converged) std::fprintf(stderr, "netsolve yield: warning: %s\n", un.message.c_str());
  first_step_ = un.strain > 0 ? un.strain / 10 : 1e-6;
  loading_norm_ = std::sqrt(loaded_.S11 * loaded_.S11 + loaded_.S22 * loaded_.S22 + 2 * loaded_.S12 * loaded_.S12) / sy;
}

/// The probes, each on its own solver restored from the unloaded state: in this process for one
/// job (or one probe), otherwise in `jobs` worker processes of this program.
void YieldRun::probe_phase() {
  using namespace netdem;
  const auto t0 = Clock::now();
  const qs::ProbeSettings ps = probe_settings(a_, first_step_, loading_norm_, sy_);
  // the unloaded state and the probe settings, which the worker processes (and anyone who wants to
  // rerun a probe) start from
  qs::save_state(solver_->state(), (out_ / "probes" / "unloaded_state.txt").string());
  app::write_file_atomic(out_ / "probes" / "worker.json",
                         json({{"setup", setup_}, {"first_step", first_step_}, {"loading_norm", loading_norm_}}).dump(1) + "\n");
  std::size_t done = 0;
  auto finished = [&](int idx, const json& r) {
    ++done;
    if (!a_.quiet)
      std::fprintf(stderr, "probe %3d (theta %6.1f deg): %s [%zu/%zu]\n", idx, from_json(r["theta"]),
                   r.value("status", "?").c_str(), done, selection_.size());
    records_[idx] = r;
  };
  if (jobs_ == 1 || selection_.size() == 1) {
    qs::run_probes(solver_->state(), solver_->options(), selection_, ps, [&](const qs::ProbeResult& p) {
      finished(p.index, yr::write_probe(p, a_.directions, an_, setup_, out_));
    });
  } else {
    const auto record_file = [&](int idx) { return out_ / "probes" / fmt::format("probe_{:03d}.json", idx); };
    app::WorkerPool pool;
    pool.argv = a_.argv;
    pool.extra_args = [](int idx) { return std::vector<std::string>{"--probe-worker", std::to_string(idx)}; };
    pool.record_file = record_file;
    pool.jobs = jobs_;
    app::run_in_workers(pool, selection_, [&](const app::WorkerResult& w) {
      if (w.ok) return finished(w.index, w.record);
      // a worker that failed gets a failed record
      const json r = yr::failed_record(w.index, a_.directions, w.failure, an_, setup_);
      app::write_file_atomic(record_file(w.index), r.dump(1) + "\n");
      finished(w.index, r);
    });
  }
  t_probes_ = seconds_since(t0);
}

/// The records in selection order, yield_points.csv, the run status and summary.json.
int YieldRun::finish() {
  using namespace netdem;
  const YieldArgs& a = a_;
  const double sy = sy_;
  std::vector<json> recs;
  double probe_wall_sum = 0;
  int ok = 0;
  for (int idx : selection_) {
    recs.push_back(records_[idx]);
    probe_wall_sum += records_[idx].value("wall_s", 0.0);
    ok += records_[idx].value("status", "") == "ok";
  }
  yr::write_yield_points(out_, recs);

  // ---- status: the precompaction's convergence, the unloading; a failed probe is its own record
  app::netsolve::RunStatus status;
  conv_.judge(status, "precompaction");
  // an unloading that stops at its noise floor within 10 x --unload-tol is the documented
  // behaviour (docs/yield.md; the default scene ends at 1.9e-3 against 1e-3): recorded in
  // "unloading", not a failure; beyond that the probes start from a loaded state
  if (!un_.converged && !(un_.stress_norm <= app::netsolve::ConvergenceRecord::kResidualFactor * a.unload_tol))
    status.add("unconverged", fmt::format("unloading ended at |Sigma| = {:.3g} sigma_y, above 10 x --unload-tol = {:.3g}: {}",
                                          un_.stress_norm, 10 * a.unload_tol, un_.message));
  const double total = seconds_since(t_start_);
  json j;
  j["command"] = command_;
  status.write(j);
  j["allow_unconverged"] = a.allow_unconverged;
  j["setup"] = setup_;
  j["seed"] = solver_->seed();
  j["initial_density"] = D0_;
  j["precompaction"] = {{"D", loaded_.density}, {"Z", loaded_.Z},           {"S11", loaded_.S11 / sy},
                        {"S22", loaded_.S22 / sy}, {"S12", loaded_.S12 / sy}, {"E11", loaded_.E11},
                        {"E22", loaded_.E22},   {"contacts", loaded_.contacts}, {"unconverged_increments", unconverged_},
                        {"increments", co_.increments}, {"max_newton_residual", conv_.max_newton_residual},
                        {"last_increment_converged", conv_.last_converged}};
  if (!a.state_file.empty()) j["precompaction"]["jammed_state"] = a.state_file;
  if (!a.from_state.empty()) {
    j["precompaction"]["from_state"] = a.from_state;
    j["precompaction"]["unconverged_increments"] = nullptr;  // not known from the state
    j["precompaction"]["increments"] = nullptr;
    j["precompaction"]["max_newton_residual"] = nullptr;
    j["precompaction"]["last_increment_converged"] = nullptr;
  }
  j["analytic"] = {{"ok", an_.ok}, {"message", an_.message}};
  if (an_.ok) {
    const auto lp = qs::affine_loading_point(an_.in);
    j["analytic"]["loading_point"] = {{"S11", lp.S11 / sy}, {"S22", lp.S22 / sy}};
    j["analytic"]["E11"] = an_.in.E11;
    j["analytic"]["E22"] = an_.in.E22;
  }
  j["handover"] = handover_;
  j["unloading"] = {{"converged", un_.converged}, {"increments", static_cast<int>(un_.path.size()) - 1},
                    {"strain", un_.strain},       {"stress_norm", un_.stress_norm},
                    {"loading_norm", un_.loading_norm}, {"message", un_.message}};
  j["probes"] = {{"run", selection_.size()},  {"ok", ok},  {"directions", a.directions}, {"jobs", jobs_},
                 {"first_step", first_step_}, {"offset", a.offset}, {"max_strain", a.max_strain}, {"window", a.window},
                 {"indices", selection_}};
  j["solver"] = {{"precompaction", {{"tol", so_.residual_tol}, {"viscosity", so_.viscosity},
                                    {"viscosity_strain", so_.viscosity_strain}, {"chord_steps", so_.chord_steps},
                                    {"linear_tol", so_.linear_tolerance}, {"max_newton", so_.max_newton}}},
                 {"probes", {{"tol", po_.residual_tol}, {"viscosity", po_.viscosity},
                             {"viscosity_strain", po_.viscosity_strain}, {"chord_steps", po_.chord_steps},
                             {"linear_tol", po_.linear_tolerance}, {"max_newton", po_.max_newton}}},
                 {"iteration", netdem::app::netsolve::iteration_name(so_.iteration)},
                 {"regularisation_scale", so_.regularisation_scale},
                 {"max_cuts", so_.max_cuts}};
  if (so_.iteration == qs::Iteration::PseudoTransient)  // the merit used (energy, energy-friction or residual)
    j["solver"]["merit"] = so_.merit_name();
  j["timing_s"] = {{"total", total},
                   {"compaction", t_compact_},
                   {"unloading", t_unload_},
                   {"probes", t_probes_},
                   {"probe_wall_sum", probe_wall_sum},
                   {"share", {{"compaction", t_compact_ / total}, {"unloading", t_unload_ / total}, {"probes", t_probes_ / total}}}};
  app::write_file_atomic(out_ / "summary.json", j.dump(2) + "\n");
  app::close_run_dir(out_);
  netdem::app::summary_printf("D = %.4f (Z = %.3f): loading point S11/sy = %.4f, S22/sy = %.4f; unloaded to |S| = %.1e in %d increments; "
              "%d/%zu probes ok; %.1f s (compaction %.1f, unloading %.1f, probes %.1f) -> %s\n",
              loaded_.density, loaded_.Z, loaded_.S11 / sy, loaded_.S22 / sy, un_.stress_norm, static_cast<int>(un_.path.size()) - 1,
              ok, selection_.size(), total, t_compact_, t_unload_, t_probes_, out_.c_str());
  if (!status.ok())
    std::fprintf(stderr, "netsolve yield: %s: %s: %s\n", a.allow_unconverged ? "warning (--allow-unconverged)" : "error",
                 status.status.c_str(), status.reason().c_str());
  return status.exit_code(a.allow_unconverged);
}


int run_yield(const YieldArgs& a, const std::string& command) {
  if (a.probe_worker >= 0) return run_probe_worker(a);
  return YieldRun(a, command).run();
}

}  // namespace

/// Entry point of `netsolve yield` and `netsolve yield-merge` (argv[1] is the subcommand).
int run_yield_command(int argc, char** argv) {
  // --dim 3: the sphere packings' command (yield3.cpp) and merge (yield3_merge.cpp); --dim 2 is this one
  std::vector<char*> args(argv, argv + argc);
  bool merge3 = false;
  for (std::size_t k = 2; k < args.size(); ++k) {
    const std::string w = args[k];
    if (w != "--dim" && w.rfind("--dim=", 0) != 0) continue;
    const std::string v = w == "--dim" ? (k + 1 < args.size() ? args[k + 1] : "") : w.substr(6);
    if (v == "3" && std::string(argv[1]) == "yield") return netdem::app::netsolve::run_yield3_command(argc, argv);
    merge3 = v == "3";
    if (v != "2" && v != "3") {
      netdem::app::print_error_line(fmt::format("netsolve {}: error: --dim must be 2 or 3, got '{}'", argv[1], v));
      return 2;
    }
    args.erase(args.begin() + static_cast<long>(k), args.begin() + static_cast<long>(k) + (w == "--dim" ? 2 : 1));
    argc = static_cast<int>(args.size());
    argv = args.data();
    break;
  }
  std::string command;
  for (int k = 0; k < argc; ++k) command += (k ? " " : "") + std::string(argv[k]);
  const std::string sub = argv[1];
  CLI::App app{"netsolve " + sub};
  YieldArgs a;
  a.law = netdem::app::netsolve::law_args(qs::SolverOptions::yield_precompaction());
  for (int k = 0; k < argc; ++k) a.argv.emplace_back(argv[k]);
  std::vector<std::string> dirs;
  std::string merge_out = "results/yield_merged";
  if (sub == "yield") {
    app.description(
        "netsolve yield: precompact, unload elastically, reload along N strain-rate directions in the (E11, E22) plane "
        "and locate the yield points (Redanz & Fleck 2001 section 3.4; docs/yield.md)");
    app.add_option("--width", a.pack.width, "box width W of a new deposition in units of R")->capture_default_str();
    app.add_option("--r-min", a.pack.r_min, "smallest radius / R")->capture_default_str();
    app.add_option("--r-max", a.pack.r_max, "largest radius / R")->capture_default_str();
    app.add_flag("--mono", a.pack.mono, "monosized disks");
    app.add_option("--seed", a.pack.seed, "random seed of the deposition, a whole number in [0, 2^64)")
        ->check(netdem::app::netsolve::seed_validator())
        ->capture_default_str();
    app.add_option("--packing", a.packing_file, "packing CSV instead of a new deposition")
        ->check(non_empty_file("a packing CSV file"));
    app.add_option("--from-state", a.from_state,
                   "start from a compacted state (state.txt of `netsolve compact --save-state`) instead of precompacting; "
                   "its strain must lie along --precompact")
        ->check(non_empty_file("a state.txt of netsolve compact --save-state"));
    app.add_option("--precompact", a.precompact, "hydrostatic | closed-die")->capture_default_str();
    app.add_option("--to-density", a.to_density, "precompaction density D")->capture_default_str();
    app.add_option("--increments", a.increments, "precompaction increments")->capture_default_str();
    app.add_option("--state", a.state_file,
                   "precompact from a jammed state (jammed.json of netsolve or demsolve compact --save-state; its law must be "
                   "the command line's) instead of a packing: walls with --compact-bc walls, a layer with die")
        ->check(non_empty_file("a jammed state file"));
    app.add_option("--compact-bc", a.compact_bc,
                   "affine | die (local relaxation) | walls (four rigid frictionless walls, nothing prescribed) | periodic "
                   "(a '# periodic' --packing) during precompaction")
        ->capture_default_str();
    app.add_option("--probe-bc", a.probe_bc, "affine | die | walls | periodic during unloading and probing (default: "
                                             "--compact-bc; with --compact-bc periodic: periodic, or affine: every centre follows "
                                             "the cell; with walls: walls, or affine)");
    app.add_option("--directions", a.directions, "probes, theta_k = 360 k / N degrees, (E11dot, E22dot) = (cos, sin)")->capture_default_str();
    app.add_option("--probe", a.probe_slice, "run only the slice i/N: probes k with k mod N == i (job arrays)");
    netdem::app::netsolve::add_list_option(app, "--probes", a.probe_list, "run only these probe indices, e.g. 0,3,5");
    app.add_option("--jobs", a.jobs, "probes run at the same time (0: number of cores)")->capture_default_str();
    app.add_option("--offset", a.offset, "offset strain of the offset yield point")->capture_default_str();
    app.add_option("--max-strain", a.max_strain, "longest probe |dE|")->capture_default_str();
    app.add_option("--window", a.window, "curvature smoothing width (normalised arc length)")->capture_default_str();
    app.add_option("--fine", a.fine, "equal fine probe steps (unloading strain / 10 each) before the steps grow")->capture_default_str();
    app.add_option("--growth", a.growth, "growth factor of the probe steps after the fine ones")->capture_default_str();
    app.add_option("--unload-tol", a.unload_tol, "unload until |Sigma| < tol sigma_y")->capture_default_str();
    app.add_option("--unload-ratio", a.unload_ratio,
                   "elastic un/reloading stiffness over the loading tangent at u_max (section 3.4): the unloading "
                   "and the probes; the precompaction too with --normal-unloading elastic")
        ->capture_default_str();
    netdem::app::netsolve::add_law_options(
        app, a.law,
        "normal law during the precompaction: 'reversible' (Eq 2 both ways, the paper's compaction) or "
        "'elastic' (section 3.4 branch throughout); unloading and probes always use the elastic branch");
    app.add_flag("--quiet", a.quiet, "no progress on stderr");
    app.add_flag("--allow-unconverged", a.allow_unconverged,
                 "exit 0 for a run that summary.json marks 'unconverged' (precompaction or unloading; the status is kept)");
    app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
    app.add_option("--out", a.out, "output folder")->capture_default_str();
    app.add_option("--probe-worker", a.probe_worker, "internal: run one probe from the run folder's unloaded state")
        ->group("");
  } else {
    app.description("netsolve yield-merge [--dim 3]: assemble yield_points.csv from the probe files of several yield runs "
                    "(--dim 3: of netsolve yield --dim 3 --probe i/N runs)");
    app.add_option("dirs", dirs, "run folders (each with probes/)")->required();
    app.add_option("--out", merge_out, "output folder")->capture_default_str();
    app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier merge in --out (README.md 'Run folders')");
  }
  netdem::app::add_scene_config(app, "netsolve", sub, netdem::app::kNetsolveSections);
  try {
    app.parse(argc - 1, argv + 1);
    netdem::app::set_scene(app, "netsolve", sub);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    netdem::app::print_error_line(fmt::format("netsolve {}: error: {} (see --help)", sub, e.what()));
    return 2;
  }
  return netdem::app::netsolve::guarded("netsolve " + sub, [&]() {
    if (sub == "yield") return run_yield(a, command);
    if (merge3) return netdem::app::netsolve::run_yield3_merge(dirs, merge_out, command, a.overwrite);
    return netdem::app::netsolve::yield::run_merge(dirs, merge_out, command, a.overwrite);
  });
}
