// netsolve yield --dim 3 (issue 30 item 2): yield surfaces of sphere packings on the network core
// NetworkSolverT<3>. Precompact (hydrostatic or closed die along z) affine, in the peripheral
// layer's die or in a periodic cell; unload elastically along the reversed path (section 3.4 of
// Redanz & Fleck, the same unloading as in 2D); reload along N directions of the axisymmetric
// (p, q) plane about z, psi_k = 360 k / N with (ev, eq) = (cos psi, sin psi) the outward normal, or
// along one six-component direction (--rate); find the maximum-curvature and 0.1 % offset points of
// each curve (sys::evaluate_probe, as in 2D), and set them beside the isotropic analytic surface
// (analytic_yield3.hpp, with the run's D, Z and E) and the fabric-resolved bound on the packing's
// own contacts (qs::fabric_affine_stress3). docs/yield.md "3D".
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <mutex>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "compact3.hpp"
#include "compact_common.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/quasistatic/analytic_yield3.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/yield_probe.hpp"
#include "output.hpp"
#include "run_status.hpp"
#include "status.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace netdem::app::netsolve {

namespace {

using Mat3 = Eigen::Matrix3d;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Yield3Args {
  PackArgs pack;
  std::string packing_file, precompact = "hydrostatic", compact_bc = "auto", probe_bc;
  std::string from_state;  ///< a 3D state.txt (netsolve compact --dim 3 --save-state): no precompaction
  std::string preconditioner = "auto";  ///< --preconditioner (qs::IterationOptions::Preconditioner)
  double to_density = 0.0;  ///< 0: D0 + 0.03
  int increments = 50;
  LawArgs law = law_args(qs::SolverOptions::yield_precompaction());
  int directions = 24;
  std::vector<double> rate;  ///< --rate: one six-component direction instead of the (p, q) plane
  std::string probe_slice;
  double offset = 1e-3, max_strain = 4e-3, window = 0.1, unload_tol = 1e-3, growth = 1.2;
  double unload_ratio = contact::PlasticIndentationParams{}.unload_ratio;
  int fine = 20;
  int jobs = 0;  ///< probes at the same time, on threads (0: the number of cores)
  bool quiet = false;
  RunArgs run;
  std::string out = "results/yield3";
};

qs::BoundaryMode parse_mode(const std::string& s, const char* opt) {
  if (s == "affine") return qs::BoundaryMode::Affine;
  if (s == "die" || s == "layer") return qs::BoundaryMode::Die;
  if (s == "periodic") return qs::BoundaryMode::Periodic;
  if (s == "walls") throw UsageError(fmt::format("{} walls is 2D only in netsolve for now (--dim 3: affine, die, periodic)", opt));
  throw UsageError(fmt::format("{} '{}' is not 'affine', 'die' or 'periodic'", opt, s));
}

const char* mode_name(qs::BoundaryMode m) {
  return m == qs::BoundaryMode::Affine ? "affine" : m == qs::BoundaryMode::Periodic ? "periodic" : "die";
}

/// The probe indices of this run: every direction, or the slice i/N (k mod N == i).
std::vector<int> select_probes(const Yield3Args& a) {
  const int n = a.rate.empty() ? a.directions : 1;
  if (n < 1 || n > 100000) throw UsageError(fmt::format("--directions must be in [1, 100000], got {}", n));
  std::vector<int> sel;
  long i = 0, m = 1;
  if (!a.probe_slice.empty()) {
    const auto slash = a.probe_slice.find('/');
    if (slash == std::string::npos || !parse_int(a.probe_slice.substr(0, slash), i) ||
        !parse_int(a.probe_slice.substr(slash + 1), m) || m < 1 || i < 0 || i >= m)
      throw UsageError(fmt::format("--probe '{}' is not a slice i/N with 0 <= i < N (probes k with k mod N == i)", a.probe_slice));
  }
  for (int k = 0; k < n; ++k)
    if (k % m == i) sel.push_back(k);
  if (sel.empty()) throw UsageError(fmt::format("--probe {} selects no probe of {}", a.probe_slice, n));
  return sel;
}

/// The unit strain-rate direction of probe k.
Mat3 probe_direction(const Yield3Args& a, int k) {
  Mat3 d;
  if (a.rate.empty()) {
    d = qs::axisymmetric_rate(2.0 * std::numbers::pi * k / a.directions);
  } else {
    d << a.rate[0], a.rate[5], a.rate[4], a.rate[5], a.rate[1], a.rate[3], a.rate[4], a.rate[3], a.rate[2];
  }
  return d / d.norm();
}

/// The packing of a compacted state (--from-state): its spheres where they are now, in the
/// initial box, so that density() is the state's initial density.
packing::Packing packing_of_state(const qs::NetworkState3& s) {
  packing::Packing pk;
  pk.dim = 3;
  pk.x = s.particles.axis(0);
  pk.y = s.particles.axis(1);
  pk.z = s.particles.axis(2);
  pk.r = s.particles.r;
  pk.box = s.box0;
  pk.periodic = s.periodic;
  pk.cell = s.cell;
  pk.seed = s.seed;
  return pk;
}

/// What a run keeps of the state at the end of the precompaction (the loading point).
struct Loaded {
  qs::StressMeasuresT<3> m;
  double d0 = 0.0;
  std::map<int, Mat3> fabric;  ///< the fabric-resolved bound of each probe direction / sigma_y
  qs::AffineYield3Input analytic;
  std::string analytic_message;  ///< empty if the analytic surface could be evaluated
};

/// The rows of yield_points.csv and a probe's curve file.
std::string points_header() {
  std::string h = "probe,psi,p,q,p_offset,q_offset";
  for (const char* l : sys::voigt_labels<3>()) h += fmt::format(",S{}_offset", l);
  return h + ",p_analytic,q_analytic,p_fabric,q_fabric,stress,stress_offset,stress_analytic,stress_fabric,strain,"
             "strain_offset,elastic_slope,increments,unconverged,status,end\n";
}

/// A text for a quoted CSV field: its double quotes become single ones.
std::string unquote(std::string t) {
  for (char& c : t)
    if (c == '"') c = '\'';
  return t;
}

/// A number, or an empty field for a missing one (no NaN in a result file).
std::string num(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v + 0.0) : std::string(); }  // no -0

