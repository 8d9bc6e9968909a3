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
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "compact.hpp"
#include "netdem/dynamic/solver.hpp"
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

/// A window: the solver advanced at its current strain rate until t_end; the mean of the samples
/// (about every `every` steps and at the end) and the steps taken.
struct Window {
  Sample mean;
  int samples = 0;
  std::int64_t steps = 0;
};

class Windows {
 public:
  Windows(DynamicSolver& s, Meter& meter) : s_(s), meter_(meter) {}
  /// Strain accumulated before the current rate was set (for the affine-deviation measures).
  double E11 = 0.0, E22 = 0.0, t_rate = 0.0;
  void set_rate(double e11, double e22) {
    E11 = strain11(), E22 = strain22();
    t_rate = s_.time();
    s_.set_strain_rate(e11, e22);
  }
  double strain11() const { return E11 + s_.strain_rate_11() * (s_.time() - t_rate); }
  double strain22() const { return E22 + s_.strain_rate_22() * (s_.time() - t_rate); }
  Sample measure() { return meter_.measure(s_, {strain11(), strain22(), 0.0}); }
  /// Advances to t_end (at least one step) with about `target` samples.
  Window run(double t_end, int target = 10) {
    Window w;
    const double span = t_end - s_.time();
    const auto every = static_cast<std::int64_t>(std::clamp(span / s_.dt() / target, 1.0, 20.0));
    Sample acc;
    std::int64_t since = 0;
    do {
      s_.step();
      ++w.steps;
      if (++since % every == 0 || !(s_.time() < t_end - 1e-12 * std::fabs(t_end))) {
        acc.add(measure(), 1.0);
        ++w.samples;
      }
    } while (s_.time() < t_end - 1e-12 * std::fabs(t_end));
    w.mean.add(acc, 1.0 / w.samples);
    s_.check_health();
    return w;
  }

  /// Holds the strain (rate 0) with the drag `drag` on until the unbalanced contact force (RMS over
  /// the free particles, DynamicSolver::unbalanced_force_rms) is below tol x f_ref (the mean contact
  /// normal force at the loading point: netsolve's Newton residual and tolerance) and the kinetic
  /// energy below tol^2 x the elastic work at the loading point (so that an overdamped creep does
  /// not pass for rest), checked every 50 steps, or for at most t_max;
  /// then the drag is off again. Returns the state at the end (a sample at rest: the drag force on
  /// it is ~0, so it is an equilibrium of the contact forces alone) and whether it settled.
  Sample settle(double drag, double tol, double f_ref, double work_ref, double t_max, bool& settled, std::int64_t& steps) {
    const double e11 = s_.strain_rate_11(), e22 = s_.strain_rate_22();
    set_rate(0.0, 0.0);
    s_.set_affine_drag(drag);
    const double t_end = s_.time() + t_max;
    Sample m = measure();
    settled = false;
    for (;;) {
      for (int k = 0; k < 50; ++k, ++steps) s_.step();
      m = measure();
      if (s_.unbalanced_force_rms() <= tol * f_ref && m.kinetic <= tol * tol * work_ref) {
        settled = true;
        break;
      }
      if (!(s_.time() < t_end)) break;
    }
    s_.check_health();
    s_.set_affine_drag(0.0);
    set_rate(e11, e22);
    return m;
  }

 private:
  DynamicSolver& s_;
  Meter& meter_;
};

double norm3(const Sample& m) { return std::sqrt(m.S[0] * m.S[0] + m.S[1] * m.S[1] + 2.0 * m.S[2] * m.S[2]); }

