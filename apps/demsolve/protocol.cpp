// demsolve prepare / sinter: the options into the library calls of netdem/dynamic/protocol.hpp, and
// the output files (see protocol.hpp and docs/dynamic.md, docs/sintering.md).
#include "protocol.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <new>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "netdem/dynamic/state.hpp"
#include "output.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

namespace {

template <int D>
std::string particles_vtp(const ParticlesT<D>& P, const std::vector<ContactInfo>& cs, const std::vector<Field>& extra) {
  std::vector<double> ps, z;
  particle_stress(P, cs, ps, z);
  constexpr bool d3 = D == 3;
  // (the spins: omega about e3 in 2D, (wx, wy, wz) in 3D: kRot per particle either way)
  Field rad{"radius", 1, P.r}, vel{"velocity", 3, {}}, om{"omega", ParticlesT<D>::kRot, P.spin};
  Field st{"particle_pressure", 1, ps}, co{"contacts", 1, z};
  for (std::size_t i = 0; i < P.size(); ++i)
    vel.values.insert(vel.values.end(), {P.vel[D * i], P.vel[D * i + 1], d3 ? P.vel[D * i + D - 1] : 0.0});
  std::vector<Field> f{rad, vel, om, st, co};
  f.insert(f.end(), extra.begin(), extra.end());
  const std::vector<double> x = P.axis(0), y = P.axis(1);
  if constexpr (d3) {
    const std::vector<double> zc = P.axis(2);
    return vtp_particles_3d(x, y, &zc, f);
  } else {
    return vtp_particles(x, y, f);
  }
}

template <int D>
std::string contacts_vtp(const ParticlesT<D>& P, const std::vector<ContactInfo>& cs) {
  std::vector<int> ii, jj;
  Field fn{"f_n", 1, {}}, ft{"f_t", 1, {}}, att{"attractive", 1, {}}, sl{"sliding", 1, {}};
  for (const auto& c : cs) {
    if (c.wall >= 0) continue;
    ii.push_back(static_cast<int>(c.i));
    jj.push_back(static_cast<int>(c.j));
    fn.values.push_back(c.f_n);
    ft.values.push_back(c.f_t);
    att.values.push_back(c.f_n < 0.0 ? 1.0 : 0.0);
    sl.values.push_back(c.sliding ? 1.0 : 0.0);
  }
  const std::vector<double> x = P.axis(0), y = P.axis(1);
  if constexpr (D == 3) {
    const std::vector<double> z = P.axis(2);
    return vtp_network_3d(x, y, &z, ii, jj, {fn, ft, att, sl});
  } else {
    return vtp_network(x, y, ii, jj, {fn, ft, att, sl});
  }
}

/// Particle-particle contacts for the distributions of LMM05 Figs 11-19: overlap over a_i + a_j,
/// normal and tangential force, f_min and the activated friction mu_t = |f_t| / (f_n - f_min);
/// mu_t = 0 where f_n <= f_min (no friction capacity, f_t = 0; docs/sintering.md).
template <int D>
std::string contacts_csv(const ParticlesT<D>& P, const std::vector<ContactInfo>& cs) {
  std::string s = "i,j,overlap_rel,f_n,f_t,f_min,mu,mu_t,sliding\n";
  for (const auto& c : cs) {
    if (c.wall >= 0) continue;
    const double den = c.f_n - c.f_min;
    const double mut = den > 0.0 ? std::fabs(c.f_t) / den : 0.0;
    s += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.9g},{}\n", c.i, c.j,
                     c.overlap / (P.r[c.i] + P.r[c.j]), c.f_n, c.f_t, c.f_min, c.mu, mut,
                     c.sliding ? 1 : 0);
  }
  return s;
}

}  // namespace

template <int D>
void write_snapshot(const DynamicSolverT<D>& s, SnapshotSeries& series, const std::string& label, double t,
                    std::vector<ContactInfo>& cs, const std::vector<Field>& extra) {
  const fs::path out = series.dir();
  s.contacts(cs);
  std::string pv = particles_vtp(s.particles(), cs, extra);
  write_file_atomic(out / fmt::format("particles_{}.vtp", label), pv);
  write_file_atomic(out / fmt::format("contacts_{}.vtp", label), contacts_vtp(s.particles(), cs));
  write_file_atomic(out / fmt::format("contacts_{}.csv", label), contacts_csv(s.particles(), cs));
  series.add(t, label);
}