class Yield3Run {
 public:
  Yield3Run(const Yield3Args& a, std::string command) : a_(a), command_(std::move(command)) {}
  int run();

 private:
  void setup();
  bool precompact();
  void loading_point();
  void unload_phase();
  void probe_phase();
  std::string probe_row(int k, const sys::ProbeResult& r, const std::vector<Mat3>& full);
  int finish();

  const Yield3Args& a_;
  std::string command_;
  Clock::time_point t0_ = Clock::now();
  qs::SolverOptions so_, po_;
  qs::CompactionOptions3 co_;
  std::vector<int> sel_;
  int jobs_ = 1;
  packing::Packing pk_;
  std::string source_;
  fs::path out_;
  std::unique_ptr<qs::NetworkSolver3> solver_;
  std::unique_ptr<qs::NetworkState3> state_;  ///< --from-state: the loading point, read in setup(), until the solver has it
  bool from_state_ = false;                    ///< the run starts from --from-state (no precompaction)
  std::unique_ptr<SnapshotSeries> series_;
  std::unique_ptr<Compact3Rows> rows_;
  std::string stopped_;
  Loaded loaded_;
  qs::UnloadResult3 un_;
  double sy_ = 1.0, mu_eff_ = 0.0, first_step_ = 0.0;
  double t_compact_ = 0.0, t_unload_ = 0.0, t_probes_ = 0.0;
  std::string points_;
  int ok_ = 0;
};

