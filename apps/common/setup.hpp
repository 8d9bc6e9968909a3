#pragma once
// Set-up shared by the netsolve subcommands (main.cpp: pack, compact; yield.cpp: yield) and by
// demsolve compact and yield, which run netsolve's scene: the
// packing, and the contact-law / Newton options both `compact` and `yield` take.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/ballistic3d.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/yield_curve.hpp"
#include "output.hpp"
#include "parse.hpp"

namespace netdem::app::netsolve {

/// Options of a new ballistic deposition.
struct PackArgs {
  double width = 80.0, r_min = 0.9, r_max = 1.1;
  bool mono = false;
  std::string lid = "centre";
  std::uint64_t seed = 1;
  int dim = 2;                     ///< netsolve pack --dim: 2 (disks) or 3 (spheres, ballistic3d.hpp)
  std::string lateral = "walls";   ///< --lateral (3D only): walls | periodic
};

/// --seed: a whole number in [0, 2^64) written with digits only (CLI11 would wrap -1 to 2^64 - 1).
inline CLI::Validator seed_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        bool digits = !s.empty() && s.size() <= 20;
        for (char c : s) digits = digits && std::isdigit(static_cast<unsigned char>(c));
        if (digits && (s.size() < 20 || s <= "18446744073709551615")) return "";
        return fmt::format("'{}' is not a whole number in [0, 18446744073709551615]", s.substr(0, 80));
      },
      "UINT64");
}

/// Largest deposition accepted (the number of disks estimated before it starts).
inline constexpr double kMaxDisks = 5e7;
/// Memory of a deposition per disk, with margin (measured: 110 B per disk at W = 800, 165k disks),
/// and of the network solver per disk (measured: 5 kB per disk in `compact` between W = 80 and 160, CHOLMOD included).
inline constexpr double kDepositionBytesPerDisk = 250.0;
inline constexpr double kSolverBytesPerDisk = 10000.0;
/// The 3D network solver per sphere at 1e4 spheres (measured: 1.52 GB peak for 1e4 spheres in a
/// periodic cell, CHOLMOD's factor most of it; bench/netsolve3d_speed.py), growing like N^(1/3)
/// with the fill of a 3D factor: the estimate of check_deposition_size.
inline constexpr double kSolverBytesPerSphere1e4 = 160000.0;
/// netsolve compact --dim 3's deposition width when --width is not given: about 1000 spheres (the
/// 2D default of 80 R would be about 7e4 spheres, hours of factorisations).
inline constexpr double kDefaultWidth3d = 20.0;

/// MemAvailable of /proc/meminfo in bytes, or 0 if unknown.
inline double mem_available_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  double kb = 0.0;
  std::string unit;
  while (in >> key >> kb >> unit)
    if (key == "MemAvailable:") return kb * 1024.0;
  return 0.0;
}

