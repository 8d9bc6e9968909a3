#!/usr/bin/env python3
"""Analytic affine upper-bound yield surfaces of Redanz & Fleck 2001, Appendix A (docs/yield_analytic.md).

usage: /usr/bin/python3 validation/redanz_fleck_yield/analytic_surface.py
           [--d0 0.814] [--density 0.85] [--z0 4] [--out validation/redanz_fleck_yield/analytic_surface.png]

Plots the hydrostatic (E11 = E22) and closed-die (E11 = 0) surfaces, normalised by sigma_y, for a
precompaction from relative density d0 to density with Z0 contacts per particle (Fig 9 of the paper,
affine curves), marks the loading points (vertices), draws the strain-rate directions (outward normals)
at a few points and prints a markdown table. Independent of the C++ code (src/quasistatic/analytic_yield.cpp):
elementary closed forms of docs/yield_analytic.md, checked here against a numerical quadrature of the
force moments. Needs numpy and matplotlib (Debian: python3-numpy, python3-matplotlib).
"""
import argparse
import math
import os

import numpy as np


def closed_form(theta, E11, E22, density, z0, sigma_y=1.0):
    """Stress (S11, S22) for the rate direction theta; E11 == E22 or E11 == 0 (elementary forms)."""
    e1, e2 = math.cos(theta), math.sin(theta)
    e1 = 0.0 if abs(e1) < 1e-15 else e1
    e2 = 0.0 if abs(e2) < 1e-15 else e2
    if e1 >= 0 and e2 >= 0:
        return 0.0, 0.0
    lo, hi = 0.0, math.pi / 2
    if e1 * e2 < 0:
        ps = math.atan(math.sqrt(-e1 / e2))  # theta_c of A9-A12 with the typo fixed
        lo, hi = (0.0, ps) if e1 < 0 else (ps, math.pi / 2)
    k = 12 / math.pi**2 * density * z0 * sigma_y
    if E11 == E22:  # hydrostatic: sqrt(-2E) constant
        a = math.sqrt(-2 * E11)
        P = lambda f: f / 2 + math.sin(2 * f) / 4
        Q = lambda f: f / 2 - math.sin(2 * f) / 4
    elif E11 == 0:  # closed die: sqrt(-2 E22) sin(phi)
        a = math.sqrt(-2 * E22)
        P = lambda f: -math.cos(f) ** 3 / 3
        Q = lambda f: -math.cos(f) + math.cos(f) ** 3 / 3
    else:
        raise ValueError("elementary forms only for E11 == E22 or E11 == 0")
    return -k * a * (P(hi) - P(lo)), -k * a * (Q(hi) - Q(lo))


def quadrature(theta, E11, E22, density, z0, sigma_y=1.0, n=64):
    """The same stress by Gauss-Legendre quadrature over the active contact angles (any E11, E22 <= 0)."""
    e1, e2 = math.cos(theta), math.sin(theta)
    if e1 >= 0 and e2 >= 0:
        return 0.0, 0.0
    lo, hi = 0.0, math.pi / 2
    if e1 * e2 < 0:
        ps = math.atan(math.sqrt(-e1 / e2))
        lo, hi = (0.0, ps) if e1 < 0 else (ps, math.pi / 2)
    x, w = np.polynomial.legendre.leggauss(n)
    phi = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x
    w = 0.5 * (hi - lo) * w
    c2, s2 = np.cos(phi) ** 2, np.sin(phi) ** 2
    root = np.sqrt(np.maximum(0.0, -2 * (E11 * c2 + E22 * s2)))
    k = 12 / math.pi**2 * density * z0 * sigma_y
    return -k * np.sum(w * root * c2), -k * np.sum(w * root * s2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--d0", type=float, default=0.814, help="relative density before precompaction")
    ap.add_argument("--density", type=float, default=0.85, help="relative density after precompaction")
    ap.add_argument("--z0", type=float, default=4.0, help="coordination number (constant)")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "analytic_surface.png"))
    args = ap.parse_args()
    if not (0 < args.d0 <= args.density <= 1 and args.z0 > 0):
        raise SystemExit("need 0 < d0 <= density <= 1 and z0 > 0")
    eps = math.log(args.density / args.d0)  # -(E11 + E22)
    cases = {"hydrostatic": (-eps / 2, -eps / 2), "closed die": (0.0, -eps)}
    thetas = np.radians(np.linspace(0, 360, 1441))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 5))
    print(f"D0 = {args.d0}, D = {args.density}, Z0 = {args.z0}: -(E11 + E22) = {eps:.6f}")
    print("| θ (deg) | " + " | ".join(f"{n} Σ11/σy | {n} Σ22/σy" for n in cases) + " |")
    print("|---" * (1 + 2 * len(cases)) + "|")
    for deg in (95, 135, 175, 225, 275, 315, 355):
        row = [closed_form(math.radians(deg), *E, args.density, args.z0) for E in cases.values()]
        print(f"| {deg} | " + " | ".join(f"{s11:.4f} | {s22:.4f}" for s11, s22 in row) + " |")
    for ax, (name, (E11, E22)) in zip(axes, cases.items()):
        pts = np.array([closed_form(t, E11, E22, args.density, args.z0) for t in thetas])
        err = max(np.hypot(*np.subtract(closed_form(t, E11, E22, args.density, args.z0),
                                        quadrature(t, E11, E22, args.density, args.z0)))
                  for t in np.radians(np.arange(1, 360, 7.0)))
        scale = np.abs(pts).max()
        print(f"{name}: loading point ({pts[720][0]:.5f}, {pts[720][1]:.5f}) sigma_y; "
              f"max |closed form - quadrature| = {err / scale:.1e} of the loading stress")
        ax.plot(pts[:, 0], pts[:, 1], "k-", lw=1.5, label="affine upper bound")
        ax.plot([], [], color="tab:blue", lw=0.8, label="strain-rate direction (normal)")
        ax.plot([pts[720][0]], [pts[720][1]], "ko", ms=5)
        for deg in (100, 120, 135, 150, 165, 200, 225, 250, 285, 300, 315, 330, 345):
            t = math.radians(deg)
            s11, s22 = closed_form(t, E11, E22, args.density, args.z0)
            ax.annotate("", xy=(s11 + 0.08 * scale * math.cos(t), s22 + 0.08 * scale * math.sin(t)),
                        xytext=(s11, s22), arrowprops=dict(arrowstyle="->", color="tab:blue", lw=0.8),
                        annotation_clip=False)
        ax.axhline(0, color="0.8", lw=0.5)
        ax.axvline(0, color="0.8", lw=0.5)
        ax.margins(0.15)
        ax.set_aspect("equal")
        ax.set_xlabel(r"$\Sigma_{11}/\sigma_y$")
        ax.set_ylabel(r"$\Sigma_{22}/\sigma_y$")
        ax.set_title(f"{name} precompaction, D = {args.density}, Z0 = {args.z0:g}\n"
                     f"(E11, E22) = ({E11:.4f}, {E22:.4f}) from D0 = {args.d0}", fontsize=9)
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
