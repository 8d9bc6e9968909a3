#!/usr/bin/env python3
"""Plots a `netsolve sinter-pair` run: x/R and shrinkage Delta L/L0 against time on logarithmic axes.

usage: /usr/bin/python3 apps/scripts/plot_sinter_pair.py RUN_DIR [RUN_DIR...] [--out FILE.png]

Reads RUN_DIR/pair.csv (and summary.json for the legend and the title); writes FILE.png (default
RUN_DIR/pair.png for one run, sinter_pair.png otherwise): x / min(R_A0, R_B0) and the shrinkage
Delta L / L0 against t [s], log-log, the rows with t > 0 and both quantities > 0. The command draws
nothing itself: this script is its plot, for one run or several on one figure. The model is a
documented reconstruction (docs/sintering_pair.md), not the authors' model.
"""
import argparse
import json
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    title = "netsolve sinter-pair (documented reconstruction of the two-particle model)"
    for d in a.runs:
        c = np.genfromtxt(os.path.join(d, "pair.csv"), delimiter=",", names=True)
        label = os.path.basename(os.path.normpath(d))
        try:
            with open(os.path.join(d, "summary.json")) as f:
                s = json.load(f)
            label += f" ({s['material']['name']}, status {s['status']}{', ' + s['stop'] if s.get('stop', 'ok') != 'ok' else ''})"
            if len(a.runs) == 1:
                T = s["temperature"]
                temp = f"T = {T['constant_K']:g} K" if "constant_K" in T else "T(t) profile"
                title = (f"sinter-pair {s['material']['name']}: R = {s['radii_m'][0]:g}, {s['radii_m'][1]:g} m, {temp} "
                         "(documented reconstruction)")
        except (OSError, ValueError, KeyError):
            pass
        c = np.atleast_1d(c)
        pos = (c["t"] > 0) & (c["shrinkage"] > 0) & (c["x_over_R"] > 0)
        axs[0].loglog(c["t"][pos], c["x_over_R"][pos], label=label)
        axs[1].loglog(c["t"][pos], c["shrinkage"][pos], label=label)
    for ax, lab in zip(axs, ("x / min(R_A0, R_B0)", "shrinkage ΔL / L0")):
        ax.set_xlabel("t [s]")
        ax.set_ylabel(lab)
        ax.grid(True, which="both", alpha=0.3)
    axs[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    out = a.out or (os.path.join(a.runs[0], "pair.png") if len(a.runs) == 1 else "sinter_pair.png")
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
