#!/usr/bin/env python3
"""Plots a netsolve compaction run and writes its short report.

usage: plot_run.py RUN_DIR

Reads RUN_DIR/history.csv, summary.json and packing.csv; writes compaction.png (normalised stresses
and coordination against density), packing.png (2D: the initial packing with its contact network;
3D, `netsolve compact --dim 3`: the initial spheres seen from an oblique direction, as
plot_packing3d.py draws them) and report.md.
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection, PatchCollection  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    head, data = rows[0], rows[1:]
    return {h: [float(r[k]) for r in data] for k, h in enumerate(head)}


def dim_of(run):
    """2 or 3: summary.json's dim (a 2D run's summary has none)."""
    with open(os.path.join(run, "summary.json")) as f:
        return json.load(f).get("dim", 2)


def read_packing(path):
    box = None
    xs, ys, rs = [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith("# box"):
                box = [float(v) for v in line.split()[2:6]]
            elif line.startswith("#") or line.startswith("id"):
                continue
            elif line.strip():
                _, x, y, r = line.strip().split(",")
                xs.append(float(x)); ys.append(float(y)); rs.append(float(r))
    return box, xs, ys, rs


def plot_packing(run, png):
    if dim_of(run) == 3:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import plot_packing3d  # noqa: E402 (this folder's)
        P, box = plot_packing3d.read_packing3d(os.path.join(run, "packing.csv"))
        plot_packing3d.draw(P, box, png, title=f"initial packing: {len(P)} spheres (colour: height)")
        return
    box, xs, ys, rs = read_packing(os.path.join(run, "packing.csv"))
    fig, ax = plt.subplots(figsize=(6, 6))
    circles = [Circle((x, y), r) for x, y, r in zip(xs, ys, rs)]
    ax.add_collection(PatchCollection(circles, facecolor="#c9d6e8", edgecolor="#50607a", linewidths=0.3))
    segs = []
    n = len(xs)
    cell = 2.3 * max(rs)
    grid = {}
    for k in range(n):
        grid.setdefault((int(xs[k] // cell), int(ys[k] // cell)), []).append(k)
    for k in range(n):
        cx, cy = int(xs[k] // cell), int(ys[k] // cell)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for q in grid.get((cx + dx, cy + dy), []):
                    if q > k and math.hypot(xs[q] - xs[k], ys[q] - ys[k]) <= (rs[q] + rs[k]) * (1 + 1e-6):
                        segs.append([(xs[k], ys[k]), (xs[q], ys[q])])
    ax.add_collection(LineCollection(segs, colors="#b03030", linewidths=0.6))
    ax.set_xlim(box[0], box[2]); ax.set_ylim(box[1], box[3]); ax.set_aspect("equal")
    ax.set_title(f"ballistic deposition: {n} disks, {len(segs)} contacts")
    ax.set_xlabel("x / R"); ax.set_ylabel("y / R")
    fig.tight_layout(); fig.savefig(png, dpi=130); plt.close(fig)


def plot_compaction(h, summary, png):
    # a run with --precompact-density (column 'leg'): against the increment, the legs apart, since
    # a constant-volume path does not move the density
    legs = "leg" in h
    x = h["increment"] if legs else h["D"]
    xlabel = "increment (leg 0: precompaction, leg 1: path)" if legs else "relative density D"
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.plot(x, [-v for v in h["S22"]], label=r"$-\Sigma_{22}/\sigma_y$")
    a1.plot(x, [-v for v in h["S11"]], "--", label=r"$-\Sigma_{11}/\sigma_y$")
    if "S33" in h:
        a1.plot(x, [-v for v in h["S33"]], "-.", label=r"$-\Sigma_{33}/\sigma_y$")
    if legs:
        a1.plot(x, [-v for v in h["S12"]], ":", label=r"$-\Sigma_{12}/\sigma_y$")
    a1.set_xlabel(xlabel); a1.set_ylabel("normalised stress"); a1.legend(); a1.grid(alpha=0.3)
    a1.set_title(f"{summary['path']['name']}, {summary['mode']}, friction {summary['friction']}")
    a2.plot(x, h["Z"])
    a2.set_xlabel(xlabel); a2.set_ylabel("coordination Z (load-bearing)"); a2.grid(alpha=0.3)
    if legs:
        end0 = max(k for k, leg in zip(h["increment"], h["leg"]) if leg == 0)
        for a in (a1, a2):
            a.axvline(end0, color="0.5", lw=0.8, ls="--")
    fig.tight_layout(); fig.savefig(png, dpi=130); plt.close(fig)


def leg_lines(summary):
    """Report rows of a run with --precompact-density: each leg's target and end."""
    out = []
    for leg in summary.get("legs", []):
        target = f"D = {leg['to_density']}" if "to_density" in leg else f"‖E‖ = {leg['to_strain']}"
        end = leg["end"]
        if end is None:
            out.append(f"| leg {leg['leg']} ({leg['name']}, {leg['path']} to {target}) | not reached |")
            continue
        out.append(f"| leg {leg['leg']} ({leg['name']}, {leg['path']} to {target}, {leg['increments']} increments) | "
                   f"D = {end['D']:.4f}, Σ11 = {end['S11']:.4f}, Σ22 = {end['S22']:.4f}, Σ12 = {end['S12']:.4f}"
                   + (f", ‖E‖ = {end['strain']:.6g}" if "strain" in end else "") + " |")
    return out


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: plot_run.py RUN_DIR")
    run = sys.argv[1]
    h = read_csv(os.path.join(run, "history.csv"))
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    plot_compaction(h, s, os.path.join(run, "compaction.png"))
    plot_packing(run, os.path.join(run, "packing.png"))
    fin = s["final"]
    three = s.get("dim", 2) == 3
    last = "S33" if three else "S22"  # the compaction axis of the closed die (z in 3D, y in 2D)
    ratio = fin[last] / fin["S11"] if fin["S11"] else float("nan")
    t = s["timing_s"]
    stress_rows = ([f"| Σ{a}/σy | {fin['S' + a]:.4f} |" for a in ("11", "22", "33", "23", "13", "12")] if three else
                   [f"| Σ11/σy | {fin['S11']:.4f} |", f"| Σ22/σy | {fin['S22']:.4f} |"])
    lines = [
        "# netsolve compaction run" + (" (3D: spheres)" if three else ""), "",
        f"Command: `{s['command']}`", "",
        f"Packing: {s['packing']} ({s['particles']} particles, D0 = {s['initial_density']:.4f}, seed {s['seed']})", "",
        "| quantity | value |", "|---|---|",
        f"| final density D | {fin['D']:.4f} |",
        *stress_rows,
        f"| Σ{last[1:]}/Σ11 | {ratio:.3f} |",
        *([f"| asymmetry (Σ12-Σ21)/2σy | {fin['S_asym']:.2e} |"] if "S_asym" in fin else []),
        f"| coordination Z | {fin['Z']:.3f} |",
        f"| sliding contacts | {fin['sliding']} of {fin['contacts']} |",
        f"| increments (unconverged) | {s['increments']} ({s['solver']['unconverged_increments']}) |",
        f"| max residual / mean contact force | {s['solver']['max_residual']:.2e} |",
        f"| wall time | {t['wall']:.2f} s (factorise {t['factorise']:.2f} s, solve {t['solve']:.2f} s, assemble {t['assemble']:.2f} s) |",
        *leg_lines(s),
        "", "![compaction curve](compaction.png)", "", "![initial packing](packing.png)", "",
    ]
    with open(os.path.join(run, "report.md.tmp"), "w") as f:
        f.write("\n".join(lines))
    os.replace(os.path.join(run, "report.md.tmp"), os.path.join(run, "report.md"))
    print(f"plot_run: wrote {run}/report.md, compaction.png, packing.png")


if __name__ == "__main__":
    main()
