// demsolve yield: the yield surface of netsolve yield (Redanz & Fleck 2001 section 3.4; docs/yield.md)
// with the explicit DEM and the plastic-indentation law: the same precompaction scene, the same
// unloading and probe directions, the same probe-step schedule and stop rule (qs::ProbeSchedule),
// the same yield-point definitions (qs::evaluate_probe) and the same yield_points.csv columns.
// docs/dynamic.md "demsolve yield".
//
// The phases: (1) precompaction as `demsolve compact` (reversible Eq 2 by default), rows averaged
// over windows that match netsolve's increments; (2) the section 3.4 elastic branch switched on
// (every contact's branch starts at its current overlap), the path reversed window by window with
// the secant prediction of the strain left to zero stress, then a hold at zero strain rate;
// (3) each probe on its own copy of the unloaded solver: strain rate gamma' (cos theta, sin theta),
// initial velocities the affine field, one window per netsolve probe step; a sample is the window
// mean at the window's mean strain. Probes run on --jobs threads (each on its own copy, so the
// result does not depend on the thread count).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "compact.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/yield_protocol.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/quasistatic/analytic_yield.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/yield_driver.hpp"
#include "output.hpp"
#include "protocol.hpp"
#include "run_status.hpp"
#include "scene.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace netdem::dem;
namespace qs = netdem::qs;