/// Refuses (UsageError) a deposition whose estimated size cannot fit: N ~ W^2 D0 / (pi <r^2>) with
/// D0 = 0.85 (ballistic packings reach 0.81), above kMaxDisks disks or, with the solver when
/// `solve`, above MemAvailable. Also a width that is not finite and positive.
/// 3D (a.dim == 3): N ~ W^3 0.65 / (4/3 pi <r^3>) spheres (deposits reach about 0.58).
inline void check_deposition_size(const PackArgs& a, bool solve = false) {
  const double r0 = a.mono ? 1.0 : a.r_min, r1 = a.mono ? 1.0 : a.r_max;
  if (!(std::isfinite(a.width) && a.width > 0.0))
    throw UsageError(fmt::format("--width must be a positive finite number of radii, got {}", a.width));
  if (!(std::isfinite(r0) && std::isfinite(r1) && r0 > 0.0 && r1 >= r0)) return;  // the deposition's own checks say why
  const double r2 = (r0 * r0 + r0 * r1 + r1 * r1) / 3.0;  // <r^2> of radii uniform in [r_min, r_max]
  const double r3 = (r0 + r1) * (r0 * r0 + r1 * r1) / 4.0;  // <r^3>
  const double disks = a.dim == 3 ? a.width * a.width * a.width * 0.65 / (4.0 / 3.0 * std::numbers::pi * r3)
                                  : a.width * a.width * 0.85 / (std::numbers::pi * r2);
  const double solver = a.dim == 3 ? kSolverBytesPerSphere1e4 * std::cbrt(std::max(disks, 1.0) / 1e4) : kSolverBytesPerDisk;
  const double bytes = disks * (kDepositionBytesPerDisk + (solve ? solver : 0.0));
  if (disks > kMaxDisks) {
    const std::string n = std::isfinite(disks) ? fmt::format("about {:.3g}", disks) : "more than 1e300";
    const std::string gb = std::isfinite(bytes) ? fmt::format("about {:.3g} GB", bytes / 1e9) : "more memory than exists";
    throw UsageError(fmt::format("--width {} with radii in [{}, {}] R: {} disks, above the limit of {:.0e} ({} and hours "
                                 "of deposition); use a smaller --width",
                                 a.width, r0, r1, n, kMaxDisks, gb));
  }
  const double avail = mem_available_bytes();
  if (avail > 0.0 && bytes > avail)
    throw UsageError(fmt::format("--width {}: about {:.3g} disks need about {:.3g} GB, more than the {:.3g} GB available "
                                 "(MemAvailable); use a smaller --width",
                                 a.width, disks, bytes / 1e9, avail / 1e9));
}

/// The ballistic deposition of `a`; throws std::invalid_argument for an unknown --lid.
inline packing::Packing make_packing(const PackArgs& a) {
  packing::DepositionOptions o;
  o.width = a.width;
  o.r_min = a.mono ? 1.0 : a.r_min;
  o.r_max = a.mono ? 1.0 : a.r_max;
  o.seed = a.seed;
  if (a.lid == "centre") {
    o.lid = packing::Lid::Centre;
  } else if (a.lid == "inside") {
    o.lid = packing::Lid::Inside;
  } else {
    throw std::invalid_argument(fmt::format("--lid '{}' is not 'centre' or 'inside'", a.lid));
  }
  return packing::ballistic_deposition(o);
}

/// The 3D deposition of `a` (netsolve pack --dim 3): Lid::Inside stop rule, --lateral walls|periodic.
inline packing::Packing make_packing_3d(const PackArgs& a) {
  packing::Deposition3dOptions o;
  o.width = a.width;
  o.r_min = a.mono ? 1.0 : a.r_min;
  o.r_max = a.mono ? 1.0 : a.r_max;
  o.seed = a.seed;
  if (a.lateral == "walls") {
    o.lateral = packing::Lateral::Walls;
  } else if (a.lateral == "periodic") {
    o.lateral = packing::Lateral::Periodic;
  } else {
    throw std::invalid_argument(fmt::format("--lateral '{}' is not 'walls' or 'periodic'", a.lateral));
  }
  auto p = packing::ballistic_deposition_3d(o);
  if (o.lateral == packing::Lateral::Periodic) p.comments.emplace_back("lateral periodic (x, y)");
  return p;
}

/// The packing file if one is given, else a new deposition; `source` describes which. `command`
/// names the (2D only) subcommand in the refusal of a 3D packing file.
/// What input_packing does with a periodic packing file ('# periodic'): refuse it (the run has no
/// periodic cell; `hint` names the option that has one), require it (a periodic run), or leave it
/// to the caller.
enum class PeriodicInput { Refuse, Require, Caller };