SnapshotSeries protocol_snapshot_series(const fs::path& out) {
  return SnapshotSeries(out / "snapshots.pvd", {"particles", "contacts"});
}

namespace {

template <int D>
double mean_radius(const ParticlesT<D>& P) {
  double r = 0.0;
  for (double v : P.r) r += v;
  return r / static_cast<double>(P.size());
}

}  // namespace

void apply_overrides(LudingParams& p, const std::vector<std::string>& items) {
  for (const auto& it : items) {
    const auto eq = it.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("--param expects NAME=VALUE, got '" + quote_input(it) + "'");
    const std::string name = it.substr(0, eq), val = it.substr(eq + 1);
    char* end = nullptr;
    const double v = std::strtod(val.c_str(), &end);
    if (val.empty() || *end != '\0')
      throw std::invalid_argument("--param " + quote_input(name) + ": '" + quote_input(val) + "' is not a number");
    set_luding_param(p, name, v);
  }
  p.validate();
}

std::string one_line(const std::string& m) {
  std::string o = m;
  for (char& c : o)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return o;
}

int guarded(const std::function<int()>& body) { return netdem::app::guarded("demsolve", body); }

void check_memory(std::size_t n) {
  // particles, histories, Verlet table (~4 pairs each, double-buffered), the last good state,
  // a state's text and the snapshots: about 4 kB a particle (docs/dynamic.md "Limits")
  const double need = 64e6 + 4096.0 * static_cast<double>(n), have = mem_available();
  if (have > 0.0 && !(need <= have))  // (0: unknown)
    throw UsageError(fmt::format("the run needs about {:.3g} GB of memory for {} particles, MemAvailable is {:.3g} GB",
                                 need / 1e9, n, have / 1e9));
}

std::string check_loading(double pressure, const LudingParams& p, const std::string& what, int dim) {
  // 2D: p [N/m] on a disk's 2 a of wall, overlap / a = 2p/k2; 3D: p [N/m^2] on a sphere's (2 a0)^2,
  // overlap / a0 = 4 p a0 / k2
  const bool d3 = dim == 3;
  const double r = d3 ? 4.0 * pressure * p.a0 / p.k2 : 2.0 * pressure / p.k2;
  const char* unit = d3 ? "N/m^2" : "N/m";
  const char* ratio = d3 ? "4 p a0/k2" : "2p/k2";
  if (!(r >= 1e-9))  // a pressure that cannot hold the sample; stresses over p would overflow
    throw UsageError(fmt::format("{} = {:g} {} gives the loading ratio {} = {:.3g}, below 1e-9: the walls would not "
                                 "hold the sample (raise the pressure)", what, pressure, unit, ratio, r));
  if (!(r <= 0.1))
    throw UsageError(fmt::format("{} = {:g} {} gives the loading ratio {} = {:.3g}, above 0.1, beyond the range of "
                                 "Luding's model (section 4); lower the pressure or raise k2 (= {:g} N/m)",
                                 what, pressure, unit, ratio, r, p.k2));
  if (r > 0.02) {
    std::string w = fmt::format("{} = {:g} {} gives the loading ratio {} = {:.3g}, above 0.02 (Luding section 4: "
                                "overlaps beyond small deformations)", what, pressure, unit, ratio, r);
    std::fprintf(stderr, "demsolve: warning: %s\n", w.c_str());
    return w;
  }
  return "";
}

void check_temperature(double T, const LudingParams& p, const std::string& what) {
  if (!(std::isfinite(T) && T > -273.15))
    throw UsageError(fmt::format("{} = {:g} deg C is not above absolute zero (-273.15 deg C)", what, T));
  const double e = p.da_T * (T - p.T_radius_ref);
  if (!(std::fabs(e) <= 0.05))
    throw UsageError(fmt::format("{} = {:g} deg C gives the thermal radius change |da_T (T - T_radius_ref)| = {:.3g}, "
                                 "above 0.05 (Eq 9 is a small-strain law)", what, T, std::fabs(e)));
}