namespace netdem::app::dem {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = std::numbers::pi;
using Clock = std::chrono::steady_clock;

std::string num(double v) { return std::isfinite(v) ? fmt::format("{:.8g}", v) : ""; }
json jnum(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::vector<int> select_probes(const DemYieldArgs& a) {
  std::vector<int> sel;
  if (!a.probe_list.empty()) {
    for (int v : a.probe_list) {  // a set of indices: sorted, each once
      if (!(v >= 0 && v < a.directions))
        throw UsageError(fmt::format("--probes: {} is not a probe index in [0, {})", v, a.directions));
      if (std::find(sel.begin(), sel.end(), v) == sel.end()) sel.push_back(v);
    }
    std::sort(sel.begin(), sel.end());
  } else {
    for (int k = 0; k < a.directions; ++k) sel.push_back(k);
  }
  return sel;
}

/// The values at the door: every option checked before anything is written.
struct YieldDoor {
  std::string compact_bc, probe_bc;
  bool affine = false, periodic = false, affine_probe = false;
  double mu = 0.0;
  std::vector<int> selection;
};

YieldDoor check_yield_args(const DemYieldArgs& a) {
  YieldDoor d;
  if (a.precompact != "hydrostatic" && a.precompact != "closed-die")
    throw UsageError(fmt::format("--precompact '{}' is not 'hydrostatic' or 'closed-die'", packing::quote_input(a.precompact)));
  auto bc = [](const std::string& v, const char* opt) {
    if (v == "affine" || v == "periodic") return v;
    if (v == "die" || v == "layer") return std::string("die");
    throw UsageError(fmt::format("{} '{}' is not 'affine', 'die' (the peripheral layer) or 'periodic'", opt,
                                 packing::quote_input(v)));
  };
  d.compact_bc = bc(a.compact_bc, "--compact-bc");
  d.probe_bc = bc(a.probe_bc.empty() ? a.compact_bc : a.probe_bc, "--probe-bc");
  // a periodic state probed affinely: every centre held on the cell's motion from the unloading on
  d.affine_probe = d.compact_bc == "periodic" && d.probe_bc == "affine";
  if (d.probe_bc != d.compact_bc && !d.affine_probe)
    throw UsageError("--probe-bc differs from --compact-bc: demsolve yield probes with the boundary mode of the "
                     "precompaction, or a periodic one affinely (netsolve's frictionless hand-over is not implemented "
                     "in the explicit solver)");
  d.affine = d.compact_bc == "affine";
  d.periodic = d.compact_bc == "periodic";
  for (const auto& [v, name, lo, hi] : {std::tuple{a.inertial_number, "--inertial-number", 0.0, 1.0},
                                         std::tuple{a.probe_inertial_number, "--probe-inertial-number", 0.0, 1.0}})
    if (!(std::isfinite(v) && v >= lo && v <= hi && (v > 0.0 || std::string(name) == "--probe-inertial-number")))
      throw UsageError(fmt::format("{} must be in (0, 1] (0 for the probes: the precompaction's), got {}", name, v));
  if (!(std::isfinite(a.damping) && a.damping >= 0.0 && a.damping <= 1.0))
    throw UsageError(fmt::format("--damping must be in [0, 1] (fraction of critical damping), got {}", a.damping));
  if (!(std::isfinite(a.first_touch) && a.first_touch > 0.0 && a.first_touch <= 0.01))
    throw UsageError(fmt::format("--first-touch must be in (0, 0.01], got {}", a.first_touch));
  // the explicit step follows the stiffest tangential spring k_t sigma_y A_c: 1e6 (1e3 x the
  // default) keeps a run within reach of --max-steps
  if (!(std::isfinite(a.k_t) && a.k_t >= 0.0 && a.k_t <= 1e6))
    throw UsageError(fmt::format("--k-t must be in [0, 1e6] sigma_y/R for the explicit solver (its time step follows "
                                 "k_t sigma_y A_c), got {}", a.k_t));
  if (!(std::isfinite(a.steps_per_contact) && a.steps_per_contact >= 10.0 && a.steps_per_contact <= 1e4))
    throw UsageError(fmt::format("--steps-per-contact must be in [10, 1e4], got {}", a.steps_per_contact));
  if (a.increments < 1 || a.increments > 1000000)
    throw UsageError(fmt::format("--increments must be in [1, 1e6], got {}", a.increments));
  if (a.directions < 1 || a.directions > 3600)
    throw UsageError(fmt::format("--directions must be in [1, 3600], got {}", a.directions));
  if (!(a.offset > 0.0) || !(a.max_strain > a.offset) || !(a.window > 0.0) || !(a.unload_tol > 0.0) || !(a.growth >= 1.0) ||
      a.fine < 5 || !std::isfinite(a.max_strain) || !std::isfinite(a.window) || !std::isfinite(a.unload_tol) ||
      !std::isfinite(a.growth) || a.max_strain > 0.1)
    throw UsageError("probe options: need finite --offset > 0, --max-strain in (--offset, 0.1], --window > 0, "
                     "--unload-tol > 0, --growth >= 1, and --fine >= 5");
  if (!(std::isfinite(a.relax_drag) && a.relax_drag > 0.0 && a.relax_drag <= 1e3))
    throw UsageError(fmt::format("--relax-drag must be in (0, 1e3] [1/t*], got {}", a.relax_drag));
  if (!(std::isfinite(a.settle_tol) && a.settle_tol > 0.0 && a.settle_tol < 1.0))
    throw UsageError(fmt::format("--settle-tol must be in (0, 1), got {}", a.settle_tol));
  if (!(std::isfinite(a.settle_time) && a.settle_time > 0.0 && a.settle_time <= 1e6))
    throw UsageError(fmt::format("--settle-time must be in (0, 1e6] [t*], got {}", a.settle_time));
  if (a.jobs < 0 || a.jobs > 256) throw UsageError(fmt::format("--jobs must be in [1, 256] (0: number of cores), got {}", a.jobs));
  d.mu = netdem::app::netsolve::parse_friction(a.friction);
  d.selection = select_probes(a);
  return d;
}

/// One demsolve yield run: the phases of the library's protocol (netdem/dynamic/yield_protocol.hpp)
/// and the run folder's files.
class YieldRun {
 public:
  YieldRun(const std::string& command, const DemYieldArgs& a, const fs::path& out, const YieldDoor& d,
           const packing::Packing& pk, std::string source)
      : command_(command), a_(a), out_(out), d_(d), pk_(pk), source_(std::move(source)),
        path_(qs::StrainPath::parse(a.precompact)) {}
  /// Sets up the solver; throws UsageError for an impossible target or too much work.
  void setup();
  /// (1) precompaction; false: it stopped unstable (summary written)
  bool precompact();
  void record_setup();
  /// (2) unloading
  void unload_phase();
  /// (3) probes and their files
  void probe_phase();
  int finish();

 private:
  const std::string& command_;
  const DemYieldArgs& a_;
  fs::path out_;
  const YieldDoor& d_;
  const packing::Packing& pk_;
  std::string source_;
  qs::StrainPath path_;
  static constexpr double sigma_y_ = 1.0;
  double D0_ = 0, gdot_ = 0, gdot_p_ = 0, norm_ = 0, T_ = 0, dt_first_ = 0, dt_elastic_ = 0;
  int jobs_ = 1;
  DynamicOptions o_;
  std::unique_ptr<DynamicSolver> s_;
  std::unique_ptr<Meter> meter_;
  std::unique_ptr<WindowRunner> win_;
  Sample loaded_;
  SettleOptions relax_;
  UnloadOutcome un_;
  RunStatus status_;
  json j_, setup_;
  qs::AffineYieldInput an_{};
  bool an_ok_ = false;
  std::vector<qs::YieldPoint> fabric_;
  double t_compact_ = 0, t_unload_ = 0, t_probes_ = 0, loading_norm_ = 0, first_step_ = 0;
  int ok_ = 0;
  std::int64_t probe_steps_ = 0;
  Clock::time_point t_start_ = Clock::now();
};

void YieldRun::setup() {
  Particles P = d_.periodic ? periodic_particles_from<2>(pk_, 1.0) : particles_from(pk_, 1.0);
  Box box(pk_.box);
  box.contact_walls = false;
  box.right.mode = box.top.mode = WallMode::Affine;
  o_ = plastic_options(d_.mu, a_.k_t, a_.normal_unloading == "reversible", a_.first_touch, a_.damping, 0.0,
                       a_.steps_per_contact);
  D0_ = pk_.density();
  qs::CompactionOptions co;
  co.path = path_;
  co.target_density = a_.to_density;
  co.increments = a_.increments;
  try {
    co.validate(D0_);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const double rho = 1.0, d_mean = 2.0;
  gdot_ = a_.inertial_number / (d_mean * std::sqrt(rho / sigma_y_));
  gdot_p_ = (a_.probe_inertial_number > 0.0 ? a_.probe_inertial_number : a_.inertial_number) / d_mean;
  norm_ = std::hypot(path_.E11, path_.E22);
  const double e11 = gdot_ * path_.E11 / norm_, e22 = gdot_ * path_.E22 / norm_;
  T_ = std::log(D0_ / a_.to_density) / (e11 + e22);

  activity() = "setting up the explicit solver";
  // periodic: every particle free in a cell that follows the strain (docs/dynamic.md "Periodic cell")
  s_ = d_.periodic ? std::make_unique<DynamicSolver>(std::move(P), o_.plastic, packing::periodic_cell<2>(pk_), o_)
                   : std::make_unique<DynamicSolver>(std::move(P), o_.plastic, box, o_);
  s_->set_strain_rate(e11, e22);
  s_->set_affine_velocities();
  if (!d_.periodic) {
    s_->set_prescribed(prescribed_particles(pk_, d_.affine, false), !d_.affine);
    // affine: every centre prescribed, the spins free except the peripheral layer's, as netsolve and Redanz &
    // Fleck section 2.4 ("the rotation of particles in the peripheral layer is prevented")
    if (d_.affine) s_->hold_spins(prescribed_particles(pk_, false, false));
  }
  s_->set_rotations(!a_.no_rotation);
  dt_first_ = s_->dt();
  // the probes run on the elastic branch, whose stiffness bound sets a smaller step
  contact::PlasticIndentationParams elastic_law = o_.plastic;
  elastic_law.reversible = false;
  dt_elastic_ = choose_time_step(s_->particles(), contact::PlasticIndentationLawT<2>(elastic_law), o_).dt;
  const double steps_est = T_ / dt_first_ + d_.selection.size() * 2.0 * a_.max_strain / gdot_p_ / dt_elastic_;
  if (!(steps_est <= a_.max_steps))
    throw UsageError(fmt::format("the run needs up to {:.3g} time steps (precompaction dt {:.3g}, probes dt {:.3g} t*), more "
                                 "than --max-steps = {:.3g}: raise --inertial-number or --max-steps, or run fewer probes",
                                 steps_est, dt_first_, dt_elastic_, a_.max_steps));
  jobs_ = std::min<int>(a_.jobs > 0 ? a_.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())),
                        static_cast<int>(d_.selection.size()));
}

bool YieldRun::precompact() {
  const std::size_t n = pk_.size();
  make_output_dir(out_ / "probes");
  packing::write_packing_csv(pk_, out_ / "packing.csv");
  if (!a_.quiet)
    std::fprintf(stderr, "demsolve yield: %zu particles, D0 = %.4f, seed %llu (%s); %s %s, friction %s; I = %g (probes %g), "
                 "%zu of %d probes, %d jobs\n", n, D0_, static_cast<unsigned long long>(pk_.seed), source_.c_str(),
                 a_.precompact.c_str(), d_.compact_bc.c_str(), a_.friction.c_str(), a_.inertial_number, 2.0 * gdot_p_,
                 d_.selection.size(), a_.directions, jobs_);
  double r_mean = 0.0;
  for (double r : s_->particles().r) r_mean += r;
  r_mean /= static_cast<double>(n);
  meter_ = std::make_unique<Meter>(false, r_mean);
  win_ = std::make_unique<WindowRunner>(*s_, *meter_);
  win_->t_rate = 0.0;  // the rate set above holds from t = 0
  DynamicSolver& s = *s_;

  const auto t0 = Clock::now();
  std::string hist = "increment,E11,E22,D,S11,S22,S12,S11_contacts,S22_contacts,Z,contacts,time,I,steps,dt\n";
  auto row = [&](int k, const Sample& m, std::int64_t steps) {
    const double Pc = -0.5 * (m.Sc[0] + m.Sc[1]);
    const double I = Pc > 0.0 ? gdot_ * 2.0 * std::sqrt(1.0 / Pc) : kNaN;
    hist += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{},{},{:.4e}\n", k,
                        win_->strain11(), win_->strain22(), s.density(), m.S[0], m.S[1], m.S[2], m.Sc[0], m.Sc[1], m.Z,
                        m.contacts, s.time(), num(I), steps, s.dt());
  };
  loaded_ = win_->measure();
  row(0, loaded_, 0);
  std::int64_t steps = 0;
  Progress progress("precompact", T_, a_.quiet);
  std::string stopped;
  int done = 0;
  activity() = "precompacting";
  try {
    for (int k = 1; k <= a_.increments; ++k) {
      const Window w = win_->run(T_ * k / a_.increments);
      steps += w.steps;
      loaded_ = w.mean;
      row(k, loaded_, steps);
      done = k;
      progress.update(s.time());
    }
  } catch (const InstabilityError& e) {
    stopped = one_line(e.what());
  }
  progress.finish();
  if (!stopped.empty()) hist += "# stopped: " + stopped + "\n";
  write_file_atomic(out_ / "history.csv", hist);
  t_compact_ = seconds_since(t0);
  int outside = 0;  // (a periodic cell has no outside: its positions are unwrapped)
  for (std::size_t p = 0; p < n && !d_.periodic; ++p) {
    const double x = s.particles().coord(p, 0), y = s.particles().coord(p, 1);
    outside += x < s.box().x_min || x > s.box().x_max || y < s.box().y_min || y > s.box().y_max;
  }
  j_["command"] = command_;
  j_["seed"] = pk_.seed;
  j_["packing"] = source_;
  j_["particles"] = n;
  j_["initial_density"] = D0_;
  j_["precompaction"] = {{"D", s.density()},  {"Z", loaded_.Z},       {"S11", loaded_.S[0]},   {"S22", loaded_.S[1]},
                         {"S12", loaded_.S[2]}, {"E11", win_->strain11()}, {"E22", win_->strain22()},
                         {"contacts", loaded_.contacts}, {"increments", a_.increments}, {"increments_done", done},
                         {"steps", steps}, {"centres_outside_box", outside}, {"inertial_number", a_.inertial_number}};
  if (!stopped.empty()) {
    status_.add("unstable", "precompaction stopped: " + stopped);
    j_["status"] = status_.status;
    j_["status_reason"] = status_.reason();
    write_file_atomic(out_ / "summary.json", j_.dump(2) + "\n");
    close_run_dir(out_);
    std::fprintf(stderr, "demsolve: error: unstable: precompaction: %s\n", stopped.c_str());
    return false;
  }
  if (outside > 0)
    status_.add("unstable", fmt::format("{} disk centres left the box between the peripheral disks in the precompaction",
                                        outside));
  return true;
}