/// Everything checked before the output folder exists (exit 2, nothing written), then the folder.
void Yield3Run::setup() {
  const Yield3Args& a = a_;
  jobs_ = a.jobs > 0 ? a.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (a.precompact != "hydrostatic" && a.precompact != "closed-die")
    throw UsageError(fmt::format("--precompact '{}' is not 'hydrostatic' or 'closed-die'", a.precompact));
  if (!a.rate.empty() && a.rate.size() != 6)
    throw UsageError(fmt::format("--rate needs six components E11,E22,E33,E23,E13,E12, got {}", a.rate.size()));
  for (double v : a.rate)
    if (!std::isfinite(v)) throw UsageError("--rate has a component that is not finite");
  if (!a.rate.empty() && !(probe_direction(a, 0).allFinite())) throw UsageError("--rate is zero: it has no direction");
  sel_ = select_probes(a);
  if (!(a.offset > 0.0) || !(a.max_strain > a.offset) || !(a.window > 0.0) || !(a.unload_tol > 0.0) || !(a.growth >= 1.0) ||
      a.fine < 5 || !std::isfinite(a.max_strain) || !std::isfinite(a.window) || !std::isfinite(a.unload_tol) ||
      !std::isfinite(a.growth))
    throw UsageError("need --offset > 0, --max-strain > --offset, --window > 0, --unload-tol > 0, --growth >= 1, --fine >= 5");
  if (!(a.unload_ratio >= 1.0 && a.unload_ratio <= 1e8))
    throw UsageError(fmt::format("--unload-ratio must lie in [1, 1e8], got {}", a.unload_ratio));
  if (!(a.increments >= 1 && a.increments <= 1000000))
    throw UsageError(fmt::format("--increments must be in [1, 1e6], got {}", a.increments));
  if (!a.from_state.empty()) {
    if (!a.packing_file.empty()) throw UsageError("--from-state and --packing exclude each other");
    if (fs::is_directory(a.from_state))
      throw UsageError(fmt::format("--from-state '{}' is a folder, not a state file (netsolve compact --dim 3 --save-state "
                                   "writes DIR/state.txt)", a.from_state.substr(0, 80)));
    activity() = "reading " + a.from_state;
    state_ = std::make_unique<qs::NetworkState3>(qs::load_state3(a.from_state));
    if (!state_->wall_history.empty())
      throw UsageError(fmt::format("--from-state {}: the state has wall contacts, and yield --dim 3 has no walls yet", a.from_state));
    pk_ = packing_of_state(*state_);
    source_ = "state " + a.from_state;
    from_state_ = true;
  } else {
    activity() = a.packing_file.empty() ? "building the 3D ballistic deposition" : "reading " + a.packing_file;
    if (a.packing_file.empty()) check_deposition_size(a.pack, true);
    pk_ = input_packing_3d(a.packing_file, a.pack, source_, "the network solver");
  }
  // auto: periodic for a periodic packing; otherwise affine (the 3D die leaks, docs/quasistatic.md).
  // affine with a periodic packing: every centre follows the cell.
  const std::string cbc = a.compact_bc == "auto" ? (pk_.periodic ? "periodic" : "affine") : a.compact_bc;
  so_ = qs::SolverOptions::yield_precompaction();
  so_.mode = parse_mode(cbc, "--compact-bc");
  if (so_.mode == qs::BoundaryMode::Affine && pk_.periodic) {  // every centre follows the periodic cell
    so_.mode = qs::BoundaryMode::Periodic;
    so_.affine_centres = true;
  }
  qs::BoundaryMode probe_mode =
      a.probe_bc.empty() ? (so_.affine_centres ? qs::BoundaryMode::Affine : so_.mode) : parse_mode(a.probe_bc, "--probe-bc");
  if ((so_.mode == qs::BoundaryMode::Periodic) != pk_.periodic)
    throw UsageError(fmt::format("--compact-bc {} {} a periodic packing ('# periodic' line; netsolve pack --dim 3 --periodic)",
                                 cbc, pk_.periodic ? "does not take" : "needs"));
  const bool affine_cell = so_.mode == qs::BoundaryMode::Periodic && probe_mode == qs::BoundaryMode::Affine;
  if (so_.affine_centres && !affine_cell)
    throw UsageError("--probe-bc: an affine precompaction in a periodic cell is probed affine");
  if (probe_mode != so_.mode && !affine_cell)
    throw UsageError("--probe-bc: in 3D the probes run in the precompaction's mode, or affine in its periodic cell");
  apply_law_args(a.law, so_, probe_mode);
  so_.law.unload_ratio = a.unload_ratio;
  so_.preconditioner = preconditioner_of(a.preconditioner);
  so_.validate();
  po_ = yield_probe_options(so_, probe_mode);
  po_.law.reversible = false;  // the probes start on the elastic branch of the unloaded state
  po_.validate();
  sy_ = so_.law.sigma_y;
  mu_eff_ = so_.law.mu_eff();
  co_.path = qs::StrainPath3::parse(a.precompact);
  co_.target_density = a.to_density > 0.0 ? a.to_density : pk_.density() + 0.03;
  co_.increments = a.increments;
  if (state_) {  // the loading point is the state's: its strain must lie along --precompact's path
    const Mat3 E = state_->strain, R = co_.path.rate();
    const double cosine = (E.array() * R.array()).sum() / (E.norm() * R.norm());
    if (!(E.norm() > 0.0) || !(cosine > 1.0 - 1e-9))
      throw UsageError(fmt::format("--from-state {}: its strain (E11, E22, E33) = ({:.4g}, {:.4g}, {:.4g}) does not lie "
                                   "along --precompact {}", a.from_state, E(0, 0), E(1, 1), E(2, 2), a.precompact));
    co_.target_density = pk_.density() * std::exp(-E.trace());  // the state's density (volume det exp(E))
  }
  co_.validate(pk_.density());
  out_ = a.out;
  check_run_dir(out_, run_dir_options(a.run, a.packing_file));
  open_run_dir(out_, command_, run_dir_options(a.run, a.packing_file));
  fs::create_directories(out_ / "probes");
  if (!state_) packing::write_packing_csv(pk_, out_ / "packing.csv");
  if (!a.quiet)
    std::fprintf(stderr, "netsolve yield: %zu spheres, D0 = %.4f, seed %llu (%s)\n", pk_.size(), pk_.density(),
                 static_cast<unsigned long long>(pk_.seed), source_.c_str());
}

