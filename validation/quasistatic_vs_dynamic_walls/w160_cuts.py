#!/usr/bin/env python3
"""Issue 28, the cut depth at W = 160: netsolve's pseudo-transient answer with 4 cuts (the default) and
with 8 (`--max-cuts 8`, which accepts every increment there) against the DEM's quasi-static limit, all
three from the same jammed states (docs/quasistatic.md "W = 160: which cut depth is nearer the DEM").

usage: /usr/bin/python3 validation/quasistatic_vs_dynamic_walls/w160_cuts.py [--run] [--runs DIR]
           [--friction mu0.1|inf] [--netsolve PATH] [--demsolve PATH]

Runs (with --run; one at a time, each skipped when its summary.json exists; about 3.5 CPU-hours for
mu = 0.1): per seed 1-3 `demsolve compact --width 160 --boundary walls --to-density 0.83 --save-state`
(the jammed state), then per path (hydrostatic, closed die) to D = 0.85 in 20 increments netsolve
`--iteration pseudo-transient` with 4 and 8 cuts and `demsolve compact` at I = 2e-4, 1e-4 and 5e-5.
The DEM's limit at D = 0.84 and 0.85 is the least-squares line sigma = sigma0 + a I; a line is valid
where se(sigma0) <= 0.5 % of max(|sigma0_11|, |sigma0_22|) (the walls case's rule). Printed: per line the
difference of each netsolve answer from sigma0 in % of that scale, and their mean, largest and count
within the case's 2 % band.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import load_module  # noqa: E402

QVD = load_module("qvd_layer", os.path.join(REPO, "validation", "quasistatic_vs_dynamic", "run.py"))  # its fit()
SEEDS = (1, 2, 3)
PATHS = ("hydrostatic", "closed-die")
INERTIAL = (2e-4, 1e-4, 5e-5)
CUTS = (4, 8)
POINTS = (0.84, 0.85)
FRICTION = {"mu0.1": "0.1", "inf": "inf"}


def plan(runs, fk, netsolve, demsolve):
    """[(folder, command)] in the order they must run (the jammed states first)."""
    fr = FRICTION[fk]
    out = []
    for s in SEEDS:
        out.append((f"{runs}/jam_{fk}_{s}", [demsolve, "compact", "--width", "160", "--seed", str(s), "--boundary", "walls",
                                              "--friction", fr, "--to-density", "0.83", "--save-state", "--snapshots", "",
                                              "--quiet"]))
    for s in SEEDS:
        jam = f"{runs}/jam_{fk}_{s}/jammed.json"
        for p in PATHS:
            common = ["compact", "--boundary", "walls", "--state", jam, "--friction", fr, "--path", p, "--to-density", "0.85",
                      "--increments", "20", "--snapshots", "", "--quiet"]
            for c in CUTS:
                out.append((f"{runs}/net_{fk}_{s}_{p}_c{c}", [netsolve] + common + [
                    "--iteration", "pseudo-transient", "--max-cuts", str(c), "--allow-unconverged"]))
            for i in INERTIAL:
                out.append((f"{runs}/dem_{fk}_{s}_{p}_I{i:g}", [demsolve] + common + ["--inertial-number", f"{i:g}"]))
    return out


def history(folder):
    path = os.path.join(folder, "history.csv")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        rows = [ln.strip().split(",") for ln in f if ln.strip() and not ln.startswith("#")]
    return {k: np.array([float(r[i]) for r in rows[1:]]) for i, k in enumerate(rows[0])}


def at(h, d, col):
    return float(np.interp(d, h["D"], h[col]))


def dem_limit(hs, d, col):
    """sigma0 and its standard error of the line sigma = sigma0 + a I through the DEM runs hs {I: history}."""
    s0, se, _, _ = QVD.fit(sorted(hs), [at(hs[i], d, col) for i in sorted(hs)])
    return s0, se


def summary_of(folder):
    try:
        with open(os.path.join(folder, "summary.json")) as f:
            s = json.load(f)
        return s.get("status", "?"), s.get("solver", {}).get("unconverged_increments")
    except (OSError, ValueError):
        return "missing", None


def evaluate(runs, fk):
    lines = []  # (seed, path, D, col, valid, {cuts: difference in % of the scale})
    print("| seed | path | D | stress | DEM limit sigma0 (se, % of scale) | " + " | ".join(f"netsolve {c} cuts" for c in CUTS) + " |")
    print("|---|---|---|---|---|" + "---|" * len(CUTS))
    for s in SEEDS:
        for p in PATHS:
            dem = {i: history(f"{runs}/dem_{fk}_{s}_{p}_I{i:g}") for i in INERTIAL}
            net = {c: history(f"{runs}/net_{fk}_{s}_{p}_c{c}") for c in CUTS}
            if any(h is None for h in dem.values()) or any(h is None for h in net.values()):
                print(f"| {s} | {p} | | | MISSING (a run of this seed and path is missing: --run) |" + " |" * len(CUTS))
                continue
            for d in POINTS:
                lim = {col: dem_limit(dem, d, col) for col in ("S11", "S22")}
                scale = max(abs(lim["S11"][0]), abs(lim["S22"][0]))
                for col in ("S11", "S22"):
                    s0, se = lim[col]
                    diff = {c: 100 * (at(net[c], d, col) - s0) / scale for c in CUTS}
                    valid = se <= 0.005 * scale
                    lines.append((s, p, d, col, valid, diff))
                    print(f"| {s} | {p} | {d} | {col} | {s0:.4f} ({100 * se / scale:.2f} %{'' if valid else ', invalid'}) | "
                          + " | ".join(f"{diff[c]:+.2f} %" for c in CUTS) + " |")
    for label, sel in (("all lines", lines), ("valid DEM fits", [ln for ln in lines if ln[4]])):
        if not sel:
            continue
        for c in CUTS:
            v = np.array([ln[5][c] for ln in sel])
            print(f"{label} ({len(v)}), {c} cuts: mean {v.mean():+.2f} % (se {v.std(ddof=1) / np.sqrt(len(v)):.2f}), "
                  f"largest |d| {np.abs(v).max():.2f} %, within 2 %: {int(np.sum(np.abs(v) <= 2))}")
    for s in SEEDS:
        for p in PATHS:
            print(f"seed {s} {p}: " + ", ".join(f"{c} cuts {summary_of(f'{runs}/net_{fk}_{s}_{p}_c{c}')}" for c in CUTS))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", action="store_true", help="run the missing runs first (hours)")
    ap.add_argument("--runs", default=os.path.join(HERE, "runs_w160"))
    ap.add_argument("--friction", default="mu0.1", choices=sorted(FRICTION))
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--demsolve", default=os.path.join(REPO, "build", "apps", "demsolve"))
    a = ap.parse_args()
    runs = os.path.abspath(a.runs)
    if a.run:
        for folder, cmd in plan(runs, a.friction, a.netsolve, a.demsolve):
            if os.path.isfile(os.path.join(folder, "summary.json")):
                continue
            print("run:", " ".join(c if c else '""' for c in cmd[1:]), file=sys.stderr, flush=True)
            subprocess.run(cmd + ["--out", folder, "--overwrite"], stdout=subprocess.DEVNULL, check=False)
    evaluate(runs, a.friction)


if __name__ == "__main__":
    main()