namespace {
// The steps and the work (particles x steps) against --max-steps and kMaxParticleSteps; `about`:
// "about" for the solver's time step, "at least" for the estimate before placing.
void check_work(std::size_t n, double steps, double dt, double max_steps, bool allow_long, const char* about) {
  if (!(std::isfinite(dt) && dt > 0.0))
    throw UsageError(fmt::format("the time step is {:g} s: check --steps-per-contact, k2 and rho_p", dt));
  if (!(std::isfinite(max_steps) && max_steps >= 1.0)) throw UsageError("--max-steps must be a number >= 1");
  if (!(steps <= max_steps))
    throw UsageError(fmt::format("the run needs {} {:.3g} time steps of {:.3g} s, more than --max-steps = {:.3g}",
                                 about, steps, dt, max_steps));
  const double work = steps * static_cast<double>(n);
  if (!allow_long && !(work <= kMaxParticleSteps))
    throw UsageError(fmt::format("the run needs {} {:.3g} particle-steps ({} particles x {:.3g} time steps of {:.3g} s), "
                                 "more than {:.3g}, about {:.1f} to {:.1f} h of one core: pass --allow-long to run it",
                                 about, work, n, steps, dt, kMaxParticleSteps, work / 2e7 / 3600.0, work / 1e7 / 3600.0));
}

// check_run_limits' steps and work before a random sample of n particles is placed (placing 1e6
// spheres takes a minute), over `duration` seconds
template <int D>
void check_work_before_placing(int n, const LudingParams& lp, const DynamicOptions& opt, double duration,
                               double max_steps, bool allow_long) {
  // the time step of the heaviest possible pair (radius a0 (1 + w0)) bounds the solver's, which
  // takes the lightest pair: so the steps below are at most the run's (choose_time_step)
  const double a = lp.a0 * (1.0 + lp.w0);
  const double m = D == 2 ? lp.rho_p * std::numbers::pi * a * a : lp.rho_p * 4.0 / 3.0 * std::numbers::pi * a * a * a;
  const double dt = contact_duration(lp.k2, lp.gamma_n, 0.5 * m) / opt.steps_per_contact;
  check_work(static_cast<std::size_t>(std::max(n, 1)), duration / dt, dt, max_steps, allow_long, "at least");
}
}  // namespace

template <int D>
void check_run_limits(const DynamicSolverT<D>& s, double steps, double max_steps, bool allow_long) {
  const double dt = s.dt();
  check_work(s.particles().size(), steps, dt, max_steps, allow_long, "about");
  const ParticlesT<D>& P = s.particles();
  const LudingParams& lp = s.params();
  double m_lo = std::numeric_limits<double>::infinity();
  for (double m : P.mass) m_lo = std::min(m_lo, m);
  // explicit damping: gamma dt / m12 of the lightest pair (stable below 2; refused above 1)
  const double damp = lp.gamma_n * dt / (0.5 * m_lo);
  if (!(damp <= 1.0))
    throw UsageError(fmt::format("normal damping gamma_n = {:g} kg/s with dt = {:.3g} s gives gamma_n dt / m12 = {:.3g} "
                                 "for the lightest pair, above 1: the explicit step is unstable (lower gamma_n or "
                                 "raise --steps-per-contact)", lp.gamma_n, dt, damp));
  for (const MovingWall* w : {&s.box().right, &s.box().top, &s.box().back}) {
    if (D == 2 && w == &s.box().back) continue;
    if (!s.box().enabled || w->mode != WallMode::Stress) continue;
    const double wd = w->damping * dt / w->mass;
    if (!(wd <= 1.0))
      throw UsageError(fmt::format("wall damping {:g} kg/s with wall mass {:g} kg and dt = {:.3g} s gives "
                                   "gamma_wall dt / m_wall = {:.3g}, above 1: the wall is unstable", w->damping, w->mass,
                                   dt, wd));
    // the wall on the disks along it (about sqrt(N) contacts of stiffness k2; 3D: N^(2/3)): >= 10 steps per period
    const double nw = D == 2 ? std::ceil(std::sqrt(static_cast<double>(P.size())))
                             : std::ceil(std::pow(static_cast<double>(P.size()), 2.0 / 3.0));
    const double k = lp.k2 * nw;
    const double tc = std::numbers::pi * std::sqrt(w->mass / k);
    if (!(tc >= 10.0 * dt))
      throw UsageError(fmt::format("wall mass {:g} kg gives the wall a contact time of {:.3g} s, fewer than 10 time "
                                   "steps of {:.3g} s: the wall is unstable (raise m_wall)", w->mass, tc, dt));
  }
}

