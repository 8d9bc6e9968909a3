#!/usr/bin/env python3
"""Validation of demsolve against Luding, Manetsberger & Muellers (2005), long-time sintering, section 4.

usage: /usr/bin/python3 validation/luding_sintering/run.py
           [--quick] [--force] [--jobs 2] [--demsolve PATH] [--out DIR] [--runs DIR] [--report-only]
           [--netsolve PATH (ignored)]

Runs the study of study.py (the section 4.1 protocol for N in {100, 300}, p in {10, 100},
t_s in {1e-4, 0.01, 0.02, 0.05, 0.1, 1}, the three-particle and da_T = 0 controls, the mu_w = 0.5
investigation, and `demsolve compress` / `demsolve vibrate` on the final states; --quick: N = 100 and
t_s in {1e-4, 0.1, 1}), skipping runs that are up to date, then writes figures in the style of
Figs 8-19, 21-22 and report.md (a table of the paper's findings beside the measured values, each with
its acceptance band) into --out (default: this folder, or ./quick with --quick).

Needs numpy and matplotlib (Debian: /usr/bin/python3 with python3-numpy, python3-matplotlib).
"""
import argparse
import datetime
import os
import shlex
import sys
import warnings

import numpy as np
import matplotlib

matplotlib.use("Agg")
warnings.filterwarnings("ignore", message=".*tight_layout.*")

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import study  # noqa: E402

REPO = study.REPO


sys.path.insert(0, os.path.join(str(REPO), "apps", "scripts"))
from report_paths import provenance, provenance_lines, shown_path, tally, totals_text  # noqa: E402


def shown(p):
    """A path for the report (apps/scripts/report_paths.py)."""
    return shown_path(p, REPO)


# ----------------------------------------------------------------------------------------- reading
class Sim:
    """A sinter run; a branched run is completed with its base run's time series and phases."""

    def __init__(self, run, sims):
        self.run, self.name, self.dir, self.info = run, run.name, run.dir, run.info
        self.summary = read_json(os.path.join(self.dir, "summary.json"))
        self.meta = read_json(os.path.join(self.dir, "meta.json")) or {}
        self.ok = self.summary is not None and os.path.isfile(os.path.join(self.dir, "timeseries.csv"))
        if not self.ok:
            return
        self.ts = read_table(os.path.join(self.dir, "timeseries.csv"))
        self.phases = {ph["phase"]: ph for ph in self.summary.get("phases", [])}
        self.phases["final"] = self.summary["final"]
        self.parent = sims.get(run.deps[0]) if run.deps else None
        if self.parent is not None and self.parent.ok:
            t0 = self.ts["t"][0]
            keep = self.parent.ts["t"] < t0 - 1e-12
            for k, v in self.parent.ts.items():
                if isinstance(v, list):
                    self.ts[k] = [x for x, m in zip(v, keep) if m] + self.ts[k]
                else:
                    self.ts[k] = np.concatenate([v[keep], self.ts[k]])
            for name in ("prepare", "heat"):
                if name not in self.phases and name in self.parent.phases:
                    self.phases[name] = self.parent.phases[name]
        elif run.deps:
            self.ok = False

    def at(self, col, t):
        return float(np.interp(t, self.ts["t"], self.ts[col]))

    def nu_ref_radii(self, phase=None):
        """nu computed with the radii at T_radius_ref (Eq 9 undone): nu / (1 - da_T (T_ref - T))^2."""
        cp = (read_json(os.path.join(self.dir, "parameters.json")) or {}).get("contact_params", {})
        da, tref = cp.get("da_T", 0.0), cp.get("T_radius_ref", cp.get("T_melt", 120.0))
        if phase is None:
            return self.ts["nu"] / (1.0 - da * (tref - self.ts["T"])) ** 2
        ph = self.phases[phase]
        return ph["nu"] / (1.0 - da * (tref - ph["T"])) ** 2

    def nu(self, phase):
        return self.phases[phase]["nu"] if phase in self.phases else float("nan")

    @property
    def densification(self):
        return self.nu("final") / self.nu("prepare") - 1.0

    def contacts(self, phase):
        p = os.path.join(self.dir, f"contacts_{phase}.csv")
        return read_table(p) if os.path.isfile(p) else None

    @property
    def t_sinter_end(self):
        return 0.3 + self.info["ts"]

    @property
    def cpu_s(self):
        return self.meta.get("cpu_s", float("nan"))


