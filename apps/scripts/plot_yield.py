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

A `netsolve yield --dim 3` run (summary.json "dim": 3) is drawn in the axisymmetric (p, q) plane
(p = -tr S / 3, q = S33 - S11): the isotropic analytic surface of the run (docs/yield_analytic.md
"3D", its (p, q) closed form written again here from the run's D, Z, E and mu_eff), the
fabric-resolved bound at the probe directions (dotted), the curvature and offset points and the
loading point (docs/yield.md "3D").
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


def analytic_pq(an, mu_eff, psi):
    """(p, q) of the isotropic 3D affine surface, normal (cos psi, sin psi) in (ev, eq), for E
    axisymmetric about z (docs/yield_analytic.md "3D", "Axisymmetric closed forms")."""
    a, c = -an["E11"], -an["E33"]
    b, dz = c - a, an["D"] * an["Z"]
    ev, eq = math.cos(psi), math.sin(psi)
    r1, r3 = -ev / 3 - eq / 2, -ev / 3 + eq
    r1, r3 = (0.0 if abs(r) < 1e-15 else r for r in (r1, r3))
    if r1 >= 0 and r3 >= 0:
        return 0.0, 0.0
    m0, m1 = 0.0, 1.0
    if r1 < 0 < r3:
        m1 = math.sqrt(-r1 / (r3 - r1))
    if r3 < 0 < r1:
        m0 = math.sqrt(r1 / (r1 - r3))
    d = lambda k: m1 ** k - m0 ** k  # noqa: E731
    i2 = a * d(3) / 3 + b * d(5) / 5
    ip = a * d(1) + (b - a) * d(3) / 3 - b * d(5) / 5
    prim = lambda m: -(a + b) * (1 - m * m) ** 1.5 / 3 + b * (1 - m * m) ** 2.5 / 5  # noqa: E731
    it = prim(m1) - prim(m0)
    sg = (r3 > r1) - (r3 < r1)
    s33 = -4.5 * dz * (i2 - mu_eff * sg * it)
    s11 = -2.25 * dz * (ip + mu_eff * sg * it)
    return -(2 * s11 + s33) / 3, s33 - s11


def plot_3d(a, rows, s):
    """The (p, q) picture of a 3D run."""
    setup, an = s.get("setup") or {}, s.get("analytic") or {}
    pts = lambda kp, kq: [(value(r[kp]), value(r[kq])) for r in rows  # noqa: E731
                          if math.isfinite(value(r[kp])) and math.isfinite(value(r[kq]))]
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    if an.get("ok") and abs(an.get("E11", 0) - an.get("E22", 1)) < 1e-12 and all(
            an.get(k, 1) == 0 for k in ("E23", "E13", "E12")):
        cur = [analytic_pq(an, setup.get("mu_eff", 0.0), 2 * math.pi * k / 720) for k in range(721)]
        ax.plot([p for p, _ in cur], [q for _, q in cur], "--", color="#888888", lw=1.2,
                label="isotropic affine (run's D, Z, E)")
    fab = sorted(((value(r["psi"]), value(r["p_fabric"]), value(r["q_fabric"])) for r in rows if r["psi"] != ""))
    if fab:
        ax.plot([f[1] for f in fab] + [fab[0][1]], [f[2] for f in fab] + [fab[0][2]], ":", color="tab:green",
                label="fabric-resolved bound")
    for (kp, kq), st, lab in ((("p", "q"), dict(color="tab:blue", marker="o", ls="-", ms=5), "max curvature"),
                              (("p_offset", "q_offset"), dict(mfc="none", mec="tab:red", marker="s", ls="none", ms=7),
                               "offset")):
        P = pts(kp, kq)
        if P:
            ax.plot([p for p, _ in P], [q for _, q in P], label=lab, **st)
    pre = s.get("precompaction") or {}
    if "p" in pre:
        ax.plot([pre["p"]], [pre["q"]], "+", color="black", ms=14, mew=2, ls="none", label="loading point")
    ax.axhline(0, color="#cccccc", lw=0.8)
    ax.set_xlabel("p/σy = −tr Σ / 3σy")
    ax.set_ylabel("q/σy = (Σ33 − Σ11)/σy")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"3D: {setup.get('precompact', '?')} to D = {setup.get('to_density', 0.0):.4g}, friction "
                 f"{setup.get('friction', '?')}, {setup.get('compact_bc', '?')} / {setup.get('probe_bc', '?')}", fontsize=9)
    fig.tight_layout()
    return fig


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
    if s.get("dim") == 3:
        fig = plot_3d(a, rows, s)
    else:
        fig = plot_2d(rows, s)
    out = a.out or os.path.join(a.run, "surface.png")
    tmp = os.path.join(os.path.dirname(out) or ".", "." + os.path.basename(out) + ".tmp.png")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, out)
    print(out)


def plot_2d(rows, s):
    """The (S11, S22) picture of a 2D run."""
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
    return fig


if __name__ == "__main__":
    main()