inline packing::Packing input_packing(const std::string& packing_file, const PackArgs& a, std::string& source,
                                      const char* command = "netsolve compact",
                                      PeriodicInput periodic_input = PeriodicInput::Refuse,
                                      const char* hint = "--boundary periodic") {
  const bool periodic = periodic_input == PeriodicInput::Require;
  if (!packing_file.empty()) {
    if (std::filesystem::is_directory(packing_file))
      throw UsageError(fmt::format("--packing '{}' is a folder, not a packing CSV file (netsolve pack writes DIR/packing.csv)",
                                   packing_file.substr(0, 80)));
    source = packing_file;
    packing::Packing p = packing::read_packing_csv(packing_file);
    if (p.dim != 2)
      throw UsageError(fmt::format("--packing {} is a 3D packing; {} is 2D only", packing_file.substr(0, 200), command));
    if (p.periodic && periodic_input == PeriodicInput::Refuse)
      throw UsageError(fmt::format("--packing {} is a periodic packing (a '# periodic' line): {} needs a periodic cell, "
                                   "run it with {}",
                                   packing_file.substr(0, 200), command, hint));
    if (!p.periodic && periodic)
      throw UsageError(fmt::format("{} needs a periodic packing, and --packing {} has no '# periodic' line", hint,
                                   packing_file.substr(0, 200)));
    return p;
  }
  if (periodic)
    throw UsageError(fmt::format("{} needs --packing FILE with a periodic packing (a '# periodic' line; netsolve pack "
                                 "--periodic)", hint));
  source = fmt::format("ballistic deposition, W = {} R, r = R[{}, {}], seed {}", a.width, a.mono ? 1.0 : a.r_min,
                       a.mono ? 1.0 : a.r_max, a.seed);
  return make_packing(a);
}

/// A 3D packing file (dim 3), or the 3D deposition of `a` (its --lateral); `source` describes which.
/// `solver` names the solver in the refusal of a lateral-periodic deposition file (periodic sides
/// and a floor: neither solver has that boundary). A fully periodic file is returned: the caller
/// decides.
inline packing::Packing input_packing_3d(const std::string& packing_file, const PackArgs& a, std::string& source,
                                         const char* solver) {
  if (!packing_file.empty()) {
    if (std::filesystem::is_directory(packing_file))
      throw UsageError(fmt::format("--packing '{}' is a folder, not a packing CSV file (netsolve pack writes "
                                   "DIR/packing.csv)", packing::quote_input(packing_file)));
    source = packing_file;
    packing::Packing p = packing::read_packing_csv(packing_file);
    if (p.dim != 3)
      throw UsageError(fmt::format("--packing {} is a 2D packing; --dim 3 needs a 3D packing file (id,x,y,z,r with "
                                   "'# dim 3', netsolve pack --dim 3)", packing::quote_input(packing_file)));
    for (const auto& c : p.comments)
      if (!p.periodic && c.find("lateral periodic") != std::string::npos)
        throw UsageError(fmt::format("--packing {} is a lateral-periodic deposition (periodic sides, a floor): "
                                     "{} has no such boundary (make one with netsolve pack --dim 3 --lateral walls, or "
                                     "use a fully periodic packing with --boundary periodic)",
                                     packing::quote_input(packing_file), solver));
    return p;
  }
  source = fmt::format("3D ballistic deposition, W = {} R, r = R[{}, {}], seed {}, lateral walls", a.width,
                       a.mono ? 1.0 : a.r_min, a.mono ? 1.0 : a.r_max, a.seed);
  return make_packing_3d(a);
}

/// Contact law and Newton options common to `compact` and `yield`.
/// The law's numbers default to the law's own (contact::PlasticIndentationParams), the Newton
/// options to the library's compaction preset (qs::SolverOptions::compact()); friction and the
/// unloading branch are the presets' too (sticking, reversible). demsolve compact and yield take
/// their defaults from here.
struct LawArgs {
  std::string friction = "inf", normal_unloading = "reversible";
  double k_t = contact::PlasticIndentationParams{}.k_t, sigma_y = contact::PlasticIndentationParams{}.sigma_y;
  double tol = qs::SolverOptions::compact().residual_tol, viscosity = qs::SolverOptions::compact().viscosity;
  double first_touch = contact::PlasticIndentationParams{}.first_touch;
  int max_newton = 0;  ///< 0: the iteration's own (legacy drag: the preset's 10; pseudo-transient: 50; energy merit: 500)
  std::string iteration = "auto";  ///< auto: qs::default_iteration of the run's boundary modes
  double regularisation_scale = 1.0;
  int max_cuts = qs::SolverOptions{}.max_cuts;
  std::string merit = "energy";
};

