// demsolve: explicit 2D DEM with Luding's sintering contact law (Luding, Manetsberger & Muellers 2005).
//
//   demsolve prepare [--n 300] [--pressure 100] [--seed 1] [--time 0.2] [--dim 2|3] [--out DIR] [--quiet]
//                    [--packing FILE [--length-unit M]]
//   demsolve sinter  [--n 300] [--pressure 100] [--sinter-time 1.0] [--seed 1] [--state FILE] [--out DIR]
//   demsolve compress --state FILE [--strain-rate 1] [--max-strain 0.1] [--out DIR]
//   demsolve vibrate  --state FILE [--frequency 100] [--amplitude 2e-4] [--time 0.1] [--out DIR]
//   demsolve compact  [--packing FILE | netsolve's pack options] [--affine] [--path hydrostatic|closed-die|E11,E22,0]
//                     [--friction MU|inf] [--no-rotation] [--to-density 0.85 | --to-strain S]
//                     [--precompact-density D1 [--precompact-increments 20]] [--boundary layer|walls|periodic]
//                     [--inertial-number I] [--increments 100] [--out DIR]
//   demsolve compact --dim 3 [--packing FILE | netsolve pack --dim 3's options] --affine | --boundary walls
//                     [--path hydrostatic|closed-die|E11,E22,E33|E11,E22,E33,E23,E13,E12 (shear: --affine only)]
//     spheres, six rigid frictionless walls or every centre affine (docs/dynamic.md "demsolve compact", 3D).
//   demsolve yield    [netsolve yield's options] [--inertial-number I] [--probe-inertial-number I] [--jobs J]
//     the yield-surface probes of netsolve yield with the explicit DEM (docs/dynamic.md "demsolve yield").
//     the plastic-indentation law of Redanz & Fleck on netsolve's compaction scene, in netsolve's
//     units (sigma_y, R, t* = R sqrt(rho/sigma_y)) and files (docs/dynamic.md "demsolve compact").
//
// prepare (section 4.1): disks with radii uniform in a0[1 - w0, 1 + w0] placed at random (no
// overlap) in a square box at density 0.35 with random velocities, compressed by the
// stress-controlled right and top walls (Eq 1) at isotropic pressure p, frictionless (unless
// --mu-prepare), 80 deg C.
// With --packing FILE the disks of a packing CSV (netsolve pack) at rest instead, every length
// times --length-unit (default: the file's mean radius mapped onto a0).
// sinter: the whole protocol of section 4.1 (prepare, heat, sinter, cool, relax; Fig 7).
// Both write command.txt, parameters.json, timeseries.csv, summary.json, particles_*.vtp,
// contacts_*.vtp/.csv and state_<phase>.txt after every phase (state.txt at the end).
// Every value is checked at the door against its documented range (docs/dynamic.md "Limits"),
// including the memory and step estimates (--max-steps); a run that breaches an instability check
// stops (docs/dynamic.md "Instability detection"). A run folder holding another run is refused
// unless --overwrite (README.md "Run folders"). Errors are one line on stderr. Exit status: 0 ok,
// 1 run error, 2 command-line error (nothing written), 3 unstable (summary.json "status",
// state_last_good.txt). Every subcommand reads its options from a scene file too, --config
// scene.toml (the command line overrides it; apps/common/scene_file.hpp), and every run writes its
// own as scene.toml. See docs/dynamic.md and docs/sintering.md.
#include <cmath>
#include <cstdio>
#include <new>
#include <vector>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "netdem/dynamic/compaction.hpp"
#include "netdem/dynamic/state.hpp"
#include "command.hpp"
#include "compact.hpp"
#include "parse.hpp"
#include "protocol.hpp"
#include "run_status.hpp"
#include "scene_file.hpp"

using namespace netdem::app::dem;
using netdem::dem::quote_input;
using netdem::app::netsolve::non_empty_file;

/// demsolve compress's options (section 4.4.1).
// --threads of every subcommand that runs the DEM
constexpr const char* kThreadsHelp =
    "threads for the pair loop and the integration; the results are the same to the last bit for any number "
    "(two threads about 1.5-1.8 x one on an idle two-core machine at 3e4 disks or 1e5 spheres; "
    "another busy process makes them slower: docs/performance.md)";

