// demsolve run driver (see protocol.hpp and docs/dynamic.md, docs/sintering.md).
#include "protocol.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

#include "netdem/dynamic/state.hpp"
#include "netdem/packing/random_fill.hpp"
#include "output.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;
using netdem::packing::uniform01;

namespace netdem::app::dem {

namespace {

struct Counts {
  std::size_t pairs = 0, walls = 0;
};

Counts count_contacts(const DynamicSolver& s, std::vector<std::pair<std::uint32_t, std::uint32_t>>& buf) {
  s.touching_pairs(buf);
  return {buf.size(), s.wall_contacts()};
}

/// Average stress of each particle, p_i = (1 / (2 pi a_i^2)) sum_c f_n d_i (normal forces,
/// compression positive, N/m like the wall pressure), and its number of contacts.
void particle_stress(const Particles& P, const std::vector<ContactInfo>& cs, std::vector<double>& p,
                     std::vector<double>& z) {
  p.assign(P.size(), 0.0);
  z.assign(P.size(), 0.0);
  for (const auto& c : cs) {
    p[c.i] += c.f_n * c.d_i;
    z[c.i] += 1.0;
    if (c.wall < 0) {
      p[c.j] += c.f_n * c.d_j;
      z[c.j] += 1.0;
    }
  }
  for (std::size_t i = 0; i < P.size(); ++i) p[i] /= 2.0 * std::numbers::pi * P.radius[i] * P.radius[i];
}

std::string particles_vtp(const Particles& P, const std::vector<ContactInfo>& cs, const std::vector<Field>& extra) {
  std::vector<double> ps, z;
  particle_stress(P, cs, ps, z);
  Field rad{"radius", 1, P.radius}, vel{"velocity", 3, {}}, om{"omega", 1, P.omega};
  Field st{"particle_pressure", 1, ps}, co{"contacts", 1, z};
  for (std::size_t i = 0; i < P.size(); ++i) vel.values.insert(vel.values.end(), {P.vx[i], P.vy[i], 0.0});
  std::vector<Field> f{rad, vel, om, st, co};
  f.insert(f.end(), extra.begin(), extra.end());
  return vtp_particles(P.x, P.y, f);
}

std::string contacts_vtp(const Particles& P, const std::vector<ContactInfo>& cs) {
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
  return vtp_network(P.x, P.y, ii, jj, {fn, ft, att, sl});
}

/// Particle-particle contacts for the distributions of LMM05 Figs 11-19: overlap over a_i + a_j,
/// normal and tangential force, f_min and the activated friction mu_t = |f_t| / (f_n - f_min).
std::string contacts_csv(const Particles& P, const std::vector<ContactInfo>& cs) {
  std::string s = "i,j,overlap_rel,f_n,f_t,f_min,mu,mu_t,sliding\n";
  for (const auto& c : cs) {
    if (c.wall >= 0) continue;
    const double den = c.f_n - c.f_min;
    const double mut = den > 0.0 ? std::fabs(c.f_t) / den : std::nan("");
    s += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.9g},{}\n", c.i, c.j,
                     c.overlap / (P.radius[c.i] + P.radius[c.j]), c.f_n, c.f_t, c.f_min, c.mu, mut,
                     c.sliding ? 1 : 0);
  }
  return s;
}

}  // namespace

void write_snapshot(const DynamicSolver& s, const fs::path& out, const std::string& label,
                    std::vector<ContactInfo>& cs, const std::vector<Field>& extra) {
  s.contacts(cs);
  std::string pv = particles_vtp(s.particles(), cs, extra);
  write_file_atomic(out / fmt::format("particles_{}.vtp", label), pv);
  write_file_atomic(out / fmt::format("contacts_{}.vtp", label), contacts_vtp(s.particles(), cs));
  write_file_atomic(out / fmt::format("contacts_{}.csv", label), contacts_csv(s.particles(), cs));
}

namespace {

double mean_radius(const Particles& P) {
  double r = 0.0;
  for (double v : P.radius) r += v;
  return r / static_cast<double>(P.size());
}

}  // namespace

void apply_overrides(LudingParams& p, const std::vector<std::string>& items) {
  for (const auto& it : items) {
    const auto eq = it.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("--param expects NAME=VALUE, got '" + it + "'");
    const std::string name = it.substr(0, eq), val = it.substr(eq + 1);
    char* end = nullptr;
    const double v = std::strtod(val.c_str(), &end);
    if (val.empty() || *end != '\0')
      throw std::invalid_argument("--param " + name + ": '" + val + "' is not a number");
    set_luding_param(p, name, v);
  }
  p.validate();
}

SolverState load_state(const std::string& file, const std::vector<std::string>& overrides) {
  SolverState st = read_state_file(file);
  apply_overrides(st.params, overrides);
  return st;
}

