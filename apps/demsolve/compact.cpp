// demsolve compact: the explicit DEM with the plastic-indentation law (Redanz & Fleck 2001) as the
// dynamic referee of netsolve compact: the same packing, strain path, boundary layer, units
// (sigma_y = 1, R = 1, rho = 1, t* = R sqrt(rho/sigma_y) = 1) and files (history.csv with netsolve's
// column names and sign convention, summary.json, .vtp snapshots). Disks (2D) and spheres
// (--dim 3) alike: the protocol is the library's (netdem/dynamic/compaction.hpp); this file is its
// command line and its files. See docs/dynamic.md "demsolve compact".
#include "compact.hpp"
#include "scene.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/dynamic/compaction.hpp"
#include "netdem/dynamic/jammed.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/jammed_state.hpp"
#include "output.hpp"
#include "protocol.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

void check_compact_numbers(const DemCompactArgs& a) {
  if (!(std::isfinite(a.damping) && a.damping >= 0.0 && a.damping <= 1.0))
    throw UsageError(fmt::format("--damping must be in [0, 1] (fraction of critical damping), got {}", a.damping));
  if (!(std::isfinite(a.drag) && a.drag >= 0.0))
    throw UsageError(fmt::format("--drag must be a finite number >= 0, got {}", a.drag));
  if (!(std::isfinite(a.first_touch) && a.first_touch > 0.0 && a.first_touch <= 0.01))
    throw UsageError(fmt::format("--first-touch must be in (0, 0.01] (the explicit solver needs the bounded first-touch "
                                 "stiffness), got {}", a.first_touch));
  // the explicit step follows the stiffest tangential spring k_t sigma_y A_c: 1e6 (1e3 x the
  // default) keeps a run within reach of --max-steps
  if (!(std::isfinite(a.k_t) && a.k_t >= 0.0 && a.k_t <= 1e6))
    throw UsageError(fmt::format("--k-t must be in [0, 1e6] sigma_y/R for the explicit solver (its time step follows "
                                 "k_t sigma_y A_c), got {}", a.k_t));
  if (!(std::isfinite(a.steps_per_contact) && a.steps_per_contact >= 10.0 && a.steps_per_contact <= 1e4))
    throw UsageError(fmt::format("--steps-per-contact must be in [10, 1e4], got {}", a.steps_per_contact));
}

