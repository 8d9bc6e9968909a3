#!/usr/bin/env python3
"""Plots the yield surface of a `netsolve yield` (or `yield-merge`) run.

usage: /usr/bin/python3 apps/scripts/plot_yield.py RUN_DIR [--out FILE.png]

Reads RUN_DIR/yield_points.csv and summary.json; writes FILE.png (default RUN_DIR/surface.png):
in the (Σ11/σy, Σ22/σy) plane, with equal axes, the analytic affine surface of the run (App. A,
docs/yield_analytic.md; dashed), the yield points by maximum curvature joined in θ order (the
paper's linear interpolation, not closed: tensile probes have no point), the 0.1 % offset points
(open squares) and the loading point (+). The analytic curve is the closed form of
validation/redanz_fleck_yield/analytic_surface.py (hydrostatic and closed-die precompaction, the
two that netsolve yield runs), evaluated at the run's D0, D and measured Z0 (summary.json
setup.analytic). The command draws nothing itself (docs/yield.md "Outputs").
"""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def value(x):
    """A yield_points.csv field: empty where there is no point."""
    return float(x) if x not in ("", None) else math.nan


def analytic_curve(analytic, n=721):
    """The affine analytic surface of setup.analytic, or [] when it cannot be evaluated."""
    sys.path.insert(0, os.path.join(ROOT, "validation", "redanz_fleck_yield"))
    from analytic_surface import closed_form  # noqa: E402
    try:
        d0, d, z0 = analytic["D0"], analytic["D"], analytic["Z0"]
        tr = math.log(d / d0)  # -(E11 + E22)
        E11, E22 = (-tr / 2, -tr / 2) if analytic["dir11"] == analytic["dir22"] else (0.0, -tr)
        return [closed_form(2 * math.pi * k / (n - 1), E11, E22, d, z0) for k in range(n)]
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return []


def title_of(setup, merged):
    t = (f"{setup.get('precompact', '?')} precompaction to D = {setup.get('to_density', 0.0):g}, friction "
         f"{setup.get('friction', '?')}, {setup.get('compact_bc', '?')}-{setup.get('probe_bc', '?')}")
    return t + (" (merged)" if merged else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    with open(os.path.join(a.run, "yield_points.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(a.run, "summary.json")) as f:
        s = json.load(f)
    setup = s.get("setup") or {}
    cur = [(value(r["S11"]), value(r["S22"])) for r in rows]
    cur = [p for p in cur if math.isfinite(p[0]) and math.isfinite(p[1])]
    off = [(value(r["S11_offset"]), value(r["S22_offset"])) for r in rows]
    off = [p for p in off if math.isfinite(p[0]) and math.isfinite(p[1])]
    ana = analytic_curve(setup["analytic"]) if "analytic" in setup else []
    load = setup.get("loading") or {}
    L11, L22 = value(load.get("S11")), value(load.get("S22"))

    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    if len(ana) > 1:
        ax.plot([p[0] for p in ana], [p[1] for p in ana], "--", color="#888888", lw=1.2, label="analytic affine (App. A)")
    if cur:
        ax.plot([p[0] for p in cur], [p[1] for p in cur], "o-", color="tab:blue", ms=5, label="max curvature")
    if off:
        ax.plot([p[0] for p in off], [p[1] for p in off], "s", mfc="none", mec="tab:red", ms=7, ls="none", label="offset")
    if math.isfinite(L11) and math.isfinite(L22):
        ax.plot([L11], [L22], "+", color="black", ms=14, mew=2, ls="none", label="loading point")
    vals = [v for p in ana + cur + off for v in p if math.isfinite(v)] + [v for v in (L11, L22) if math.isfinite(v)]
    lo, hi = min(vals + [0.0]), max(vals + [0.0])
    span = max(hi - lo, 1e-6)
    lo, hi = lo - 0.08 * span, hi + 0.08 * span
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal")
    ax.set_xlabel("Σ11/σy")
    ax.set_ylabel("Σ22/σy")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title_of(setup, "sources" in s), fontsize=9)
    fig.tight_layout()
    out = a.out or os.path.join(a.run, "surface.png")
    tmp = os.path.join(os.path.dirname(out) or ".", "." + os.path.basename(out) + ".tmp.png")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, out)
    print(out)


if __name__ == "__main__":
    main()