template <int D>
int report_unstable(const InstabilityError& e, const DynamicSolverT<D>& s, const fs::path& out, nlohmann::json summary) {
  if (const SolverState* good = s.last_good()) {
    write_file_atomic(out / "state_last_good.txt", format_state(*good));
    summary["last_good_time_s"] = good->time;
  }
  summary["status"] = "unstable";
  summary["status_reason"] = e.what();
  summary["unstable_quantity"] = e.quantity();
  summary["unstable_step"] = e.step();
  summary["unstable_time_s"] = e.time();
  write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
  close_run_dir(out);
  std::fprintf(stderr, "demsolve: error: %s\n", one_line(e.what()).c_str());
  return exit_code::untrustworthy;
}

SolverState load_state(const std::string& file, const std::vector<std::string>& overrides) {
  SolverState st = read_state_file(file);
  apply_overrides(st.params, overrides);
  return st;
}

namespace {

/// The output of a protocol run: timeseries rows, and per phase its state, snapshot and summary.
std::array<double, 3> diagonal(const Stress2& s) { return {s.xx, s.yy, 0.0}; }
std::array<double, 3> diagonal(const Stress3& s) { return {s.s[0][0], s.s[1][1], s.s[2][2]}; }

template <int D>
class PhaseWriter final : public PhaseObserverT<D> {
 public:
  PhaseWriter(const DynamicSolverT<D>& s, const std::vector<SinterPhase>& phases, double pressure, const fs::path& out,
              std::int64_t total, bool quiet)
      : phases_(phases),
        pressure_(pressure),
        k1c_(s.params().k1()),
        out_(out),
        progress_("demsolve", static_cast<double>(total), quiet),
        cpu_phase_(cpu_now()),
        cpu_start_(cpu_phase_),
        t_start_(std::chrono::steady_clock::now()),
        t_phase_(t_start_) {
    if constexpr (D == 2)
      csv_ =
          "t,phase,T,k1,nu,C,C_without_walls,sxx,szz,sxx_over_p,szz_over_p,sxx_contacts,szz_contacts,"
          "Ekin,box_width,box_height\n";
    else
      csv_ =
          "t,phase,T,k1,nu,C,C_without_walls,sxx,syy,szz,sxx_over_p,syy_over_p,szz_over_p,sxx_contacts,syy_contacts,"
          "szz_contacts,Ekin,box_x,box_y,box_z\n";
  }

  void sample(const DynamicSolverT<D>& s, std::size_t phase, std::int64_t steps) override {
    if (steps == 0) {
      s.check_health();
      write_snapshot(s, series_, "initial", s.time(), cs_);
    }
    const ContactCounts c = count_contacts(s, buf_);
    const auto ws = s.wall_stress();
    const auto cst = s.contact_stress();
    const std::size_t n = s.particles().size();
    if constexpr (D == 2) {
      csv_ += fmt::format("{:.9g},{},{:.6g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.9g},{:.9g}\n",
                          s.time(), phases_[phase].name, s.thermal().T, s.thermal().k1_Tt / k1c_, s.density(),
                          c.coordination(n), c.coordination_without_walls(n), ws.xx, ws.yy, ws.xx / pressure_,
                          ws.yy / pressure_, cst.xx, cst.yy, s.energies().kinetic, s.box().x_max - s.box().x_min,
                          s.box().y_max - s.box().y_min);
    } else {
      const auto w = diagonal(ws), k = diagonal(cst);
      csv_ += fmt::format("{:.9g},{},{:.6g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},"
                          "{:.9g},{:.6g},{:.9g},{:.9g},{:.9g}\n",
                          s.time(), phases_[phase].name, s.thermal().T, s.thermal().k1_Tt / k1c_, s.density(),
                          c.coordination(n), c.coordination_without_walls(n), w[0], w[1], w[2], w[0] / pressure_,
                          w[1] / pressure_, w[2] / pressure_, k[0], k[1], k[2], s.energies().kinetic,
                          s.box().x_max - s.box().x_min, s.box().y_max - s.box().y_min, s.box().z_max - s.box().z_min);
    }
    if (steps > 0) progress_.update(static_cast<double>(steps));
  }