/// Newton iterations per increment of the pseudo-transient iteration when --max-newton is not given.
inline constexpr int kPseudoTransientMaxNewton = 50;
/// The trust region on the energy (pseudo-transient, frictionless): its rejected steps cost a
/// factorisation each, and frictionless increments that rearrange need more of them (measured:
/// docs/quasistatic.md "Frictionless: a trust region on the energy").
inline constexpr int kEnergyMaxNewton = 500;

/// The name of an iteration, as --iteration spells it and summary.json records it.
inline const char* iteration_name(qs::Iteration it) {
  return it == qs::Iteration::PseudoTransient ? "pseudo-transient" : "legacy-drag";
}

/// The preconditioner's names, as --preconditioner spells them and summary.json records them.
inline const char* preconditioner_name(qs::IterationOptions::Preconditioner p) {
  using P = qs::IterationOptions::Preconditioner;
  return p == P::Translations ? "translations" : p == P::Full ? "full" : "auto";
}
inline qs::IterationOptions::Preconditioner preconditioner_of(const std::string& name) {
  using P = qs::IterationOptions::Preconditioner;
  return name == "translations" ? P::Translations : name == "full" ? P::Full : P::Auto;
}

/// The LawArgs of a library preset (the command's defaults).
inline LawArgs law_args(const qs::SolverOptions& o) {
  LawArgs a;
  a.friction = std::isinf(o.law.mu) ? "inf" : fmt::format("{}", o.law.mu);
  a.normal_unloading = o.law.reversible ? "reversible" : "elastic";
  a.k_t = o.law.k_t;
  a.sigma_y = o.law.sigma_y;
  a.first_touch = o.law.first_touch;
  a.tol = o.residual_tol;
  a.viscosity = o.viscosity;
  a.iteration = "auto";  // the preset's iteration is the library's; the commands choose by the boundary
  a.regularisation_scale = o.regularisation_scale;
  a.max_cuts = o.max_cuts;
  a.merit = o.energy_merit ? (o.friction_energy_merit ? "energy-friction" : "energy") : "residual";
  return a;
}

/// Registers the LawArgs options; `unloading_help` describes --normal-unloading for this command.
inline void add_law_options(CLI::App& app, LawArgs& a, const std::string& unloading_help) {
  app.add_option("--friction", a.friction, "Coulomb coefficient mu, or inf for sticking")->capture_default_str();
  app.add_option("--k-t", a.k_t, "tangential spring on the shear stress, tau = k_t u_T [sigma_y/R]")->capture_default_str();
  app.add_option("--sigma-y", a.sigma_y, "yield stress of the solid")->capture_default_str();
  app.add_option("--first-touch", a.first_touch,
                 "first-touch overlap u_c/(2R*): below u_c the loading force is the chord F_2(u_c) u/u_c "
                 "(bounded stiffness; the same law as demsolve); 0: Eq 2 down to u = 0")
      ->capture_default_str();
  app.add_option("--tol", a.tol, "Newton tolerance: RMS residual / mean contact force")->capture_default_str();
  app.add_option("--max-newton", a.max_newton,
                 "Newton iterations per increment (0: the iteration's own, legacy-drag 10, pseudo-transient " +
                     std::to_string(kPseudoTransientMaxNewton) + ", pseudo-transient on the energy merit " +
                     std::to_string(kEnergyMaxNewton) + ")")
      ->capture_default_str();
  app.add_option("--viscosity", a.viscosity,
                 "drag / mean contact stiffness: legacy-drag: on the non-affine motion of the increment (0: pure "
                 "Newton); pseudo-transient: its start value, on each Newton step")
      ->capture_default_str();
  app.add_option("--iteration", a.iteration,
                 "pseudo-transient: the drag acts on each Newton step only and an increment is accepted on the "
                 "undragged residual, RMS <= --tol and max <= 10 x --tol; legacy-drag: the drag of the increment "
                 "stays in the answer (earlier results); auto: pseudo-transient, but legacy-drag when a phase runs "
                 "in the die's prescribed layer, which holds no undragged equilibrium (docs/quasistatic.md)")
      ->check(CLI::IsMember({"auto", "legacy-drag", "pseudo-transient"}))
      ->capture_default_str();
  app.add_option("--regularisation-scale", a.regularisation_scale,
                 "multiplies the drag (the regularisation the iteration keeps); a converged pseudo-transient answer "
                 "must not depend on it")
      ->capture_default_str();
  app.add_option("--max-cuts", a.max_cuts,
                 "pseudo-transient: an increment not accepted within --max-newton iterations is redone as two halves, "
                 "down to 2^-N of it")
      ->capture_default_str();
  app.add_option("--merit", a.merit,
                 "pseudo-transient without friction: energy (a trust region on the contact energy, whose minimum "
                 "the frictionless equilibrium is) or residual (the residual line search used with friction); "
                 "energy-friction: the trust region also with friction (2D), on the energy with each tangential "
                 "spring's stiffness and limit frozen at the iterate")
      ->check(CLI::IsMember({"energy", "residual", "energy-friction"}))
      ->capture_default_str();
  app.add_option("--normal-unloading", a.normal_unloading, unloading_help)
      ->check(CLI::IsMember({"reversible", "elastic"}))
      ->capture_default_str();
}