Particles place_sample(const SampleArgs& a, const LudingParams& lp, Box& box) {
  if (a.n < 1 || a.n > 1000000) throw std::invalid_argument(fmt::format("--n must be in [1, 1e6], got {}", a.n));
  if (!(a.initial_density > 0.0 && a.initial_density < 0.6))
    throw std::invalid_argument(fmt::format("initial density must be in (0, 0.6), got {}", a.initial_density));
  Particles P;
  if (a.arrangement != "random") {  // LMM05 section 4.1.3 control: three equal disks
    if (a.n != 3) throw std::invalid_argument("--arrangement triangle|line needs --n 3");
    const double r = lp.a0;
    if (a.arrangement == "line") {
      box.x_min = box.y_min = 0.0;
      box.x_max = 6.0 * r;
      box.y_max = 2.0 * r;
      for (int k = 0; k < 3; ++k) P.add((1.0 + 2.0 * k) * r, r, r, lp);
    } else if (a.arrangement == "triangle") {
      // two on the floor, one on top; the box closes around them
      const double h = std::sqrt(3.0) * r;
      box.x_min = box.y_min = 0.0;
      box.x_max = 4.0 * r;
      box.y_max = 2.0 * r + h;
      P.add(r, r, r, lp);
      P.add(3.0 * r, r, r, lp);
      P.add(2.0 * r, r + h, r, lp);
    } else {
      throw std::invalid_argument("--arrangement must be random, triangle or line, got '" + a.arrangement + "'");
    }
    return P;
  }
  std::mt19937_64 rng(a.seed);
  std::vector<double> r(static_cast<std::size_t>(a.n));
  double area = 0.0;
  for (auto& ri : r) {  // draw order: all radii first, then positions, then velocities
    ri = lp.a0 * (1.0 - lp.w0 + 2.0 * lp.w0 * uniform01(rng));
    area += std::numbers::pi * ri * ri;
  }
  const double L = std::sqrt(area / a.initial_density);
  box.x_min = box.y_min = 0.0;
  box.x_max = box.y_max = L;
  netdem::packing::Packing placed;
  try {
    placed = netdem::packing::random_fill(r, {0.0, 0.0, L, L}, rng);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("{} at density {}", e.what(), a.initial_density));
  }
  for (std::size_t i = 0; i < r.size(); ++i) P.add(placed.x[i], placed.y[i], r[i], lp);
  const double v0 = 0.01;  // [m/s]
  for (std::size_t i = 0; i < r.size(); ++i) {
    P.vx[i] = v0 * (2.0 * uniform01(rng) - 1.0);
    P.vy[i] = v0 * (2.0 * uniform01(rng) - 1.0);
  }
  return P;
}