class Test:
    def __init__(self, run):
        self.run, self.name, self.dir, self.info = run, run.name, run.dir, run.info
        self.summary = read_json(os.path.join(self.dir, "summary.json"))
        self.meta = read_json(os.path.join(self.dir, "meta.json")) or {}
        self.ok = self.summary is not None
        self.table = None
        fname = "compress.csv" if run.kind == "compress" else "clusters.csv"
        if self.ok and os.path.isfile(os.path.join(self.dir, fname)):
            try:
                self.table = read_table(os.path.join(self.dir, fname))
            except (OSError, IndexError, ValueError):
                self.table = None


# ----------------------------------------------------------------------------------------- helpers
from analysis import branching_check, evaluate, experiment_table, fmt, read_json, read_table  # noqa: E402
from figures import (fig8, fig9, fig10, fig11, fig_cluster_sizes, fig_compress, fig_controls, fig_cooldown,  # noqa: E402
                     fig_force, fig_overlap, fig_vibrate, fig_vibration_snapshots)


def write_report(out, a, runs, sims, tests, figs, F, notes, binary, t_total, nb, ns):
    L = []
    mode = "quick" if a.quick else "full"
    prov = provenance(REPO, "luding_sintering", [binary])
    L.append("# Validation: long-time sintering (Luding, Manetsberger & Muellers 2005), section 4\n")
    L.append(f"Generated {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')} by "
             f"`/usr/bin/python3 validation/luding_sintering/run.py{' --quick' if a.quick else ''}` ({mode} grid).\n")
    L.append(f"* binary given to this invocation (used for the runs made now): `{shown(binary)}`, git revision "
             f"{a.revision or (prov['commit'] or 'unknown')[:10] + (' (work tree modified)' if prov['modified'] else '')}")
    shas = {}
    for r in list(sims.values()) + list(tests.values()):
        if r.meta.get("binary_sha256"):
            k = (r.meta["binary_sha256"][:12], shown(r.meta.get("binary", "?")))
            shas[k] = shas.get(k, 0) + 1
    L.append("* binaries of the runs (sha256 first 12 hex, path, runs): "
             + ("; ".join(f"{h} `{b}` ({c})" for (h, b), c in sorted(shas.items())) or "n/a"))
    for note in a.note or []:
        L.append(f"* {note}")
    L.append("* paper: S. Luding, K. Manetsberger, J. Muellers, J. Mech. Phys. Solids 53 (2005) 455-491")
    cpu = sum(x.meta.get("cpu_s", 0.0) or 0.0 for x in list(sims.values()) + list(tests.values()))
    wall = sum(x.meta.get("wall_s", 0.0) or 0.0 for x in list(sims.values()) + list(tests.values()))
    L.append(f"* run time: {cpu:.0f} CPU-s summed over {len(sims) + len(tests)} runs ({wall:.0f} s wall summed; "
             f"this invocation {t_total:.0f} s wall, shared 2-core machine, `nice -n 10`)")
    L.append(f"* branching check (`--state state_heat.txt` vs the unbranched run, N = 100, p = 100, t_s = 0.1): "
             f"{branching_check(sims)}\n")
    if notes:
        L.append("Notes from the runner:\n")
        for n in notes:
            L.append(f"* {n}")
        L.append("")
    L.append("## Findings\n")
    counts = tally(r[5] for r in F.rows)
    L.append(f"{totals_text(counts)} (other: investigation or information; MISSING: could not be evaluated, the reason "
             "in the measured column). Bands are fixed in `run.py` (`evaluate()`) and are never widened to make a finding pass.\n")
    L.append("| # | paper's finding | source | measured | band | result | note |")
    L.append("|---|---|---|---|---|---|---|")
    for r in F.rows:
        L.append("| " + " | ".join(str(x).replace("|", "/") for x in r) + " |")
    L.append("")
    L.append("## Summary of the sinter runs\n")
    L.append("| run | nu(t_heat) | nu(0.3) | nu(end sinter) | nu(t_f) | densification | C(end sinter) | C w/o walls | "
             "k1/k1 end sinter | CPU s |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    for s in sims.values():
        if not s.ok:
            L.append(f"| {s.name} | failed or missing |||||||||")
            continue
        sp = s.phases.get("sinter", {})
        L.append(f"| {s.name} | {fmt(s.nu('prepare'), 4)} | {fmt(s.nu('heat'), 4)} | {fmt(s.nu('sinter'), 4)} | "
                 f"{fmt(s.nu('final'), 4)} | {100 * s.densification:.2f} % | {fmt(sp.get('C'), 2)} | "
                 f"{fmt(sp.get('C_without_walls'), 2)} | {sp.get('k1_over_k1', float('nan')):.4g} | {fmt(s.cpu_s, 1)} |")
    L.append("")
    if tests:
        L.append("## Material tests\n")
        L.append("| run | stiffness [N/m] | peak szz | peak strain | largest cluster / N | single grains / N | clusters | CPU s |")
        L.append("|---|---|---|---|---|---|---|---|")
        for t in tests.values():
            sm = t.summary or {}
            def g4(k, sm=sm):
                v = sm.get(k)
                return f"{v:.4g}" if isinstance(v, (int, float)) else ""
            L.append(f"| {t.name} | {g4('stiffness')} | {g4('peak_szz')} | {g4('peak_strain')} | "
                     f"{g4('largest_cluster_fraction')} | {g4('single_grain_fraction')} | "
                     f"{g4('clusters')} | {fmt(t.meta.get('cpu_s'), 1)} |")
        L.append("")
    L.append("## Figures\n")
    for f_ in figs:
        if f_:
            L.append(f"![{f_}]({f_})\n")
    L.append(experiment_table(sims, nb))
    L.append(KNOWN_DIFFERENCES)
    L.append("## Commands\n")
    L.append("Every run (dependency order; `study.py --print-commands"
             f"{' --quick' if a.quick else ''}` prints the same list), each run under `nice -n 10`:\n")
    L.append("```")
    for r in runs:
        L.append(shlex.join([shown(binary)] + [shown(x) for x in r.args]))
    L.append("```\n")
    L += provenance_lines(prov, counts)
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write("\n".join(L) + "\n")


KNOWN_DIFFERENCES = """## Known differences, explanations and open points

Numbers below are from the full grid (N = 300 unless stated); the findings table above is the
reference for the current runs.

### Issue 15: the headline findings, what the audit changed, what does not reproduce and why

* **The law audit** (docs/luding.md, audit table) found one departure from the text: on cooling,
  section 3.3.2 ends "also the stiffness is increased accordingly", while our k2' line was kept.
  Fixed: delta_max^- now solves delta_max (1 - k1(T)/k2(delta_max)) = delta_0 with Eq 7 at the new
  delta_max, and k2', k_c (Eq 13), f_min (Eq 15) and k_t (Eq 23) grow with it (test
  `Luding.CoolingReevaluatesEq7`). A contact at delta_max = 0.1 a0 cools to k2' = 1.63e5 N/m instead
  of 1.25e5. Before/after (experiment "k2' kept on cooling" against the reference, N = 300, t_s = 1):
  attractive fraction after cool-down 0.000 -> 0.004 (p = 10) and 0.025 -> 0.037 (p = 100), width
  q95 - q05 after/before cool-down 0.84 -> 0.93 (p = 10) and 0.99 -> 1.14 (p = 100); nu(t_f) moves by
  < 0.0005. The freeze rule of section 3.4, the quenched time axis (t0 = 0.1 s during sintering only),
  Eq 9-12, footnote 5 and Eq 1 are implemented as written.
* **Attractive contacts after cool-down (15a): not reproduced.** Band >= 0.2; measured 0.004
  (p = 10) and 0.037 (p = 100), and 0.000-0.054 in every experiment of the table above that cools
  in 0.1 s or slower: three seeds
  (p = 100: 0.037, 0.000, 0.006 - the fraction is seed noise at this level), N = 1000 (0.015, 0.004),
  no thermal expansion (0.045, 0.054), the text's larger expansion da_T = 2.5e-4 (0.000, 0.000),
  footnote 5 off (0.010, 0.007: cohesion while sliding does not create attraction), wall contacts
  that do not creep (0.005, 0.006), the old k2' rule. |q05|/q95 stays at 0.001-0.27 (band 0.5-2):
  the pdf stays one-sided. **Why:** at the end of sintering 97-99.7 % of the pair contacts sit on
  their loading line (delta >= delta_0; delta < delta_0 for 2.9 % at p = 10 and 0.3 % at p = 100,
  from `state_sinter.txt`), and
  the cool-down is affine: the box contracts by 0.601-0.628 % (linear) while Eq 9 shrinks the radii
  by 0.599 % (column "box / radius contraction"; 1.51-1.55 % vs 1.49 % with da_T = 2.5e-4). An
  affine contraction changes every overlap by the fraction 0.6 % of itself, a change of 0.6 % of
  delta_0 ~ 6e-4 a0 that is nearly proportional to the contact force (delta_0 ~ f/k1(T,t) after
  creep), so it rescales the force state instead of making it two-sided; the rising k1 moves
  delta_max, not the force (section 3.3.2), and the re-evaluated k2' scales the forces on the line by
  the same sign. Attraction needs contacts pulled below delta_0, i.e. a non-affine cool-down. The
  result turns on the **cooling rate relative to the packing's response**: cooling in 1 ms instead
  of 0.1 s (experiment "quench", branched at t = 1.3) leaves the box behind the radii (0.35-0.38 %
  against 0.60 %) and freezes in a self-stressed block: at p = 10 the attractive fraction becomes
  0.205 (>= 0.2; 20.5 % of the contacts below delta_0 in `state.txt`; 425 pair contacts against 563 after the 0.1 s cool-down) and
  the width grows x 2.7, at p = 100 0.073 and x 1.6; cooling in 1 s changes
  nothing (0.037, x 1.13). The walls are not the bottleneck: 100 x the wall damping (20 kg/s) during
  the cool-down creates no attraction either (0.000 at p = 10, 0.035 at p = 100). The section 4.1 protocol states the cool-down time (0.1) but
  calls "the time unit ... arbitrary" and the process quasi-static; with Table 1's parameters our
  0.1 s cool-down is quasi-static, so the paper's "almost equally strong attractive and repulsive
  contact forces" are reproduced only by a cool-down about 100 times faster than the text's, and
  even then |q05|/q95 stays below 0.5 (0.23 at p = 10). None of the Table 1 parameters we varied
  (da_T, footnote 5, the wall law and damping, the k2' rule) turns the result on.
* **Broadening on cool-down (15a, width):** passes at p = 100 (x 1.14), fails at p = 10 (x 0.93);
  with the seeds 2 and 3 at p = 100 it is x 0.91 and x 0.90, so the p = 100 pass is not robust.
* **Density through the cool-down (15b):** nu(t_f) = 0.9245 at p = 100, t_s = 1 passes (band
  0.92-0.96; seeds: 0.9250 +- 0.0032); the rise on cool-down is +0.0003 against the paper's about
  +0.02 (fails). With the radii held at T_melt (nu computed from fixed radii) the same run rises by
  +0.011: the paper's rise "due to negative thermal expansion" is what a fixed-radius nu gives for
  an affine contraction of 0.6 % (1.2 % in area); with da_T = 2.5e-4 it would be 3 %. The paper
  does not say which radii its nu uses; its only definition (section 3.1.3) is N pi h a0^2 / V.
* **Coordination dips (15c):** 0 dips in the N = 300 grid runs (t_s = 1, both p) with the issue's
  definition; seeds 2 give 1 dip each (p = 10 and p = 100), seeds 3 and N = 1000 none. At N = 100
  one lost contact is already a dip (2/N = 0.02): p = 100 has 1, p = 10 none. The largest fall
  of the smoothed C over 10 ms while nu rises is one contact (-0.0067 at N = 300), so in our runs C
  rises almost monotonically on the 10 ms scale. **At 0.1 ms (15f, 15g; issue 32)** the same
  sintering, rerun from state_heat.txt with 12000 samples, shows 18 (p = 10) and 19 (p = 100)
  dips of at least one contact within 1 ms while nu rises, and the wall stress moves with them: the
  largest 5 % of the 1 ms changes of szz/p occur in 20 % and 28 % of the dip windows (4.0 and 5.7
  times the base rate). So the paper's dips with "large stress fluctuations" (Fig 11) are there, as
  millisecond events that lose single contacts; the 10 ms / 5-sample smoothing of 15c removes them.
* **Attraction after cool-down against the cool-down time (15h, 15i; issue 32).** From the
  reference's state at the end of sintering, the cool-down takes 1 ms to 1 s. The relaxation time
  used is the walls', tau_w = m_wall / gamma_wall (Eq 1; 50 ms with Table 1's wall): a
  stress-controlled wall needs it to reach the speed its force imbalance drives, so the box follows
  the thermal contraction of the radii (Eq 9) no faster. At p = 10 the attractive fraction is 20-22 %
  for cool-downs of 1-3 ms (below tau_w / 10), 12 % at 10 ms and below 1 % from 30 ms on: the
  paper's "strongly attractive" contacts are those of a cool-down faster than the walls can follow.
  At p = 100 a floor of 3.7 % does not depend on the cool-down time (30 ms to 1 s), and only the 1 ms
  cool-down raises it (7.3 %). The lighter wall (tau_w = 5 ms) does not collapse the p = 100 data on
  cool-down / tau_w: 15i passes its band (0.044 at the ratio 0.2), but the fractions agree better at
  equal cool-down time (1 ms: 0.081 against 0.073), so at p = 100 the short time that matters is not
  the walls'. The paper's own cool-down (0.1 s in its time unit) would need its wall mass and
  damping in the same unit to place it on this axis.
* **Narrowing (15d):** (q95 - q05)/mean of f_n at the end of sintering falls with t_s at p = 100
  (2.34 -> 1.81, Spearman -0.89, passes) but not at p = 10 (Spearman +0.09).
* **Three-particle control (3c, 3d, 15e).** The law is homogeneous of degree one in force and
  overlap while delta << delta_max^fluid = 0.4 a0 (Eq 7) and delta_0 < delta_fluid, so the
  densification of a fixed arrangement scales with p: our p = 100 / p = 10 ratio is 10.4-10.6
  (creeping walls) and 10.2-10.6 (non-creeping walls), while the paper's estimates (8 % and 0.2 %)
  have the ratio 40; no Table 1 parameter makes the three-particle densification non-linear in p
  at these overlaps. With creeping wall contacts (default) the triangle densifies 24 % at p = 100,
  more than the paper's bulk samples (16 %), which would contradict the paper's conclusion drawn
  from this control ("the strong increase in density observed for larger samples is caused by
  re-arrangements"); with `--param wall_sintering=0` the values are 5.8 % / 3.4 % (p = 100,
  triangle / line) and 0.57 % / 0.32 % (p = 10), i.e. 0.4-0.7 x and 1.6-2.9 x the paper's. We keep
  creeping walls as the default because the bulk density then agrees with Fig 9 (N = 300, p = 100:
  nu(t_f) = 0.9245 with, 0.9108 without creeping walls).
* **Preparation density:** seeds 1-3 give 0.8262 +- 0.0021 (p = 10) and 0.8296 +- 0.0023
  (p = 100) at N = 300, N = 1000 gives 0.836 / 0.838 and N = 100 0.811: nu grows with N (fewer wall
  particles); the paper's 0.8 at N = 300 is 12-13 sample standard deviations below our seeds.

* **Preparation density (finding 1a).** The paper reports nu ~ 0.8 after the frictionless
  preparation; demsolve gives 0.825 (p = 10) and 0.828 (p = 100) for N = 300 (0.812 and 0.811 for
  N = 100, within the band). These numbers move by ~0.003 with round-off: a binary differing only
  in the last bits of the force loop (before the issue #4 speed commit) gave 0.827 and 0.831. The paper says that the wall friction was switched off at t_heat, which
  implies wall friction during the preparation, while Table 1 gives mu_w = 0; our default follows
  Table 1. The **investigation** run `N300_p100_ts1_muw0.5` (`--mu-wall 0.5` during the preparation,
  not a default) does *not* explain the difference: it prepares slightly denser (0.831), and no jump
  appears at t_heat (findings 1c, 1d). Nor do the walls' mass and damping: frictionless, every
  m_w in [0.001, 0.1] kg and gamma_w in [0.02, 20] gives 0.825-0.835 (README.md). **Particle
  friction during the preparation** does (issue 32; `--mu-prepare 0.5`, not a default, findings
  1e and 3h): nu = 0.807 (p = 100) and 0.802 (p = 10) after the preparation, and densifications of
  14.5 % and 3.7 %, inside the paper's 12-20 % and 3-7 %, with C at the end of sintering inside the
  bands of 4a. The paper's text prepares frictionless and calls its p = 10 samples near-isostatic
  (C ~ 4), so this stays an investigation: the frictional start reproduces the paper's numbers, not
  its stated protocol.
* **Jump at t_heat (finding 1b).** With mu_w = 0 there is nothing to switch off at t_heat and the
  frictionless packing is already static, so the small jump of Fig 9 is absent by construction
  (nu(0.3) - nu(0.2) < 1e-5); also absent with mu_w = 0.5.
* **Densification (findings 3a, 3b).** The *final* densities agree with those the paper implies
  (p = 100: 0.925 vs 0.8 x 1.16 = 0.928; p = 10: 0.838 vs 0.8 x 1.05 = 0.84, finding 3e), and the
  densities at t = 1.3 and t_f pass (2b, 2c). The densification nu(t_f)/nu(t_heat) - 1 falls short
  (11.7 % vs 16 +- 4 %, 1.5 % vs 5 +- 2 %) because our sample starts denser (previous point): from
  nu = 0.80 the same final density would be a 15.6 % densification at p = 100.
* **Three-particle controls (3c, 3d, 3g, 15e).** demsolve applies the full sintering law to
  particle-wall contacts as well (default `wall_sintering=1`), and a three-particle sample has more
  wall contacts than particle contacts (triangle: 3 pairs + 5 wall contacts; line: 2 pairs + 8 wall
  contacts), so its box shrinks by the creep of the wall contacts too: 17-24 % at p = 100 and
  1.7-2.3 % at p = 10 against the paper's estimates 8 % and 0.2 % ("data not shown"). With wall
  contacts that keep the cold k1 (`--param wall_sintering=0`, line 15e) it is 3.4-5.8 % and
  0.32-0.57 %; the estimate from the snapshots with the wall overlaps frozen (3g) agrees. See the
  issue 15 section above for the p-scaling (10 in our law, 40 in the paper's estimates).
* **Cooling (findings 2c, 2d, 5c).** See the issue 15 section above (15a, 15b): the cool-down is
  affine, adds +0.0003 to nu computed from the current radii and +0.011 computed from the radii at
  T_melt (2d); min f_n / max f_n after cool-down is in line 5c, the attractive fraction in 15a.
  Fixed radii would not explain the preparation density (0.828 / 0.992 = 0.835 with radii at T_melt).
* **Force homogenisation (5b, 15d).** std(f_n)/mean(f_n) at the end of sintering falls from
  t_s = 1e-4 to 1 for p = 100 (0.73 -> 0.55, but not monotonically: Spearman -0.49) and not for
  p = 10; the width (q95 - q05)/mean (15d) falls with Spearman -0.89 at p = 100 (pass) and not at
  p = 10.
* **Fully activated friction after cool-down (5d).** No contact has mu_t >= 0.99 mu after the
  relaxation, for any t_s: the tangential springs were limited by the hot mu(T, t) = mu k1(T,t)/k1
  (~0.01 at the end of long sintering) and the nearly affine, quasi-static cool-down does not
  re-mobilise them once mu is back to 0.5. The trend "rarer with t_s" can therefore not be seen;
  at the end of sintering (5e, information) the fraction of fully activated contacts is 0-34 %.
* **Compression test (6a-6c).** The top wall starts smoothly (`--ramp-time`, default 5 ms, speed
  rising as (1 - cos)/2): the first version of this grid started it at full speed, and the
  stress-controlled right wall (m_w = 0.01 kg, ~260 particle masses, gamma_w = 0.2 kg/s, damping
  time 0.05 s) then rang with a period of ~7 ms, comparable with the 5 ms needed to reach
  eps = 0.005, which made the fitted stiffness of weak samples negative and the ratio 3.1 (N = 100)
  and 4.0 (N = 300). With the ramp the ratio over the issue's window [0, 0.005] was 2.95 and 2.85
  before issue 15; the section 3.3.2 fix (k2' re-evaluated on cooling) makes the cooled contacts
  stiffer, more so the strongly sintered ones of p = 100 (stiffness 9.0e4 -> 1.13e5 N/m at N = 100,
  9.9e4 -> 1.25e5 at N = 300, against 3.0e4 -> 3.5e4 and 3.5e4 -> 3.8e4 at p = 10), so the ratio is
  now 3.27 and 3.32, just above the band (6a FAIL; the band is not widened). The initial slope over
  [0, 0.002] gives 2.06 and 2.06 and the secant to the peak 2.20 and 2.19, in line with the paper's
  "about two" (notes of 6a). The stiffness of the weak p = 10 samples depends on the strain rate:
  the 10 times slower **investigation** (`*_compress_slow`, 0.1/s) gives 1.2e4 instead of 3.5e4 N/m
  for N = 100 while the p = 100 value stays, so the ratio there is 9.2 and 14: at 1/s part of the
  p = 10 response is the
  damping and inertia of the contacts, and the paper does not state its rate. For weak samples the
  peak of sigma_zz comes early (eps ~ 0.003-0.004, inside the window) and the failure strain of
  unsintered samples is ill-defined (a noisy plateau after an early yield, stick-slip of the right
  wall), which breaks the monotonic trend of the failure strain at short t_s (6c); the failure
  stress rises with t_s everywhere (6b).
* **Vibration (7a, 7b).** `demsolve vibrate` defines a cluster by touching pairs at the end of the
  test; in a vibrated bed (peak floor acceleration 8 g) non-cohesive grains that happen to collide or
  rest on each other count as clusters, so the single-grain fraction of unsintered samples stays near
  0.6-0.9 even though the largest cluster holds only 1-3 % of N; conversely, rattlers (disks without
  contacts inside the sintered block, already present before the vibration, see the note of 7a)
  count as broken-off single grains and lower the largest-cluster fraction of sintered samples.
  A cluster definition by cohesive (attractive or sintered) bonds, or by distance with a small
  gap tolerance, would match the paper's visual judgement better. After the issue 15 fix the
  N = 300, p = 10, t_s = 1 sample keeps 0.897 N in its largest cluster (0.923 before; 0.960 N
  before vibrating, 4 % rattlers), just below the band (7a FAIL); 7b for N = 300, p = 10 now passes
  (0.947, was 0.853). These lines move by a few per cent between binaries: one or two fragments.
* **Zero-length phases (demsolve), fixed.** The first version of this study found that
  `demsolve sinter --sinter-time 0 --cool-time 0 --relax-time 0` did not end in the heated state:
  the last time step (t = K dt slightly past 0.3) fell past the zero-length phases into `relax` at
  T_cold. Fixed (the schedule time is clamped to the protocol's end; CLI test
  `zero_length_phases_end_hot`) before the current grid ran. The study still branches from
  `state_heat.txt` of the t_s = 1e-4 run, whose first 0.3 s are identical.
* The three-particle, da_T = 0 and mu_w investigation runs are made from scratch (no branching).
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="N = 100, t_s in {1e-4, 0.1, 1}")
    ap.add_argument("--demsolve", default=study.DEFAULT_BIN)
    ap.add_argument("--netsolve", default=None, help="ignored (accepted for validation/run_all.sh)")
    ap.add_argument("--jobs", type=int, default=2, help="simulations in parallel (default 2)")
    ap.add_argument("--out", default=None, help="folder for report.md and PNGs (default: this folder or ./quick)")
    ap.add_argument("--runs", default=None, help="folder of the run folders (default: ./runs)")
    ap.add_argument("--force", action="store_true", help="rerun every run")
    ap.add_argument("--report-only", action="store_true", help="run nothing, only rebuild the report")
    ap.add_argument("--timeout", type=float, default=7200, help="per-run time limit in seconds")
    ap.add_argument("--note", action="append", help="a line to add to the report header (repeatable)")
    ap.add_argument("--revision", default=None,
                    help="git revision to record for the binary (default: this repository's HEAD and its state)")
    a = ap.parse_args()
    import time
    t0 = time.time()
    out = os.path.abspath(a.out or (os.path.join(HERE, "quick") if a.quick else HERE))
    runs_dir = os.path.abspath(a.runs or os.path.join(HERE, "runs"))
    os.makedirs(out, exist_ok=True)
    runs = study.build_runs(runs_dir, a.quick)
    notes = []
    binary = os.path.abspath(a.demsolve)
    if os.access(binary, os.X_OK):
        runs_x, notes = study.adapt_to_binary(runs, binary)
        if not a.report_only:
            print(f"luding_sintering: {len(runs_x)} runs, --jobs {a.jobs}")
            res = study.execute(runs_x, binary, a.jobs, a.force, a.timeout)
            for name, (ok, msg) in res.items():
                if not ok:
                    notes.append(f"{name}: {msg}")
    else:
        notes.append(f"no executable demsolve at {binary}: report from existing runs only")
    sims, tests = {}, {}
    for r in runs:
        if r.kind == "sinter":
            sims[r.name] = Sim(r, sims)
        elif os.path.isfile(os.path.join(r.dir, "summary.json")):
            tests[r.name] = Test(r)
    ns = study.QUICK_N if a.quick else study.GRID_N
    nb = max(ns)
    figs = [fig8(sims, nb, out), fig9(sims, nb, out), fig10(sims, ns, out), fig11(sims, nb, out),
            fig_overlap(sims, nb, "sinter", 12, out), fig_overlap(sims, nb, "relax", 13, out),
            fig_force(sims, nb, 10, 14, out), fig_force(sims, nb, 100, 15, out)]
    for role in ("compress", "compress_slow"):
        for n, f1, f2 in ((100, 16, 17), (300, 18, 19)):
            if n in ns:
                figs += [fig_compress(tests, n, "nu", "nu", f1, out, role),
                         fig_compress(tests, n, "szz", "sigma_zz [N/m]", f2, out, role)]
    figs += [fig_vibrate(tests, ns, out), fig_cluster_sizes(tests, nb, out)] + fig_vibration_snapshots(tests, nb, out)
    figs += [fig_controls(sims, nb, out), fig_cooldown(sims, nb, out)]
    F = evaluate(sims, tests, nb, ns, a.quick)
    write_report(out, a, runs, sims, tests, figs, F, notes, binary, time.time() - t0, nb, ns)
    for r in F.rows:
        print(f"  [{r[5]}] {r[0]} {r[1]}: {r[3]} (band {r[4]})")
    print(f"luding_sintering: report -> {os.path.join(out, 'report.md')}")
    bad = [n for n in notes if "failed" in n or "rc=" in n]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
