#!/usr/bin/env python3
"""The 3D network against the literature's affine models of cold compaction (issue 30): Fleck (1995),
Helle, Easterling & Ashby (1985) and Arzt (1982), on periodic sphere packings.

usage: /usr/bin/python3 validation/literature_3d/run.py
           [--quick] [--netsolve PATH] [--jobs 2] [--runs DIR] [--force] [--only PATTERN,...]
           [--report-only] [--timeout S]

Packings: `netsolve pack --dim 3 --periodic --n 2000 --seed 1|2|3` (--quick: --n 500, seed 1), as in
validation/compaction_3d. Runs per seed, frictionless unless said:
  * `affine/sS`: `netsolve compact --dim 3 --affine --boundary periodic`, hydrostatic, D0 -> D0 + 0.10 in
    50 increments: the exact affine compaction of the packing (every centre follows the cell);
  * `periodic/sS`: `netsolve compact --dim 3 --boundary periodic`, sticking, D0 -> D0 + 0.03 in 30
    increments (pseudo-transient): the non-affine compaction of validation/compaction_3d;
  * `yield_aa/sS`: `netsolve yield --dim 3 --compact-bc affine`, hydrostatic to D0 + 0.03, 12 affine
    probes in the (p, q) plane;
  * `yield_pa/sS`: the same with the non-affine periodic precompaction of `periodic/sS` (sticking;
    `--compact-bc periodic --probe-bc affine`), against the sticking form of the analytic surface.
The references and bands (fixed before the first run, never widened): README.md of this folder.
"""
import csv
import math
import os
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import MISSING, load_module, provenance, provenance_lines, shown_path, tally  # noqa: E402

P = load_module("qvd_periodic", os.path.join(REPO, "validation", "quasistatic_vs_dynamic_periodic", "run.py"))
Run, fmt = P.Run, P.fmt

CASE = "literature_3d"
FULL = {"name": "full", "n": 2000, "seeds": (1, 2, 3)}
QUICK = {"name": "quick", "n": 500, "seeds": (1,)}
AFFINE_DD, AFFINE_INC = 0.10, 50
PRE_DD, PRE_INC = 0.03, 30
DIRECTIONS = 12
# bands (README.md): Fleck with the initial coordination at D - D0 = 0.01; Helle at 0.02, 0.05, 0.10;
# Arzt's slope; the shape of the affine yield surface (each direction's offset stress over the psi = 0
# one, against the analytic surface's same ratio)
FLECK_AT, FLECK_BAND = 0.01, 0.10
HELLE_AT, HELLE_BAND = (0.02, 0.05, 0.10), 0.25
ARZT_SLOPE, ARZT_BAND = 9.5, 0.25
SHAPE_BAND, SHAPE_MIN = 0.10, 0.1


def pack_dir(runs, seed):
    return os.path.join(runs, "pack", f"s{seed}")


def read_d0(runs, seed):
    s = P.read_preps({"seeds": (seed,)}, runs)
    return None if not s.get(seed) or s[seed].get("status") != "ok" else float(s[seed]["density"])


def to(d0, dd):
    return f"{d0 + dd:.6f}"


def all_runs(mode, runs):
    out = [(f"pack/s{s}", "netsolve", ["pack", "--dim", "3", "--periodic", "--n", str(mode["n"]), "--seed", str(s),
                                       "--quiet"], (s, 0)) for s in mode["seeds"]]
    for s in mode["seeds"]:
        d0 = read_d0(runs, s)
        if d0 is None:
            continue
        pk = os.path.join(pack_dir(runs, s), "packing.csv")
        base = ["--dim", "3", "--packing", pk, "--quiet"]
        out += [
            (f"affine/s{s}", "netsolve", ["compact"] + base + ["--affine", "--boundary", "periodic", "--friction", "0",
                                                              "--to-density", to(d0, AFFINE_DD), "--increments",
                                                              str(AFFINE_INC), "--snapshots", ""], (s, 1)),
            (f"periodic/s{s}", "netsolve", ["compact"] + base + ["--boundary", "periodic", "--friction", "inf",
                                                                "--iteration", "pseudo-transient", "--to-density",
                                                                to(d0, PRE_DD), "--increments", str(PRE_INC),
                                                                "--snapshots", ""], (s, 3)),
            (f"yield_aa/s{s}", "netsolve", ["yield"] + base + ["--compact-bc", "affine", "--friction", "0", "--to-density",
                                                              to(d0, PRE_DD), "--increments", str(PRE_INC),
                                                              "--directions", str(DIRECTIONS)], (s, 2)),
            (f"yield_pa/s{s}", "netsolve", ["yield"] + base + ["--compact-bc", "periodic", "--probe-bc", "affine",
                                                              "--friction", "inf", "--to-density", to(d0, PRE_DD),
                                                              "--increments", str(PRE_INC), "--directions",
                                                              str(DIRECTIONS)], (s, 4)),
        ]
    return out


