// netsolve pack --dim 3 --route green-body (apps/netsolve/pack_green.hpp).
#include "pack_green.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/laminar.hpp"
#include "netdem/packing/random_fill.hpp"
#include "output.hpp"
#include "run_status.hpp"

namespace netdem::app::netsolve {

namespace {

nlohmann::json box_json(const packing::Box& b) { return {b.x_min, b.y_min, b.z_min, b.x_max, b.y_max, b.z_max}; }

/// The route's options from the command line, checked (UsageError naming the option).
dem::GreenBodyOptions green_options(const GreenArgs& a, std::uint64_t seed) {
  dem::GreenBodyOptions o = a.body;
  if (!(std::isfinite(a.diameter) && a.diameter > 0.0))
    throw UsageError(fmt::format("--diameter must be a positive finite length in metres, got {}", a.diameter));
  if (!(a.diameter <= 1e-2))
    throw UsageError(fmt::format("--diameter {} m: the route is in SI metres (50e-6 is 50 um); above 1 cm is refused", a.diameter));
  if (!(std::isfinite(a.lamina) && a.lamina > 0.0))
    throw UsageError(fmt::format("--lamina must be a positive finite length in metres, got {}", a.lamina));
  if (!(std::isfinite(a.bulk_margin) && a.bulk_margin >= 0.0))
    throw UsageError(fmt::format("--bulk-margin must be >= 0 mean diameters, got {}", a.bulk_margin));
  if (!(std::isfinite(o.gravity) && o.gravity >= 1e-6 && o.gravity <= 1e4))
    throw UsageError(fmt::format("--gravity must be in [1e-6, 1e4] m/s^2 (demsolve's range), got {}", o.gravity));
  o.mean_radius = 0.5 * a.diameter;
  o.seed = seed;
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return o;
}

/// The checks of the route that need the options together, before the output folder exists
/// (issue 27 item 8): the lamina width against the expected box, and the random cloud itself
/// (step 1 of the route, deterministic for the options: made here once more, it cannot fail later).
void check_green_door(const dem::GreenBodyOptions& o, const GreenArgs& a) {
  // the final box: solid volume / target density, height / width = aspect
  const double r = o.mean_radius;
  const double vs = static_cast<double>(o.n) * 4.0 / 3.0 * std::numbers::pi * r * r * r * (1.0 + o.dispersion * o.dispersion);
  const double width = std::cbrt(vs / (o.target_density * o.aspect));
  const double extent = std::max(width, o.aspect * width);
  if (!(extent / a.lamina <= 5e5))
    throw UsageError(fmt::format("--lamina {:g} m cuts the green body's expected extent of about {:.3g} m into more than "
                                 "5e5 laminae (laminar.csv allows 1e6): give a wider --lamina", a.lamina, extent));
  const double steps = dem::green_body_min_steps(o), work = steps * static_cast<double>(o.n);
  if (!a.allow_long && !(work <= kMaxGreenParticleSteps))
    throw UsageError(fmt::format("--n {}, --steps-per-contact {:g} and --wall-speed {:g}: the route needs at least {:.3g} "
                                 "particle-steps ({:.3g} time steps), more than {:.3g} (hours of one core): pass --allow-long "
                                 "to run it",
                                 o.n, o.steps_per_contact, o.wall_speed, work, steps, kMaxGreenParticleSteps));
  packing::Packing cloud;
  try {
    cloud = packing::random_fill_3d(dem::green_body_cloud_options(o));
  } catch (const std::exception& e) {
    std::string why = e.what();
    if (why.rfind("random_fill_3d: ", 0) == 0) why = why.substr(16);
    if (const auto k = why.find("; use a larger box"); k != std::string::npos) why.resize(k);
    throw UsageError(fmt::format("--n {} with --dispersion {:g}, --cloud-fraction {:g} and --aspect {:g}: the route's random "
                                 "cloud cannot be made ({}); change these options",
                                 o.n, o.dispersion, o.cloud_fraction, o.aspect, packing::quote_input(why, 200)));
  }
  // the solver's time step rule (the mean pair's period / --steps-per-contact, >= 10 steps for the
  // lightest pair): a wide dispersion failed it after the folder existed (issue 27 item 8)
  const double spc = dem::green_body_lightest_steps_per_contact(o, cloud), spc_min = dem::DynamicOptions{}.min_steps_per_contact;
  if (!(spc >= spc_min))
    throw UsageError(fmt::format("--dispersion {:g} with --steps-per-contact {:g}: the lightest pair of the route's cloud gets "
                                 "{:.3g} steps per contact from the mean pair's time step, fewer than {:g}: lower --dispersion "
                                 "or raise --steps-per-contact",
                                 o.dispersion, o.steps_per_contact, spc, spc_min));
}

}  // namespace

int run_pack_green_body(const GreenArgs& a, std::uint64_t seed, bool overwrite, const std::string& command,
                        const std::filesystem::path& out) {
  const dem::GreenBodyOptions o = green_options(a, seed);
  RunDirOptions ro;
  ro.overwrite = overwrite;
  check_run_dir(out, ro);
  check_green_door(o, a);
  activity() = "running the green-body route";
  open_run_dir(out, command, ro);
  const auto t0 = std::chrono::steady_clock::now();
  auto last = t0;
  bool printed = false;
  const auto observer = [&](const dem::GreenBodyProgress& p) {
    if (a.quiet) return;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last).count() < 0.5) return;
    last = now;
    printed = true;
    const std::string done = p.fraction >= 0.0 ? fmt::format(" {:5.1f} %", 100.0 * p.fraction) : "";
    std::fprintf(stderr, "\rgreen body: %-8s%s step %8lld  t = %.4e s  density %.4f  E_kin %.2e m g r   ", p.phase, done.c_str(),
                 static_cast<long long>(p.steps), p.time, p.density, p.kinetic);
  };
  const dem::GreenBodyResult res = dem::make_green_body(o, observer);
  if (printed) std::fprintf(stderr, "\n");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  activity() = "measuring and writing the packing";
  packing::Packing pk = res.packing;
  pk.comments.emplace_back("green-body route (Ivannikov et al. section 3.2): lengths in metres");
  pk.comments.emplace_back(fmt::format("target density {} status {}", o.target_density, res.status));
  packing::write_packing_csv(pk, out / "packing.csv");
  write_file_atomic(out / "particles.vtp", vtp_particles_3d(pk.x, pk.y, &pk.z, {{"radius", 1, pk.r}, {"z", 1, pk.z}}));

  const packing::Box& b = pk.box;
  const double vs = pk.solid_volume();
  const packing::Box bb = packing::bounding_box(pk);
  const double margin = a.bulk_margin * a.diameter;
  packing::Box inner{b.x_min + margin, b.y_min + margin, b.x_max - margin, b.y_max - margin, b.z_min + margin, b.z_max - margin};
  // a window narrower than one mean diameter samples a sphere or two, not a bulk: null (issue 27)
  const bool has_bulk = inner.width() >= a.diameter && inner.height() >= a.diameter && inner.depth() >= a.diameter;
  const double bulk = has_bulk ? packing::sampled_density(pk, inner, a.bulk_spacing * o.mean_radius) : -1.0;

  std::string lam = "# Eq 48 of Ivannikov et al.: laminae of width ~q_s along x, y, z; lengths in metres\n";
  lam += fmt::format("# q_s {:.9g}\n", a.lamina);
  lam += "axis,lamina,lo,hi,density\n";
  nlohmann::json jl;
  jl["q_s"] = a.lamina;
  jl["interior_margin"] = margin;
  const char* names[3] = {"x", "y", "z"};
  const double lo[3] = {b.x_min, b.y_min, b.z_min}, hi[3] = {b.x_max, b.y_max, b.z_max};
  for (int ax = 0; ax < 3; ++ax) {
    const packing::LaminarProfile prof = packing::laminar_density(pk, ax, a.lamina);
    for (std::size_t s = 0; s < prof.density.size(); ++s)
      lam += fmt::format("{},{},{:.9g},{:.9g},{:.6f}\n", names[ax], s, prof.lo[s], prof.hi[s], prof.density[s]);
    const auto in = prof.interior(lo[ax], hi[ax], margin);
    double all_min = 1e300, all_max = -1e300;
    for (double d : prof.density) {
      all_min = std::min(all_min, d);
      all_max = std::max(all_max, d);
    }
    jl[names[ax]] = {{"laminae", prof.density.size()}, {"width", prof.width}, {"min", all_min}, {"max", all_max},
                     {"interior", {{"laminae", in.count}, {"min", in.count ? nlohmann::json(in.min) : nlohmann::json(nullptr)},
                                   {"max", in.count ? nlohmann::json(in.max) : nlohmann::json(nullptr)},
                                   {"mean", in.count ? nlohmann::json(in.mean) : nlohmann::json(nullptr)}}}};
  }
  write_file_atomic(out / "laminar.csv", lam);

  nlohmann::json j;
  j["command"] = command;
  j["dim"] = 3;
  j["route"] = "green-body";
  j["units"] = "SI: m, kg, s, Pa";
  j["seed"] = seed;
  j["particles"] = pk.size();
  j["options"] = {{"mean_diameter", a.diameter},
                  {"dispersion", o.dispersion},
                  {"target_density", o.target_density},
                  {"aspect", o.aspect},
                  {"solid_density", o.solid_density},
                  {"gravity", o.gravity},
                  {"stiffness_number", o.stiffness_number},
                  {"restitution", o.restitution},
                  {"friction", {{"settle", o.mu_settle}, {"compress", o.mu_compress}, {"final", o.mu_final}, {"wall", o.mu_wall}}},
                  {"steps_per_contact", o.steps_per_contact},
                  {"wall_speed", o.wall_speed},
                  {"rest_energy", o.rest_energy},
                  {"max_mean_overlap", o.max_mean_overlap},
                  {"cloud_fraction", o.cloud_fraction},
                  {"settled_guess", o.settled_guess},
                  {"max_phase_time", o.max_phase_time}};
  j["model"] = {{"law", "linear spring-dashpot, Cundall-Strack tangential spring k_t = 2/7 k"},
                {"stiffness", res.stiffness},
                {"gamma_n", res.gamma_n},
                {"gamma_t", res.gamma_t},
                {"dt", res.dt},
                {"contact_time", res.contact_time},
                {"mean_mass", res.mean_mass},
                {"time_unit_sqrt_r_over_g", res.time_unit}};
  j["boxes"] = {{"cloud", box_json(res.cloud_box)}, {"settled", box_json(res.settled_box)},
                {"target", box_json(res.target_box)}, {"final", box_json(b)}, {"bounding", box_json(bb)}};
  j["final_box_mm"] = {1e3 * b.width(), 1e3 * b.height(), 1e3 * b.depth()};
  j["density"] = {{"box", vs / b.volume()},
                  {"bounding_box", vs / bb.volume()},
                  {"bulk", has_bulk ? nlohmann::json(bulk) : nlohmann::json(nullptr)},
                  {"bulk_region", has_bulk ? box_json(inner) : nlohmann::json(nullptr)},
                  {"bulk_spacing", a.bulk_spacing * o.mean_radius},
                  {"settled", res.settled_density},
                  {"lens_volume_fraction", res.overlaps.lens_volume / b.volume()}};
  j["laminar"] = jl;
  const auto& ov = res.overlaps;
  j["overlaps"] = {{"pairs", ov.pairs},           {"pair_mean", ov.pair_mean}, {"pair_max", ov.pair_max},
                   {"wall_contacts", ov.wall_contacts}, {"wall_mean", ov.wall_mean}, {"wall_max", ov.wall_max},
                   {"coordination", ov.coordination},   {"compress_max_pair_mean", res.compress_max_mean_overlap}};
  j["compression"] = {{"scale", res.scale},
                      {"shape", res.exact_aspect ? "aspect" : "equal strains"},
                      {"aspect", b.depth() / b.width()},
                      {"limit_density", res.limit_density > 0.0 ? nlohmann::json(res.limit_density) : nlohmann::json(nullptr)},
                      {"wall_speed_m_per_s", o.wall_speed * std::sqrt(o.gravity * o.mean_radius)},
                      {"wall_velocity", {res.wall_velocity[0], res.wall_velocity[1], res.wall_velocity[2]}},
                      {"strain_rate", res.strain_rate},
                      {"inertial_number", res.inertial_number}};
  j["wall_stress"] = {res.wall_stress[0], res.wall_stress[1], res.wall_stress[2]};
  nlohmann::json ph = nlohmann::json::array();
  std::int64_t steps = 0;
  for (const auto& p : res.phases) {
    ph.push_back({{"name", p.name}, {"steps", p.steps}, {"time", p.time}, {"wall_s", p.wall_seconds},
                  {"density", p.density}, {"kinetic", p.kinetic}, {"at_rest", p.at_rest}});
    steps += p.steps;
  }
  j["phases"] = ph;
  j["steps"] = steps;
  j["timing_s"] = {{"total", wall}};
  j["status"] = res.status;
  j["status_reason"] = res.ok() ? std::string("every criterion met") : res.reason;
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  netdem::app::summary_printf("seed %llu (green body): %zu spheres, box %.4f x %.4f x %.4f mm, density %.4f (bulk %s), mean overlap %.2e r "
              "(max %.2e), %lld steps, %.1f s -> %s\n",
              static_cast<unsigned long long>(seed), pk.size(), 1e3 * b.width(), 1e3 * b.height(), 1e3 * b.depth(),
              vs / b.volume(), has_bulk ? fmt::format("{:.4f}", bulk).c_str() : "n/a: the window is under one diameter",
              ov.pair_mean, ov.pair_max, static_cast<long long>(steps), wall,
              (out / "packing.csv").c_str());
  if (!res.ok()) {
    std::fprintf(stderr, "netsolve: error: %s: %s\n", res.status.c_str(), res.reason.c_str());
    return exit_code::untrustworthy;
  }
  return exit_code::ok;
}

}  // namespace netdem::app::netsolve