void YieldRun::record_setup() {
  const DynamicSolver& s = *s_;
  setup_["precompact"] = a_.precompact;
  setup_["to_density"] = a_.to_density;
  setup_["friction"] = a_.friction;
  setup_["normal_unloading"] = a_.normal_unloading;
  setup_["first_touch"] = a_.first_touch;
  setup_["compact_bc"] = d_.compact_bc;
  setup_["probe_bc"] = d_.probe_bc;
  setup_["directions"] = a_.directions;
  setup_["packing"] = source_;
  setup_["particles"] = pk_.size();
  setup_["sigma_y"] = sigma_y_;
  setup_["offset"] = a_.offset;
  setup_["window"] = a_.window;
  setup_["solver"] = "demsolve";
  setup_["inertial_number"] = a_.inertial_number;
  setup_["probe_inertial_number"] = 2.0 * gdot_p_;
  setup_["analytic"] = {{"D0", D0_}, {"D", s.density()}, {"Z0", loaded_.Z}, {"sigma_y", sigma_y_},
                        {"dir11", path_.E11}, {"dir22", path_.E22}};
  setup_["loading"] = {{"S11", loaded_.S[0]}, {"S22", loaded_.S[1]}, {"S12", loaded_.S[2]}};
  try {
    an_ = qs::affine_yield_input(D0_, s.density(), loaded_.Z, sigma_y_, path_.E11, path_.E22);
    an_ok_ = true;
  } catch (const std::exception&) {
  }
  std::vector<ContactInfo> cs;
  s.contacts(cs);
  json f11 = json::array(), f22 = json::array();
  for (int k = 0; k < a_.directions; ++k) {
    fabric_.push_back(fabric_affine_point(s, cs, 2 * kPi * k / a_.directions));
    f11.push_back(jnum(fabric_.back().S11));
    f22.push_back(jnum(fabric_.back().S22));
  }
  setup_["fabric"] = {{"S11", f11}, {"S22", f22}};
}