/// The precompaction and history.csv (the columns of compact --dim 3); false when it stopped.
bool Yield3Run::precompact() {
  const auto t0 = Clock::now();
  activity() = "setting up the network solver";
  solver_ = state_ ? std::make_unique<qs::NetworkSolver3>(*state_, so_) : std::make_unique<qs::NetworkSolver3>(pk_, so_);
  state_.reset();  // the solver holds it now
  std::vector<std::string> kinds = {"particles", "contacts"};
  if (so_.mode == qs::BoundaryMode::Periodic) kinds.emplace_back("cell");
  series_ = std::make_unique<SnapshotSeries>(out_ / "snapshots.pvd", kinds);
  write_snapshot_3d(*solver_, *series_, "initial", 0.0);  // timesteps: the phases 0, 1, 2
  rows_ = std::make_unique<Compact3Rows>(*solver_, *series_, std::vector<double>{}, so_, co_, a_.quiet);
  if (from_state_) {  // the loading point itself: history.csv's one row
    qs::CompactionRowT<3> row;
    row.state = solver_->stress();
    row.report.converged = true;
    rows_->add(row);
    rows_->progress.finish();
    write_file_atomic(out_ / "history.csv", rows_->csv);
    t_compact_ = seconds_since(t0);
    return true;
  }
  activity() = "precompacting";
  try {
    qs::run_compaction(*solver_, co_, [&](const qs::CompactionRowT<3>& row) { rows_->add(row); });
  } catch (const StopRun& s) {
    stopped_ = s.reason;
  } catch (const qs::DivergedError& e) {
    stopped_ = fmt::format("increment {}: {}", rows_->done + 1, e.what());
  }
  rows_->progress.finish();
  if (!stopped_.empty()) rows_->csv += "# stopped: " + stopped_ + "\n";
  write_file_atomic(out_ / "history.csv", rows_->csv);
  t_compact_ = seconds_since(t0);
  return stopped_.empty();
}

/// The loading point: its measures, the snapshot, the analytic input and the fabric bound of each
/// probe direction (on the contacts before unloading).
void Yield3Run::loading_point() {
  Loaded& l = loaded_;
  l.m = rows_->last;
  l.d0 = solver_->initial_density();
  write_snapshot_3d(*solver_, *series_, "loaded", 1.0);
  try {
    l.analytic.density = l.m.density;
    l.analytic.z0 = l.m.Z;
    l.analytic.sigma_y = 1.0;  // stresses / sigma_y
    l.analytic.E = 0.5 * (l.m.strain + l.m.strain.transpose());
    l.analytic.mu_eff = mu_eff_;
    l.analytic.validate();
  } catch (const std::invalid_argument& e) {
    l.analytic_message = e.what();
  }
  for (int k : sel_) l.fabric[k] = qs::fabric_affine_stress3(*solver_, probe_direction(a_, k), mu_eff_, sy_);
}