CLI::App* add_compress(CLI::App& app, CompressArgs& ca, std::string& out_compress) {
  auto* comp = app.add_subcommand("compress", "bi-axial compression test of a sample (section 4.4.1): sigma_xx = p held, top wall at constant strain rate");
  comp->add_option("--state", ca.state_file, "state file of the sample (e.g. state.txt of a sinter run)")
      ->required()
      ->check(non_empty_file("a state file"));
  comp->add_option("--strain-rate", ca.strain_rate, "vertical strain rate [1/s] (eps_zz = 1 - z/z0)")->capture_default_str();
  comp->add_option("--max-strain", ca.max_strain, "final vertical strain")->capture_default_str();
  comp->add_option("--ramp-time", ca.ramp_time, "the top wall's speed rises smoothly over this time [s]")->capture_default_str();
  comp->add_option("--pressure", ca.pressure, "sigma_xx held by the right wall [N/m]; 0: the state's");
  comp->add_option("--param", ca.param_overrides, "contact parameter NAME=VALUE");
  comp->add_option("--threads", ca.threads, kThreadsHelp)->check(CLI::Range(1, 256))->capture_default_str();
  comp->add_flag("--quiet", ca.quiet, "no progress on stderr");
  comp->add_option("--max-steps", ca.max_steps, "refuse a run of more time steps than this")->capture_default_str();
  comp->add_flag("--allow-long", ca.allow_long, "run even above 5e10 particle-steps (about 1-3 h of one core)");
  comp->add_flag("--overwrite", ca.overwrite, "clear an output folder that holds another run's files first");
  comp->add_option("--out", out_compress, "output folder")->default_val("results/compress");
  return comp;
}

/// demsolve vibrate's options (section 4.4).
CLI::App* add_vibrate(CLI::App& app, VibrateArgs& va, std::string& out_vibrate) {
  auto* vib = app.add_subcommand("vibrate", "vibration test (section 4.4): walls removed, vertical vibration on a flat bottom in gravity");
  vib->add_option("--state", va.state_file, "state file of the sample")->required()->check(non_empty_file("a state file"));
  vib->add_option("--frequency", va.frequency, "[Hz]")->capture_default_str();
  vib->add_option("--amplitude", va.amplitude, "[m]")->capture_default_str();
  vib->add_option("--time", va.time, "vibration time [s]")->capture_default_str();
  vib->add_option("--gravity", va.gravity, "[m/s^2]")->capture_default_str();
  vib->add_option("--param", va.param_overrides, "contact parameter NAME=VALUE");
  vib->add_option("--threads", va.threads, kThreadsHelp)->check(CLI::Range(1, 256))->capture_default_str();
  vib->add_flag("--quiet", va.quiet, "no progress on stderr");
  vib->add_option("--max-steps", va.max_steps, "refuse a run of more time steps than this")->capture_default_str();
  vib->add_flag("--allow-long", va.allow_long, "run even above 5e10 particle-steps (about 1-3 h of one core)");
  vib->add_flag("--overwrite", va.overwrite, "clear an output folder that holds another run's files first");
  vib->add_option("--out", out_vibrate, "output folder")->default_val("results/vibrate");
  return vib;
}

/// demsolve compact's options (docs/dynamic.md); the subcommand and the options checked after parsing.
struct DemCompactCli {
  CLI::App* app;
  CLI::Option* lid;
  CLI::Option* lateral;
  CLI::Option* density;
  CLI::Option* strain;
  CLI::Option* precompact_density;
  CLI::Option* precompact_increments;
};

