"""Yield surface of a compacted powder, plotted with matplotlib.

`netdem.netsolve.yield_` precompacts a 2D packing of disks hydrostatically to D = 0.85, unloads it
elastically and reloads it along N strain-rate directions in the (E11, E22) plane (Redanz & Fleck
2001, section 3.4; docs/yield.md). Each probe's yield point is in `.yield_points` (yield_points.csv):
S11, S22 at the curvature point (tension positive, in units of the solid's yield stress). Probes
that unload the compact (extension directions) find no yield point: a compact without bonds has
no tensile strength; their S11, S22 are NaN and their `status` says why. The plot also shows the
analytic surface that netsolve yield computes from the contact fabric (S11_analytic, S22_analytic).

    PYTHONPATH=build/python /usr/bin/python3 examples/yield_surface.py [--small] [--out DIR]

Writes DIR/yield_surface.png and the run folder DIR/run (yield_points.csv, summary.json, ...).
--small: W = 24 R and 8 directions (under a second); default: W = 80 R and 24 directions, one
probe per core (25 s measured on a 2-core machine with one core busy).
"""
import argparse
import os
import sys

import matplotlib.pyplot as plt
import numpy as np

import netdem


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="a small box and 8 directions (the ctest run)")
    ap.add_argument("--out", default="results/examples/yield_surface", help="output folder")
    args = ap.parse_args()
    width, directions, jobs = (24, 8, 1) if args.small else (80, 24, 0)
    os.makedirs(args.out, exist_ok=True)

    r = netdem.netsolve.yield_(width=width, directions=directions, jobs=jobs, quiet=True,
                               out=os.path.join(args.out, "run"), overwrite=True)
    yp = r.yield_points
    found = yp["status"] == "ok"
    print(f"status {r.status}: {found.sum()} of {len(yp['probe'])} probes found a yield point")

    fig, ax = plt.subplots(figsize=(5, 5))
    order = np.argsort(yp["theta"])
    order = np.append(order, order[0])  # closed
    ax.plot(yp["S11_analytic"][order], yp["S22_analytic"][order], "--", color="grey", label="analytic (fabric)")
    ax.plot(yp["S11"][found], yp["S22"][found], "o-", label="netsolve yield (curvature point)")
    ax.axhline(0, color="k", lw=0.5), ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel(r"$\Sigma_{11}/\sigma_y$"), ax.set_ylabel(r"$\Sigma_{22}/\sigma_y$")
    ax.set_title(f"W = {width} R, D = 0.85, {directions} probes"), ax.set_aspect("equal"), ax.legend()
    png = os.path.join(args.out, "yield_surface.png")
    fig.savefig(png, dpi=100)
    print(f"wrote {png}")
    return check(r, directions, png)


def check(r, directions, png):
    """What a run must satisfy (the ctest test runs --small): the number of probes asked for, a
    finite compressive yield point for every probe that reports one, and at least half of them."""
    yp = r.yield_points
    found = yp["status"] == "ok"
    errors = []
    if r.status != "ok":
        errors.append(f"run status {r.status}")
    if len(yp["probe"]) != directions:
        errors.append(f"{len(yp['probe'])} probes, asked for {directions}")
    if not np.all(np.isfinite(yp["S11_analytic"]) & np.isfinite(yp["S22_analytic"])):
        errors.append("non-finite analytic points")
    if 2 * found.sum() < directions:
        errors.append(f"only {found.sum()} of {directions} probes found a yield point")
    if not np.all(np.isfinite(yp["S11"][found]) & np.isfinite(yp["S22"][found])):
        errors.append("a probe reports a yield point that is not finite")
    if not np.all(yp["S11"][found] + yp["S22"][found] < 0):
        errors.append("a yield point with a tensile mean stress")
    if not (os.path.isfile(png) and os.path.getsize(png) > 0):
        errors.append(f"no {png}")
    for e in errors:
        print(f"check failed: {e}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