/// The unloading along the reversed precompaction path, and unload.csv.
void Yield3Run::unload_phase() {
  const auto t0 = Clock::now();
  activity() = "unloading";
  // from here on in the probes' mode, as in 2D (an affine probe of a periodic cell unloads affinely)
  qs::SolverOptions o = po_;
  o.law.reversible = so_.law.reversible;
  solver_ = std::make_unique<qs::NetworkSolver3>(solver_->state(), o);
  solver_->set_reversible_normal(false);
  qs::UnloadOptions uo;
  uo.tol = a_.unload_tol;
  uo.first_step = 0.2 * 2.0 * loaded_.m.strain.norm() / so_.law.unload_ratio;
  un_ = qs::unload<3>(*solver_, co_.path.rate(), sy_, so_.law.unload_ratio, uo);
  std::string csv = "increment,strain";
  for (const char* l : sys::voigt_labels<3>()) csv += fmt::format(",S{}", l);
  csv += ",p,q,D,Z,contacts,newton,converged\n";
  for (std::size_t k = 0; k < un_.path.size(); ++k) {
    const auto& m = un_.path[k].state;
    csv += fmt::format("{},{:.9g}", k, un_.path[k].strain);
    for (double v : voigt(m.eq13)) csv += fmt::format(",{:.9g}", v / sy_);
    const auto pq = qs::pq_of(m.eq13 / sy_);
    csv += fmt::format(",{:.9g},{:.9g},{:.9g},{:.6g},{},{},{}\n", pq.p, pq.q, m.density, m.Z, m.contact_count,
                       un_.path[k].report.newton_iterations, k == 0 || un_.path[k].report.converged ? 1 : 0);
  }
  write_file_atomic(out_ / "unload.csv", csv);
  write_snapshot_3d(*solver_, *series_, "unloaded", 2.0);
  if (!a_.quiet && !un_.converged) std::fprintf(stderr, "netsolve yield: warning: %s\n", un_.message.c_str());
  first_step_ = un_.strain > 0 ? un_.strain / 10 : 1e-6;
  t_unload_ = seconds_since(t0);
}

/// Probe k's row of yield_points.csv (and its curve file probes/probe_K.csv).
std::string Yield3Run::probe_row(int k, const sys::ProbeResult& r, const std::vector<Mat3>& full) {
  std::string curve = "strain,stress";
  for (const char* l : sys::voigt_labels<3>()) curve += fmt::format(",S{}", l);
  curve += ",p,q,D,Z,newton,converged,residual\n";
  for (std::size_t i = 0; i < r.curve.samples.size(); ++i) {
    const auto& s = r.curve.samples[i];
    curve += fmt::format("{:.9g},{:.9g}", s.strain, s.stress);
    for (double v : voigt(full[i])) curve += fmt::format(",{:.9g}", v);
    const auto pq = qs::pq_of(full[i]);
    curve += fmt::format(",{:.9g},{:.9g},{:.9g},{:.6g},{},{},{:.3e}\n", pq.p, pq.q, s.density, s.Z, s.newton,
                         i == 0 || s.converged ? 1 : 0, s.residual);
  }
  write_file_atomic(out_ / "probes" / fmt::format("probe_{:03d}.csv", k), curve);
  // the stress tensor at a fractional sample position
  auto at = [&](const qs::YieldEstimate& e) {
    Mat3 m = Mat3::Constant(std::numeric_limits<double>::quiet_NaN());
    if (!e.found) return m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        std::vector<double> v;
        for (const auto& f : full) v.push_back(f(i, j));
        m(i, j) = qs::interpolate_at(v, e.position);
      }
    return m;
  };
  const Mat3 dir = probe_direction(a_, k);
  const Mat3 sc = at(r.curvature), so = at(r.offset);
  const auto pc = qs::pq_of(sc), po = qs::pq_of(so);
  Mat3 an = Mat3::Constant(std::numeric_limits<double>::quiet_NaN());
  if (loaded_.analytic_message.empty()) an = qs::affine_yield3_stress(loaded_.analytic, dir);
  const Mat3& fb = loaded_.fabric.at(k);
  const auto pa = qs::pq_of(an), pf = qs::pq_of(fb);
  std::string row = fmt::format("{},{},{},{},{},{}", k, a_.rate.empty() ? num(360.0 * k / a_.directions) : "",
                                num(pc.p), num(pc.q), num(po.p), num(po.q));
  for (double v : voigt(so)) row += "," + num(v);
  row += fmt::format(",{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\",\"{}\"\n", num(pa.p), num(pa.q), num(pf.p),
                     num(pf.q), num(r.curvature.found ? r.curvature.stress : NAN),
                     num(r.offset.found ? r.offset.stress : NAN), num(an.cwiseProduct(dir).sum()),
                     num(fb.cwiseProduct(dir).sum()), num(r.curvature.found ? r.curvature.strain : NAN),
                     num(r.offset.found ? r.offset.strain : NAN), num(r.fit.slope),
                     static_cast<int>(r.curve.samples.size()) - 1, r.curve.unconverged, unquote(r.status),
                     unquote(r.curve.end));
  return row;
}