DemCompactCli add_dem_compact(CLI::App& app, DemCompactArgs& dc, std::string& out_dcompact) {
  auto* dcomp = app.add_subcommand("compact", "explicit DEM with the plastic-indentation law (Redanz & Fleck 2001) on "
                                              "netsolve compact's scene, units and files (docs/dynamic.md)");
  dcomp->add_option("--width", dc.pack.width, "box width W of a new deposition in units of the mean radius R (netsolve pack)")->capture_default_str();
  dcomp->add_option("--r-min", dc.pack.r_min, "smallest radius / R")->capture_default_str();
  dcomp->add_option("--r-max", dc.pack.r_max, "largest radius / R")->capture_default_str();
  dcomp->add_flag("--mono", dc.pack.mono, "monosized disks (r = R)");
  dcomp->add_option("--seed", dc.pack.seed, "random seed of the deposition")
      ->check(netdem::app::netsolve::seed_validator())
      ->capture_default_str();
  auto* dcomp_lid = dcomp->add_option("--lid", dc.pack.lid, "deposition stop rule: centre | inside (netsolve pack)")->capture_default_str();
  dcomp->add_option("--dim", dc.pack.dim, "2: disks; 3: spheres (netsolve pack --dim 3's deposition or a 3D --packing; "
                                          "--boundary walls or --affine)")
      ->check(CLI::IsMember({2, 3}))
      ->capture_default_str();
  auto* dcomp_lateral = dcomp->add_option("--lateral", dc.pack.lateral, "3D only: side boundary of the deposition (walls; "
                                                                        "the explicit DEM has no lateral-periodic one)")
                            ->capture_default_str();
  dcomp->add_option("--packing", dc.packing_file, "packing CSV (netsolve pack's packing.csv) instead of a new deposition");
  dcomp->add_option("--state", dc.state_file, "a jammed state (jammed.json of netsolve or demsolve compact --save-state) "
                                             "instead of a new deposition: its particles, box, walls and contact histories")
      ->check(non_empty_file("a jammed state file"));
  dcomp->add_flag("--save-state", dc.save_state, "write the final jammed state to jammed.json (netsolve and demsolve compact "
                                                 "--state start from it)");
  dcomp->add_flag("--affine", dc.affine, "every centre follows the macroscopic strain (spins free); default: the peripheral layer only");
  dcomp->add_option("--path", dc.path, "hydrostatic | closed-die | E11,E22,E12 strain-rate direction (walls: E12 = 0 only); "
                                       "--dim 3: E11,E22,E33[,E23,E13,E12] (closed-die along z)")->capture_default_str();
  dcomp->add_option("--friction", dc.friction, "Coulomb coefficient mu, or inf for sticking")->capture_default_str();
  dcomp->add_flag("--no-rotation", dc.no_rotation, "hold every spin at zero");
  auto* dcomp_density = dcomp->add_option("--to-density", dc.to_density, "target relative density D")->capture_default_str();
  auto* dcomp_strain = dcomp->add_option("--to-strain", dc.to_strain,
                                         "run to this equivalent strain |E| = sqrt(E11^2 + E22^2 + 2 E12^2) along --path "
                                         "instead of to a density, in [1e-9, 1] (pure shear: --path 1,-1,0)");
  dcomp_strain->excludes(dcomp_density);
  auto* dcomp_pre = dcomp->add_option("--precompact-density", dc.precompact_density,
                                      "first compact hydrostatically from the start density to this density (leg 0), "
                                      "then run --path to --to-density or --to-strain (leg 1); history.csv gets the "
                                      "column 'leg'");
  auto* dcomp_pre_n = dcomp->add_option("--precompact-increments", dc.precompact_increments,
                                        "output windows of the precompaction (with --precompact-density)")
                          ->capture_default_str();
  dcomp->add_option("--boundary", dc.boundary, "layer: netsolve's die mode (peripheral layer prescribed); walls: four rigid "
                                               "frictionless walls driven along the path; periodic: a periodic cell "
                                               "following the path (--packing of netsolve pack --periodic)")->capture_default_str();
  dcomp->add_flag("--simple-shear", dc.simple_shear, "--boundary periodic: the path's shear rates as simple shear (x moves "
                                                     "with y, L12 = 2 E12): the cell tilts and is re-mapped (Lees-Edwards)");
  dcomp->add_option("--normal-unloading", dc.normal_unloading, "reversible (Eq 2 retraced) | elastic (section 3.4 branch)")
      ->check(CLI::IsMember({"reversible", "elastic"}))
      ->capture_default_str();
  dcomp->add_option("--first-touch", dc.first_touch, "first-touch overlap u_c/(2R*) of the linear chord (bounded stiffness)")->capture_default_str();
  dcomp->add_option("--k-t", dc.k_t, "tangential spring on the shear stress, tau = k_t u_T [sigma_y/R]")->capture_default_str();
  dcomp->add_option("--inertial-number", dc.inertial_number, "I = gamma' 2R sqrt(rho/sigma_y) sets the strain rate gamma' = |E'|")->capture_default_str();
  dcomp->add_option("--damping", dc.damping, "contact dashpots (normal and tangential): fraction of critical damping of the first-touch chord stiffness")->capture_default_str();
  dcomp->add_option("--drag", dc.drag, "background drag on the motion relative to the affine field [1/t*]")->capture_default_str();
  dcomp->add_option("--steps-per-contact", dc.steps_per_contact, "time step: the stiffest contact period / this")->capture_default_str();
  dcomp->add_option("--increments", dc.increments, "output windows (equal strain, as netsolve's increments)")->capture_default_str();
  netdem::app::netsolve::add_list_option(*dcomp, "--snapshots", dc.snapshots,
                                         "densities at which VTK snapshots are written, a comma list in any order (\"\": none)");
  dcomp->add_option("--max-steps", dc.max_steps, "refuse a run estimated to need more time steps; stop at it (incomplete, exit 3)")->capture_default_str();
  dcomp->add_option("--threads", dc.threads, kThreadsHelp)->check(CLI::Range(1, 256))->capture_default_str();
  dcomp->add_flag("--quiet", dc.quiet, "no progress on stderr");
  dcomp->add_flag("--overwrite", dc.overwrite, "clear an output folder that holds another run's files first");
  dcomp->add_option("--out", out_dcompact, "output folder")->default_val("results/dem_compact");
  return {dcomp, dcomp_lid, dcomp_lateral, dcomp_density, dcomp_strain, dcomp_pre, dcomp_pre_n};
}

