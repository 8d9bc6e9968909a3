#!/usr/bin/env python3
"""Redanz & Fleck's finding 2 (mu = 0.1 about 10 % below sticking) on converged runs and on the DEM's
quasi-static limit: 1 - Sigma(mu = 0.1) / Sigma(sticking) per seed, from the 16-seed ensemble of
validation/quasistatic_vs_dynamic_walls (ensemble.csv: netsolve's pseudo-transient answer at x1 and the
DEM's fitted sigma0, both from the seed's jammed state at D0 = 0.83, which each friction prepares with
its own law), at D0 + 0.01 and 0.02 in the walls' box. Means with their standard errors; netsolve also
over the seeds whose two runs (mu = 0.1 and sticking) accepted every increment.

usage: /usr/bin/python3 validation/redanz_fleck_walls/finding2_ensemble.py
(the DEM fit is the case's, I = 4e-4 ... 1e-4: ensemble.csv has the low-I fit for mu = 0.1 only)
"""
import argparse
import collections
import csv
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CSV = os.path.join(HERE, "..", "quasistatic_vs_dynamic_walls", "ensemble.csv")
BAND = (0.05, 0.15)  # validation/redanz_fleck_compaction's band for finding 2 (the paper: about 10 %)


def mean_se(v):
    v = np.asarray(v, dtype=float)
    return v.mean(), v.std(ddof=1) / np.sqrt(len(v))


def main():
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    V = collections.defaultdict(dict)
    with open(CSV) as f:
        for r in csv.DictReader(f):
            if r["fit"] == "case":
                V[(r["path"], r["x"], r["col"], r["friction"])][int(r["seed"])] = (
                    float(r["sigma0"]), float(r["net"]), int(r["unaccepted"]))
    print(f"| path | D - D0 | stress | seeds | DEM limit | netsolve | netsolve, fully accepted seeds | band {BAND[0]:g}-{BAND[1]:g} |")
    print("|---|---|---|---|---|---|---|---|")
    for path in ("hydro", "die"):
        for x in ("0.01", "0.02"):
            for col in ("S22", "S11"):
                m, s = V.get((path, x, col, "mu0.1")), V.get((path, x, col, "inf"))
                if not m or not s:
                    continue
                seeds = sorted(set(m) & set(s))
                dem = mean_se([1 - m[k][0] / s[k][0] for k in seeds])
                net = mean_se([1 - m[k][1] / s[k][1] for k in seeds])
                acc = [k for k in seeds if m[k][2] == 0 and s[k][2] == 0]
                neta = mean_se([1 - m[k][1] / s[k][1] for k in acc]) if len(acc) > 1 else (np.nan, np.nan)
                inside = all(BAND[0] <= v <= BAND[1] for v in (dem[0], net[0]))
                print(f"| {path} | {x} | {col} | {len(seeds)} | {dem[0]:.3f} ± {dem[1]:.3f} | {net[0]:.3f} ± {net[1]:.3f} "
                      f"| {neta[0]:.3f} ± {neta[1]:.3f} ({len(acc)}) | {'inside' if inside else 'outside'} |")


if __name__ == "__main__":
    main()
