#!/usr/bin/env python3
"""Validation of `netsolve sinter-pair`, the two-particle sintering model (a documented reconstruction of
the model note described in docs/sintering_pair.md, not the model of Thomsen et al. / Ivannikov et al.).

usage: /usr/bin/python3 validation/sintering_pair/run.py
           [--quick] [--force] [--netsolve PATH] [--out DIR] [--runs DIR] [--jobs N (ignored)] [--demsolve PATH (ignored)]

Runs `netsolve sinter-pair` for: Cu at 950, 1000, 1050 C (R = 50 um, 16 h); the single-mechanism runs of the
note's section 7.2; GB diffusion alone (Bouvard-McMeeking); the initial neck x0/R in {0.01, 0.003, 0.001};
the integrators; the asymmetric pair; Ti (both readings of the note's section 5.2). Skips runs whose
command.txt is unchanged (unless --force), then writes the figures and report.md (a table of findings, each
with its band and PASS/FAIL, and whether it passes by construction) into --out (default: this folder, or
./quick with --quick; --quick leaves out Ti and x0/R = 0.001). The whole study takes a few seconds.

Needs numpy and matplotlib (Debian: /usr/bin/python3 with python3-numpy, python3-matplotlib).
"""
import argparse
import datetime
import json
import math
import os
import shlex
import subprocess
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import MISSING, missing_text, provenance, provenance_lines, tally, totals_text, verdict  # noqa: E402
KB = 1.380649e-23
TIMES = [60.0, 600.0, 3600.0, 14400.0, 57600.0]
TIME_LABELS = ["1 min", "10 min", "1 h", "4 h", "16 h"]

# note section 7.3 (as printed)
NOTE_CU = {
    950.0: ([0.0805, 0.1207, 0.1663, 0.2135, 0.2748], [1.84e-3, 4.10e-3, 7.71e-3, 1.27e-2, 2.09e-2]),
    1000.0: ([0.087687, 0.132522, 0.183640, 0.237033, 0.306532], [2.0979e-3, 4.7586e-3, 9.1060e-3, 1.5151e-2, 2.5325e-2]),
    1050.0: ([0.0956, 0.1456, 0.2029, 0.2631, 0.3415], [2.40e-3, 5.56e-3, 1.08e-2, 1.82e-2, 3.08e-2]),
}
# note section 7.4
NOTE_74 = [(0.088, 5.69e-4, 9.08e-4, 3.04e-4), (0.184, 5.33e-4, 9.33e-4, 3.04e-4), (0.307, 4.78e-4, 9.66e-4, 3.04e-4)]
# note section 7.2 (prototype exponent_runs) and the targets
EXPONENT_TARGETS = {"I": (6.00, 94.2, 6, "deltaD_gb0"), "III": (5.00, 19.6, 5, "D_vol0"), "IV": (4.98, 1.21, 5, "D_vol0")}
EXP_MATERIAL = {"Omega": 1e-29, "gamma_s": 1.0, "deltaD_gb0": 1e-15, "D_vol0": 1e-5, "deltaD_s0": 1e-10}


def runs_list(quick):
    cu = ["--material", "cu", "--radius", "50e-6", "--rtol", "1e-10"]
    r = {}
    for tc in (950, 1000, 1050):
        r[f"cu_{tc}C"] = cu + ["--temperature", f"{tc + 273.15:.2f}", "--time", "57600"]
    r["cu_1000C_gb_only"] = cu + ["--temperature", "1273.15", "--time", "57600", "--paths", "I"]
    exp = ["--material", os.path.join(HERE, "exponent_material.txt"), "--radius", "10e-6", "--temperature", "1300",
           "--t-first", "1e-9", "--time", "1e4", "--x-max", "0.2", "--per-decade", "40", "--rtol", "1e-9"]
    for p in ("I", "II", "III", "IV"):
        r[f"exponent_{p}"] = exp + ["--paths", p]
    for x0 in (["0.003"] if quick else ["0.003", "0.001"]):
        r[f"cu_1000C_x0_{x0}"] = cu + ["--temperature", "1273.15", "--time", "3600", "--x0", x0]
    for integ, extra in (("rk4", ["--rk4-c", "0.005"]), ("cvode", []), ("arkode", [])):
        r[f"cu_1000C_{integ}"] = cu + ["--temperature", "1273.15", "--time", "3600", "--integrator", integ] + extra
    r["cu_1000C_asymmetric"] = ["--material", "cu", "--radii", "25e-6,50e-6", "--rtol", "1e-10", "--temperature", "1273.15",
                                "--time", "57600"]
    if not quick:
        ti = ["--material", "ti", "--radius", "25e-6", "--temperature", "1573.15", "--time", "14400", "--rtol", "1e-9"]
        r["ti_1300C_stored"] = ti
        r["ti_1300C_dvol_1.9e-7"] = ti + ["--set", "D_vol0=1.9e-7"]
    return r