namespace {

/// The packing: a packing file of the run's dimension, or netsolve pack's deposition.
template <int D>
packing::Packing input_packing_of(const DemCompactArgs& a, std::string& source) {
  if constexpr (D == 2) {
    try {
      return netdem::app::netsolve::input_packing(a.packing_file, a.pack, source, "demsolve compact",
                                                  netdem::app::netsolve::PeriodicInput::Caller);
    } catch (const UsageError& e) {  // a 3D packing file: say how to run it
      if (std::string(e.what()).find("is a 3D packing") != std::string::npos)
        throw UsageError(std::string(e.what()) + " without --dim 3");
      throw;
    }
  } else {
    return netdem::app::netsolve::input_packing_3d(a.packing_file, a.pack, source, "the explicit DEM");
  }
}

/// The jammed state of --state, checked against the command line (dimension, walls, law).
template <int D>
std::optional<sys::JammedStateT<D>> input_state(const DemCompactArgs& a, bool walls, const DynamicOptions& o) {
  if (a.state_file.empty()) return std::nullopt;
  if (!a.packing_file.empty()) throw UsageError("--state and --packing exclude each other");
  const std::string text = sys::read_text_file(a.state_file, "jammed state file");
  if (const int dim = sys::jammed_state_dim(text, a.state_file); dim != D)
    throw UsageError(fmt::format("--state {} is a {}D state: run it with --dim {}", packing::quote_input(a.state_file), dim, dim));
  sys::JammedStateT<D> j = sys::parse_jammed_state<D>(text, a.state_file);
  if (j.walls != walls)
    throw UsageError(fmt::format("--state {} holds a box {} contact walls: run it {} --boundary walls",
                                 packing::quote_input(a.state_file), j.walls ? "with" : "without", j.walls ? "with" : "without"));
  if (const std::string d = sys::law_difference(j.law, o.plastic); !d.empty())
    throw UsageError(fmt::format("--state {}: its contact law is not the command line's ({}; state vs command line): give "
                                 "the state's --friction, --k-t, --first-touch and --normal-unloading",
                                 packing::quote_input(a.state_file), d));
  return j;
}

/// The checks of the options that depend on the dimension.
template <int D>
void check_boundary(const DemCompactArgs& a, bool walls) {
  if (walls && a.affine) throw UsageError("--affine and --boundary walls exclude each other (affine prescribes every centre)");
  const bool periodic = a.boundary == "periodic";
  if (a.simple_shear && !periodic)
    throw UsageError("--simple-shear needs --boundary periodic (walls and the peripheral layer stay axis-aligned)");
  if (periodic) {
    if (a.affine)
      throw UsageError("--affine and --boundary periodic exclude each other (in a periodic cell the cell follows the strain "
                       "and every particle is free)");
    if (!a.state_file.empty())
      throw UsageError("--state: a jammed state has no periodic cell yet; --boundary periodic takes --packing FILE");
    if (a.save_state) throw UsageError("--save-state: a jammed state has no periodic cell yet (--boundary periodic)");
    if (a.packing_file.empty())
      throw UsageError("--boundary periodic needs --packing FILE, a periodic packing ('# periodic'; netsolve pack --periodic)");
    return;
  }
  if constexpr (D == 3) {
    if (!walls && !a.affine)
      throw UsageError("--dim 3 takes --boundary walls or --affine, or --boundary periodic with a periodic packing "
                       "(--boundary layer, netsolve's peripheral layer, is 2D only)");
    if (a.pack.lateral != "walls")
      throw UsageError(fmt::format("--lateral '{}': the explicit DEM has no lateral-periodic boundary (demsolve compact "
                                   "--dim 3 takes --lateral walls; a fully periodic packing runs with --boundary periodic)", packing::quote_input(a.pack.lateral)));
    if (a.pack.lid != "centre" && a.pack.lid != "inside")
      throw UsageError(fmt::format("--lid '{}' is not 'centre' or 'inside'", packing::quote_input(a.pack.lid)));
  }
}

/// The run's files: history.csv rows, snapshots at the --snapshots densities, checkpoints, progress.
template <int D>
class CompactFiles : public CompactionObserverT<D> {
 public:
  /// simple_shear: no Figs 7-8 columns (the cell's spin turns every branch, and Eq 16's u_T^a, from the
  /// symmetric strain, has no spin: docs/dynamic.md)
  CompactFiles(const DynamicSolverT<D>& s, const fs::path& out, std::vector<double> snaps, bool walls, double t_end,
               bool quiet, bool legs, bool simple_shear)
      : s_(s), out_(out), series_(compact_snapshot_series(out, s.periodic())), snaps_(std::move(snaps)), walls_(walls),
        periodic_(s.periodic()), legs_(legs), tangential_(D == 2 && !simple_shear),
        progress_("compact", t_end, quiet) {
    const auto& lab = sys::voigt_labels<D>();
    csv_ = legs_ ? "increment,leg" : "increment";
    for (const char* l : lab) csv_ += fmt::format(",E{}", l);
    csv_ += ",D";
    for (const char* l : lab) csv_ += fmt::format(",S{}", l);
    for (const char* l : lab) csv_ += fmt::format(",S{}_contacts", l);
    csv_ += ",Z,contacts,sliding,mean_fn,dev_un_mean_ratio,dev_un_ratio_of_means,affine_ut,";
    if (tangential_) csv_ += "dev_ut_centres,dev_ut_rotations,";  // (netsolve's Figs 7-8 columns)
    csv_ += "time,I,kinetic_ratio,steps,samples,dt,outside,D_in_box";
    if (walls_) csv_ += ",wall_vs_contact_gap";
    if (periodic_)
      for (const char* l : lab) csv_ += fmt::format(",S{}_kinetic", l);
    csv_ += "\n";
  }
  void row(const CompactionRowT<D>& r) override {
    const auto& m = r.mean;
    csv_ += fmt::format("{}", r.increment);
    if (legs_) csv_ += fmt::format(",{}", r.leg);
    for (double e : r.E) csv_ += fmt::format(",{:.9g}", e);
    csv_ += fmt::format(",{:.9g}", r.density);
    for (double v : m.S) csv_ += fmt::format(",{:.9g}", v);
    for (double v : m.Sc) csv_ += fmt::format(",{:.9g}", v);
    csv_ += fmt::format(",{:.6g},{:.6g},{:.6g},{:.9g},{:.6g},{:.6g},{:.6g}", m.Z, m.contacts, m.sliding, m.mean_fn,
                        m.dev_mean_ratio, m.dev_ratio_of_means, m.affine_ut);
    if (tangential_) csv_ += fmt::format(",{:.6g},{:.6g}", m.dev_ut_centres, m.dev_ut_rotations);
    csv_ += fmt::format(",{:.9g},{},{:.4e},{},{},{:.4e}", r.time,
                        std::isfinite(r.I) ? fmt::format("{:.6g}", r.I) : std::string(), r.kinetic_ratio, r.steps,
                        r.samples, r.dt);
    csv_ += fmt::format(",{},{:.9g}", r.outside, r.density_in_box);
    if (walls_) csv_ += fmt::format(",{:.4e}", r.wall_gap);
    if (periodic_)
      for (double v : m.Sk) csv_ += fmt::format(",{:.6g}", v);
    csv_ += "\n";
    if (leg_end_.size() <= static_cast<std::size_t>(r.leg)) leg_end_.resize(static_cast<std::size_t>(r.leg) + 1);
    leg_end_[static_cast<std::size_t>(r.leg)] = r;
    if (r.increment == 0) return;
    while (next_snap_ < snaps_.size() && s_.density() >= snaps_[next_snap_] - 1e-9) {
      write_compact_snapshot(s_, series_, fmt::format("D{:.3f}", snaps_[next_snap_]), cs_);
      ++next_snap_;
    }
  }
  void progress(double t) override { progress_.update(t); }
  void checkpoint(int) override { write_file_atomic(out_ / "history.csv", csv_); }
  void finish(const std::string& stopped) {
    progress_.finish();
    if (!stopped.empty()) csv_ += "# stopped: " + stopped + "\n";
    write_file_atomic(out_ / "history.csv", csv_);
  }
  /// A snapshot of the solver's state now (initial, final), in the series.
  void snapshot(const std::string& tag) { write_compact_snapshot(s_, series_, tag, cs_); }
  /// The last row of each leg reached.
  const std::vector<CompactionRowT<D>>& leg_ends() const { return leg_end_; }