/// The probes, each on its own solver restored from the unloaded state, on --jobs threads (each
/// probe is independent of the others and of the order, so the files do not depend on --jobs).
void Yield3Run::probe_phase() {
  const auto t0 = Clock::now();
  const qs::NetworkSolver3::State start = solver_->state();
  const sys::ProbeSettings ps = yield_probe_settings(a_, a_.rate.empty() ? a_.directions : 1, first_step_,
                                                     loaded_.m.eq13.norm() / sy_, sy_);
  struct Result {
    sys::ProbeResult r;
    std::vector<Mat3> full;
  };
  std::vector<Result> res(sel_.size());
  std::atomic<std::size_t> next{0};
  std::mutex mutex;  // the progress lines and the first usage error
  std::exception_ptr usage;
  std::size_t done = 0;
  const auto work = [&]() {
    for (std::size_t i = next++; i < sel_.size(); i = next++) {
      const int k = sel_[i];
      Result& out = res[i];
      try {
        qs::NetworkSolver3 s(start, po_);
        out.r = sys::evaluate_probe(qs::probe_along<3>(s, probe_direction(a_, k), sy_, sys::probe_options(ps), &out.full),
                                    k, ps);
      } catch (const std::invalid_argument&) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!usage) usage = std::current_exception();
        return;
      } catch (const std::exception& e) {
        out.r = sys::ProbeResult{};
        out.r.index = k;
        out.r.status = std::string("error: ") + e.what();
        out.full.clear();
      }
      const std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (!a_.quiet)
        std::fprintf(stderr, "probe %3d%s: %s [%zu/%zu]\n", k,
                     a_.rate.empty() ? fmt::format(" (psi {:6.1f} deg)", 360.0 * k / a_.directions).c_str() : "",
                     out.r.status.c_str(), done, sel_.size());
    }
  };
  activity() = "probing";
  const std::size_t threads = std::min<std::size_t>(static_cast<std::size_t>(jobs_), sel_.size());
  if (threads <= 1) {
    work();
  } else {
    std::vector<std::thread> pool;
    for (std::size_t t = 0; t < threads; ++t) pool.emplace_back(work);
    for (auto& t : pool) t.join();
  }
  if (usage) std::rethrow_exception(usage);
  points_ = points_header();
  for (std::size_t i = 0; i < sel_.size(); ++i) {
    Result& r = res[i];
    if (r.r.curve.samples.size() != r.full.size()) r.full.resize(r.r.curve.samples.size(), Mat3::Zero());
    points_ += probe_row(sel_[i], r.r, r.full);
    ok_ += r.r.status == "ok";
  }
  write_file_atomic(out_ / "yield_points.csv", points_);
  t_probes_ = seconds_since(t0);
}