def run_all(netsolve, runs_dir, quick, force):
    out = {}
    for name, args in runs_list(quick).items():
        d = os.path.join(runs_dir, name)
        cmd = [netsolve, "sinter-pair"] + args + ["--quiet", "--out", d]
        cmd_text = " ".join(cmd)
        # finished: summary.json and command.txt, and no .incomplete marker (a failed or killed run)
        done = (os.path.isfile(os.path.join(d, "summary.json")) and os.path.isfile(os.path.join(d, "command.txt"))
                and not os.path.exists(os.path.join(d, ".incomplete")))
        if done and not force:
            with open(os.path.join(d, "command.txt")) as f:
                done = f.read().strip().replace(" --overwrite", "") == cmd_text
        if not done or force:
            print("run:", " ".join(shlex.quote(c) for c in cmd[1:]), flush=True)
            held = any(os.path.exists(os.path.join(d, f)) for f in ("command.txt", "summary.json", ".incomplete"))
            run = cmd[:-2] + (["--overwrite"] if held else []) + cmd[-2:]  # a rerun replaces the old files
            subprocess.run(run, check=True, stdout=subprocess.DEVNULL)
        out[name] = load(d)
    return out


def load(d):
    with open(os.path.join(d, "summary.json")) as f:
        s = json.load(f)
    data = np.genfromtxt(os.path.join(d, "pair.csv"), delimiter=",", names=True)
    return {"summary": s, "csv": data, "dir": d}


def at(run, t, key):
    return run["summary"]["at"][f"{t:g}"][key]


class Findings:
    def __init__(self):
        self.rows = []

    def add(self, finding, measured, band, ok, construction, note=""):
        self.rows.append((finding, measured, band, verdict(ok), construction, note))

    def missing(self, finding, band, reason, construction, note=""):
        """A line that cannot be evaluated: MISSING, with the reason, counted in the totals."""
        self.rows.append((finding, missing_text(reason), band, MISSING, construction, note))

    def table(self):
        s = "| finding | measured | band | result | by construction? | note |\n|---|---|---|---|---|---|\n"
        for r in self.rows:
            s += "| " + " | ".join(x.replace("|", "\\|") for x in r) + " |\n"
        return s


