#!/usr/bin/env python3
"""Plots a sintering run: `demsolve sinter` (or prepare) or `netsolve sinter`.

usage: /usr/bin/python3 apps/scripts/plot_sinter.py RUN_DIR [--label final]

demsolve sinter / prepare (RUN_DIR holds timeseries.csv): reads timeseries.csv, summary.json,
state_<label>.txt or state.txt and contacts_<label>.csv; writes sintering.png (temperature,
k1(T,t)/k1, density and coordination against time, in the style of LMM05 Figs 8-11), sample.png
(the sample in the style of Fig 20: disks coloured by their average stress, contacts blue =
attractive, red = repulsive) and report.md.

netsolve sinter (RUN_DIR holds history.csv; the command writes its own report.md, which names
this script): reads history.csv and writes history.png, two linear panels against t [s]: the
shrinkage per axis shrink_x, shrink_y, shrink_z (-F_ii, the least-squares homogeneous strain of
the centres) and the mean neck x / R_min (docs/staggered.md "Files of a run folder").
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
from matplotlib.patches import Circle, Rectangle  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, data = rows[0], rows[1:]
    out = {}
    for k, h in enumerate(head):
        col = [r[k] for r in data]
        try:
            out[h] = [float(v) for v in col]
        except ValueError:
            out[h] = col
    return out


def read_state(path):
    """Particles (x, y, radius) and box of a demsolve state file (the state archive, docs/dynamic.md)."""
    with open(path) as f:
        j = json.load(f)
    p, b = j["particles"], j["box"]
    return p["x"], p["y"], p["radius"], [b["min"][0], b["min"][1], b["max"][0], b["max"][1]]


def save(fig, path):
    """Writes the figure through a temporary file and a rename (never a half-written PNG)."""
    tmp = os.path.join(os.path.dirname(path) or ".", "." + os.path.basename(path) + ".tmp.png")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, path)


def plot_series(ts, out):
    t = ts["t"]
    fig, ax = plt.subplots(3, 1, figsize=(6.4, 7.5), sharex=True)
    ax[0].plot(t, ts["T"], color="tab:red")
    ax[0].set_ylabel("T [°C]")
    a2 = ax[0].twinx()
    a2.semilogy(t, ts["k1"], color="tab:blue")
    a2.set_ylabel("k1(T,t)/k1", color="tab:blue")
    ax[1].plot(t, ts["nu"], color="k")
    ax[1].set_ylabel("density ν")
    ax[2].plot(t, ts["C"], label="C = (2N_pp + N_pw)/N")
    ax[2].plot(t, ts["C_without_walls"], label="without wall contacts")
    ax[2].plot(t, ts["szz_over_p"], label="σzz/p (top wall)", lw=0.6)
    ax[2].set_ylabel("C, σzz/p")
    ax[2].set_xlabel("t [s]")
    ax[2].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, out)


def plot_sample(state, contacts, out, title):
    xs, ys, rs, box = read_state(state)
    n = len(xs)
    pres = [0.0] * n
    segs, cols, widths = [], [], []
    fmax = 1e-300
    if contacts and os.path.exists(contacts):
        c = read_csv(contacts)
        fmax = max([abs(v) for v in c["f_n"]] + [1e-300])
        for i, j, fn in zip(c["i"], c["j"], c["f_n"]):
            i, j = int(i), int(j)
            segs.append([(xs[i], ys[i]), (xs[j], ys[j])])
            cols.append("tab:blue" if fn < 0 else "tab:red")
            widths.append(0.3 + 2.0 * abs(fn) / fmax)
            # average particle stress from the pair contacts (normal part), Fig 20 colouring
            d = math.hypot(xs[j] - xs[i], ys[j] - ys[i])
            for a, b in ((i, j), (j, i)):
                q = (rs[a] ** 2 - rs[b] ** 2) / (2 * d)
                pres[a] += fn * (0.5 * d + q) / (2 * math.pi * rs[a] ** 2)
    fig, ax = plt.subplots(figsize=(6, 6))
    patches = [Circle((x, y), r) for x, y, r in zip(xs, ys, rs)]
    pc = PatchCollection(patches, cmap="viridis", alpha=0.8, edgecolor="none")
    pc.set_array(pres)
    ax.add_collection(pc)
    if segs:
        ax.add_collection(LineCollection(segs, colors=cols, linewidths=widths))
    if box:
        ax.add_patch(Rectangle((box[0], box[1]), box[2] - box[0], box[3] - box[1], fill=False, lw=1.5))
    fig.colorbar(pc, ax=ax, shrink=0.7, label="average particle stress [N/m]")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_title(title, fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
    fig.tight_layout()
    save(fig, out)


def read_history(path):
    """The columns of netsolve sinter's history.csv (a '# stopped:' line of a stopped run skipped)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(line for line in f if not line.startswith("#")))
    head, data = rows[0], rows[1:]
    return {h: [float(r[k]) for r in data] for k, h in enumerate(head)}