void YieldRun::unload_phase() {
  // every centre follows the cell from here on, the spins free (netsolve's affine_centres)
  if (d_.affine_probe) s_->set_prescribed(prescribed_particles(pk_, true, false), false);
  // unloading on the elastic branch: netsolve's secant steps along -E', each a ramp at the probe
  // rate and a hold with the relaxation drag until the state is at rest
  relax_.drag = a_.relax_drag;
  relax_.tol = a_.settle_tol;
  relax_.t_max = a_.settle_time;
  relax_.work_ref = loaded_.work;
  relax_.f_ref = loaded_.mean_fn;
  const auto t0 = Clock::now();
  contact::PlasticIndentationParams elastic_law = o_.plastic;
  elastic_law.reversible = false;
  s_->set_plastic_law(elastic_law);
  const double eload = std::hypot(win_->strain11(), win_->strain22());
  win_->set_rate(-gdot_p_ * path_.E11 / norm_, -gdot_p_ * path_.E22 / norm_);
  UnloadOptions uo;
  uo.tol = a_.unload_tol * sigma_y_;
  uo.first_step = 0.2 * 2.0 * eload / elastic_law.unload_ratio;
  std::string ucsv = "increment,strain,S11,S22,S12,D,Z,contacts,steps\n";
  un_ = unload(*s_, *win_, loaded_, gdot_p_, relax_, uo, [&](const UnloadRow& r) {
    const Sample& m = r.sample;
    ucsv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{}\n", r.increment, r.strain, m.S[0], m.S[1],
                        m.S[2], r.density, m.Z, m.contacts, r.steps);
  });
  write_file_atomic(out_ / "unload.csv", ucsv);
  t_unload_ = seconds_since(t0);
  if (!un_.message.empty() && !a_.quiet) std::fprintf(stderr, "demsolve yield: warning: unloading: %s\n", un_.message.c_str());
  if (un_.message.rfind("unstable", 0) == 0) {
    status_.add("unstable", "unloading " + un_.message);
  } else if (!un_.converged && un_.stress_norm > 10.0 * a_.unload_tol * sigma_y_) {
    status_.add("unconverged", fmt::format("unloading ended at |Sigma| = {:.3g} sigma_y, above 10 x --unload-tol",
                                           un_.stress_norm));
  }
}