def fit_exponent(run, key, n_int):
    c = run["csv"]
    R = run["summary"]["radii_m"][0]
    T = c["T"][0]
    m = run["summary"]["material"]
    sel = (c["x_over_R"] >= 0.05) & (c["x_over_R"] <= 0.15) & (c["t"] > 0)
    lx, lt = np.log(c["x_over_R"][sel]), np.log(c["t"][sel])
    n = np.polyfit(lx, lt, 1)[0]
    x = c["x_over_R"][sel] * R
    C = np.exp(np.mean(np.log(x ** n_int * KB * T / (EXP_MATERIAL[key] * m["gamma_s"] * m["Omega"] * R * R * c["t"][sel]))))
    return n, C, int(sel.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--demsolve", default=None, help="ignored (accepted for validation/run_all.sh)")
    ap.add_argument("--jobs", type=int, default=1, help="ignored (the study takes seconds)")
    ap.add_argument("--out", default=None)
    ap.add_argument("--runs", default=None, help="run folders (default: results/validation/sintering_pair[_quick], git-ignored)")
    a = ap.parse_args()
    outdir = a.out or (os.path.join(HERE, "quick") if a.quick else HERE)
    runs_dir = a.runs or os.path.join(REPO, "results", "validation", "sintering_pair" + ("_quick" if a.quick else ""))
    os.makedirs(outdir, exist_ok=True)
    os.makedirs(runs_dir, exist_ok=True)
    R = run_all(os.path.abspath(a.netsolve), runs_dir, a.quick, a.force)
    F = Findings()
    rep = []

    # ---- 1. Cu at 950 / 1000 / 1050 C against the note's table 7.3
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = {950.0: "#1f77b4", 1000.0: "#2ca02c", 1050.0: "#d62728"}
    table = "| T | quantity | source | " + " | ".join(TIME_LABELS) + " |\n|---|---|---|" + "---|" * 5 + "\n"
    for tc in (950.0, 1000.0, 1050.0):
        run = R[f"cu_{tc:.0f}C"]
        c = run["csv"]
        pos = c["t"] > 0
        axs[0].loglog(c["t"][pos], c["x_over_R"][pos], color=colours[tc], label=f"{tc:.0f} C model")
        axs[1].loglog(c["t"][pos], c["shrinkage"][pos], color=colours[tc], label=f"{tc:.0f} C model")
        nx, nd = NOTE_CU[tc]
        axs[0].loglog(TIMES, nx, "o", mfc="none", color=colours[tc], label=f"{tc:.0f} C note 7.3")
        axs[1].loglog(TIMES, nd, "o", mfc="none", color=colours[tc], label=f"{tc:.0f} C note 7.3")
        mx = [at(run, t, "x_over_R") for t in TIMES]
        md = [at(run, t, "shrinkage") for t in TIMES]
        fx = "{:.6f}" if tc == 1000.0 else "{:.4f}"
        fd = "{:.4e}" if tc == 1000.0 else "{:.2e}"
        table += f"| {tc:.0f} C | x/R | note | " + " | ".join(fx.format(v) for v in nx) + " |\n"
        table += "| | | netsolve | " + " | ".join(f"{v:.6f}" for v in mx) + " |\n"
        table += "| | ΔL/L0 | note | " + " | ".join(fd.format(v) for v in nd) + " |\n"
        table += "| | | netsolve | " + " | ".join(f"{v:.5e}" for v in md) + " |\n"
        if tc == 1000.0:
            dev = max(max(abs(m / n - 1) for m, n in zip(mx, nx)), max(abs(m / n - 1) for m, n in zip(md, nd)))
            F.add("Cu 1000 C, x/R and ΔL/L0 at 1 min ... 16 h against note table 7.3", f"max relative deviation {dev:.1e}",
                  "≤ 1e-4 relative", dev <= 1e-4, "yes: the note's table comes from the same reconstruction (its prototype)",
                  "verifies the implementation, not the physics")
        else:
            okx = all(abs(m - n) <= 0.5e-4 + 1e-12 for m, n in zip(mx, nx))
            okd = all(abs(m - n) <= 0.5 * 10 ** (math.floor(math.log10(n)) - 2) + 1e-15 for m, n in zip(md, nd))
            wx = max(abs(m - n) for m, n in zip(mx, nx))
            F.add(f"Cu {tc:.0f} C, x/R and ΔL/L0 against note table 7.3", f"max |Δ(x/R)| = {wx:.1e}; ΔL/L0 all within",
                  "half a unit in the last printed digit", okx and okd, "yes (same reconstruction)")
    for ax, lab in zip(axs, ("x / R", "shrinkage ΔL / L0")):
        ax.set_xlabel("t [s]")
        ax.set_ylabel(lab)
        ax.grid(True, which="both", alpha=0.3)
    axs[0].legend(fontsize=7, ncol=2)
    fig.suptitle("Cu, R = 50 µm, all paths (documented reconstruction; material: note section 5.1)")
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "fig_cu_neck_shrinkage.png"), dpi=110)
    plt.close(fig)
    rep.append("## 1. Copper at 950, 1000 and 1050 °C beside the note's table 7.3\n\n"
               "R = 50 µm, x0/R = 0.01, h0 = R, all five path types, rtol 1e-10 (DP45).\n\n"
               "![Cu neck growth and shrinkage](fig_cu_neck_shrinkage.png)\n\n" + table)

    # asymmetric pair
    ra = R["cu_1000C_asymmetric"]
    xs = [at(ra, t, "x_over_R") for t in (60.0, 3600.0, 57600.0)]
    note_a = [0.151, 0.316, 0.524]
    proto_a = [0.151326, 0.315497, 0.524200]
    dev = [abs(m - n) for m, n in zip(xs, note_a)]
    F.add("asymmetric pair R_A = 25 µm, R_B = 50 µm, 1000 C: x/R_A at 1 min / 1 h / 16 h against the note's 0.151 / 0.316 / 0.524",
          " / ".join(f"{v:.6f}" for v in xs), "± 5e-4 (the issue's band)", all(d <= 5e-4 for d in dev), "yes (same reconstruction)",
          "1 h misses by 3e-7: the note's prototype itself gives 0.315497 (printed as 0.316); against the prototype's "
          "unrounded 0.151326 / 0.315497 / 0.524200 the deviation is "
          + f"{max(abs(m / p - 1) for m, p in zip(xs, proto_a)):.0e} relative")
    dp = max(abs(m / p - 1) for m, p in zip(xs, proto_a))
    F.add("asymmetric pair: x/R_A against the note's prototype unrounded (0.151326 / 0.315497 / 0.524200, "
          "sintering_pair_proto.integrate at rtol 1e-10)", f"max relative deviation {dp:.1e}", "≤ 2e-5 relative", dp <= 2e-5,
          "yes (same reconstruction)")
    fa = ra["summary"]["final"]
    F.add("asymmetric pair: R_A/R_A0 at 16 h (slow coarsening of the small particle)", f"{fa['R_A_over_R_A0']:.5f}",
          "0.998 ± 5e-4 (note 7.3)", abs(fa["R_A_over_R_A0"] - 0.998) <= 5e-4, "yes (same reconstruction)")

    # ---- 2. single-mechanism exponents
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    etab = "| path | mechanism | n (fit, 0.05 ≤ x/R ≤ 0.15) | target n | prefactor C | note 7.2 | points |\n|---|---|---|---|---|---|---|\n"
    names = {"I": "GB diffusion", "II": "surface diffusion", "III": "lattice, GB → neck", "IV": "lattice, cap → neck"}
    for p in ("I", "II", "III", "IV"):
        run = R[f"exponent_{p}"]
        c = run["csv"]
        pos = c["t"] > 0
        ax.loglog(c["t"][pos], c["x_over_R"][pos], label=f"path {p} ({names[p]})")
        if p == "II":
            sel = (c["x_over_R"] >= 0.05) & (c["x_over_R"] <= 0.15) & (c["t"] > 0)
            n = np.polyfit(np.log(c["x_over_R"][sel]), np.log(c["t"][sel]), 1)[0]
            etab += f"| II | {names[p]} | {n:.3f} | 5-7 classical; note ≈ 5.6 (1/n = 0.176-0.179) | - | - | {int(sel.sum())} |\n"
            F.add("path II (surface diffusion) exponent", f"n = {n:.2f}", "note: 1/n = 0.176-0.179 (n = 5.6-5.7)",
                  0.176 <= 1 / n <= 0.180, "yes (same reconstruction)",
                  "under-resolved by the model's uniform-cap supply (note section 7.2); the classical value is 7")
            # the independent reference (issue 32): the classical two-sphere law of surface diffusion,
            # Kuczynski (1949), x^7 / R^3 ∝ t; the band (5 %) was set before the line was evaluated
            loc = []
            for lo, hi in ((0.02, 0.05), (0.05, 0.15), (0.15, 0.2)):
                s = (c["x_over_R"] >= lo) & (c["x_over_R"] <= hi) & (c["t"] > 0)
                loc.append(f"{np.polyfit(np.log(c['x_over_R'][s]), np.log(c['t'][s]), 1)[0]:.2f} over {lo:g}-{hi:g}"
                           if s.sum() > 3 else f"- over {lo:g}-{hi:g}")
            F.add("path II (surface diffusion) exponent against the classical two-sphere law (Kuczynski 1949: "
                  "x^7 / R^3 ∝ t, n = 7)", f"n = {n:.2f}", "7 ± 0.35 (5 %)", abs(n - 7) <= 0.35,
                  "no: an independent closed form",
                  "the experiment: the local exponent " + ", ".join(loc) + " (x/R); it drifts away from 7 as the neck "
                  "grows, so the miss is not a fit-range effect: the model feeds the neck from the whole cap through a "
                  "ln(r_t/x) resistance (note sections 3 and 7.2), where Kuczynski's derivation moves matter over the "
                  "neck's curvature radius ρ ∝ x²/R")
            continue
        n_t, C_t, n_int, key = EXPONENT_TARGETS[p]
        n, C, npts = fit_exponent(run, key, n_int)
        etab += f"| {p} | {names[p]} | {n:.4f} | {n_t:.2f} ± 0.03 | {C:.4g} | {C_t} (± 2 %) | {npts} |\n"
        classical = {"I": "6 (Coble, Kuczynski: GB diffusion)", "III": "5 (lattice diffusion)", "IV": "5 (lattice diffusion)"}[p]
        F.add(f"path {p} ({names[p]}): neck-growth exponent n in x ∝ t^(1/n)", f"{n:.3f}", f"{n_t:.2f} ± 0.03",
              abs(n - n_t) <= 0.03, "no: self-similar growth follows from the physics of the path; classical value " + classical)
        F.add(f"path {p}: prefactor of x^{n_int} = C {key} γ_s Ω R² t / kT", f"{C:.4g}", f"{C_t} ± 2 %",
              abs(C / C_t - 1) <= 0.02, "yes (same reconstruction: the note's prototype value)",
              "classical prefactors depend on the assumed neck geometry [unverified]")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x / R")
    ax.axhspan(0.05, 0.15, color="#eee")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("one path at a time (note 7.2 material, R = 10 µm, 1300 K)\ngrey: fit range 0.05 ≤ x/R ≤ 0.15", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "fig_exponents.png"), dpi=110)
    plt.close(fig)
    rep.append("## 2. Neck-growth exponents, one path at a time\n\n"
               "The material of the prototype's `exponent_runs` (`exponent_material.txt`: Ω = 1e-29 m³, γ_s = 1, "
               "γ_gb = 0.3 J/m², no activation energies), R = 10 µm, 1300 K, x0/R = 0.01, one path on "
               "(`--paths`). n is the least-squares slope of ln t against ln x over 0.05 ≤ x/R ≤ 0.15; C is the "
               "least-squares prefactor at the integer exponent.\n\n![exponents](fig_exponents.png)\n\n" + etab)

    # ---- 3. Bouvard-McMeeking and the effective law
    gb = R["cu_1000C_gb_only"]
    ratios = [at(gb, t, "viscosity") / at(gb, t, "viscosity_bouvard_mcmeeking") for t in TIMES]
    dev = max(abs(r - 1) for r in ratios)
    F.add("GB diffusion alone: η_eff / (π x⁴ / 8 Δ_b) (Bouvard-McMeeking) along the free trajectory", f"max |ratio − 1| = {dev:.1e}",
          "≤ 1e-10", dev <= 1e-10, "no: an exact identity of the model (note 4.7), checked through the whole right-hand side")
    cu = R["cu_1000C"]
    m = cu["summary"]["material"]
    Rr = 50e-6
    c = cu["csv"]
    half_psi = math.acos(m["gamma_gb"] / (2 * m["gamma_s"]))
    ftab = "| x/R | F_s,eff (model) | note 7.4 | Bouvard-McMeeking form (Kratos) | note | Martin form (MUSEN) | note | η_eff/η_BM (all paths) |\n|---|---|---|---|---|---|---|---|\n"
    worst = 0.0
    for t, (xr_n, fs_n, fbm_n, fm_n) in zip((60.0, 3600.0, 57600.0), NOTE_74):
        xr = at(cu, t, "x_over_R")
        fs = at(cu, t, "sintering_force")
        fbm = math.pi * m["gamma_s"] * (4 * Rr * (1 - math.cos(half_psi)) + xr * Rr * math.sin(half_psi))
        fmar = 1.125 * math.pi * (2 * Rr / 2) * m["gamma_s"]
        er = at(cu, t, "viscosity") / at(cu, t, "viscosity_bouvard_mcmeeking")
        worst = max(worst, abs(fs / fs_n - 1))
        ftab += f"| {xr:.3f} | {fs:.4e} N | {fs_n:.3g} N | {fbm:.3e} N | {fbm_n:.3g} N | {fmar:.3e} N | {fm_n:.3g} N | {er:.3f} |\n"
    F.add("F_s,eff (all paths) at x/R = 0.088 / 0.184 / 0.307 against note table 7.4", f"max relative deviation {worst:.1e}",
          "≤ 1e-3", worst <= 1e-3, "yes (same reconstruction)")
    F.add("F_s,eff lies between the two published closed forms (Martin/MUSEN < F_s,eff < Bouvard-McMeeking/Kratos)",
          "see table", "strictly between", None if False else all(fm < fs < fb for fs, fb, fm in
                                                                   [(at(cu, t, "sintering_force"),
                                                                     math.pi * m["gamma_s"] * (4 * Rr * (1 - math.cos(half_psi)) + at(cu, t, "x_over_R") * Rr * math.sin(half_psi)),
                                                                     1.125 * math.pi * Rr * m["gamma_s"]) for t in TIMES]),
          "no: a comparison with independent closed forms (note 8)")
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.2))
    pos = gb["csv"]["t"] > 0
    g = gb["csv"]
    # the CSV does not carry eta; the ratio is shown at the output times of summary.json
    axs[0].semilogx([at(gb, t, "x_over_R") for t in TIMES], ratios, "o-", label="GB only (paths I)")
    axs[0].semilogx([at(cu, t, "x_over_R") for t in TIMES],
                    [at(cu, t, "viscosity") / at(cu, t, "viscosity_bouvard_mcmeeking") for t in TIMES], "s-", label="all paths")
    axs[0].set_xlabel("x / R")
    axs[0].set_ylabel("η_eff / (π x⁴ / 8 Δ_b)")
    axs[0].legend()
    axs[0].grid(True, which="both", alpha=0.3)
    xr = c["x_over_R"][c["t"] > 0]
    axs[1].plot(xr, c["sintering_force"][c["t"] > 0] * 1e3, label="F_s,eff (model, all paths)")
    axs[1].plot(xr, [math.pi * m["gamma_s"] * (4 * Rr * (1 - math.cos(half_psi)) + v * Rr * math.sin(half_psi)) * 1e3 for v in xr],
                "--", label="Bouvard-McMeeking form (Kratos)")
    axs[1].plot(xr, [1.125 * math.pi * Rr * m["gamma_s"] * 1e3] * len(xr), ":", label="Martin form (MUSEN)")
    axs[1].plot([r[0] for r in NOTE_74], [r[1] * 1e3 for r in NOTE_74], "ko", mfc="none", label="note 7.4")
    axs[1].set_xlabel("x / R")
    axs[1].set_ylabel("sintering force [mN]")
    axs[1].legend(fontsize=8)
    axs[1].grid(True, alpha=0.3)
    fig.suptitle("effective contact law (note 4.7), Cu, R = 50 µm, 1000 C")
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "fig_bouvard_mcmeeking.png"), dpi=110)
    plt.close(fig)
    del g, pos
    rep.append("## 3. Bouvard-McMeeking cross-check and the effective sintering force\n\n"
               "η_eff = F₁/(ṡ(F₁) − ṡ(0)) and F_s,eff = η_eff ṡ(0) from two right-hand-side evaluations (note 4.7). With GB "
               "diffusion alone (`--paths I`) η_eff must equal π x⁴/(8 Δ_b), Δ_b = Ω δD_gb/(k_B T), the Bouvard-McMeeking "
               "neck viscosity used by Kratos and MUSEN (note 8).\n\n![effective law](fig_bouvard_mcmeeking.png)\n\n"
               + "GB only: η_eff/η_BM at 1 min ... 16 h = " + ", ".join(f"{r:.12f}" for r in ratios) + "\n\n" + ftab)

    # ---- 4. sensitivity to x0/R
    base = R["cu_1000C"]
    xtab = "| x0/R | x/R at 1 min | rel. diff. to x0/R = 0.01 | x/R at 1 h | rel. diff. |\n|---|---|---|---|---|\n"
    xtab += f"| 0.01 | {at(base, 60.0, 'x_over_R'):.6f} | - | {at(base, 3600.0, 'x_over_R'):.6f} | - |\n"
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    cb = base["csv"]
    ax.loglog(cb["t"][cb["t"] > 0], cb["x_over_R"][cb["t"] > 0], label="x0/R = 0.01")
    d1, d60 = 0.0, 0.0
    for name, run in R.items():
        if not name.startswith("cu_1000C_x0_"):
            continue
        x0 = name.split("_")[-1]
        c = run["csv"]
        ax.loglog(c["t"][c["t"] > 0], c["x_over_R"][c["t"] > 0], "--", label=f"x0/R = {x0}")
        r1 = abs(at(run, 60.0, "x_over_R") / at(base, 60.0, "x_over_R") - 1)
        r2 = abs(at(run, 3600.0, "x_over_R") / at(base, 3600.0, "x_over_R") - 1)
        d1, d60 = max(d1, r1), max(d60, r2)
        xtab += f"| {x0} | {at(run, 60.0, 'x_over_R'):.6f} | {r1:.1e} | {at(run, 3600.0, 'x_over_R'):.6f} | {r2:.1e} |\n"
    F.add("insensitivity to x0/R in {0.01, 0.003" + ("" if a.quick else ", 0.001") + "}: x/R at 1 min", f"max rel. diff. {d1:.1e}",
          "≤ 3e-4 (note 4.6)", d1 <= 3e-4, "no: a property of the model's early stage (x^6 forgets x0); the bound is the note's")
    F.add("insensitivity to x0/R: x/R at 1 h", f"max rel. diff. {d60:.2e}",
          "< 2.5e-5 (the note's '2e-5', one significant digit)", d60 < 2.5e-5, "no (as above)",
          "the note's prototype gives 2.07e-5 (0.003) and 2.09e-5 (0.001) at 1 h")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x / R")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("sensitivity to the initial neck, Cu, R = 50 µm, 1000 C")
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "fig_x0_sensitivity.png"), dpi=110)
    plt.close(fig)
    rep.append("## 4. Sensitivity to the initial neck x0/R\n\n![x0](fig_x0_sensitivity.png)\n\n" + xtab)

    # ---- 5. integrators and invariants
    itab = "| integrator | x/R at 1 h | ΔL/L0 at 1 h | rel. diff. to dp45 | RHS evaluations |\n|---|---|---|---|---|\n"
    x_ref, s_ref = at(base, 3600.0, "x_over_R"), at(base, 3600.0, "shrinkage")
    worst = 0.0
    for integ in ("rk4", "cvode", "arkode"):
        run = R[f"cu_1000C_{integ}"]
        x, s = at(run, 3600.0, "x_over_R"), at(run, 3600.0, "shrinkage")
        d = max(abs(x / x_ref - 1), abs(s / s_ref - 1))
        worst = max(worst, d)
        itab += f"| {integ} | {x:.9f} | {s:.9e} | {d:.1e} | {run['summary']['stats']['rhs_evals']} |\n"
    F.add("DP45 (rtol 1e-10), RK4 (c = 0.005), CVODE and ARKODE (rtol 1e-10) agree at 1 h", f"max rel. diff. {worst:.1e}", "≤ 1e-6",
          worst <= 1e-6, "no: independent integrators of the same equations")
    drift = max(R[f"cu_{tc}C"]["summary"]["max_volume_drift"] for tc in (950, 1000, 1050))
    F.add("volume relative to V(q0) (incl. the fillet), Cu runs at rtol 1e-10", f"max |V/V0 − 1| = {drift:.1e}", "≤ 1e-10",
          drift <= 1e-10, "no: the model conserves volume exactly; the integrator only to its tolerance")
    fe = all(np.all(np.diff(R[f"cu_{tc}C"]["csv"]["free_energy"]) <= 0) for tc in (950, 1000, 1050))
    F.add("free energy never increases (Cu runs, every output row)", "non-increasing" if fe else "increases somewhere", "Ė ≤ 0",
          fe, "no: the model is a gradient flow of E at fixed volume (note 4.5)")
    rep.append("## 5. Integrators and invariants (Cu, 1000 C, 1 h)\n\n" + itab)

    # ---- 6. titanium
    if not a.quick:
        ttab = "| reading | quantity | source | 1 min | 1 h | 4 h |\n|---|---|---|---|---|---|\n"
        notes = {"ti_1300C_stored": ([0.138, 0.271, 0.340], [0.6, 2.4, 3.8], "D_vol0 = 19e-12 (as stored)"),
                 "ti_1300C_dvol_1.9e-7": ([0.196, 0.435, 0.567], [1.1, 5.6, 9.4], "D_vol0 = 1.9e-7")}
        for name, (nx, nd, lab) in notes.items():
            run = R[name]
            mx = [at(run, t, "x_over_R") for t in (60.0, 3600.0, 14400.0)]
            md = [100 * at(run, t, "shrinkage") for t in (60.0, 3600.0, 14400.0)]
            ttab += f"| {lab} | x/R | note | " + " | ".join(f"{v:.3f}" for v in nx) + " |\n"
            ttab += "| | | netsolve | " + " | ".join(f"{v:.4f}" for v in mx) + " |\n"
            ttab += "| | ΔL/L0 [%] | note | " + " | ".join(f"{v:.1f}" for v in nd) + " |\n"
            ttab += "| | | netsolve | " + " | ".join(f"{v:.3f}" for v in md) + " |\n"
            ok = all(abs(m - n) <= 0.5e-3 for m, n in zip(mx, nx)) and all(abs(m - n) <= 0.05 for m, n in zip(md, nd))
            F.add(f"Ti (hpsint set, δ = 0.5 nm), {lab}, R = 25 µm, 1300 C, against note 7.3", "see table",
                  "half a unit in the last printed digit", ok, "yes (same reconstruction)")
        rep.append("## 6. Titanium, the two readings of the note's section 5.2\n\n"
                   "hpsint β-Ti set as shipped in `src/contact/materials/ti.txt` (δ = 0.5 nm assumed for both "
                   "interfaces); the second reading via `--set D_vol0=1.9e-7`. Neither is the paper's Table 4.\n\n" + ttab)
    else:
        for lab in ("D_vol0 = 19e-12 (as stored)", "D_vol0 = 1.9e-7"):
            F.missing(f"Ti (hpsint set, δ = 0.5 nm), {lab}, R = 25 µm, 1300 C, against note 7.3",
                      "half a unit in the last printed digit", "the Ti runs are not part of --quick",
                      "yes (same reconstruction)")

    # ---- experiment
    F.missing("Kingery & Berg (1955) Cu neck growth / shrinkage", "-",
              "the data could not be retrieved here; no numbers are cited", "-")

    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    counts = tally(r[3] for r in F.rows)
    head = (f"# netsolve sinter-pair: validation of the two-particle sintering model\n\n"
            f"Generated {now} by `validation/sintering_pair/run.py`{' --quick' if a.quick else ''}; run folders in "
            f"`{os.path.relpath(runs_dir, REPO)}`. {totals_text(counts)} (MISSING: a line that could not be "
            "evaluated, the reason in its measured column).\n\n"
            "**What is validated.** The model is a *documented reconstruction* "
            "(the model note described in `docs/sintering_pair.md`), not the model of Thomsen et al. used by Ivannikov et al. "
            "(whose flux and material tables are not public). Most lines below compare against the note's tables, "
            "which come from the note's own Python prototype of the same reconstruction: they pass *by construction* "
            "when the implementation is right and say nothing about the physics. The lines marked 'no' test "
            "properties that could fail independently of the note's numbers (exponents, exact identities, "
            "conservation, independent integrators, published closed forms).\n\n"
            "**Experiment.** The paper's reference for copper is Kingery & Berg, J. Appl. Phys. 26 (1955) 1205 "
            "(neck growth of Cu spheres). Their data could not be retrieved here (the note says the same), so no "
            "experimental points are set beside the model and no agreement with experiment is claimed. The Cu "
            "material set itself (note 5.1) is partly [unverified] (γ_s, γ_gb) and partly derived (δ_s D_s).\n\n"
            "## Findings\n\n" + F.table() + "\n")
    with open(os.path.join(outdir, "report.md"), "w") as f:
        f.write(head + "\n".join(rep) + "\n".join(provenance_lines(provenance(REPO, "sintering_pair", [a.netsolve]),
                                                                       counts)) + "\n")
    print(f"report: {os.path.join(outdir, 'report.md')} ({totals_text(counts)})")
    return 0  # FAIL lines are findings of the report; a failed run raises above


if __name__ == "__main__":
    sys.exit(main())