int run_phases(DynamicSolver& s, const std::vector<SinterPhase>& phases, const RunArgs& a,
               const fs::path& out, nlohmann::json& summary) {
  const double dt = s.dt();
  const std::size_t n = s.particles().size();
  const double pressure = s.box().right.pressure > 0.0 ? s.box().right.pressure : a.pressure;
  auto step_of = [dt](double t) { return static_cast<std::int64_t>(std::ceil(t / dt - 1e-6)); };
  const std::int64_t k0 = static_cast<std::int64_t>(std::llround(s.time() / dt));
  const std::int64_t K = step_of(phase_end(phases, phases.size() - 1));
  std::vector<std::int64_t> ends;
  for (std::size_t p = 0; p < phases.size(); ++p) ends.push_back(step_of(phase_end(phases, p)));
  const std::int64_t total = std::max<std::int64_t>(0, K - k0);
  const std::int64_t every = std::max<std::int64_t>(1, total / 3000);
  const double k1c = s.params().k1();
  const LudingParams base = s.params();

  std::string csv =
      "t,phase,T,k1,nu,C,C_without_walls,sxx,szz,sxx_over_p,szz_over_p,sxx_contacts,szz_contacts,"
      "Ekin,box_width,box_height\n";
  std::vector<std::pair<std::uint32_t, std::uint32_t>> buf;
  std::vector<ContactInfo> cs;
  std::size_t cur_phase = schedule_at(phases, s.time()).phase;
  auto row = [&] {
    const Counts c = count_contacts(s, buf);
    const auto ws = s.wall_stress();
    const auto cst = s.contact_stress();
    const double nn = static_cast<double>(n);
    csv += fmt::format("{:.9g},{},{:.6g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.9g},{:.9g}\n",
                       s.time(), phases[cur_phase].name, s.thermal().T, s.thermal().k1_Tt / k1c, s.density(),
                       (2.0 * static_cast<double>(c.pairs) + static_cast<double>(c.walls)) / nn,
                       2.0 * static_cast<double>(c.pairs) / nn, ws.xx, ws.yy, ws.xx / pressure, ws.yy / pressure,
                       cst.xx, cst.yy, s.energies().kinetic, s.box().x_max - s.box().x_min,
                       s.box().y_max - s.box().y_min);
  };
  auto snapshot = [&](const std::string& label) { write_snapshot(s, out, label, cs); };
  auto cpu_now = [] { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; };
  double cpu_phase = cpu_now();
  const double cpu_start = cpu_phase;
  auto phase_json = [&](const std::string& name, double wall_s, double cpu_s) {
    const Counts c = count_contacts(s, buf);
    const auto ws = s.wall_stress();
    const double nn = static_cast<double>(n);
    return nlohmann::json{{"phase", name},
                           {"t", s.time()},
                           {"T", s.thermal().T},
                           {"k1_over_k1", s.thermal().k1_Tt / k1c},
                           {"nu", s.density()},
                           {"C", (2.0 * static_cast<double>(c.pairs) + static_cast<double>(c.walls)) / nn},
                           {"C_without_walls", 2.0 * static_cast<double>(c.pairs) / nn},
                           {"sxx_over_p", ws.xx / pressure},
                           {"szz_over_p", ws.yy / pressure},
                           {"Ekin_J", s.energies().kinetic},
                           {"wall_time_s", wall_s},
                           {"cpu_time_s", cpu_s}};
  };

  snapshot("initial");
  row();
  bool friction_known = false, friction = false;
  Progress progress("demsolve", static_cast<double>(total), a.quiet);
  const auto t_start = std::chrono::steady_clock::now();
  auto t_phase = t_start;
  nlohmann::json phase_list = nlohmann::json::array();
  std::int64_t steps_done = 0;
  const double t_final = phase_end(phases, phases.size() - 1);
  for (std::int64_t k = k0 + 1; k <= K; ++k) {
    // the last step may end a fraction of dt past the protocol: it still belongs to the last
    // phase of non-zero length (zero-length trailing phases must not change T)
    const double t = std::min(static_cast<double>(k) * dt, t_final);
    const ScheduleAt at = schedule_at(phases, t);
    cur_phase = at.phase;
    if (!friction_known || at.friction != friction) {  // LMM05 4.1: mu on and mu_w off at t_heat
      LudingParams q = base;
      q.mu = at.friction ? a.mu : 0.0;
      q.mu_wall = at.friction ? 0.0 : a.mu_wall_prepare;
      s.set_params(q);
      friction = at.friction;
      friction_known = true;
    }
    s.advance_temperature(at.T, dt, at.t0);
    s.step();
    ++steps_done;
    if ((k - k0) % every == 0) {
      row();
      progress.update(static_cast<double>(k - k0));
    }
    for (std::size_t p = 0; p < phases.size(); ++p) {
      if (ends[p] != k) continue;
      const auto now = std::chrono::steady_clock::now();
      const std::string& name = phases[p].name;
      write_file_atomic(out / fmt::format("state_{}.txt", name), format_state(s.state()));
      snapshot(name);
      const double cpu = cpu_now();
      phase_list.push_back(phase_json(name, std::chrono::duration<double>(now - t_phase).count(), cpu - cpu_phase));
      t_phase = now;
      cpu_phase = cpu;
    }
  }
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  if ((K - k0) % every != 0 || total == 0) row();
  write_file_atomic(out / "timeseries.csv", csv);
  write_file_atomic(out / "state.txt", format_state(s.state()));
  snapshot("final");
  summary["phases"] = phase_list;
  const double cpu = cpu_now() - cpu_start;
  summary["final"] = phase_json("final", wall, cpu);
  summary["cpu_time_s"] = cpu;
  summary["particle_steps_per_cpu_s"] = static_cast<double>(steps_done) * static_cast<double>(n) / std::max(cpu, 1e-9);
  summary["steps"] = steps_done;
  summary["dt_s"] = dt;
  summary["wall_time_s"] = wall;
  summary["particle_steps_per_s"] = static_cast<double>(steps_done) * static_cast<double>(n) / std::max(wall, 1e-9);
  summary["neighbour_rebuilds"] = s.rebuilds();
  summary["mean_radius_m"] = mean_radius(s.particles());
  return 0;
}