def p_of(r):
    """Pressure -tr S / 3 of every row of a compact --dim 3 history."""
    return -(r.h["S11"] + r.h["S22"] + r.h["S33"]) / 3.0


def fleck(Z, D, E):
    """Fleck (1995) isotropic affine bound, small strain: p = 1.5 Z D sigma_y |E| (E: the linear strain)."""
    return 1.5 * Z * D * abs(E)


def helle(D, d0):
    """Helle, Easterling & Ashby (1985), stage I: p = 3 D^2 (D - D0) / (1 - D0) sigma_y."""
    return 3.0 * D * D * (D - d0) / (1.0 - d0)


def interp(r, col, x, d0):
    d = r.h["D"] - d0
    return float(np.interp(x, d, r.h[col])) if r.ok and d[0] <= x <= d[-1] + 1e-6 else float("nan")


def read_points(d):
    try:
        with open(os.path.join(d, "yield_points.csv"), newline="") as f:
            return list(csv.DictReader(f))
    except OSError:
        return None


def num(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return float("nan")


def compaction_lines(R, mode, runs):
    rows = []
    for s in mode["seeds"]:
        d0 = read_d0(runs, s)
        a, pr = R.get(f"affine/s{s}"), R.get(f"periodic/s{s}")
        if d0 is None or a is None or not a.ok:
            why = "no packing" if d0 is None else "affine run missing or failed"
            rows.append(dict(seed=s, what="Fleck (1995), initial Z", x=FLECK_AT, ref=None, got=None,
                             verdict=f"{MISSING} ({why})", note=""))
            continue
        p = p_of(a)
        Z0 = float(a.h["Z"][0])
        # Fleck with the initial coordination at D - D0 = FLECK_AT
        pm, D, E = float(np.interp(FLECK_AT, a.h["D"] - d0, p)), d0 + FLECK_AT, interp(a, "E11", FLECK_AT, d0)
        ref = fleck(Z0, D, E)
        ok = abs(pm / ref - 1.0) <= FLECK_BAND
        rows.append(dict(seed=s, what=f"Fleck (1995) p = 1.5 Z0 D σ_y \\|E\\|, Z0 = {Z0:.3f} (touching pairs at D0)",
                         x=FLECK_AT, ref=ref, got=pm, verdict="PASS" if ok else "FAIL",
                         note=f"ratio {pm / ref:.3f}, band ±{100 * FLECK_BAND:g} %"))
        # Fleck with the run's own Z(D): information (an upper bound without the initial overlaps)
        for x in HELLE_AT:
            pm = float(np.interp(x, a.h["D"] - d0, p))
            D, E, Z = d0 + x, interp(a, "E11", x, d0), interp(a, "Z", x, d0)
            rows.append(dict(seed=s, what=f"Fleck (1995) with the run's Z(D) = {Z:.3f} (information)", x=x,
                             ref=fleck(Z, D, E), got=pm, verdict="ratio",
                             note=f"ratio {pm / fleck(Z, D, E):.3f}: the contacts formed after D0 carry less than −2R n·E·n"))
            ref = helle(D, d0)
            ok = abs(pm / ref - 1.0) <= HELLE_BAND
            rows.append(dict(seed=s, what="Helle, Easterling & Ashby (1985) p = 3D²(D − D0)/(1 − D0) σ_y", x=x, ref=ref,
                             got=pm, verdict="PASS" if ok else "FAIL",
                             note=f"ratio {pm / ref:.3f}, band ±{100 * HELLE_BAND:g} %"))
        # Arzt's slope dZ/dD over the affine run
        m = (a.h["D"] - d0) <= AFFINE_DD + 1e-9
        slope = float(np.polyfit(a.h["D"][m], a.h["Z"][m], 1)[0])
        first = float(np.polyfit(a.h["D"][m][: len(a.h["D"][m]) // 5 + 2], a.h["Z"][m][: len(a.h["D"][m]) // 5 + 2], 1)[0])
        ok = abs(slope / ARZT_SLOPE - 1.0) <= ARZT_BAND
        rows.append(dict(seed=s, what="Arzt (1982) dZ/dD = 9.5 (least squares over D0 … D0 + 0.10)", x=AFFINE_DD,
                         ref=ARZT_SLOPE, got=slope, verdict="PASS" if ok else "FAIL",
                         note=f"ratio {slope / ARZT_SLOPE:.3f}, band ±{100 * ARZT_BAND:g} %; over the first fifth: {first:.2f}"))
        # the non-affine compaction, as ratios
        if pr is None or not pr.ok:
            rows.append(dict(seed=s, what="non-affine (periodic, sticking) / affine", x=PRE_DD, ref=None, got=None,
                             verdict=f"{MISSING} (periodic run missing or failed)", note=""))
        else:
            pn = float(np.interp(PRE_DD, pr.h["D"] - d0, p_of(pr)))
            pa = float(np.interp(PRE_DD, a.h["D"] - d0, p))
            D, E, Z = d0 + PRE_DD, interp(pr, "E11", PRE_DD, d0), interp(pr, "Z", PRE_DD, d0)
            ua = P.unaccepted(pr)
            note = (f"/ affine {pn / pa:.3f}; / Fleck (its Z = {Z:.3f}) {pn / fleck(Z, D, E):.3f}; / Helle "
                    f"{pn / helle(D, d0):.3f}; unaccepted increments {ua[0] if ua else '?'}")
            rows.append(dict(seed=s, what="non-affine periodic compaction (sticking): ratios", x=PRE_DD, ref=pa, got=pn,
                             verdict="ratio", note=note))
    return rows


def yield_lines(mode, runs):
    """The shape of the affine yield surface: each direction's offset stress S:E over the psi = 0 one,
    against the isotropic analytic surface's same ratio (the run's D, Z, E); the absolute level at psi = 0
    as information. yield_aa: affine precompaction (graded); yield_pa: non-affine (ratios only)."""
    rows = []
    for s in mode["seeds"]:
        for kind, graded in (("yield_aa", True), ("yield_pa", False)):
            pts = read_points(os.path.join(runs, kind, f"s{s}"))
            label = "affine precompaction" if graded else "periodic (non-affine) precompaction"
            if not pts:
                rows.append(dict(seed=s, kind=kind, psi=None, got=None, ref=None,
                                 verdict=f"{MISSING} ({kind} run missing or failed)", note=label))
                continue
            by = {num(r["psi"]): r for r in pts}
            r0 = by.get(0.0)
            g0, a0, f0 = (num(r0["stress_offset"]), num(r0["stress_analytic"]), num(r0["stress_fabric"])) if r0 else (
                math.nan, math.nan, math.nan)
            rows.append(dict(seed=s, kind=kind, psi=0.0, got=None, ref=None, verdict="ratio",
                             note=f"{label}, the level along ψ = 0: offset Σ:Ê = {g0:.5f} σ_y, / analytic {g0 / a0:.3f}, "
                                  f"/ fabric bound {g0 / f0:.3f}"))
            for r in pts:
                psi = num(r["psi"])
                if psi == 0.0:
                    continue
                g, an, fb = num(r["stress_offset"]), num(r["stress_analytic"]), num(r["stress_fabric"])
                if not (an > SHAPE_MIN * a0):
                    continue  # the analytic surface loads this direction with < 10 % of psi = 0: no line
                rg, ra = g / g0, an / a0
                if not math.isfinite(rg):
                    v = f"{MISSING} (no offset point: {r['status'][:80]})" if graded else "ratio"
                elif graded:
                    v = "PASS" if abs(rg / ra - 1.0) <= SHAPE_BAND else "FAIL"
                else:
                    v = "ratio"
                rows.append(dict(seed=s, kind=kind, psi=psi, got=rg, ref=ra, verdict=v,
                                 note=f"{label}: shape ratio {rg / ra:.3f}; offset / fabric bound {g / fb:.3f}"
                                 if math.isfinite(rg) else label))
    return rows


def figures(R, mode, runs, out):
    figs = []
    s = mode["seeds"][0]
    d0 = read_d0(runs, s)
    a = R.get(f"affine/s{s}")
    if d0 is not None and a is not None and a.ok:
        fig, axs = plt.subplots(1, 2, figsize=(10, 3.8))
        D = a.h["D"]
        axs[0].plot(D, p_of(a), "k-", label="netsolve affine (periodic cell)")
        axs[0].plot(D, fleck(a.h["Z"], D, a.h["E11"]), "C0--", label="Fleck, the run's Z(D)")
        axs[0].plot(D, fleck(a.h["Z"][0], D, a.h["E11"]), "C0:", label="Fleck, Z0")
        axs[0].plot(D, helle(D, d0), "C1-.", label="Helle et al.")
        pr = R.get(f"periodic/s{s}")
        if pr is not None and pr.ok:
            axs[0].plot(pr.h["D"], p_of(pr), "C3-", label="netsolve periodic (sticking)")
        axs[0].set_xlabel("D")
        axs[0].set_ylabel("p [σ_y]")
        axs[0].legend(fontsize=7)
        axs[1].plot(D, a.h["Z"], "k-", label="affine: touching pairs")
        axs[1].plot(D, a.h["Z"][0] + ARZT_SLOPE * (D - d0), "C1--", label="Arzt slope 9.5")
        axs[1].set_xlabel("D")
        axs[1].set_ylabel("Z")
        axs[1].legend(fontsize=7)
        fig.suptitle(f"seed {s}: hydrostatic compaction")
        fig.tight_layout()
        fig.savefig(os.path.join(out, "fig_compaction.png"), dpi=110)
        plt.close(fig)
        figs.append("fig_compaction.png")
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    drawn = False
    for kind, c in (("yield_aa", "k"), ("yield_pa", "C3")):
        pts = read_points(os.path.join(runs, kind, f"s{s}"))
        if not pts:
            continue
        drawn = True
        pts = sorted(pts, key=lambda r: num(r["psi"]))
        ax.plot([num(r["p_offset"]) for r in pts], [num(r["q_offset"]) for r in pts], c + "o",
                label=f"{kind}: 0.1 % offset points")
        ax.plot([num(r["p_analytic"]) for r in pts], [num(r["q_analytic"]) for r in pts], c + "--", lw=0.8,
                label=f"{kind}: isotropic analytic (run's D, Z, E)")
        ax.plot([num(r["p_fabric"]) for r in pts], [num(r["q_fabric"]) for r in pts], c + ":", lw=0.8,
                label=f"{kind}: fabric bound")
    if drawn:
        ax.set_xlabel("p [σ_y]")
        ax.set_ylabel("q = Σ33 − Σ11 [σ_y]")
        ax.legend(fontsize=6)
        ax.set_title(f"seed {s}: yield points in the (p, q) plane")
        fig.tight_layout()
        fig.savefig(os.path.join(out, "fig_yield.png"), dpi=110)
        figs.append("fig_yield.png")
    plt.close(fig)
    return figs


def write_report(R, mode, runs, out):
    crow = compaction_lines(R, mode, runs)
    yrow = yield_lines(mode, runs)
    packs = P.read_preps(mode, runs)
    L = [f"# Validation: the 3D network against the literature's affine compaction models ({mode['name']} mode)", "",
         "Generated by `validation/literature_3d/run.py" + (" --quick" if mode["name"] == "quick" else "") +
         "`; references, bands and why: README.md of this folder. p = −tr Σ/3 and q = Σ33 − Σ11 in units of σ_y. "
         "The formulas of Fleck (1995), Helle et al. (1985) and Arzt (1982) are taken from "
         "`../shared/notes/equilibrium-periodic-3d.md` §3 (marked [recall] there: the papers are not in "
         "`../shared/papers/`); the isotropic affine surface is docs/yield_analytic.md \"3D\". "
         "Lines marked `ratio` are the non-affine runs reported as ratios to these models (the issue's "
         "request), not graded.", "", "## Packings", "",
         "| seed | spheres | D0 | Z | Z without rattlers | rattlers | status |", "|---|---|---|---|---|---|---|"]
    for seed in mode["seeds"]:
        p = packs.get(seed) or {}
        L.append(f"| {seed} | {p.get('particles', '—')} | {fmt(p.get('density'), 4)} | {fmt(p.get('coordination'), 3)} | "
                 f"{fmt(p.get('coordination_without_rattlers'), 3)} | {fmt(p.get('rattler_fraction'), 3)} | "
                 f"{p.get('status', 'missing')} |")
    L += ["", "## Hydrostatic compaction", "",
          "| seed | model | D − D0 | model p | netsolve p | result | note |", "|---|---|---|---|---|---|---|"]
    for r in crow:
        L.append(f"| {r['seed']} | {r['what']} | {r['x']:g} | {fmt(r['ref'], 5)} | {fmt(r['got'], 5)} | {r['verdict']} | "
                 f"{r['note']} |")
    L += ["", "## Yield surfaces (12 affine probes, hydrostatic precompaction to D0 + 0.03, frictionless)", "",
          "Shape lines: the offset point's stress Σ:Ê along ψ over the one along ψ = 0, against the same ratio of the "
          f"isotropic analytic surface; band ±{100 * SHAPE_BAND:g} % for the affine precompaction, directions the "
          f"analytic surface loads with at least {100 * SHAPE_MIN:g} % of ψ = 0.", "",
          "| seed | run | ψ [°] | analytic ratio | netsolve ratio | result | note |", "|---|---|---|---|---|---|---|"]
    for r in yrow:
        L.append(f"| {r['seed']} | {r['kind']} | {fmt(r['psi'], 0)} | {fmt(r['ref'], 4)} | {fmt(r['got'], 4)} | "
                 f"{r['verdict']} | {r['note']} |")
    figs = figures(R, mode, runs, out)
    c = tally([r["verdict"] for r in crow] + [r["verdict"] for r in yrow])
    L += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figs]
    L += ["", "## Runs", ""] + P.run_table(R, sorted(R))
    notes = os.path.join(HERE, "notes.md")
    if os.path.isfile(notes):
        L += ["", "## Notes (notes.md, written by hand)", "", open(notes, encoding="utf-8").read().strip()]
    prov = provenance(REPO, CASE, [])
    prov["binaries"] = {f"netsolve (the runs' meta.json)": ", ".join(sorted({(r.meta or {}).get("binary_sha256", "?")
                                                                          for r in R.values() if r.meta}))}
    L += provenance_lines(prov, c)
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(L) + "\n")
    print(f"report: {shown_path(os.path.join(out, 'report.md'), REPO)} ({c})")


def main():
    a, runs, out, only, bins = P.parse_case_args(__doc__, HERE, "pack/*,affine/*")
    mode = QUICK if a.quick else FULL
    if not a.report_only:
        P.run_all(a.jobs, bins, runs, a.force, a.timeout, [p for p in all_runs(mode, runs) if p[0].startswith("pack/")
                                                           and P.selected(p[0], only)])
        P.run_all(a.jobs, bins, runs, a.force, a.timeout, [r for r in all_runs(mode, runs)
                                                           if not r[0].startswith("pack/") and P.selected(r[0], only)])
    R = {name: Run(os.path.join(runs, name), tool) for name, tool, _, _ in all_runs(mode, runs)
         if not name.startswith("pack/")}
    write_report(R, mode, runs, out)


if __name__ == "__main__":
    main()