/// The run status, summary.json and the closing line; the exit status.
int Yield3Run::finish() {
  RunStatus status;
  if (!stopped_.empty()) status.add("unstable", "precompaction stopped: " + stopped_);
  rows_->tally.conv.judge(status, "precompaction");
  if (stopped_.empty()) rows_->tally.equilibrium.judge(status);
  const int outside = so_.mode == qs::BoundaryMode::Die ? centres_outside_3d(*solver_, pk_.box) : 0;
  if (outside > 0) status.add("unstable", fmt::format("{} sphere centres left the box between the peripheral spheres", outside));
  if (stopped_.empty() && !un_.converged &&
      !(un_.stress_norm <= ConvergenceRecord::kResidualFactor * a_.unload_tol))
    status.add("unconverged", fmt::format("unloading ended at |Sigma| = {:.3g} sigma_y, above 10 x --unload-tol = {:.3g}: {}",
                                          un_.stress_norm, 10 * a_.unload_tol, un_.message));
  const double total = seconds_since(t0_);
  json j;
  j["command"] = command_;
  status.write(j);
  j["allow_unconverged"] = a_.run.allow_unconverged;
  j["dim"] = 3;
  j["packing"] = source_;
  j["seed"] = pk_.seed;
  j["particles"] = pk_.size();
  j["initial_density"] = pk_.density();
  j["sigma_y"] = sy_;
  j["setup"] = {{"precompact", a_.precompact}, {"to_density", co_.target_density}, {"increments", co_.increments},
                {"compact_bc", so_.affine_centres ? "affine (periodic cell)" : mode_name(so_.mode)}, {"probe_bc", po_.affine_centres ? "affine (periodic cell)" : mode_name(po_.mode)},
                {"friction", a_.law.friction}, {"mu_eff", mu_eff_}, {"unload_ratio", so_.law.unload_ratio},
                {"k_t", so_.law.k_t}, {"first_touch", so_.law.first_touch}, {"rotations", so_.rotations}};
  j["precompaction"] = rows_->done > 0 || from_state_ ? state_json(rows_->last, sy_) : json(nullptr);
  if (from_state_) j["precompaction"]["from_state"] = a_.from_state;
  if (rows_->done > 0 || from_state_) {
    const auto pq = qs::pq_of(rows_->last.eq13 / sy_);
    j["precompaction"]["p"] = pq.p;
    j["precompaction"]["q"] = pq.q;
    j["precompaction"]["increments_done"] = from_state_ ? json(nullptr) : json(rows_->done);  // not known from a state
    j["precompaction"]["unconverged_increments"] = from_state_ ? json(nullptr) : json(rows_->tally.unconverged);
  }
  j["solver"] = solver_summary(so_, solver_->timings(), solver_->free_dofs(), rows_->tally, 3);
  if (stopped_.empty()) {
    const auto& an = loaded_.analytic;
    j["analytic"] = {{"ok", loaded_.analytic_message.empty()}, {"message", loaded_.analytic_message},
                     {"model", "isotropic affine bound with the run's D, Z and E (docs/yield_analytic.md 3D)"}};
    if (loaded_.analytic_message.empty()) {
      const auto v = qs::pq_of(qs::affine_vertex3(an)), l = qs::pq_of(qs::affine_yield3_stress(an, co_.path.rate()));
      j["analytic"]["vertex"] = {{"p", v.p}, {"q", v.q}};
      j["analytic"]["loading_point"] = {{"p", l.p}, {"q", l.q}};
      j["analytic"].update(voigt_json(an.E, "E"));
      j["analytic"]["Z"] = an.z0;
      j["analytic"]["D"] = an.density;
    }
    j["unloading"] = {{"converged", un_.converged}, {"increments", static_cast<int>(un_.path.size()) - 1},
                      {"strain", un_.strain},       {"stress_norm", un_.stress_norm},
                      {"loading_norm", un_.loading_norm}, {"message", un_.message}};
    j["probes"] = {{"run", sel_.size()}, {"ok", ok_}, {"directions", a_.rate.empty() ? a_.directions : 1},
                   {"plane", a_.rate.empty() ? "axisymmetric (p, q) about z: (ev, eq) = (cos psi, sin psi)" : "--rate"},
                   {"first_step", first_step_}, {"offset", a_.offset}, {"max_strain", a_.max_strain},
                   {"window", a_.window}, {"indices", sel_}, {"jobs", jobs_}};
    if (!a_.rate.empty()) j["probes"]["rate"] = a_.rate;
  }
  j["centres_outside_box"] = outside;
  j["timing_s"] = {{"total", total}, {"compaction", t_compact_}, {"unloading", t_unload_}, {"probes", t_probes_}};
  write_file_atomic(out_ / "summary.json", j.dump(2) + "\n");
  close_run_dir(out_);
  if (stopped_.empty()) {
    const auto pq = qs::pq_of(loaded_.m.eq13 / sy_);
    summary_printf("D = %.4f (Z = %.3f): loading point p/sy = %.4f, q/sy = %.4f; unloaded to |S| = %.1e; %d/%zu probes ok; "
                   "%.1f s -> %s\n",
                   loaded_.m.density, loaded_.m.Z, pq.p, pq.q, un_.stress_norm, ok_, sel_.size(), total, out_.c_str());
  }
  if (!stopped_.empty()) {
    print_error_line(fmt::format("netsolve yield: error: unstable: precompaction stopped: {}", stopped_));
    return exit_code::untrustworthy;
  }
  if (!status.ok())
    print_error_line(fmt::format("netsolve yield: {}: {}: {}", a_.run.allow_unconverged ? "warning (--allow-unconverged)" : "error",
                                 status.status, status.reason()));
  return status.exit_code(a_.run.allow_unconverged);
}

int Yield3Run::run() {
  setup();
  if (precompact()) {
    loading_point();
    unload_phase();
    probe_phase();
  }
  return finish();
}

}  // namespace