 private:
  const DynamicSolverT<D>& s_;
  fs::path out_;
  SnapshotSeries series_;
  std::vector<double> snaps_;
  bool walls_, periodic_, legs_, tangential_;
  Progress progress_;
  std::string csv_;
  std::size_t next_snap_ = 0;
  std::vector<ContactInfo> cs_;
  std::vector<CompactionRowT<D>> leg_end_;
};

/// summary.json: what the run was asked.
template <int D>
nlohmann::json compact_summary(const std::string& command, const DemCompactArgs& a, const sys::StrainPathT<D>& path,
                               const CompactionRateT<D>& rate, const std::string& source, std::uint64_t seed,
                               std::size_t n, std::size_t prescribed) {
  const auto& lab = sys::voigt_labels<D>();
  nlohmann::json j;
  j["command"] = command;
  j["dim"] = D;
  j["packing"] = source;
  j["seed"] = seed;
  j["particles"] = n;
  j["initial_density"] = rate.initial_density;
  j["sigma_y"] = 1.0;
  j["friction"] = a.friction;
  j["mode"] = a.affine ? "affine" : a.boundary == "walls" ? "walls" : a.boundary == "periodic" ? "periodic" : "die";
  j["boundary"] = a.affine ? "affine" : a.boundary;
  j["prescribed"] = prescribed;
  j["rotations"] = !a.no_rotation;
  j["path"] = {{"name", path.name}};
  if (a.boundary == "periodic") j["simple_shear"] = a.simple_shear;
  j["strain_rate"] = {{"gamma_dot", rate.gamma_dot}};
  for (std::size_t k = 0; k < lab.size(); ++k) {
    j["path"][std::string("E") + lab[k]] = path.E[k];
    j["strain_rate"][std::string("E") + lab[k]] = rate.rate[k];
  }
  j["increments"] = a.increments;
  j["to_density"] = a.to_strain > 0.0 ? nlohmann::json(nullptr) : nlohmann::json(a.to_density);
  if (a.to_strain > 0.0) j["to_strain"] = a.to_strain;
  j["k_t"] = a.k_t;
  j["first_touch"] = a.first_touch;
  j["normal_unloading"] = a.normal_unloading;
  j["inertial_number"] = a.inertial_number;
  j["t_end"] = rate.t_end;
  j["damping"] = {{"normal", a.damping}, {"tangential", a.damping}};
  j["drag"] = a.drag;
  j["steps_per_contact"] = a.steps_per_contact;
  j["threads"] = a.threads;
  j["units"] = "sigma_y = 1, R = 1 (lengths of the packing), rho = 1, t* = R sqrt(rho/sigma_y) = 1";
  j["contact_forces"] =
      "Z, mean_fn, sliding, the snapshots' normal_force: the loaded particle contacts, spring force without the dashpot";
  return j;
}

/// summary.json: what the run did.
template <int D>
void add_results(nlohmann::json& j, const CompactionSummaryT<D>& r, const DynamicSolverT<D>& s, bool walls) {
  const auto& lab = sys::voigt_labels<D>();
  const auto& m = r.last.mean;
  nlohmann::json fin = {{"D", s.density()},         {"Z", m.Z}, {"contacts", m.contacts}, {"sliding", m.sliding},
                        {"I", r.last.I},            {"kinetic_ratio", m.work > 0 ? m.kinetic / m.work : 0.0},
                        {"time", s.time()}};
  for (std::size_t k = 0; k < lab.size(); ++k) {
    fin[std::string("S") + lab[k]] = m.S[k];
    fin[std::string("S") + lab[k] + "_contacts"] = m.Sc[k];
    fin[std::string("E") + lab[k]] = r.last.E[k];
  }
  if (s.periodic()) {  // the kinetic stress of the fluctuations, apart from the contact stress
    for (std::size_t k = 0; k < lab.size(); ++k) fin[std::string("S") + lab[k] + "_kinetic"] = m.Sk[k];
    nlohmann::json cell = nlohmann::json::array();
    for (int c = 0; c < D; ++c)
      for (int r = 0; r < D; ++r) cell.push_back(s.cell().h(r, c));
    fin["cell"] = cell;
    fin["cell_remaps"] = s.cell_remaps();
  }
  j["final"] = fin;
  if (walls) {
    j["wall_vs_contact_gap"] = r.last_wall_gap;
    j["max_wall_vs_contact_gap"] = r.max_wall_gap;
    j["wall_vs_contact_warning"] = r.max_wall_gap > 0.02;
  }
  j["dt"] = {{"first", r.dt_first}, {"last", s.dt()}};
  j["steps"] = r.steps;
  j["neighbour_rebuilds"] = s.rebuilds();
}

/// summary.json "legs" of a run that precompacts: each leg's path, target, windows, strain rate and
/// duration, and its last row (null if the run stopped before it); the path's equivalent strain
/// |E| = sqrt(dE:dE) from the end of the precompaction.
template <int D>
nlohmann::json legs_summary(const std::vector<CompactionLegT<D>>& legs, const std::string& path,
                            const std::vector<CompactionRowT<D>>& ends) {
  const auto& lab = sys::voigt_labels<D>();
  nlohmann::json out = nlohmann::json::array();
  int last_row = 0;  // the row that ends leg l
  for (std::size_t l = 0; l < legs.size(); ++l) {
    const CompactionLegT<D>& leg = legs[l];
    last_row += leg.increments;
    nlohmann::json j = {{"leg", l},
                        {"name", l == 0 ? "precompaction" : "path"},
                        {"path", l == 0 ? std::string("hydrostatic") : path},
                        {"increments", leg.increments},
                        {"duration", leg.rate.t_end},
                        {"strain_rate", {{"gamma_dot", leg.rate.gamma_dot}}}};
    for (std::size_t k = 0; k < lab.size(); ++k) j["strain_rate"][std::string("E") + lab[k]] = leg.rate.rate[k];
    if (leg.target_strain > 0.0) {
      j["to_strain"] = leg.target_strain;
    } else {
      j["to_density"] = leg.target_density;
    }
    if (!(l < ends.size() && ends[l].increment == last_row)) {  // the run stopped before the leg's end
      j["end"] = nullptr;
      out.push_back(j);
      continue;
    }
    const CompactionRowT<D>& e = ends[l];
    nlohmann::json end = {{"increment", e.increment}, {"D", e.density}, {"time", e.time}, {"Z", e.mean.Z}};
    double e2 = 0.0;
    for (std::size_t k = 0; k < lab.size(); ++k) {
      end[std::string("S") + lab[k]] = e.mean.S[k];
      end[std::string("E") + lab[k]] = e.E[k];
      const double d = l == 0 ? e.E[k] : e.E[k] - ends[l - 1].E[k];
      e2 += (k < static_cast<std::size_t>(D) ? 1.0 : 2.0) * d * d;
    }
    end["strain"] = std::sqrt(e2);
    j["end"] = end;
    out.push_back(j);
  }
  return out;
}

/// jammed.json: the final state at rest, its strain the state's (if it started from one) plus the run's.
template <int D>
void save_jammed(const DynamicSolverT<D>& s, const Voigt<D>& run_strain, Eigen::Matrix<double, D, D> E,
                 std::uint64_t seed, const fs::path& out) {
  for (int k = 0; k < kVoigt<D>; ++k) {
    const double e = run_strain[static_cast<std::size_t>(k)];
    const int r = sys::voigt_row<D>(k), c = sys::voigt_col<D>(k);
    E(r, c) += e;
    if (r != c) E(c, r) += e;
  }
  sys::write_jammed_state(jammed_state(s, E, seed), (out / "jammed.json").string());
}

/// How a run that cannot be trusted ends: its status and reason in summary.json, the text that
/// closes the files, the one line on stderr.
struct UntrustedEnd {
  std::string status, reason, finish, message;
};

/// Closes the files and the folder of a run that stopped unstable or incomplete; exit status 3.
template <int D>
int stop_untrustworthy(CompactFiles<D>& files, nlohmann::json& summary, const fs::path& out,
                       const CompactionSummaryT<D>& r, const UntrustedEnd& end) {
  files.finish(end.finish);
  summary["increments_done"] = r.increments_done;
  summary["steps"] = r.steps;
  summary["status"] = end.status;
  summary["status_reason"] = end.reason;
  write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
  close_run_dir(out);
  print_error_line("demsolve: error: " + end.message);
  return exit_code::untrustworthy;
}

/// The prescribed particles of the boundary mode, set on the solver: layer: the peripheral layer,
/// its spins held; affine: every centre, the spins free but the layer's (2D); walls and a periodic
/// cell: none.
template <int D>
std::vector<std::uint32_t> prescribe(DynamicSolverT<D>& s, const packing::Packing& pk, const DemCompactArgs& a, bool walls,
                                     bool periodic) {
  std::vector<std::uint32_t> pre;
  if (periodic) {  // every particle free, the cell follows the strain
  } else if constexpr (D == 2) {
    // layer: the layer prescribed, its spins held; affine: every centre prescribed, the spins free
    // except the peripheral layer's, as netsolve and Redanz & Fleck section 2.4 ("the rotation of
    // particles in the peripheral layer is prevented")
    pre = prescribed_particles(pk, a.affine, walls);
    s.set_prescribed(pre, !a.affine);
    if (a.affine) s.hold_spins(prescribed_particles(pk, false, false));
  } else {
    // affine: every centre prescribed, every spin free (3D has no peripheral layer); walls: none
    if (a.affine)
      for (std::uint32_t p = 0; p < pk.size(); ++p) pre.push_back(p);
    s.set_prescribed(pre, false);
  }
  return pre;
}

/// The compaction options of the command line (the door checks them against the packing).
CompactionOptions compaction_options(const DemCompactArgs& a) {
  CompactionOptions co;
  co.target_density = a.to_density;
  co.target_strain = a.to_strain;
  co.precompact_density = a.precompact_density;
  co.simple_shear = a.simple_shear;
  co.precompact_increments = a.precompact_increments;
  co.inertial_number = a.inertial_number;
  co.increments = a.increments;
  co.max_steps = a.max_steps;
  co.walls = a.boundary == "walls";
  co.check_numbers();
  return co;
}

/// The end of a run that finished: the final snapshot, jammed.json, summary.json, the line on
/// stdout; the exit status.
template <int D>
int finish_run(CompactFiles<D>& files, nlohmann::json& summary, const CompactionSummaryT<D>& r, const DynamicSolverT<D>& s,
               const DemCompactArgs& a, const std::optional<sys::JammedStateT<D>>& jammed, std::uint64_t seed,
               double wall, const fs::path& out) {
  files.snapshot("final");
  if (a.save_state) save_jammed<D>(s, r.last.E, jammed ? jammed->strain : Eigen::Matrix<double, D, D>::Zero(), seed, out);
  if (a.save_state || jammed) summary["jammed_state"] = {{"from", a.state_file}, {"saved", a.save_state ? "jammed.json" : ""}};
  summary["status"] = r.status;
  std::string reason = r.ok() ? "every instability check passed" : r.reason;
  for (const auto& w : r.warnings) reason += "; warning: " + w;
  summary["status_reason"] = reason;
  summary["warnings"] = r.warnings;
  summary["increments_done"] = r.increments_done;
  summary["centres_outside_box"] = r.outside;
  add_results(summary, r, s, a.boundary == "walls");
  const std::size_t n = s.particles().size();
  summary["timing_s"] = {{"wall", wall}, {"particle_steps_per_s", static_cast<double>(r.steps) * n / std::max(wall, 1e-9)}};
  write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
  close_run_dir(out);
  const auto& m = r.last.mean;
  std::string diag = fmt::format("S11/sy = {:.4f}, S22/sy = {:.4f}", m.S[0], m.S[1]);
  std::string diag_c = fmt::format("{:.4f}, {:.4f}", m.Sc[0], m.Sc[1]);
  if constexpr (D == 3) {
    diag += fmt::format(", S33/sy = {:.4f}", m.S[2]);
    diag_c += fmt::format(", {:.4f}", m.Sc[2]);
  }
  netdem::app::summary_printf("D = %.4f: %s (contacts %s), Z = %.3f, I = %.3g, %lld steps, %.2f s -> %s\n", s.density(), diag.c_str(),
              diag_c.c_str(), m.Z, r.last.I, static_cast<long long>(r.steps), wall, out.c_str());
  for (const auto& w : r.warnings) print_error_line("demsolve: warning: " + w);
  if (!r.ok()) {
    print_error_line("demsolve: error: " + r.status + ": " + r.reason);
    return exit_code::untrustworthy;
  }
  return exit_code::ok;
}

template <int D>
int run_compact(const std::string& command, const DemCompactArgs& a, const fs::path& out) {
  // ---- the door: every value before anything is written ----------------------------------------
  const auto path = sys::StrainPathT<D>::parse(a.path);
  const CompactionOptions co = compaction_options(a);
  check_compact_numbers(a);
  if (a.boundary != "layer" && a.boundary != "walls" && a.boundary != "periodic")
    throw UsageError(fmt::format("--boundary '{}' is not 'layer', 'walls' or 'periodic'", packing::quote_input(a.boundary)));
  const bool walls = a.boundary == "walls", periodic = a.boundary == "periodic";
  check_boundary<D>(a, walls);
  const double mu = netdem::app::netsolve::parse_friction(a.friction);
  std::vector<double> snaps = a.snapshots;  // a set of densities (the file names carry each): any order
  std::sort(snaps.begin(), snaps.end());
  const RunDirOptions rdo =
      check_scene_run_dir(out, a.overwrite, a.state_file.empty() ? a.packing_file : a.state_file, a.pack);
  DynamicOptions o = plastic_options(mu, a.k_t, a.normal_unloading == "reversible", a.first_touch, a.damping,
                                     a.drag, a.steps_per_contact);
  o.threads = a.threads;
  const auto jammed = input_state<D>(a, walls, o);
  std::string source = jammed ? "jammed state " + a.state_file : std::string();
  const packing::Packing pk = jammed ? jammed->packing() : input_packing_of<D>(a, source);
  check_memory(pk.size());
  const std::size_t n = pk.size();
  if (n == 0) throw UsageError("the packing has no particles");
  if (pk.periodic && !periodic)
    throw UsageError(fmt::format("--packing {} is periodic ('# periodic'): run it with --boundary periodic (a box would cut "
                                 "its contacts across the faces)", packing::quote_input(a.packing_file)));
  if (periodic && !pk.periodic)
    throw UsageError(fmt::format("--boundary periodic needs a periodic packing ('# periodic'; netsolve pack --periodic); "
                                 "--packing {} is not", packing::quote_input(a.packing_file)));

  // rho = 1
  ParticlesT<D> P = periodic ? periodic_particles_from<D>(pk, 1.0) : particles_at_rest<D>(pk, 1.0);
  // the walls enclose every particle at the start (the deposition's top particles stick out of its
  // box); a jammed state brings its own box
  Box box(jammed ? jammed->box : walls ? netdem::app::netsolve::walls_box(pk) : pk.box);
  box.contact_walls = walls;
  box.right.mode = box.top.mode = WallMode::Affine;
  if constexpr (D == 3) box.back.mode = WallMode::Affine;
  double solid = 0.0;
  for (double r : P.r) solid += D == 2 ? std::numbers::pi * r * r : 4.0 / 3.0 * std::numbers::pi * r * r * r;
  double box_measure = (box.x_max - box.x_min) * (box.y_max - box.y_min);
  if constexpr (D == 3) box_measure *= box.z_max - box.z_min;
  if (periodic) box_measure = packing::periodic_cell<D>(pk).measure();
  const double D0 = solid / box_measure;
  co.validate(path, D0);
  // the legs: the precompaction (if any), then the path; the rate of the path is the summary's
  const std::vector<CompactionLegT<D>> legs = compaction_legs(path, co, D0);
  const CompactionRateT<D>& rate = legs.back().rate;
  double t_end = 0.0;
  for (const auto& leg : legs) t_end += leg.rate.t_end;

  activity() = "setting up the explicit solver";
  DynamicSolverT<D> s = jammed      ? solver_from_jammed(*jammed, 1.0, box, o)
                        : periodic  ? DynamicSolverT<D>(std::move(P), o.plastic, packing::periodic_cell<D>(pk), o)
                                    : DynamicSolverT<D>(std::move(P), o.plastic, box, o);
  set_strain_rate(s, legs.front().rate.rate, co.simple_shear);
  s.set_affine_velocities();
  const std::vector<std::uint32_t> pre = prescribe(s, pk, a, walls, periodic);
  s.set_rotations(!a.no_rotation);
  const double dt_first = s.dt();
  const double steps_est = t_end / dt_first;
  if (!(steps_est <= a.max_steps))  // the library refuses it too; here before the folder opens
    throw UsageError(fmt::format("the run needs at least {:.3g} time steps of {:.3g} t* (I = {:g}), more than --max-steps "
                                 "= {:.3g}: raise --inertial-number or --max-steps", steps_est, dt_first,
                                 a.inertial_number, a.max_steps));

  open_run_dir(out, command, rdo);
  packing::write_packing_csv(pk, out / "packing.csv");
  if (!a.quiet)
    std::fprintf(stderr, "demsolve compact%s: %zu %s, D0 = %.4f, seed %llu (%s); I = %g, gamma' = %.4g, t_end = %.4g, "
                 "dt = %.3g, about %.3g steps\n", D == 3 ? " --dim 3" : "", n, D == 2 ? "particles" : "spheres", D0,
                 static_cast<unsigned long long>(pk.seed), source.c_str(), a.inertial_number, rate.gamma_dot, t_end,
                 dt_first, steps_est);
  CompactFiles<D> files(s, out, snaps, walls, t_end, a.quiet, legs.size() > 1, co.simple_shear);
  files.snapshot("initial");
  nlohmann::json summary = compact_summary<D>(command, a, path, rate, source, pk.seed, n, pre.size());
  if (legs.size() > 1) summary["t_end"] = t_end;

  const auto t0 = std::chrono::steady_clock::now();
  activity() = "compacting";
  const CompactionSummaryT<D> r = run_compaction(s, legs, co, files);
  if (legs.size() > 1) summary["legs"] = legs_summary<D>(legs, path.name, files.leg_ends());
  if (r.instability) {
    // as report_unstable(), without state_last_good.txt (compact writes no state file)
    summary["unstable_quantity"] = r.instability_quantity;
    summary["unstable_step"] = r.instability_step;
    summary["unstable_time"] = r.instability_time;
    return stop_untrustworthy(files, summary, out, r, {"unstable", r.instability_what, one_line(r.instability_what),
                                                        one_line(r.instability_what)});
  }
  if (r.status == "incomplete")  // --max-steps reached during the run: the rows so far, no final snapshot
    return stop_untrustworthy(files, summary, out, r, {r.status, r.reason, r.reason, "incomplete: " + r.reason});
  files.finish("");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return finish_run(files, summary, r, s, a, jammed, pk.seed, wall, out);
}

}  // namespace

int run_dem_compact(const std::string& command, const DemCompactArgs& a, const fs::path& out) {
  return a.pack.dim == 3 ? run_compact<3>(command, a, out) : run_compact<2>(command, a, out);
}

}  // namespace netdem::app::dem
