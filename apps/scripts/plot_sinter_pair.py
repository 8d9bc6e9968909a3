#!/usr/bin/env python3
"""Plots a `netsolve sinter-pair` run: x/R and shrinkage Delta L/L0 against time on logarithmic axes.

usage: /usr/bin/python3 apps/scripts/plot_sinter_pair.py RUN_DIR [RUN_DIR...] [--out FILE.png]

Reads RUN_DIR/pair.csv (and summary.json for the legend); writes FILE.png (default RUN_DIR/pair.png for
one run, sinter_pair.png otherwise). The command itself already writes pair.svg with the same curves;
this script is for PNG figures and for several runs on one plot. The model is a documented
reconstruction (docs/sintering_pair.md), not the authors' model.
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
    for d in a.runs:
        c = np.genfromtxt(os.path.join(d, "pair.csv"), delimiter=",", names=True)
        label = os.path.basename(os.path.normpath(d))
        try:
            with open(os.path.join(d, "summary.json")) as f:
                s = json.load(f)
            label += f" ({s['material']['name']}, status {s['status']}{', ' + s['stop'] if s.get('stop', 'ok') != 'ok' else ''})"
        except (OSError, ValueError, KeyError):
            pass
        pos = (c["t"] > 0) & (c["shrinkage"] > 0)
        axs[0].loglog(c["t"][pos], c["x_over_R"][pos], label=label)
        axs[1].loglog(c["t"][pos], c["shrinkage"][pos], label=label)
    for ax, lab in zip(axs, ("x / min(R_A0, R_B0)", "shrinkage ΔL / L0")):
        ax.set_xlabel("t [s]")
        ax.set_ylabel(lab)
        ax.grid(True, which="both", alpha=0.3)
    axs[0].legend(fontsize=7)
    fig.suptitle("netsolve sinter-pair (documented reconstruction of the two-particle model)")
    fig.tight_layout()
    out = a.out or (os.path.join(a.runs[0], "pair.png") if len(a.runs) == 1 else "sinter_pair.png")
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