/// qs::fabric_affine_point on the explicit solver's contacts: the stress if every load-bearing
/// disk contact that the strain rate (cos theta, sin theta) compresses keeps its normal force and
/// every other one carries none (docs/yield.md "Fabric-resolved affine bound").
qs::YieldPoint fabric_point(const DynamicSolver& s, const std::vector<ContactInfo>& cs, double theta) {
  const double e11 = std::cos(theta), e22 = std::sin(theta);
  const Box& b = s.box();
  const double area = (b.x_max - b.x_min) * (b.y_max - b.y_min);
  double s11 = 0.0, s22 = 0.0;
  for (const auto& c : cs) {
    if (c.wall >= 0 || !(c.f_n > 0.0)) continue;
    if (e11 * c.nx * c.nx + e22 * c.ny * c.ny >= 0.0) continue;
    const double L = c.d_i + c.d_j;
    s11 -= c.f_n * L * c.nx * c.nx;
    s22 -= c.f_n * L * c.ny * c.ny;
  }
  return {s11 / area, s22 / area};
}

std::vector<int> select_probes(const DemYieldArgs& a) {
  std::vector<int> sel;
  if (!a.probe_list.empty()) {
    for (double v : netdem::app::netsolve::parse_number_list(a.probe_list, "--probes")) {
      if (!(v >= 0 && v < a.directions && v == std::floor(v)))
        throw UsageError(fmt::format("--probes: {} is not a probe index in [0, {})", v, a.directions));
      if (std::find(sel.begin(), sel.end(), static_cast<int>(v)) == sel.end()) sel.push_back(static_cast<int>(v));
    }
    std::sort(sel.begin(), sel.end());
  } else {
    for (int k = 0; k < a.directions; ++k) sel.push_back(k);
  }
  return sel;
}

struct ProbeRun {
  qs::ProbeResult result;
  std::int64_t steps = 0;
  std::vector<double> kinetic;  ///< per sample: fluctuating kinetic energy / elastic work
};

/// One probe on a copy of the unloaded solver.
/// The hold after each strain increment of the unloading and the probes.
struct Relax {
  double drag = 30.0, tol = 1e-3, f_ref = 0.0, work_ref = 0.0, t_max = 50.0;
};

ProbeRun run_dem_probe(const DynamicSolver& unloaded, const Windows& wref, Meter meter, int index,
                       const qs::ProbeSettings& ps, double gdot, const Sample& start, const Relax& relax,
                       const std::function<void(double)>& on_increment) {
  const auto t0 = Clock::now();
  ProbeRun out;
  DynamicSolver s = unloaded;
  Windows w(s, meter);
  w.E11 = wref.strain11(), w.E22 = wref.strain22();
  w.t_rate = s.time();
  const double theta = 2 * kPi * index / ps.directions;
  const double ct = std::cos(theta), st = std::sin(theta);
  w.set_rate(gdot * ct, gdot * st);
  s.set_affine_velocities();
  qs::ProbeCurve c;
  c.theta = theta;
  auto sample_of = [&](const Sample& m, double strain, int steps) {
    qs::ProbeSample p;
    p.strain = strain;
    p.S11 = m.S[0], p.S22 = m.S[1], p.S12 = m.S[2];
    p.stress = p.S11 * ct + p.S22 * st;
    p.density = s.density();
    p.Z = m.Z;
    p.newton = steps;
    return p;
  };
  c.samples.push_back(sample_of(start, 0.0, 0));
  out.kinetic.push_back(start.work > 0 ? start.kinetic / start.work : 0.0);
  qs::ProbeSchedule schedule(qs::probe_options(ps), 0.0, c.samples[0].stress);
  for (;;) {
    const double h = schedule.next();
    if (!(h > 0.0)) {
      c.end = schedule.end();
      break;
    }
    Sample m;
    bool settled = false;
    try {
      const Window ramp = w.run(s.time() + h / gdot, 1);
      out.steps += ramp.steps;
      m = w.settle(relax.drag, relax.tol, relax.f_ref, relax.work_ref, relax.t_max, settled, out.steps);
    } catch (const InstabilityError& e) {
      c.end = std::string("unstable: ") + one_line(e.what());
      break;
    }
    c.samples.push_back(sample_of(m, schedule.strain() + h, static_cast<int>(out.steps)));
    c.samples.back().converged = settled;
    c.unconverged += !settled;
    out.kinetic.push_back(m.work > 0 ? m.kinetic / m.work : 0.0);
    if (!schedule.record(h, c.samples.back().strain, c.samples.back().stress)) {
      c.end = schedule.end();
      break;
    }
    if (on_increment) on_increment(schedule.strain());
  }
  out.result = qs::evaluate_probe(std::move(c), index, ps);
  out.result.wall_s = seconds_since(t0);
  return out;
}

}  // namespace