  void phase_end(const DynamicSolverT<D>& s, std::size_t p) override {
    s.check_health();  // nothing unchecked reaches a file
    const auto now = std::chrono::steady_clock::now();
    const std::string& name = phases_[p].name;
    write_file_atomic(out_ / fmt::format("state_{}.txt", name), format_state(s.state()));
    write_snapshot(s, series_, name, s.time(), cs_);
    const double cpu = cpu_now();
    phase_list_.push_back(phase_json(s, name, std::chrono::duration<double>(now - t_phase_).count(), cpu - cpu_phase_));
    t_phase_ = now;
    cpu_phase_ = cpu;
  }

  /// timeseries.csv, state.txt, the final snapshot and the summary entries.
  void finish(const DynamicSolverT<D>& s, const PhaseRun& run, nlohmann::json& summary) {
    s.check_health();
    progress_.finish();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start_).count();
    write_file_atomic(out_ / "timeseries.csv", csv_);
    write_file_atomic(out_ / "state.txt", format_state(s.state()));
    write_snapshot(s, series_, "final", s.time(), cs_);
    const auto n = static_cast<double>(s.particles().size());
    summary["phases"] = phase_list_;
    const double cpu = cpu_now() - cpu_start_;
    summary["final"] = phase_json(s, "final", wall, cpu);
    summary["cpu_time_s"] = cpu;
    summary["particle_steps_per_cpu_s"] = static_cast<double>(run.steps) * n / std::max(cpu, 1e-9);
    summary["steps"] = run.steps;
    summary["dt_s"] = s.dt();
    summary["wall_time_s"] = wall;
    summary["particle_steps_per_s"] = static_cast<double>(run.steps) * n / std::max(wall, 1e-9);
    summary["neighbour_rebuilds"] = s.rebuilds();
    summary["mean_radius_m"] = mean_radius(s.particles());
  }

 private:
  static double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

  nlohmann::json phase_json(const DynamicSolverT<D>& s, const std::string& name, double wall_s, double cpu_s) {
    const ContactCounts c = count_contacts(s, buf_);
    const auto ws = diagonal(s.wall_stress());
    const std::size_t n = s.particles().size();
    if constexpr (D == 3)
      return nlohmann::json{{"phase", name},
                            {"t", s.time()},
                            {"T", s.thermal().T},
                            {"k1_over_k1", s.thermal().k1_Tt / k1c_},
                            {"nu", s.density()},
                            {"C", c.coordination(n)},
                            {"C_without_walls", c.coordination_without_walls(n)},
                            {"sxx_over_p", ws[0] / pressure_},
                            {"syy_over_p", ws[1] / pressure_},
                            {"szz_over_p", ws[2] / pressure_},
                            {"Ekin_J", s.energies().kinetic},
                            {"wall_time_s", wall_s},
                            {"cpu_time_s", cpu_s}};
    return nlohmann::json{{"phase", name},
                          {"t", s.time()},
                          {"T", s.thermal().T},
                          {"k1_over_k1", s.thermal().k1_Tt / k1c_},
                          {"nu", s.density()},
                          {"C", c.coordination(n)},
                          {"C_without_walls", c.coordination_without_walls(n)},
                          {"sxx_over_p", ws[0] / pressure_},
                          {"szz_over_p", ws[1] / pressure_},
                          {"Ekin_J", s.energies().kinetic},
                          {"wall_time_s", wall_s},
                          {"cpu_time_s", cpu_s}};
  }