def run_title(run):
    """The title of a netsolve sinter run: the first line of its report.md, else the folder."""
    try:
        with open(os.path.join(run, "report.md")) as f:
            first = f.readline().strip()
        if first.startswith("# "):
            return first[2:]
    except OSError:
        pass
    return f"netsolve sinter: {os.path.basename(os.path.normpath(run))}"


def plot_history(run, out):
    """history.png of a netsolve sinter run: shrinkage per axis and the mean neck against t."""
    h = read_history(os.path.join(run, "history.csv"))
    t = h["t"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4.5))
    fig.suptitle(run_title(run), fontsize=10)
    if len(t) < 2:
        a1.text(0.5, 0.5, "fewer than two rows to plot", ha="center", transform=a1.transAxes)
    else:
        for key, colour in (("shrink_x", "tab:blue"), ("shrink_y", "tab:green"), ("shrink_z", "tab:red")):
            a1.plot(t, h[key], color=colour, lw=2, label=key)
        a2.plot(t, h["neck_mean"], color="tab:purple", lw=2, label="mean neck x / R_min")
        a1.legend(fontsize=8, loc="upper left")
        a2.legend(fontsize=8, loc="upper left")
    a1.set_ylabel("shrinkage -F_ii (homogeneous strain)")
    a2.set_ylabel("neck x / R_min")
    for a in (a1, a2):
        a.set_xlabel("t [s]")
        a.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, out)


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) >= 2 else 2
    run = sys.argv[1]
    if not os.path.exists(os.path.join(run, "timeseries.csv")) and os.path.exists(os.path.join(run, "history.csv")):
        plot_history(run, os.path.join(run, "history.png"))  # netsolve sinter: its report.md is the command's
        print(f"wrote {run}/history.png")
        return 0
    label = sys.argv[sys.argv.index("--label") + 1] if "--label" in sys.argv else "final"
    ts = read_csv(os.path.join(run, "timeseries.csv"))
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    plot_series(ts, os.path.join(run, "sintering.png"))
    state = os.path.join(run, f"state_{label}.txt")
    if not os.path.exists(state):
        state = os.path.join(run, "state.txt")
    plot_sample(state, os.path.join(run, f"contacts_{label}.csv"), os.path.join(run, "sample.png"),
                f"{s['particles']} disks, p = {s['pressure_N_per_m']:g} N/m, t = {s['final']['t']:.3f} s "
                "(red: repulsive, blue: attractive contacts)")
    lines = [f"# demsolve run `{run}`", "", f"Command: `{s['command']}`", ""]
    if "seed" in s:
        lines.append(f"Seed: {s['seed']}")
        lines.append("")
    lines += ["| phase | t [s] | T [°C] | k1(T,t)/k1 | ν | C | C without walls | σxx/p | σzz/p | CPU s |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for p in s.get("phases", []):
        lines.append(f"| {p['phase']} | {p['t']:.4f} | {p['T']:.1f} | {p['k1_over_k1']:.4g} | {p['nu']:.4f} | "
                     f"{p['C']:.3f} | {p['C_without_walls']:.3f} | {p['sxx_over_p']:.4f} | {p['szz_over_p']:.4f} | "
                     f"{p.get('cpu_time_s', float('nan')):.1f} |")
    lines.append("")
    if "densification" in s:
        lines.append(f"Densification ν(t_f)/ν(t_heat) − 1 = {100 * s['densification']:.2f} %.")
    lines.append(f"{s['steps']} steps of {s['dt_s']:.3g} s, {s.get('particle_steps_per_cpu_s', float('nan')):.3g} "
                 "particle-steps per CPU-second.")
    lines += ["", "![sintering](sintering.png)", "", "![sample](sample.png)", ""]
    tmp = os.path.join(run, ".report.md.tmp")
    with open(tmp, "w") as f:
        f.write("\n".join(lines))
    os.replace(tmp, os.path.join(run, "report.md"))
    print(f"wrote {run}/report.md, sintering.png, sample.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