int run_yield3_command(int argc, char** argv) {
  std::string command;
  for (int k = 0; k < argc; ++k) command += (k ? " " : "") + std::string(argv[k]);
  CLI::App app{"netsolve yield --dim 3: yield surfaces of sphere packings (docs/yield.md \"3D\")"};
  Yield3Args a;
  int dim = 3;
  app.add_option("--dim", dim, "3: spheres (this command); 2: disks, the paper's (see netsolve yield --help)")
      ->check(CLI::IsMember({3}));
  app.add_option("--width", a.pack.width, "box width W of a new 3D deposition in units of R")->capture_default_str();
  app.add_option("--r-min", a.pack.r_min, "smallest radius / R")->capture_default_str();
  app.add_option("--r-max", a.pack.r_max, "largest radius / R")->capture_default_str();
  app.add_flag("--mono", a.pack.mono, "monosized spheres");
  app.add_option("--seed", a.pack.seed, "random seed of the deposition")->check(seed_validator())->capture_default_str();
  app.add_option("--lateral", a.pack.lateral, "walls | periodic sides of a new deposition")->capture_default_str();
  app.add_option("--packing", a.packing_file, "3D packing CSV (netsolve pack --dim 3 [--periodic]) instead of a new deposition");
  app.add_option("--from-state", a.from_state, "a compacted state (state.txt of netsolve compact --dim 3 --save-state) as the "
                 "loading point instead of a precompaction; its strain must lie along --precompact, and --compact-bc "
                 "must be the mode it was compacted in")->check(CLI::ExistingFile);
  app.add_option("--precompact", a.precompact, "hydrostatic | closed-die (along z)")->capture_default_str();
  app.add_option("--to-density", a.to_density, "precompaction density D (0: D0 + 0.03)")->capture_default_str();
  app.add_option("--increments", a.increments, "precompaction increments")->capture_default_str();
  app.add_option("--compact-bc", a.compact_bc,
                 "affine | die (the peripheral layer) | periodic | auto (periodic for a periodic packing, else affine: the "
                 "3D die leaks)")
      ->capture_default_str();
  app.add_option("--probe-bc", a.probe_bc, "affine | die | periodic (default: --compact-bc; affine also in a periodic cell)");
  app.add_option("--directions", a.directions, "probes psi_k = 360 k / N degrees, (ev, eq) = (cos psi, sin psi)")
      ->capture_default_str();
  app.add_option("--rate", a.rate, "one probe along E11,E22,E33,E23,E13,E12 instead of the (p, q) plane")->delimiter(',');
  app.add_option("--probe", a.probe_slice, "run only the slice i/N: probes k with k mod N == i (job arrays; "
                 "netsolve yield-merge --dim 3 assembles the slices)");
  app.add_option("--jobs", a.jobs, "probes run at the same time, on threads (0: number of cores); the files do not "
                 "depend on it")->capture_default_str()->check(CLI::NonNegativeNumber);
  app.add_option("--offset", a.offset, "offset strain of the offset yield point")->capture_default_str();
  app.add_option("--max-strain", a.max_strain, "longest probe |dE|")->capture_default_str();
  app.add_option("--window", a.window, "curvature smoothing width (normalised arc length)")->capture_default_str();
  app.add_option("--fine", a.fine, "equal fine probe steps (unloading strain / 10 each) before the steps grow")->capture_default_str();
  app.add_option("--growth", a.growth, "growth factor of the probe steps after the fine ones")->capture_default_str();
  app.add_option("--preconditioner", a.preconditioner, "the linear solver's preconditioner, precompaction and probes: "
                 "translations (the factor of the translations' block, each sphere's rotation block inverted; GMRES on the "
                 "whole matrix), full (the whole matrix's factor), auto (translations where rotations are unknowns)")
      ->check(CLI::IsMember({"auto", "full", "translations"}))->capture_default_str();
  app.add_option("--unload-tol", a.unload_tol, "unload until |Sigma| < tol sigma_y")->capture_default_str();
  app.add_option("--unload-ratio", a.unload_ratio, "elastic un/reloading stiffness / loading tangent (section 3.4)")
      ->capture_default_str();
  add_law_options(app, a.law, "normal law of the precompaction: reversible (Eq 2) or elastic (section 3.4 branch)");
  app.add_flag("--quiet", a.quiet, "no progress on stderr");
  app.add_flag("--allow-unconverged", a.run.allow_unconverged, "exit 0 even if the result is untrustworthy");
  app.add_flag("--overwrite", a.run.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
  app.add_option("--out", a.out, "output folder")->capture_default_str();
  try {
    app.parse(argc - 1, argv + 1);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    print_error_line(fmt::format("netsolve yield --dim 3: error: {} (see --help)", e.what()));
    return exit_code::usage;
  }
  return guarded("netsolve yield", [&]() { return Yield3Run(a, command).run(); });
}

}  // namespace netdem::app::netsolve