/// The targets of demsolve compact: --to-strain's range, the precompaction's options together.
void check_compact_targets(const DemCompactCli& c, const DemCompactArgs& dc) {
  using CO = netdem::dem::CompactionOptions;
  if (c.strain->count() > 0 && !(dc.to_strain >= CO::kMinTargetStrain && dc.to_strain <= CO::kMaxTargetStrain))
    throw netdem::app::UsageError(fmt::format("--to-strain must be in [{:g}, {:g}], got {}", CO::kMinTargetStrain,
                                              CO::kMaxTargetStrain, dc.to_strain));
  if (c.precompact_increments->count() > 0 && c.precompact_density->count() == 0)
    throw netdem::app::UsageError("--precompact-increments is an option of --precompact-density");
  if (c.precompact_density->count() == 0) return;
  if (c.density->count() == 0 && c.strain->count() == 0)
    throw netdem::app::UsageError("--precompact-density: give the path's target after it, --to-density or --to-strain");
  if (!(dc.precompact_density > 0.0 && dc.precompact_density < 1.0))
    throw netdem::app::UsageError(fmt::format("--precompact-density must be in (0, 1) (a relative density), got {}",
                                              dc.precompact_density));
}

/// demsolve yield's options (docs/dynamic.md).
CLI::App* add_dem_yield(CLI::App& app, DemYieldArgs& dy, std::string& out_dyield) {
  auto* dyield = app.add_subcommand("yield", "yield-surface probes after precompaction with the explicit DEM and the "
                                             "plastic-indentation law: netsolve yield's scene, probes and files (docs/dynamic.md)");
  dyield->add_option("--width", dy.pack.width, "box width W of a new deposition in units of R (netsolve pack)")->capture_default_str();
  dyield->add_option("--r-min", dy.pack.r_min, "smallest radius / R")->capture_default_str();
  dyield->add_option("--r-max", dy.pack.r_max, "largest radius / R")->capture_default_str();
  dyield->add_flag("--mono", dy.pack.mono, "monosized disks (r = R)");
  dyield->add_option("--seed", dy.pack.seed, "random seed of the deposition")
      ->check(netdem::app::netsolve::seed_validator())
      ->capture_default_str();
  dyield->add_option("--packing", dy.packing_file, "packing CSV instead of a new deposition");
  dyield->add_option("--precompact", dy.precompact, "hydrostatic | closed-die")->capture_default_str();
  dyield->add_option("--to-density", dy.to_density, "precompaction density D")->capture_default_str();
  dyield->add_option("--increments", dy.increments, "precompaction output windows (netsolve's increments)")->capture_default_str();
  dyield->add_option("--compact-bc", dy.compact_bc, "affine | die (the peripheral layer prescribed) | periodic (a periodic --packing in a cell that follows the strain)")->capture_default_str();
  dyield->add_option("--probe-bc", dy.probe_bc, "affine | die | periodic during unloading and probing (must equal --compact-bc; or affine with --compact-bc periodic: every centre follows the cell, the spins free)");
  dyield->add_option("--friction", dy.friction, "Coulomb coefficient mu, or inf for sticking")->capture_default_str();
  dyield->add_option("--normal-unloading", dy.normal_unloading, "the law during the precompaction: reversible | elastic")
      ->check(CLI::IsMember({"reversible", "elastic"}))
      ->capture_default_str();
  dyield->add_option("--first-touch", dy.first_touch, "first-touch overlap u_c/(2R*)")->capture_default_str();
  dyield->add_option("--k-t", dy.k_t, "tangential spring on the shear stress [sigma_y/R]")->capture_default_str();
  dyield->add_flag("--no-rotation", dy.no_rotation, "hold every spin at zero");
  dyield->add_option("--directions", dy.directions, "probes, theta_k = 360 k / N degrees, (E11dot, E22dot) = (cos, sin)")->capture_default_str();
  netdem::app::netsolve::add_list_option(*dyield, "--probes", dy.probe_list, "run only these probe indices, e.g. 0,3,5");
  dyield->add_option("--jobs", dy.jobs, "probes run at the same time on threads (0: number of cores)")->capture_default_str();
  dyield->add_option("--offset", dy.offset, "offset strain of the offset yield point")->capture_default_str();
  dyield->add_option("--max-strain", dy.max_strain, "longest probe |dE|")->capture_default_str();
  dyield->add_option("--window", dy.window, "curvature smoothing width (normalised arc length)")->capture_default_str();
  dyield->add_option("--fine", dy.fine, "equal fine probe steps (unloading strain / 10 each) before the steps grow")->capture_default_str();
  dyield->add_option("--growth", dy.growth, "growth factor of the probe steps after the fine ones")->capture_default_str();
  dyield->add_option("--unload-tol", dy.unload_tol, "unload until |Sigma| < tol sigma_y")->capture_default_str();
  dyield->add_option("--inertial-number", dy.inertial_number, "I = gamma' 2R sqrt(rho/sigma_y) of the precompaction")->capture_default_str();
  dyield->add_option("--probe-inertial-number", dy.probe_inertial_number, "the same for the unloading and the probes (0: --inertial-number)")->capture_default_str();
  dyield->add_option("--relax-drag", dy.relax_drag, "drag of the hold after each unloading and probe increment [1/t*]")->capture_default_str();
  dyield->add_option("--settle-tol", dy.settle_tol, "a hold ends when the RMS unbalanced force is below this x the mean contact force of the loading point (and the kinetic energy below its square x the elastic work)")->capture_default_str();
  dyield->add_option("--settle-time", dy.settle_time, "longest hold [t*]; a sample that did not settle counts as unconverged")->capture_default_str();
  dyield->add_option("--damping", dy.damping, "contact dashpots: fraction of critical damping of the first-touch chord stiffness")->capture_default_str();
  dyield->add_option("--steps-per-contact", dy.steps_per_contact, "time step: the stiffest contact period / this")->capture_default_str();
  dyield->add_option("--max-steps", dy.max_steps, "refuse a run of more time steps than this")->capture_default_str();
  dyield->add_flag("--quiet", dy.quiet, "no progress on stderr");
  dyield->add_flag("--allow-unconverged", dy.allow_unconverged, "exit 0 even if the status is unconverged or unstable");
  dyield->add_flag("--overwrite", dy.overwrite, "clear an output folder that holds another run's files first");
  dyield->add_option("--out", out_dyield, "output folder")->default_val("results/dem_yield");
  return dyield;
}