  const std::vector<SinterPhase>& phases_;
  double pressure_, k1c_;
  fs::path out_;
  SnapshotSeries series_ = protocol_snapshot_series(out_);
  Progress progress_;
  double cpu_phase_, cpu_start_;
  std::chrono::steady_clock::time_point t_start_, t_phase_;
  std::string csv_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> buf_;
  std::vector<ContactInfo> cs_;
  nlohmann::json phase_list_ = nlohmann::json::array();
};

/// Runs the phases from the solver's current time to the end of the last phase, writing
/// timeseries.csv, per-phase state/vtp/contact files and filling `summary`.
template <int D>
void run_and_write_phases(DynamicSolverT<D>& s, const std::vector<SinterPhase>& phases, const RunArgs& a,
                          const fs::path& out, nlohmann::json& summary) {
  const double pressure = s.box().right.pressure > 0.0 ? s.box().right.pressure : a.pressure;
  PhaseWriter<D> writer(s, phases, pressure, out, steps_to_end(s, phases), a.quiet);
  const PhaseRun run = netdem::dem::run_phases(s, phases, {a.mu, a.mu_wall_prepare, a.mu_prepare}, a.samples, writer);
  writer.finish(s, run, summary);
}

}  // namespace

namespace {
template <int D>
int run_protocol_body(const std::string& command, const SampleSpec& sample, const RunArgs& args,
                      const std::vector<SinterPhase>& phases, bool prepare_only, const fs::path& out,
                      SolverState* state) {
  DynamicOptions opt;
  opt.model = ContactModel::Full;
  opt.steps_per_contact = args.steps_per_contact;
  opt.threads = args.threads;
  opt.temperature = phases.front().T_start;
  std::unique_ptr<DynamicSolverT<D>> s;
  nlohmann::json summary;
  std::string warning;
  auto check_protocol_T = [&](const LudingParams& lp) {
    for (const auto& ph : phases) {
      check_temperature(ph.T_start, lp, "the temperature of phase " + ph.name + " (--T-cold / --T-hot)");
      check_temperature(ph.T_end, lp, "the temperature of phase " + ph.name + " (--T-cold / --T-hot)");
    }
  };
  if (!args.state_file.empty()) {
    SolverState& st = *state;
    if (args.pressure_given) st.box.right.pressure = st.box.top.pressure = st.box.back.pressure = args.pressure;
    // --param m_wall / gamma_wall also apply to the state's stress-controlled walls (Eq 1)
    for (const auto& it : args.param_overrides)
      for (MovingWall* w : {&st.box.right, &st.box.top, &st.box.back}) {
        if (w->mode != WallMode::Stress) continue;
        if (it.rfind("m_wall=", 0) == 0) w->mass = st.params.m_wall;
        if (it.rfind("gamma_wall=", 0) == 0) w->damping = st.params.gamma_wall;
      }
    check_protocol_T(st.params);
    check_temperature(st.thermal.T, st.params, "the state's temperature");
    if (st.box.right.mode == WallMode::Stress || st.box.top.mode == WallMode::Stress ||
        (D == 3 && st.box.back.mode == WallMode::Stress))
      warning = check_loading(std::max({st.box.right.pressure, st.box.top.pressure, D == 3 ? st.box.back.pressure : 0.0}),
                              st.params, args.pressure_given ? "--pressure" : "the state's wall pressure", D);
    check_memory(st.particle_count());
    s = std::make_unique<DynamicSolverT<D>>(st, opt);
    summary["state_file"] = args.state_file;
    if (s->time() >= phase_end(phases, phases.size() - 1) - 0.5 * s->dt())
      throw std::invalid_argument(fmt::format("state file time {} is past the end of the protocol ({})", s->time(),
                                              phase_end(phases, phases.size() - 1)));
  } else {
    LudingParams lp;
    apply_overrides(lp, args.param_overrides);
    check_protocol_T(lp);
    // 3D default: 100 N/m over 2 a0 (the 2D default's overlap ratio)
    const double pressure = D == 3 && !args.pressure_given ? args.pressure / (2.0 * lp.a0) : args.pressure;
    warning = check_loading(pressure, lp, "--pressure", D);
    if (sample.packing_file.empty()) {  // before placing: 1e6 spheres take a minute to place
      check_memory(static_cast<std::size_t>(std::max(sample.n, 1)));
      check_work_before_placing<D>(sample.n, lp, opt, phase_end(phases, phases.size() - 1), args.max_steps,
                                   args.allow_long);
    }
    Box box;
    double length_unit = 0.0;
    ParticlesT<D> P;
    if constexpr (D == 2) P = make_sample(sample, lp, box, &length_unit);
    else P = make_sample3(sample, lp, box, &length_unit);
    check_memory(P.size());
    set_stress_walls(box, pressure, lp, D);
    s = std::make_unique<DynamicSolverT<D>>(std::move(P), lp, box, opt);
    summary["seed"] = sample.seed;
    summary["arrangement"] = sample.arrangement;
    if (!sample.packing_file.empty()) {
      summary["packing_file"] = sample.packing_file;
      summary["length_unit_m"] = length_unit;
    }
  }
  check_run_limits(*s, (phase_end(phases, phases.size() - 1) - s->time()) / s->dt(), args.max_steps, args.allow_long);
  RunDirOptions rdo;
  rdo.overwrite = args.overwrite;
  rdo.inputs = {args.state_file, sample.packing_file};
  open_run_dir(out, command, rdo);
  nlohmann::json params;
  for (const auto& name : luding_param_names()) params[name] = get_luding_param(s->params(), name);
  nlohmann::json prot = nlohmann::json::array();
  for (const auto& ph : phases)
    prot.push_back({{"phase", ph.name}, {"duration_s", ph.duration}, {"T_start", ph.T_start}, {"T_end", ph.T_end},
                    {"t0_s", ph.t0}, {"friction", ph.friction}});
  const double pressure = s->box().right.pressure;
  nlohmann::json pj{{"command", command},      {"particles", s->particles().size()},
                    {D == 2 ? "pressure_N_per_m" : "pressure_N_per_m2", pressure}, {"mu", args.mu},
                    {"mu_wall_prepare", args.mu_wall_prepare}, {"mu_prepare", args.mu_prepare},
                    {"steps_per_contact", args.steps_per_contact}, {"samples", args.samples},
                    {"threads", args.threads},
                    {"dt_s", s->dt()},          {"steps_per_contact_lightest_pair", s->time_step().steps_per_contact_lightest},
                    {"contact_params", params}, {"protocol", prot}};
  if (args.state_file.empty()) pj["seed"] = sample.seed;
  if constexpr (D == 3) pj["dim"] = 3;
  write_file_atomic(out / "parameters.json", pj.dump(2) + "\n");
  if (!args.quiet && args.state_file.empty())
    std::fprintf(stderr, "demsolve: seed %llu, %zu %s, dt = %.3g s\n", static_cast<unsigned long long>(sample.seed),
                 s->particles().size(), D == 2 ? "disks" : "spheres", s->dt());
  summary["command"] = command;
  summary["particles"] = s->particles().size();
  summary[D == 2 ? "pressure_N_per_m" : "pressure_N_per_m2"] = pressure;
  if constexpr (D == 3) summary["dim"] = 3;
  summary["steps_per_contact_lightest_pair"] = s->time_step().steps_per_contact_lightest;
  try {
    run_and_write_phases(*s, phases, args, out, summary);
  } catch (const InstabilityError& e) {
    return report_unstable(e, *s, out, summary);
  }
  summary["status"] = "ok";
  summary["status_reason"] = warning.empty() ? "every instability check passed" : "every instability check passed; warning: " + warning;
  // densification nu(t_f) / nu(t_heat) - 1 (LMM05 section 4.1.3)
  for (const auto& ph : summary["phases"])
    if (!prepare_only && ph["phase"] == "prepare") summary["densification"] = summary["final"]["nu"].get<double>() / ph["nu"].get<double>() - 1.0;
  write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
  close_run_dir(out);
  const auto& f = summary["final"];
  netdem::app::summary_printf("t = %.4f s: nu = %.4f, C = %.3f (%.3f without walls), sxx/p = %.4f, szz/p = %.4f, k1(T,t)/k1 = %.4f, "
              "Ekin = %.3e J, %.1f s -> %s\n",
              f["t"].get<double>(), f["nu"].get<double>(), f["C"].get<double>(), f["C_without_walls"].get<double>(),
              f["sxx_over_p"].get<double>(), f["szz_over_p"].get<double>(), f["k1_over_k1"].get<double>(),
              f["Ekin_J"].get<double>(), summary["wall_time_s"].get<double>(), out.c_str());
  return 0;
}
}  // namespace