int run_dem_yield(const std::string& command, const DemYieldArgs& a, const fs::path& out) {
  const auto t_start = Clock::now();
  // ---- the door
  if (a.precompact != "hydrostatic" && a.precompact != "closed-die")
    throw UsageError(fmt::format("--precompact '{}' is not 'hydrostatic' or 'closed-die'", packing::quote_input(a.precompact)));
  const qs::StrainPath path = qs::StrainPath::parse(a.precompact);
  auto bc = [](const std::string& v, const char* opt) {
    if (v == "affine") return std::string("affine");
    if (v == "die" || v == "layer") return std::string("die");
    throw UsageError(fmt::format("{} '{}' is not 'affine' or 'die' (the peripheral layer)", opt, packing::quote_input(v)));
  };
  const std::string compact_bc = bc(a.compact_bc, "--compact-bc");
  const std::string probe_bc = bc(a.probe_bc.empty() ? a.compact_bc : a.probe_bc, "--probe-bc");
  if (probe_bc != compact_bc)
    throw UsageError("--probe-bc differs from --compact-bc: demsolve yield probes with the boundary mode of the "
                     "precompaction (netsolve's frictionless hand-over is not implemented in the explicit solver)");
  const bool affine = compact_bc == "affine";
  for (const auto& [v, name, lo, hi] : {std::tuple{a.inertial_number, "--inertial-number", 0.0, 1.0},
                                         std::tuple{a.probe_inertial_number, "--probe-inertial-number", 0.0, 1.0}})
    if (!(std::isfinite(v) && v >= lo && v <= hi && (v > 0.0 || std::string(name) == "--probe-inertial-number")))
      throw UsageError(fmt::format("{} must be in (0, 1] (0 for the probes: the precompaction's), got {}", name, v));
  if (!(std::isfinite(a.damping) && a.damping >= 0.0 && a.damping <= 1.0))
    throw UsageError(fmt::format("--damping must be in [0, 1] (fraction of critical damping), got {}", a.damping));
  if (!(std::isfinite(a.first_touch) && a.first_touch > 0.0 && a.first_touch <= 0.01))
    throw UsageError(fmt::format("--first-touch must be in (0, 0.01], got {}", a.first_touch));
  if (!(std::isfinite(a.k_t) && a.k_t >= 0.0)) throw UsageError(fmt::format("--k-t must be a finite number >= 0, got {}", a.k_t));
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
  const double mu = netdem::app::netsolve::parse_friction(a.friction);
  const auto selection = select_probes(a);
  RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  if (!a.packing_file.empty()) rdo.inputs.emplace_back(a.packing_file);
  check_run_dir(out, rdo);
  if (a.packing_file.empty()) netdem::app::netsolve::check_deposition_size(a.pack);
  activity() = a.packing_file.empty() ? "building the ballistic deposition" : "reading the packing " + a.packing_file;
  std::string source;
  const packing::Packing pk = netdem::app::netsolve::input_packing(a.packing_file, a.pack, source, "demsolve yield");
  check_memory(pk.size());

  Particles P = particles_from(pk, 1.0);
  Box box(pk.box);
  box.contact_walls = false;
  box.right.mode = box.top.mode = WallMode::Affine;
  const DynamicOptions o = plastic_options(mu, a.k_t, a.normal_unloading == "reversible", a.first_touch, a.damping, 0.0,
                                           a.steps_per_contact);
  const double D0 = pk.density();
  qs::CompactionOptions co;
  co.path = path;
  co.target_density = a.to_density;
  co.increments = a.increments;
  try {
    co.validate(D0);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const double rho = 1.0, sigma_y = 1.0, d_mean = 2.0;
  const double gdot = a.inertial_number / (d_mean * std::sqrt(rho / sigma_y));
  const double gdot_p = (a.probe_inertial_number > 0.0 ? a.probe_inertial_number : a.inertial_number) / d_mean;
  const double norm = std::hypot(path.E11, path.E22);
  const double e11 = gdot * path.E11 / norm, e22 = gdot * path.E22 / norm;
  const double T = std::log(D0 / a.to_density) / (e11 + e22);

  activity() = "setting up the explicit solver";
  const std::size_t n = P.size();
  DynamicSolver s(std::move(P), LudingParams{}, box, o);
  s.set_strain_rate(e11, e22);
  s.set_affine_velocities();
  const std::vector<std::uint32_t> pre = prescribed_particles(pk, affine, false);
  s.set_prescribed(pre, !affine);
  // affine: every centre prescribed, the spins free except the peripheral layer's, as netsolve and Redanz &
  // Fleck section 2.4 ("the rotation of particles in the peripheral layer is prevented")
  if (affine) s.hold_spins(prescribed_particles(pk, false, false));
  s.set_rotations(!a.no_rotation);
  const double dt_first = s.dt();
  // the probes run on the elastic branch, whose stiffness bound sets a smaller step
  contact::PlasticIndentationParams elastic_law = o.plastic;
  elastic_law.reversible = false;
  const double dt_elastic = plastic_time_step(s.particles(), elastic_law, o, 0.0).dt;
  const double steps_est = T / dt_first + selection.size() * 2.0 * a.max_strain / gdot_p / dt_elastic;
  if (!(steps_est <= a.max_steps))
    throw UsageError(fmt::format("the run needs up to {:.3g} time steps (precompaction dt {:.3g}, probes dt {:.3g} t*), more "
                                 "than --max-steps = {:.3g}: raise --inertial-number or --max-steps, or run fewer probes",
                                 steps_est, dt_first, dt_elastic, a.max_steps));
  const int jobs = std::min<int>(a.jobs > 0 ? a.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())),
                                 static_cast<int>(selection.size()));

  open_run_dir(out, command, rdo);
  make_output_dir(out / "probes");
  packing::write_packing_csv(pk, out / "packing.csv");
  if (!a.quiet)
    std::fprintf(stderr, "demsolve yield: %zu particles, D0 = %.4f, seed %llu (%s); %s %s, friction %s; I = %g (probes %g), "
                 "%zu of %d probes, %d jobs\n", n, D0, static_cast<unsigned long long>(pk.seed), source.c_str(),
                 a.precompact.c_str(), compact_bc.c_str(), a.friction.c_str(), a.inertial_number, 2.0 * gdot_p,
                 selection.size(), a.directions, jobs);
  double r_mean = 0.0;
  for (double r : s.particles().radius) r_mean += r;
  r_mean /= static_cast<double>(n);
  Meter meter(false, r_mean);
  Windows win(s, meter);
  win.t_rate = 0.0;  // the rate set above holds from t = 0

  // ---- (1) precompaction
  auto t0 = Clock::now();
  std::string hist = "increment,E11,E22,D,S11,S22,S12,S11_contacts,S22_contacts,Z,contacts,time,I,steps,dt\n";
  auto row = [&](int k, const Sample& m, std::int64_t steps) {
    const double Pc = -0.5 * (m.Sc[0] + m.Sc[1]);
    const double I = Pc > 0.0 ? gdot * d_mean * std::sqrt(rho / Pc) : kNaN;
    hist += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{},{},{:.4e}\n", k,
                        win.strain11(), win.strain22(), s.density(), m.S[0], m.S[1], m.S[2], m.Sc[0], m.Sc[1], m.Z, m.contacts,
                        s.time(), num(I), steps, s.dt());
  };
  Sample loaded = win.measure();
  row(0, loaded, 0);
  std::int64_t steps = 0;
  Progress progress("precompact", T, a.quiet);
  std::string stopped;
  int done = 0;
  activity() = "precompacting";
  try {
    for (int k = 1; k <= a.increments; ++k) {
      const Window w = win.run(T * k / a.increments);
      steps += w.steps;
      loaded = w.mean;
      row(k, loaded, steps);
      done = k;
      progress.update(s.time());
    }
  } catch (const InstabilityError& e) {
    stopped = one_line(e.what());
  }
  progress.finish();
  if (!stopped.empty()) hist += "# stopped: " + stopped + "\n";
  write_file_atomic(out / "history.csv", hist);
  const double t_compact = seconds_since(t0);
  int outside = 0;
  for (std::size_t p = 0; p < n; ++p) {
    const double x = s.particles().x[p], y = s.particles().y[p];
    outside += x < s.box().x_min || x > s.box().x_max || y < s.box().y_min || y > s.box().y_max;
  }
  RunStatus status;
  json j;
  j["command"] = command;
  j["seed"] = pk.seed;
  j["packing"] = source;
  j["particles"] = n;
  j["initial_density"] = D0;
  const double E11l = win.strain11(), E22l = win.strain22();
  j["precompaction"] = {{"D", s.density()},  {"Z", loaded.Z},       {"S11", loaded.S[0]},   {"S22", loaded.S[1]},
                        {"S12", loaded.S[2]}, {"E11", E11l},         {"E22", E22l},         {"contacts", loaded.contacts},
                        {"increments", a.increments}, {"increments_done", done}, {"steps", steps},
                        {"centres_outside_box", outside}, {"inertial_number", a.inertial_number}};
  if (!stopped.empty()) {
    status.add("unstable", "precompaction stopped: " + stopped);
    j["status"] = status.status;
    j["status_reason"] = status.reason();
    write_file_atomic(out / "summary.json", j.dump(2) + "\n");
    close_run_dir(out);
    std::fprintf(stderr, "demsolve: error: unstable: precompaction: %s\n", stopped.c_str());
    return exit_code::untrustworthy;
  }
  if (outside > 0)
    status.add("unstable", fmt::format("{} disk centres left the box between the peripheral disks in the precompaction",
                                       outside));

  json setup;
  setup["precompact"] = a.precompact;
  setup["to_density"] = a.to_density;
  setup["friction"] = a.friction;
  setup["normal_unloading"] = a.normal_unloading;
  setup["first_touch"] = a.first_touch;
  setup["compact_bc"] = compact_bc;
  setup["probe_bc"] = probe_bc;
  setup["directions"] = a.directions;
  setup["packing"] = source;
  setup["particles"] = n;
  setup["sigma_y"] = sigma_y;
  setup["offset"] = a.offset;
  setup["window"] = a.window;
  setup["solver"] = "demsolve";
  setup["inertial_number"] = a.inertial_number;
  setup["probe_inertial_number"] = 2.0 * gdot_p;
  setup["analytic"] = {{"D0", D0}, {"D", s.density()}, {"Z0", loaded.Z}, {"sigma_y", sigma_y},
                       {"dir11", path.E11}, {"dir22", path.E22}};
  setup["loading"] = {{"S11", loaded.S[0]}, {"S22", loaded.S[1]}, {"S12", loaded.S[2]}};
  qs::AffineYieldInput an{};
  bool an_ok = false;
  try {
    an = qs::affine_yield_input(D0, s.density(), loaded.Z, sigma_y, path.E11, path.E22);
    an_ok = true;
  } catch (const std::exception&) {
  }
  std::vector<qs::YieldPoint> fabric;
  {
    std::vector<ContactInfo> cs;
    s.contacts(cs);
    json f11 = json::array(), f22 = json::array();
    for (int k = 0; k < a.directions; ++k) {
      fabric.push_back(fabric_point(s, cs, 2 * kPi * k / a.directions));
      f11.push_back(jnum(fabric.back().S11));
      f22.push_back(jnum(fabric.back().S22));
    }
    setup["fabric"] = {{"S11", f11}, {"S22", f22}};
  }

  // ---- (2) unloading on the elastic branch: netsolve's secant steps along -E', each a ramp at the
  // probe rate and a hold with the relaxation drag until the state is at rest
  Relax relax;
  relax.drag = a.relax_drag;
  relax.tol = a.settle_tol;
  relax.t_max = a.settle_time;
  relax.work_ref = loaded.work;
  relax.f_ref = loaded.mean_fn;
  t0 = Clock::now();
  s.set_plastic_law(elastic_law);
  win.set_rate(-gdot_p * path.E11 / norm, -gdot_p * path.E22 / norm);
  const double s0 = norm3(loaded);
  const double w11 = loaded.S[0] / s0, w22 = loaded.S[1] / s0, w12 = loaded.S[2] / s0;
  auto proj = [&](const Sample& m) { return m.S[0] * w11 + m.S[1] * w22 + 2.0 * m.S[2] * w12; };
  std::string ucsv = "increment,strain,S11,S22,S12,D,Z,contacts,steps\n";
  auto urow = [&](int k, double strain, const Sample& m, std::int64_t st) {
    ucsv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{}\n", k, strain, m.S[0], m.S[1], m.S[2], s.density(),
                        m.Z, m.contacts, st);
  };
  urow(0, 0.0, loaded, 0);
  const double eload = std::hypot(E11l, E22l);
  double h = 0.2 * 2.0 * eload / elastic_law.unload_ratio;
  double lambda = 0.0, p_prev = proj(loaded), slope_last = 0.0;
  double lambda_cap = std::numeric_limits<double>::infinity();
  Sample unloaded = loaded;
  std::string umsg;
  bool uconv = false;
  int uk = 0, unsettled = 0;
  std::int64_t usteps = 0;
  try {
    // the first hold settles the precompacted state on the elastic branch (zero strain)
    bool settled = false;
    unloaded = win.settle(relax.drag, relax.tol, relax.f_ref, relax.work_ref, relax.t_max, settled, usteps);
    unsettled += !settled;
    p_prev = proj(unloaded);
    double un_prev = norm3(unloaded);
    for (uk = 1; uk <= 40; ++uk) {
      const Window ramp = win.run(s.time() + h / gdot_p, 1);
      usteps += ramp.steps;
      unloaded = win.settle(relax.drag, relax.tol, relax.f_ref, relax.work_ref, relax.t_max, settled, usteps);
      unsettled += !settled;
      lambda += h;
      urow(uk, lambda, unloaded, usteps);
      const double un = norm3(unloaded);
      if (un < a.unload_tol * sigma_y) break;
      // netsolve's noise floor: once |Sigma| is below 5 % of the loading stress, a rise means the
      // floor is reached (the held states of a die network are equilibria to the settle tolerance)
      if (un < 0.05 * s0 && un > un_prev) {
        umsg = fmt::format("noise floor: |Sigma| rose from {:.3g} to {:.3g} sigma_y (tolerance {:.3g}); probing from there",
                           un_prev, un, a.unload_tol);
        break;
      }
      un_prev = un;
      const double p = proj(unloaded);
      if (!(p > 0.0)) {
        umsg = fmt::format("the stress projection on the loading stress crossed zero at |Sigma| = {:.3g} sigma_y", un);
        break;
      }
      const double slope = (p_prev - p) / h;
      if (uk == 1 && slope > 0.0) lambda_cap = 3.0 * p_prev / slope;
      if (slope > 0.0) slope_last = slope;
      const double next = slope_last > 0.0 ? p / slope_last : h;
      h = std::clamp(next, 1e-3 * h, 4.0 * h);
      if (lambda >= lambda_cap * (1 - 1e-9)) {
        umsg = fmt::format("|Sigma| = {:.3g} sigma_y at 3 x the linear spring-back strain", un);
        break;
      }
      h = std::min(h, lambda_cap - lambda);
      p_prev = p;
    }
  } catch (const InstabilityError& e) {
    umsg = std::string("unstable: ") + one_line(e.what());
  }
  write_file_atomic(out / "unload.csv", ucsv);
  const double unorm = norm3(unloaded);
  uconv = umsg.empty() && unorm < a.unload_tol * sigma_y;
  if (umsg.empty() && !uconv)
    umsg = fmt::format("|Sigma| = {:.3g} sigma_y after {} unloading increments (tolerance {:.3g})", unorm, uk, a.unload_tol);
  const double t_unload = seconds_since(t0);
  if (!umsg.empty() && !a.quiet) std::fprintf(stderr, "demsolve yield: warning: unloading: %s\n", umsg.c_str());
  if (umsg.rfind("unstable", 0) == 0) status.add("unstable", "unloading " + umsg);
  else if (!uconv && unorm > 10.0 * a.unload_tol * sigma_y)
    status.add("unconverged", fmt::format("unloading ended at |Sigma| = {:.3g} sigma_y, above 10 x --unload-tol", unorm));

  // ---- (3) probes, each on its own copy of the unloaded solver
  t0 = Clock::now();
  const double first_step = lambda > 0 ? lambda / 10 : 1e-6;
  const double loading_norm = s0 / sigma_y;
  qs::ProbeSettings ps;
  ps.directions = a.directions;
  ps.offset = a.offset;
  ps.max_strain = a.max_strain;
  ps.window = a.window;
  ps.growth = a.growth;
  ps.fine = a.fine;
  ps.first_step = first_step;
  ps.loading_norm = loading_norm;
  ps.sigma_y = sigma_y;
  std::map<int, ProbeRun> runs;
  std::mutex mtx;
  std::atomic<std::size_t> next{0};
  std::size_t finished = 0;
  // progress: the probes done plus each running probe's strain over its expected length (the stop
  // rule ends most compressive probes near 1.3 x the offset strain past the knee: 2 x offset)
  Progress pprog("probes", static_cast<double>(selection.size()), a.quiet);
  std::vector<double> frac(selection.size(), 0.0);
  auto report = [&](std::size_t q, double f) {
    std::lock_guard<std::mutex> lock(mtx);
    frac[q] = f;
    double sum = 0.0;
    for (double v : frac) sum += v;
    pprog.update(sum);
  };
  auto worker = [&] {
    for (;;) {
      const std::size_t q = next.fetch_add(1);
      if (q >= selection.size()) return;
      const int idx = selection[q];
      ProbeRun r;
      try {
        r = run_dem_probe(s, win, meter, idx, ps, gdot_p, unloaded, relax,
                        [&](double strain) { report(q, std::min(0.95, strain / (2.0 * a.offset))); });
      } catch (const std::exception& e) {
        r.result.index = idx;
        r.result.theta = 2 * kPi * idx / a.directions;
        r.result.status = std::string("error: ") + one_line(e.what());
      }
      report(q, 1.0);
      std::lock_guard<std::mutex> lock(mtx);
      ++finished;
      if (!a.quiet)
        std::fprintf(stderr, "\rprobe %3d (theta %6.1f deg): %s [%zu/%zu]\n", idx, r.result.theta * 180 / kPi,
                     r.result.status.c_str(), finished, selection.size());
      runs[idx] = std::move(r);
    }
  };
  {
    std::vector<std::thread> threads;
    for (int t = 1; t < jobs; ++t) threads.emplace_back(worker);
    worker();
    for (auto& t : threads) t.join();
  }
  pprog.finish();
  const double t_probes = seconds_since(t0);

  // ---- files: probes/probe_NNN.csv and .json, yield_points.csv (netsolve's columns)
  std::string ycsv =
      "probe,theta,S11,S22,S11_offset,S22_offset,S11_analytic,S22_analytic,S11_fabric,S22_fabric,strain,strain_offset,"
      "stress,stress_offset,elastic_slope,curvature,increments,unconverged,status,end\n";
  int ok = 0;
  std::int64_t probe_steps = 0;
  auto text = [](std::string v) {
    std::replace(v.begin(), v.end(), ',', ';');
    std::replace(v.begin(), v.end(), '\n', ' ');
    return v;
  };
  for (int idx : selection) {
    const ProbeRun& pr = runs[idx];
    const qs::ProbeResult& p = pr.result;
    probe_steps += pr.steps;
    ok += p.status == "ok";
    qs::YieldPoint ap{kNaN, kNaN};
    if (an_ok) try {
        ap = qs::affine_yield_point(an, p.theta);
      } catch (const std::exception&) {
      }
    const auto& yc = p.curvature;
    const auto& yf = p.offset;
    std::string pcsv = "increment,strain,stress,S11,S22,S12,D,Z,steps,settled,kinetic_ratio\n";
    for (std::size_t i = 0; i < p.curve.samples.size(); ++i) {
      const auto& q = p.curve.samples[i];
      pcsv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{:.4e}\n", i, q.strain, q.stress, q.S11,
                          q.S22, q.S12, q.density, q.Z, q.newton, q.converged ? 1 : 0,
                          i < pr.kinetic.size() ? pr.kinetic[i] : 0.0);
    }
    const auto stem = fmt::format("probe_{:03d}", idx);
    if (!p.curve.samples.empty()) write_file_atomic(out / "probes" / (stem + ".csv"), pcsv);
    const double fs11 = fabric[static_cast<std::size_t>(idx)].S11, fs22 = fabric[static_cast<std::size_t>(idx)].S22;
    json r = {{"probe", idx},
              {"directions", a.directions},
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
    write_file_atomic(out / "probes" / (stem + ".json"), r.dump(1) + "\n");
    ycsv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", idx, num(p.theta * 180.0 / kPi),
                        num(p.S11), num(p.S22), num(p.S11_offset), num(p.S22_offset), num(ap.S11), num(ap.S22), num(fs11),
                        num(fs22), num(yc.found ? yc.strain : kNaN), num(yf.found ? yf.strain : kNaN),
                        num(yc.found ? yc.stress : kNaN), num(yf.found ? yf.stress : kNaN),
                        num(p.fit.ok ? p.fit.slope : kNaN), num(yc.found ? yc.curvature : kNaN),
                        static_cast<int>(p.curve.samples.size()) - 1, p.curve.unconverged, text(p.status),
                        text(p.curve.end));
  }
  write_file_atomic(out / "yield_points.csv", ycsv);
  if (ok < static_cast<int>(selection.size()))
    status.add("incomplete", fmt::format("{} of {} probes found no yield point or failed (their status is in "
                                         "yield_points.csv)", selection.size() - ok, selection.size()));

  const double total = seconds_since(t_start);
  j["status"] = status.status;
  j["status_reason"] = status.ok() ? "every check passed" : status.reason();
  j["setup"] = setup;
  j["unloading"] = {{"converged", uconv},       {"increments", uk},         {"strain", lambda}, {"unsettled", unsettled},
                    {"stress_norm", unorm},     {"loading_norm", loading_norm}, {"message", umsg},
                    {"steps", usteps}};
  j["probes"] = {{"run", selection.size()},  {"ok", ok},  {"directions", a.directions}, {"jobs", jobs},
                 {"first_step", first_step}, {"offset", a.offset}, {"max_strain", a.max_strain}, {"window", a.window},
                 {"indices", selection},     {"steps", probe_steps}};
  j["analytic"] = {{"ok", an_ok}};
  j["dt"] = {{"precompaction_first", dt_first}, {"probes", dt_elastic}};
  j["damping"] = a.damping;
  j["steps_per_contact"] = a.steps_per_contact;
  j["units"] = "sigma_y = 1, R = 1 (lengths of the packing), rho = 1, t* = R sqrt(rho/sigma_y) = 1";
  j["timing_s"] = {{"total", total}, {"compaction", t_compact}, {"unloading", t_unload}, {"probes", t_probes}};
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  std::printf("D = %.4f (Z = %.3f): loading point S11/sy = %.4f, S22/sy = %.4f; unloaded to |S| = %.1e; %d/%zu probes ok; "
              "%.1f s (compaction %.1f, unloading %.1f, probes %.1f) -> %s\n",
              s.density(), loaded.Z, loaded.S[0], loaded.S[1], unorm, ok, selection.size(), total, t_compact, t_unload,
              t_probes, out.c_str());
  if (!status.ok())
    std::fprintf(stderr, "demsolve: %s: %s: %s\n", a.allow_unconverged || status.status == "incomplete" ? "warning" : "error",
                 status.status.c_str(), status.reason().c_str());
  return status.exit_code(a.allow_unconverged);
}

}  // namespace netdem::app::dem