int demsolve_command(int argc, char** argv) {
  netdem::app::reset_run_state();
  std::string command;
  command = netdem::app::shell_command(argc, argv);
  CLI::App app{"demsolve: explicit 2D DEM with Luding's sintering contact law (Luding et al. 2005)"};
  app.require_subcommand(1);
  netdem::dem::SampleSpec sample;
  RunArgs run;
  netdem::dem::SinterProtocol prot;
  std::string out_prepare, out_sinter;

  std::vector<CLI::Option*> pressure_opts, sample_opts, packing_opts, dim_opts;
  // CLI11 turns "-1" into 2^64 - 1 for an unsigned option: refuse a sign
  auto unsigned_only = [](const std::string& v) -> std::string {
    return v.find_first_not_of("0123456789") == std::string::npos && !v.empty() ? ""
                                                                                  : "must be an integer >= 0";
  };
  double max_steps = 1e9;
  auto limits = [&](CLI::App* c) {
    c->add_option("--max-steps", max_steps, "refuse a run of more time steps than this (the estimate is in the message)")
        ->capture_default_str();
    c->add_flag("--allow-long", run.allow_long, "run even above 5e10 particle-steps (about 1-3 h of one core)");
    c->add_flag("--overwrite", run.overwrite, "clear an output folder that holds another run's files first");
  };
  auto common = [&](CLI::App* c) {
    sample_opts.push_back(c->add_option("--n", sample.n, "number of disks")->capture_default_str());
    pressure_opts.push_back(
        c->add_option("--pressure", run.pressure, "wall pressure p [N/m] (Eq 1); with --state default the state's")
            ->capture_default_str());
    sample_opts.push_back(c->add_option("--seed", sample.seed, "random seed of placement and velocities")
                              ->check(unsigned_only)
                              ->capture_default_str());
    sample_opts.push_back(
        c->add_option("--arrangement", sample.arrangement, "random, or the three-particle control: triangle | line (--n 3)")
            ->capture_default_str());
    packing_opts.push_back(c->add_option("--packing", sample.packing_file,
                  "start from the disks of this packing CSV (e.g. netsolve pack's packing.csv), at rest; --n, --seed and "
                  "--arrangement are then unused"));
    c->add_option("--length-unit", sample.length_unit,
                  "metres per length unit of the --packing file; 0: the file's mean radius becomes Luding's a0 "
                  "(Table 1, 1 mm), i.e. a0 / mean r (docs/sintering.md)")
        ->capture_default_str();
    c->add_option("--mu", run.mu, "particle friction once friction is on (Table 1)")->capture_default_str();
    c->add_option("--mu-wall", run.mu_wall_prepare, "wall friction during preparation (switched off at t_heat)")
        ->capture_default_str();
    c->add_option("--samples", run.samples,
                  "rows of timeseries.csv over the run, equal steps apart (3000: e.g. every 0.5 ms of the default "
                  "sinter)")
        ->capture_default_str();
    c->add_option("--mu-prepare", run.mu_prepare,
                  "particle friction during preparation (the paper: 0, frictionless; an investigation option)")
        ->capture_default_str();
    c->add_option("--steps-per-contact", run.steps_per_contact, "time step t_c/this for the mean pair (Eq 6)")
        ->capture_default_str();
    c->add_option("--param", run.param_overrides, "contact parameter NAME=VALUE (Table 1 names, e.g. k2=2e5, da_T=0)");
    c->add_option("--threads", run.threads, kThreadsHelp)->check(CLI::Range(1, 256))->capture_default_str();
    c->add_flag("--quiet", run.quiet, "no progress on stderr");
    dim_opts.push_back(c->add_option("--dim", run.dim, "2: disks (LMM05); 3: spheres in a box of six walls, three of them "
                                                       "stress-controlled, --pressure in N/m^2 (default 100 N/m / (2 a0)); "
                                                       "a state file gives its own")
                           ->check(CLI::IsMember({2, 3}))
                           ->capture_default_str());
    limits(c);
  };
  auto* prep = app.add_subcommand("prepare", "random disks compressed by stress-controlled walls, frictionless unless --mu-prepare, 80 deg C (section 4.1)");
  common(prep);
  prep->add_option("--time", prot.t_heat, "simulated preparation time [s] (the paper's t_heat = 0.2)")->capture_default_str();
  prep->add_option("--out", out_prepare, "output folder")->default_val("results/prepare");

  auto* sint = app.add_subcommand("sinter", "the long-time sintering protocol of section 4.1 (Fig 7)");
  common(sint);
  sint->add_option("--state", run.state_file, "start from this state file (e.g. state_prepare.txt of a run)")
      ->check(non_empty_file("a state file"));
  sint->add_option("--t-heat", prot.t_heat, "preparation time t_heat [s]")->capture_default_str();
  sint->add_option("--heat-time", prot.heat, "heating time t_sinter - t_heat [s]")->capture_default_str();
  sint->add_option("--sinter-time", prot.sinter, "sintering time t_s [s] (quenched axis)")->capture_default_str();
  sint->add_option("--cool-time", prot.cool, "cooling time [s]")->capture_default_str();
  sint->add_option("--relax-time", prot.relax, "relaxation time after cooling [s]")->capture_default_str();
  sint->add_option("--T-cold", prot.T_cold, "preparation and final temperature [deg C]")->capture_default_str();
  sint->add_option("--T-hot", prot.T_hot, "sintering temperature [deg C]")->capture_default_str();
  sint->add_option("--t0", prot.t0, "relaxation time t0 outside sintering [s] (Table 1)")->capture_default_str();
  sint->add_option("--t0-sinter", prot.t0_sinter, "relaxation time t0 during sintering [s]")->capture_default_str();
  sint->add_option("--out", out_sinter, "output folder")->default_val("results/sinter");
  CompressArgs ca;
  std::string out_compress;
  auto* comp = add_compress(app, ca, out_compress);
  VibrateArgs va;
  std::string out_vibrate;
  auto* vib = add_vibrate(app, va, out_vibrate);
  DemCompactArgs dc;
  std::string out_dcompact;
  const DemCompactCli dcli = add_dem_compact(app, dc, out_dcompact);
  auto* dcomp = dcli.app;
  DemYieldArgs dy;
  std::string out_dyield;
  auto* dyield = add_dem_yield(app, dy, out_dyield);
  netdem::app::add_scene_config(app, "demsolve", "", netdem::app::kDemsolveSections);
  try {
    app.parse(argc, argv);
    netdem::app::set_scene(*app.get_subcommands().front(), "demsolve", app.get_subcommands().front()->get_name());
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    // CLI11 quotes the input: at most 80 printable characters of each argument
    std::string m = e.what();
    for (int k = 1; k < argc; ++k) {
      const std::string a = argv[k];
      if (a.size() <= 80) continue;
      for (auto at = m.find(a); at != std::string::npos; at = m.find(a, at + 1)) m.replace(at, a.size(), quote_input(a));
    }
    if (m.size() > 300) m = quote_input(m.substr(0, 80)) + " ...";
    netdem::app::print_error_line(fmt::format("demsolve: error: {} (see --help)", one_line(m)));
    return netdem::app::exit_code::usage;
  }
  for (auto* o : pressure_opts) run.pressure_given = run.pressure_given || o->count() > 0;
  for (auto* o : sample_opts) run.sample_given = run.sample_given || o->count() > 0;
  for (auto* o : packing_opts) run.packing_given = run.packing_given || o->count() > 0;
  for (auto* o : dim_opts) run.dim_given = run.dim_given || o->count() > 0;
  run.max_steps = max_steps;
  return guarded([&] {
    if (prep->parsed()) return run_protocol(command, sample, run, prot, true, out_prepare);
    if (comp->parsed()) return run_compress(command, ca, out_compress);
    if (vib->parsed()) return run_vibrate(command, va, out_vibrate);
    if (dcomp->parsed()) {
      if (dcomp->count("--packing") > 0 && dc.packing_file.empty())
        throw netdem::app::UsageError("--packing is empty: give a packing CSV file, or leave --packing out for a new deposition");
      if (dc.pack.dim == 2 && dcli.lateral->count() > 0)
        throw netdem::app::UsageError("--lateral is for --dim 3 only (the 2D deposition has side walls)");
      if (dc.pack.dim == 3 && dcli.lid->count() > 0 && dc.pack.lid != "inside")
        throw netdem::app::UsageError("--lid '" + quote_input(dc.pack.lid) +
                                      "': the 3D deposition implements only --lid inside (whole spheres below the lid)");
      check_compact_targets(dcli, dc);
      return run_dem_compact(command, dc, out_dcompact);
    }
    if (dyield->parsed()) {
      if (dyield->count("--packing") > 0 && dy.packing_file.empty())
        throw netdem::app::UsageError("--packing is empty: give a packing CSV file, or leave --packing out for a new deposition");
      return run_dem_yield(command, dy, out_dyield);
    }
    return run_protocol(command, sample, run, prot, false, out_sinter);
  });
}