int run_protocol(const std::string& command, const SampleSpec& sample, const RunArgs& args,
                 const SinterProtocol& protocol, bool prepare_only, const fs::path& out) {
  if (!(std::isfinite(args.pressure) && args.pressure > 0.0))
    throw std::invalid_argument(fmt::format("--pressure must be a positive number of N/m, got {}", args.pressure));
  if (!(std::isfinite(args.mu) && args.mu >= 0.0 && args.mu <= 10.0)) throw UsageError("--mu must be in [0, 10]");
  if (!(std::isfinite(args.mu_wall_prepare) && args.mu_wall_prepare >= 0.0 && args.mu_wall_prepare <= 10.0))
    throw UsageError("--mu-wall must be in [0, 10]");
  if (!(std::isfinite(args.mu_prepare) && args.mu_prepare >= 0.0 && args.mu_prepare <= 10.0))
    throw UsageError("--mu-prepare must be in [0, 10]");
  if (args.samples < 1 || args.samples > 10000000)
    throw UsageError(fmt::format("--samples must be in [1, 1e7], got {}", args.samples));
  if (!(std::isfinite(args.steps_per_contact) && args.steps_per_contact > 0.0 && args.steps_per_contact <= 1e4))
    throw UsageError(fmt::format("--steps-per-contact must be in (0, 1e4], got {}", args.steps_per_contact));
  if (!args.state_file.empty() && args.sample_given)
    throw UsageError("--n, --seed and --arrangement describe a new sample and cannot be used with --state");
  if (args.packing_given && sample.packing_file.empty())
    throw UsageError("--packing is empty: give a packing CSV file, or leave --packing out for a random sample");
  auto phases = protocol.phases();
  if (prepare_only) {
    phases.resize(1);
    if (!(protocol.t_heat > 0.0))
      throw std::invalid_argument(fmt::format("--time must be a positive number of seconds, got {}", protocol.t_heat));
  }
  if (!(phase_end(phases, phases.size() - 1) > 0.0)) throw std::invalid_argument("the protocol has zero length");
  if (!args.state_file.empty() && !sample.packing_file.empty())
    throw std::invalid_argument("--state and --packing both give the sample: use one of them");
  if (!(args.dim == 2 || args.dim == 3)) throw UsageError(fmt::format("--dim must be 2 or 3, got {}", args.dim));
  if (!args.state_file.empty()) {
    SolverState st = load_state(args.state_file, args.param_overrides);
    if (args.dim_given && st.dim() != args.dim)
      throw UsageError(fmt::format("--dim {} but the state file {} is {}D", args.dim, quote_input(args.state_file), st.dim()));
    if (st.dim() == 3) return run_protocol_body<3>(command, sample, args, phases, prepare_only, out, &st);
    return run_protocol_body<2>(command, sample, args, phases, prepare_only, out, &st);
  }
  if (args.dim == 3) return run_protocol_body<3>(command, sample, args, phases, prepare_only, out, nullptr);
  return run_protocol_body<2>(command, sample, args, phases, prepare_only, out, nullptr);
}

template void write_snapshot<2>(const DynamicSolverT<2>&, SnapshotSeries&, const std::string&, double,
                                 std::vector<ContactInfo>&, const std::vector<Field>&);
template void write_snapshot<3>(const DynamicSolverT<3>&, SnapshotSeries&, const std::string&, double,
                                 std::vector<ContactInfo>&, const std::vector<Field>&);
template void check_run_limits<2>(const DynamicSolverT<2>&, double, double, bool);
template void check_run_limits<3>(const DynamicSolverT<3>&, double, double, bool);
template int report_unstable<2>(const InstabilityError&, const DynamicSolverT<2>&, const fs::path&, nlohmann::json);
template int report_unstable<3>(const InstabilityError&, const DynamicSolverT<3>&, const fs::path&, nlohmann::json);

}  // namespace netdem::app::dem