void YieldRun::probe_phase() {
  const auto t0 = Clock::now();
  first_step_ = un_.strain > 0 ? un_.strain / 10 : 1e-6;
  loading_norm_ = stress_norm(loaded_) / sigma_y_;
  const sys::ProbeSettings ps =
      netdem::app::netsolve::yield_probe_settings(a_, a_.directions, first_step_, loading_norm_, sigma_y_);
  const auto& selection = d_.selection;
  // progress: the probes done plus each running probe's strain over its expected length
  Progress pprog("probes", static_cast<double>(selection.size()), a_.quiet);
  std::vector<double> frac(selection.size(), 0.0);
  std::size_t finished = 0;
  const auto runs = run_probes(
      *s_, *win_, *meter_, selection, jobs_, ps, gdot_p_, un_.unloaded, relax_,
      [&](std::size_t q, double f) {
        frac[q] = f;
        double sum = 0.0;
        for (double v : frac) sum += v;
        pprog.update(sum);
      },
      [&](std::size_t, const DemProbeRun& r) {
        ++finished;
        if (!a_.quiet)
          std::fprintf(stderr, "\rprobe %3d (theta %6.1f deg): %s [%zu/%zu]\n", r.result.index, r.result.theta * 180 / kPi,
                       r.result.status.c_str(), finished, selection.size());
      });
  pprog.finish();
  t_probes_ = seconds_since(t0);

  // ---- files: probes/probe_NNN.csv and .json, yield_points.csv (netsolve's columns)
  std::string ycsv =
      "probe,theta,S11,S22,S11_offset,S22_offset,S11_analytic,S22_analytic,S11_fabric,S22_fabric,strain,strain_offset,"
      "stress,stress_offset,elastic_slope,curvature,increments,unconverged,status,end\n";
  auto text = [](std::string v) {
    std::replace(v.begin(), v.end(), ',', ';');
    std::replace(v.begin(), v.end(), '\n', ' ');
    return v;
  };
  for (std::size_t q = 0; q < selection.size(); ++q) {
    const int idx = selection[q];
    const DemProbeRun& pr = runs[q];
    const sys::ProbeResult& p = pr.result;
    probe_steps_ += pr.steps;
    ok_ += p.status == "ok";
    qs::YieldPoint ap{kNaN, kNaN};
    if (an_ok_) try {
        ap = qs::affine_yield_point(an_, p.theta);
      } catch (const std::exception&) {
      }
    const auto& yc = p.curvature;
    const auto& yf = p.offset;
    std::string pcsv = "increment,strain,stress,S11,S22,S12,D,Z,steps,settled,kinetic_ratio\n";
    for (std::size_t i = 0; i < p.curve.samples.size(); ++i) {
      const auto& c = p.curve.samples[i];
      pcsv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{:.4e}\n", i, c.strain, c.stress, c.S11,
                          c.S22, c.S12, c.density, c.Z, c.newton, c.converged ? 1 : 0,
                          i < pr.kinetic.size() ? pr.kinetic[i] : 0.0);
    }
    const auto stem = fmt::format("probe_{:03d}", idx);
    if (!p.curve.samples.empty()) write_file_atomic(out_ / "probes" / (stem + ".csv"), pcsv);
    const double fs11 = fabric_[static_cast<std::size_t>(idx)].S11, fs22 = fabric_[static_cast<std::size_t>(idx)].S22;
    const json r = {{"probe", idx},
                    {"directions", a_.directions},
                    {"theta", p.theta * 180.0 / kPi},
                    {"S11", jnum(p.S11)},
                    {"S22", jnum(p.S22)},
                    {"S11_offset", jnum(p.S11_offset)},
                    {"S22_offset", jnum(p.S22_offset)},
                    {"S11_analytic", jnum(ap.S11)},
                    {"S22_analytic", jnum(ap.S22)},
                    {"S11_fabric", jnum(fs11)},
                    {"S22_fabric", jnum(fs22)},
                    {"strain", jnum(yc.found ? yc.strain : kNaN)},
                    {"strain_offset", jnum(yf.found ? yf.strain : kNaN)},
                    {"stress", jnum(yc.found ? yc.stress : kNaN)},
                    {"stress_offset", jnum(yf.found ? yf.stress : kNaN)},
                    {"elastic_slope", jnum(p.fit.ok ? p.fit.slope : kNaN)},
                    {"curvature", jnum(yc.found ? yc.curvature : kNaN)},
                    {"increments", static_cast<int>(p.curve.samples.size()) - 1},
                    {"unconverged", p.curve.unconverged},
                    {"status", p.status},
                    {"end", p.curve.end},
                    {"steps", pr.steps},
                    {"wall_s", p.wall_s}};
    write_file_atomic(out_ / "probes" / (stem + ".json"), r.dump(1) + "\n");
    ycsv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", idx, num(p.theta * 180.0 / kPi),
                        num(p.S11), num(p.S22), num(p.S11_offset), num(p.S22_offset), num(ap.S11), num(ap.S22), num(fs11),
                        num(fs22), num(yc.found ? yc.strain : kNaN), num(yf.found ? yf.strain : kNaN),
                        num(yc.found ? yc.stress : kNaN), num(yf.found ? yf.stress : kNaN),
                        num(p.fit.ok ? p.fit.slope : kNaN), num(yc.found ? yc.curvature : kNaN),
                        static_cast<int>(p.curve.samples.size()) - 1, p.curve.unconverged, text(p.status),
                        text(p.curve.end));
  }
  write_file_atomic(out_ / "yield_points.csv", ycsv);
  if (ok_ < static_cast<int>(selection.size()))
    status_.add("incomplete", fmt::format("{} of {} probes found no yield point or failed (their status is in "
                                          "yield_points.csv)", selection.size() - ok_, selection.size()));
}