/// The box of --boundary walls (both tools): the packing's box enlarged to enclose every disk or
/// sphere (the ballistic deposition's top particles stick out of its lid), so that none starts
/// inside a wall.
inline packing::Box walls_box(const packing::Packing& pk) {
  packing::Box b = pk.box;
  for (std::size_t i = 0; i < pk.size(); ++i) {
    b.x_min = std::min(b.x_min, pk.x[i] - pk.r[i]);
    b.x_max = std::max(b.x_max, pk.x[i] + pk.r[i]);
    b.y_min = std::min(b.y_min, pk.y[i] - pk.r[i]);
    b.y_max = std::max(b.y_max, pk.y[i] + pk.r[i]);
    if (pk.dim == 3) {
      b.z_min = std::min(b.z_min, pk.z[i] - pk.r[i]);
      b.z_max = std::max(b.z_max, pk.z[i] + pk.r[i]);
    }
  }
  return b;
}

/// The probe settings of netsolve yield (2D and 3D) and demsolve yield from a command line `a` (offset, max_strain, window,
/// growth, fine), with the run's number of directions, fine step and loading stress.
template <class Args>
sys::ProbeSettings yield_probe_settings(const Args& a, int directions, double first_step, double loading_norm,
                                        double sigma_y) {
  sys::ProbeSettings ps;
  ps.directions = directions;
  ps.offset = a.offset;
  ps.max_strain = a.max_strain;
  ps.window = a.window;
  ps.growth = a.growth;
  ps.fine = a.fine;
  ps.first_step = first_step;
  ps.loading_norm = loading_norm;
  ps.sigma_y = sigma_y;
  return ps;
}

/// Copies the LawArgs into the solver options; throws std::invalid_argument for a bad --friction.
/// `probing`: the boundary mode of a later phase on the same iteration (yield's probes); the
/// default iteration (`auto`) depends on both modes.
inline void apply_law_args(const LawArgs& a, qs::SolverOptions& so, std::optional<qs::BoundaryMode> probing = {}) {
  so.law.mu = parse_friction(a.friction);
  so.law.k_t = a.k_t;
  so.law.sigma_y = a.sigma_y;
  so.law.first_touch = a.first_touch;
  so.law.reversible = a.normal_unloading == "reversible";
  so.residual_tol = a.tol;
  so.iteration = a.iteration == "pseudo-transient" ? qs::Iteration::PseudoTransient
                 : a.iteration == "legacy-drag"    ? qs::Iteration::LegacyDrag
                                                   : qs::default_iteration(so.mode, probing.value_or(so.mode));
  so.energy_merit = a.merit == "energy" || a.merit == "energy-friction";
  so.friction_energy_merit = a.merit == "energy-friction";
  if (a.max_newton > 0) {
    so.max_newton = a.max_newton;
  } else if (so.iteration == qs::Iteration::PseudoTransient) {
    so.max_newton = so.uses_energy_merit() ? kEnergyMaxNewton : kPseudoTransientMaxNewton;
  }
  so.viscosity = a.viscosity;
  so.regularisation_scale = a.regularisation_scale;
  so.max_cuts = a.max_cuts;
}

}  // namespace netdem::app::netsolve
