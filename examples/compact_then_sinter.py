"""Compaction then sintering of the same packing (3D spheres, SI units).

Which tools share a packing: `netdem.netsolve.compact` is 2D (disks, the plastic-indentation law)
and `netdem.netsolve.sinter` is 3D (spheres, Ivannikov et al.'s staggered scheme), so they do not.
The route the libraries support is the green body of `netdem.netsolve.pack(dim=3,
route="green-body")`: a random cloud of spheres settles under gravity and is compacted by a
triaxial compression with the 3D DEM to a target density (Ivannikov et al. 3.2); its packing.csv is
what `netdem.netsolve.sinter(packing=...)` sinters (this is also what `netsolve sinter --generate
cu` does in one process). The other pair, in 2D with Luding's sintering law, is
`netdem.demsolve.prepare` (pressure-controlled compression) then `netdem.demsolve.sinter`.

    PYTHONPATH=build/python /usr/bin/python3 examples/compact_then_sinter.py [--small] [--out DIR]

Writes DIR/green (the green body: packing.csv, laminar.csv, particles.vtp, summary.json),
DIR/sinter (history.csv, the snapshots and snapshots.pvd for ParaView, ...) and
DIR/compact_then_sinter.png (density and mean neck against time).
--small: 60 spheres to density 0.50, 500 s at 1293 K (about a second); default: the Cu benchmark,
805 spheres to 0.58 and 5000 s (15 s measured).
"""
import argparse
import csv
import os
import sys

import matplotlib.pyplot as plt
import numpy as np

import netdem


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="60 spheres and 500 s (the ctest run)")
    ap.add_argument("--out", default="results/examples/compact_then_sinter", help="output folder")
    args = ap.parse_args()
    n, density, t_end = (60, 0.50, 500.0) if args.small else (805, 0.58, 5000.0)
    os.makedirs(args.out, exist_ok=True)
    green_dir, sinter_dir = os.path.join(args.out, "green"), os.path.join(args.out, "sinter")

    # 1. compaction: the green body (Cu spheres of mean diameter 50 um)
    green = netdem.netsolve.pack(dim=3, route="green-body", n=n, target_density=density, quiet=True,
                                 out=green_dir, overwrite=True)
    print(f"green body: status {green.status}, density {green.summary['density']['box']:.4f}")
    if green.status != "ok":
        print(f"the green body did not reach density {density}: {green.summary.get('status_reason')}", file=sys.stderr)
        return 1

    # 2. sintering of that packing at 1293 K
    s = netdem.netsolve.sinter(packing=os.path.join(green_dir, "packing.csv"), time=t_end, quiet=True,
                               out=sinter_dir, overwrite=True)
    h = s.history
    print(f"sintering: status {s.status}, density {h['density'][0]:.4f} -> {h['density'][-1]:.4f}, "
          f"mean neck x/R {h['neck_mean'][-1]:.3f} after {h['t'][-1]:g} s")

    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 4))
    a.plot(h["t"], h["density"]), a.set_xlabel("t [s]"), a.set_ylabel("density")
    b.plot(h["t"], h["neck_mean"]), b.set_xlabel("t [s]"), b.set_ylabel("mean neck x / R")
    fig.suptitle(f"{n} Cu spheres: green body at {density}, sintered at 1293 K")
    fig.tight_layout()
    png = os.path.join(args.out, "compact_then_sinter.png")
    fig.savefig(png, dpi=100)
    print(f"wrote {png}")
    return check(green_dir, n, s, t_end, png)


def check(green_dir, n, s, t_end, png):
    """What the pair must satisfy (the ctest test runs --small): the green body has the spheres
    asked for, the sintering ran on them to the end time, and it densifies: the density never
    falls and ends above the start, every box dimension shrinks and the mean neck grows."""
    errors = []
    with open(os.path.join(green_dir, "packing.csv"), newline="") as f:
        spheres = sum(1 for r in csv.reader(f) if r and not r[0].startswith("#")) - 1
    if spheres != n:
        errors.append(f"green body has {spheres} spheres, asked for {n}")
    h = s.history
    if s.status != "ok":
        errors.append(f"sintering status {s.status}")
    if abs(h["t"][-1] - t_end) > 1e-9 * t_end:
        errors.append(f"sintering stopped at t = {h['t'][-1]}")
    if not all(np.all(np.isfinite(h[k])) for k in ("density", "neck_mean", "shrink_x", "shrink_y", "shrink_z")):
        errors.append("non-finite values in history.csv")
    if np.any(np.diff(h["density"]) < -1e-12) or not h["density"][-1] > h["density"][0]:
        errors.append(f"density does not rise: {h['density'][0]} -> {h['density'][-1]}")
    if not all(h[k][-1] > 0 for k in ("shrink_x", "shrink_y", "shrink_z")):
        errors.append("a box dimension did not shrink")
    if not h["neck_mean"][-1] > h["neck_mean"][0]:
        errors.append("the mean neck did not grow")
    if not (os.path.isfile(png) and os.path.getsize(png) > 0):
        errors.append(f"no {png}")
    for e in errors:
        print(f"check failed: {e}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