int run_protocol(const std::string& command, const SampleArgs& sample, const RunArgs& args,
                 const SinterProtocol& protocol, bool prepare_only, const fs::path& out) {
  if (!(std::isfinite(args.pressure) && args.pressure > 0.0))
    throw std::invalid_argument(fmt::format("--pressure must be a positive number of N/m, got {}", args.pressure));
  if (!(std::isfinite(args.mu) && args.mu >= 0.0)) throw std::invalid_argument("--mu must be >= 0");
  if (!(std::isfinite(args.mu_wall_prepare) && args.mu_wall_prepare >= 0.0))
    throw std::invalid_argument("--mu-wall must be >= 0");
  auto phases = protocol.phases();
  if (prepare_only) {
    phases.resize(1);
    if (!(protocol.t_heat > 0.0))
      throw std::invalid_argument(fmt::format("--time must be a positive number of seconds, got {}", protocol.t_heat));
  }
  if (!(phase_end(phases, phases.size() - 1) > 0.0)) throw std::invalid_argument("the protocol has zero length");
  DynamicOptions opt;
  opt.model = ContactModel::Full;
  opt.steps_per_contact = args.steps_per_contact;
  opt.temperature = phases.front().T_start;
  std::unique_ptr<DynamicSolver> s;
  nlohmann::json summary;
  if (!args.state_file.empty()) {
    SolverState st = load_state(args.state_file, args.param_overrides);
    if (args.pressure_given) st.box.right.pressure = st.box.top.pressure = args.pressure;
    s = std::make_unique<DynamicSolver>(st, opt);
    summary["state_file"] = args.state_file;
    if (s->time() >= phase_end(phases, phases.size() - 1) - 0.5 * s->dt())
      throw std::invalid_argument(fmt::format("state file time {} is past the end of the protocol ({})", s->time(),
                                              phase_end(phases, phases.size() - 1)));
  } else {
    LudingParams lp;
    apply_overrides(lp, args.param_overrides);
    Box box;
    Particles P = place_sample(sample, lp, box);
    const double p = args.pressure;
    for (MovingWall* w : {&box.right, &box.top}) {
      w->mode = WallMode::Stress;
      w->pressure = p;
      w->mass = lp.m_wall;
      w->damping = lp.gamma_wall;
    }
    s = std::make_unique<DynamicSolver>(std::move(P), lp, box, opt);
    summary["seed"] = sample.seed;
    summary["arrangement"] = sample.arrangement;
  }
  start_run_dir(out);
  write_file_atomic(out / "command.txt", command + "\n");
  nlohmann::json params;
  for (const auto& name : luding_param_names()) params[name] = get_luding_param(s->params(), name);
  nlohmann::json prot = nlohmann::json::array();
  for (const auto& ph : phases)
    prot.push_back({{"phase", ph.name}, {"duration_s", ph.duration}, {"T_start", ph.T_start}, {"T_end", ph.T_end},
                    {"t0_s", ph.t0}, {"friction", ph.friction}});
  const double pressure = s->box().right.pressure;
  nlohmann::json pj{{"command", command},      {"particles", s->particles().size()},
                    {"pressure_N_per_m", pressure}, {"mu", args.mu},
                    {"mu_wall_prepare", args.mu_wall_prepare}, {"steps_per_contact", args.steps_per_contact},
                    {"dt_s", s->dt()},          {"steps_per_contact_lightest_pair", s->time_step().steps_per_contact_lightest},
                    {"contact_params", params}, {"protocol", prot}};
  if (args.state_file.empty()) pj["seed"] = sample.seed;
  write_file_atomic(out / "parameters.json", pj.dump(2) + "\n");
  if (!args.quiet && args.state_file.empty())
    std::fprintf(stderr, "demsolve: seed %llu, %zu disks, dt = %.3g s\n", static_cast<unsigned long long>(sample.seed),
                 s->particles().size(), s->dt());
  summary["command"] = command;
  summary["particles"] = s->particles().size();
  summary["pressure_N_per_m"] = pressure;
  summary["steps_per_contact_lightest_pair"] = s->time_step().steps_per_contact_lightest;
  run_phases(*s, phases, args, out, summary);
  // densification nu(t_f) / nu(t_heat) - 1 (LMM05 section 4.1.3)
  for (const auto& ph : summary["phases"])
    if (!prepare_only && ph["phase"] == "prepare") summary["densification"] = summary["final"]["nu"].get<double>() / ph["nu"].get<double>() - 1.0;
  write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
  const auto& f = summary["final"];
  std::printf("t = %.4f s: nu = %.4f, C = %.3f (%.3f without walls), sxx/p = %.4f, szz/p = %.4f, k1(T,t)/k1 = %.4f, "
              "Ekin = %.3e J, %.1f s -> %s\n",
              f["t"].get<double>(), f["nu"].get<double>(), f["C"].get<double>(), f["C_without_walls"].get<double>(),
              f["sxx_over_p"].get<double>(), f["szz_over_p"].get<double>(), f["k1_over_k1"].get<double>(),
              f["Ekin_J"].get<double>(), summary["wall_time_s"].get<double>(), out.c_str());
  return 0;
}

}  // namespace netdem::app::dem