int YieldRun::finish() {
  const double total = seconds_since(t_start_);
  const auto& selection = d_.selection;
  j_["status"] = status_.status;
  j_["status_reason"] = status_.ok() ? "every check passed" : status_.reason();
  j_["setup"] = setup_;
  j_["unloading"] = {{"converged", un_.converged},     {"increments", un_.increments}, {"strain", un_.strain},
                     {"unsettled", un_.unsettled},     {"stress_norm", un_.stress_norm},
                     {"loading_norm", loading_norm_},  {"message", un_.message},       {"steps", un_.steps}};
  j_["probes"] = {{"run", selection.size()},   {"ok", ok_},  {"directions", a_.directions}, {"jobs", jobs_},
                  {"first_step", first_step_}, {"offset", a_.offset}, {"max_strain", a_.max_strain}, {"window", a_.window},
                  {"indices", selection},      {"steps", probe_steps_}};
  j_["analytic"] = {{"ok", an_ok_}};
  j_["dt"] = {{"precompaction_first", dt_first_}, {"probes", dt_elastic_}};
  j_["damping"] = a_.damping;
  j_["steps_per_contact"] = a_.steps_per_contact;
  j_["units"] = "sigma_y = 1, R = 1 (lengths of the packing), rho = 1, t* = R sqrt(rho/sigma_y) = 1";
  j_["timing_s"] = {{"total", total}, {"compaction", t_compact_}, {"unloading", t_unload_}, {"probes", t_probes_}};
  write_file_atomic(out_ / "summary.json", j_.dump(2) + "\n");
  close_run_dir(out_);
  netdem::app::summary_printf("D = %.4f (Z = %.3f): loading point S11/sy = %.4f, S22/sy = %.4f; unloaded to |S| = %.1e; %d/%zu probes ok; "
              "%.1f s (compaction %.1f, unloading %.1f, probes %.1f) -> %s\n",
              s_->density(), loaded_.Z, loaded_.S[0], loaded_.S[1], un_.stress_norm, ok_, selection.size(), total,
              t_compact_, t_unload_, t_probes_, out_.c_str());
  if (!status_.ok())
    std::fprintf(stderr, "demsolve: %s: %s: %s\n", a_.allow_unconverged || status_.status == "incomplete" ? "warning" : "error",
                 status_.status.c_str(), status_.reason().c_str());
  return status_.exit_code(a_.allow_unconverged);
}

}  // namespace

int run_dem_yield(const std::string& command, const DemYieldArgs& a, const fs::path& out) {
  // ---- the door
  const YieldDoor d = check_yield_args(a);
  const RunDirOptions rdo = check_scene_run_dir(out, a.overwrite, a.packing_file, a.pack);
  std::string source;
  const packing::Packing pk = netdem::app::netsolve::input_packing(a.packing_file, a.pack, source, "demsolve yield",
                                                                   netdem::app::netsolve::PeriodicInput::Caller);
  if (pk.periodic && !d.periodic)
    throw UsageError(fmt::format("--packing {} is periodic ('# periodic'): run it with --compact-bc periodic",
                                 packing::quote_input(a.packing_file)));
  if (d.periodic && !pk.periodic)
    throw UsageError("--compact-bc periodic needs a periodic packing ('# periodic'; netsolve pack --periodic) as --packing FILE");
  check_memory(pk.size());
  YieldRun run(command, a, out, d, pk, source);
  run.setup();
  open_run_dir(out, command, rdo);
  if (!run.precompact()) return exit_code::untrustworthy;
  run.record_setup();
  run.unload_phase();
  run.probe_phase();
  return run.finish();
}

}  // namespace netdem::app::dem
