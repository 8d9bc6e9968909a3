#!/usr/bin/env python3
"""Redanz & Fleck's frictionless compaction findings (3a, 3b, 6a, 7a/7b; 1c beside them) re-evaluated on
converged runs with walls and on the DEM limit (issue 28, "Redanz & Fleck's frictionless findings").

usage: /usr/bin/python3 validation/redanz_fleck_frictionless/run.py
           [--quick] [--netsolve PATH] [--demsolve PATH] [--jobs 2] [--runs DIR] [--force]
           [--only PATTERN,...] [--report-only] [--timeout S]

The paper's die (a prescribed peripheral layer) does not hold a converged frictionless packing: without
the drag in the answer the disks are extruded through it (docs/quasistatic.md, "Frictionless: the die
leaks"). This case departs from the paper's boundary: four rigid frictionless walls around the same
ballistic deposition (W = 80, seeds 1-8; --quick: W = 40, seeds 1-2), driven hydrostatically or as a
closed die to D = 0.85. Runs per seed:
  * `demsolve compact --boundary walls --friction 0` from the deposition, hydrostatic and closed die, at
    I = 1.5e-4 (the tool's default) and 5e-5: the DEM limit, with its distance shown by the two rates;
  * the same, sticking, hydrostatic, at I = 1.5e-4 (finding 1c's reference);
  * `demsolve compact ... --to-density 0.84 --save-state` (hydrostatic, mu = 0: every wall loaded, Z 3.9)
    and from its jammed.json `netsolve compact --boundary walls --iteration pseudo-transient` to 0.85:
    the converged network's answer where the network has one (a frictionless packing below jamming is a
    mechanism: its quasi-static stress is zero, so netsolve cannot start from the deposition);
  * `netsolve compact --affine --friction 0` from the same deposition (the affine reference of 3a; the
    walls exclude --affine, so it runs in the die's box and is compared at the same strain, its stress
    scaled to the walls' box area, see the report).
The findings' definitions and bands are validation/redanz_fleck_compaction/run.py's (never widened);
each is evaluated per seed, and over the seeds as mean +- standard error, graded on the mean.
"""
import argparse
import math
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import (MISSING, load_module, missing_text, provenance, provenance_lines, shown_path,  # noqa: E402
                          tally, verdict)

Q = load_module("qvd", os.path.join(REPO, "validation", "quasistatic_vs_dynamic", "run.py"))
PER = load_module("qvd_periodic", os.path.join(REPO, "validation", "quasistatic_vs_dynamic_periodic", "run.py"))

CASE = "redanz_fleck_frictionless"
TARGET_D = 0.85
JAM_D = 0.84        # the frictionless jammed state netsolve starts from (as the walls ensemble)
AFFINE_TO_D = 0.87  # the affine run's end density in the die's box: past the walls' 0.85 at equal strain
INERTIAL = (1.5e-4, 5e-5)
FULL = {"name": "full", "width": 80, "seeds": tuple(range(1, 9))}
QUICK = {"name": "quick", "width": 40, "seeds": (1, 2)}
PATHS = (("hydro", "hydrostatic"), ("die", "closed-die"))


def dem_name(seed, pk, fk, I):
    return f"dem/s{seed}_{pk}_{fk}_I{I:g}"


def base(mode, seed):
    return ["compact", "--width", f"{mode['width']:g}", "--seed", str(seed)]


def prep_runs(mode):
    """(name, tool, args, priority): the DEM runs from the deposition, the jammed states, the affine runs."""
    out = []
    for s in mode["seeds"]:
        out.append((f"jam/s{s}", "demsolve", base(mode, s) + [
            "--boundary", "walls", "--friction", "0", "--to-density", f"{JAM_D:g}", "--save-state",
            "--snapshots", "", "--quiet"], (0, s)))
        for I in INERTIAL:
            for pk, pv in PATHS:
                out.append((dem_name(s, pk, "mu0", I), "demsolve", dem_args(mode, s, pv, "0", I), (1 if I < 1e-4 else 2, s)))
        out.append((dem_name(s, "hydro", "inf", INERTIAL[0]), "demsolve",
                    dem_args(mode, s, "hydrostatic", "inf", INERTIAL[0]), (3, s)))
        out.append((f"aff/s{s}", "netsolve", base(mode, s) + [
            "--affine", "--friction", "0", "--to-density", f"{AFFINE_TO_D:g}", "--increments", "200", "--quiet"], (3, s)))
    return out


def dem_args(mode, seed, path, friction, I):
    return base(mode, seed) + ["--boundary", "walls", "--friction", friction, "--path", path, "--to-density",
                               f"{TARGET_D:g}", "--increments", "100", "--inertial-number", f"{I:g}",
                               "--snapshots", "", "--quiet"]


def net_runs(mode, runs):
    return [(f"net/s{s}", "netsolve", ["compact", "--boundary", "walls", "--state",
                                       os.path.join(runs, "jam", f"s{s}", "jammed.json"), "--friction", "0",
                                       "--to-density", f"{TARGET_D:g}", "--increments", "10", "--iteration",
                                       "pseudo-transient", "--snapshots", "", "--allow-unconverged", "--quiet"], (0, s))
            for s in mode["seeds"]]



# ---------------------------------------------------------------------------------------- reading
C = load_module("rf_compaction", os.path.join(REPO, "validation", "redanz_fleck_compaction", "run.py"))
COMPACTION_REPORT = os.path.join(REPO, "validation", "redanz_fleck_compaction", "report.md")


def load(mode, runs):
    """The runs, every walls run's density column converted to the die's box at equal strain (D × k, k =
    D0 of the affine run / D0 of the walls runs of the same deposition): the paper's box, in which the
    compaction case's findings and bands are stated. The raw walls density is kept as column D_walls."""
    R = {}
    for name, tool, _, _ in prep_runs(mode) + net_runs(mode, runs):
        R[name] = Q.Run(os.path.join(runs, name), tool)
    for s in mode["seeds"]:
        k = box_factor_of(R, s)
        if R[f"aff/s{s}"].ok:
            R[f"aff/s{s}"].k = k  # (box_factor_of reads it from here once the jammed run's D is converted)
        for name, r in R.items():
            if r.ok and not name.startswith("aff/") and name.split("/")[1].split("_")[0] == f"s{s}":
                r.k = k
                for h in {id(r.h): r.h, id(r.hw): r.hw}.values():
                    h["D_walls"] = h["D"].copy()
                    h["D"] = h["D"] * k
    return R


def box_factor_of(R, s):
    a, d = R.get(f"aff/s{s}"), R.get(f"jam/s{s}")
    if not (a and a.ok and d and d.ok):
        return float("nan")
    return getattr(a, "k", None) or float(a.h["D"][0]) / float(d.h["D"][0])


def ok(R, name):
    r = R.get(name)
    return r is not None and r.ok and r.status == "ok"


class Affine:
    """The affine run (in the die's box) as the reference of a walls run of the same deposition at the same
    strain: every centre on the same homogeneous strain, so the contact forces and branch vectors are the
    same in both boxes; the stress (a sum over the contacts over the box area, area ∝ 1 / D for the same
    disks) is scaled to the walls' box by 1 / k."""

    def __init__(self, run, k):
        self.r, self.k = run, k

    def at(self, col, D):
        v = self.r.at(col, D, window=False)
        return v / self.k if col.startswith("S") else v


def upturn(r):
    """validation/redanz_fleck_compaction's up-turn density (its definition) of a run's |S22|(D), on the
    run up to D = TARGET_D in the die's box (where the paper's and the compaction case's runs end: the
    final slope is taken over the last 0.005 before it)."""
    m = r.h["D"] <= TARGET_D + 1e-9
    h = {k: v[m] for k, v in r.h.items()}

    class H:  # the compaction script's reader reads r.h["D"] and r.mag("S22")
        pass
    H.h = h
    H.mag = staticmethod(lambda col: -h[col])
    return C.upturn_density(H)


def early_z(r):
    d = r.h["D"]
    lim = d[0] + 0.2 * (TARGET_D - d[0])
    m = (np.arange(len(d)) > 0) & (d <= lim + 1e-12)
    return float(np.mean(r.h["Z"][m])), lim


def peak(r, col):
    y = r.h[col][1:]
    k = int(np.argmax(y))
    return float(y[k]), float(r.h["D"][1:][k])


# --------------------------------------------------------------------------------------- findings
def measures(mode, R):
    """The lines: (id, finding, paper, band text, test of a value, the value of a seed at an inertial
    number, extra: 1c's sticking value of a seed, the deviation column of 7a/7b, or "net" for netsolve's
    line), and the DEM's and netsolve's 3a ratio functions (for the netsolve line's notes)."""
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)

    def dem(s, pk, I, fk="mu0"):
        n = dem_name(s, pk, fk, I)
        return R[n] if ok(R, n) else None

    def ratio(s, I, D):
        r, a = dem(s, "hydro", I), R.get(f"aff/s{s}")
        if r is None or a is None or not a.ok:
            return float("nan")
        return r.at("S22", D) / Affine(a, r.k).at("S22", D)

    def net_ratio(s, D=None):
        """netsolve's ratio at D, or at the end of its run (D None)."""
        n, a = R.get(f"net/s{s}"), R.get(f"aff/s{s}")
        if not (ok(R, f"net/s{s}") and a.ok) or n.summary.get("solver", {}).get("unconverged_increments", 1) != 0:
            return float("nan")  # only runs that accept every increment: a converged answer
        D = float(n.h["D"][-1]) if D is None else D
        return n.at("S22", D, window=False) / Affine(a, n.k).at("S22", D)

    def aniso(s, I, fk, D):
        r = dem(s, "hydro", I, fk)
        return float("nan") if r is None else r.at("S22", D) / r.at("S11", D) - 1

    def up(s, I):
        r = dem(s, "hydro", I)
        return float("nan") if r is None else upturn(r)[0]

    def ez(s, I):
        r = dem(s, "die", I)
        return float("nan") if r is None else early_z(r)[0]

    def pk_v(s, I, path, col, what):
        r = dem(s, path, I)
        if r is None:
            return float("nan")
        v, d = peak(r, col)
        return v if what == "value" else d

    L = []
    for D in C.EVAL_D:
        L.append(("1c", f"hydrostatic, S22/S11 − 1 at D = {D:g}: frictionless (this line) < sticking (beside)",
                  "difference even smaller for frictionless (3.1)", "below sticking's mean",
                  None, lambda s, I, D=D: aniso(s, I, "mu0", D), lambda s, D=D: aniso(s, I_hi, "inf", D)))
    for D in C.EVAL_D:
        L.append(("3a", f"hydrostatic S22: frictionless / affine at D = {D:g} (DEM)",
                  "at most half that for affine (3.1, Fig 5a)", "≤ 0.6", lambda v: v <= 0.6,
                  lambda s, I, D=D: ratio(s, I, D), None))
    L.append(("3a", f"hydrostatic S22: frictionless / affine at the end of netsolve's run from the jammed state "
                    f"(D = {TARGET_D:g} in the walls' box)", "at most half that for affine (3.1, Fig 5a)", "≤ 0.6",
              lambda v: v <= 0.6, lambda s, I: net_ratio(s), "net"))
    L.append(("3b", "hydrostatic frictionless: up-turn density, first D where d|S22|/dD ≥ half its final value",
              "sharp up-turn at D = 0.825 (3.1, Fig 5a)", "0.815..0.835", lambda v: 0.815 <= v <= 0.835, up, None))
    L.append(("6a", "closed die frictionless: mean Z over the first 20 % of the D range",
              "Z about 3.5, frictionless (3.2, Fig 6b)", "3.2..3.8", lambda v: 3.2 <= v <= 3.8, ez, None))
    for path, where in (("hydro", "hydrostatic"), ("die", "closed die")):
        for col, sym in (("dev_un_ratio_of_means", "⟨|uN−uNA|⟩/⟨uNA⟩"), ("dev_un_mean_ratio", "⟨|uN−uNA|/uNA⟩")):
            L.append((f"7a-{path}", f"{where} frictionless: peak of {sym}", "> 200 % in the initial stages (3.3, Fig 7)",
                      "> 2.0", lambda v: v > 2.0, lambda s, I, p=path, c=col: pk_v(s, I, p, c, "value"), col))
            L.append((f"7b-{path}", f"{where} frictionless: density of the peak of {sym}", "peak at D ~ 0.83 (3.3, Fig 7)",
                      "0.82..0.84", lambda v: 0.82 <= v <= 0.84, lambda s, I, p=path, c=col: pk_v(s, I, p, c, "density"),
                      col))
    return L, ratio, net_ratio


def box_factor(mode, R):
    """The mean over the seeds of k = D0 (die's box) / D0 (walls' box) of the same deposition."""
    k = [box_factor_of(R, s) for s in mode["seeds"]]
    k = [x for x in k if math.isfinite(x)]
    return float(np.mean(k)) if k else float("nan")


def stats(vals):
    v = np.array([x for x in vals if math.isfinite(x)], float)
    if len(v) == 0:
        return float("nan"), float("nan"), 0
    se = float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan")
    return float(np.mean(v)), se, len(v)


def fmt_ms(m, se, n, p=3):
    if n == 0:
        return "—"
    if abs(m) >= 1000:
        return f"{m:.3g} ± {se:.2g} (n = {n})" if math.isfinite(se) else f"{m:.3g} (n = {n})"
    return f"{m:.{p}f} ± {se:.{p}f} (n = {n})" if math.isfinite(se) else f"{m:.{p}f} (n = {n})"


def ill(extra, mean):
    return extra == "dev_un_mean_ratio" and math.isfinite(mean) and mean > 100


def evaluate(mode, R):
    """Rows: (id, finding, paper, band, at I_lo, at I_hi, seeds in band, verdict, notes) and the
    per-seed table {id+finding: {seed: (v_lo, v_hi)}}."""
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)
    seeds = mode["seeds"]
    rows, per_seed, invalid = [], {}, set()
    lines, dem_ratio, net_ratio = measures(mode, R)
    for fid, fin, paper, band, test, fn, extra in lines:
        if extra == "net":
            lo = [fn(s, None) for s in seeds]
            hi = [float("nan")] * len(seeds)
        else:
            lo = [fn(s, I_lo) for s in seeds]
            hi = [fn(s, I_hi) for s in seeds]
        per_seed[(fid, fin)] = {s: (a, b) for s, a, b in zip(seeds, lo, hi)}
        m_lo, se_lo, n_lo = stats(lo)
        m_hi, se_hi, n_hi = stats(hi)
        p = 4 if fid in ("3b", "7b-hydro", "7b-die") else 3
        notes = []
        if fid == "1c":
            ref = stats([extra(s) for s in seeds])
            vd = verdict(m_lo < ref[0]) if n_lo and ref[2] else None
            inb = sum(1 for s, a in zip(seeds, lo) if math.isfinite(a) and a < extra(s))
            notes.append(f"sticking (I = {I_hi:g}): {fmt_ms(*ref)}; frictionless at I = {I_hi:g}: {fmt_ms(m_hi, se_hi, n_hi)}")
        else:
            vd = verdict(test(m_lo)) if n_lo else None
            inb = sum(1 for a in lo if math.isfinite(a) and test(a))
        if extra == "net":
            un = [R[f"net/s{s}"].summary.get("solver", {}).get("unconverged_increments", -1)
                  for s in seeds if R.get(f"net/s{s}") and R[f"net/s{s}"].ok]
            notes.append(f"netsolve runs with unaccepted increments (left out): {sum(1 for u in un if u)} of {len(un)}")
            ends = [(s, float(R[f"net/s{s}"].h["D"][-1])) for s in seeds if R.get(f"net/s{s}") and R[f"net/s{s}"].ok]
            if ends:
                dem_end = stats([dem_ratio(s, I_lo, d) for s, d in ends])
                diff = stats([net_ratio(s) - dem_ratio(s, I_lo, d) for s, d in ends])
                notes.append(f"the end is D = {min(d for _, d in ends):.4f}..{max(d for _, d in ends):.4f} in the die's "
                             f"box, {TARGET_D - JAM_D:g} past the shared jammed state (walls' box {JAM_D:g}), beyond the "
                             f"paper's 0.85; the DEM there (I = {I_lo:g}): {fmt_ms(*dem_end)}, netsolve − DEM "
                             f"{fmt_ms(*diff)}; at the paper's 0.85 netsolve has only started (from D = "
                             f"{min(float(R[f'net/s{s}'].h['D'][0]) for s, _ in ends):.4f}..)")
        if fid.startswith("7a") and ill(extra, m_lo):
            invalid.add((fid[3:], extra))
        if (fid[3:], extra) in invalid:
            vd = "INVALID"
            notes.append("ill-conditioned: the mean of ratios is dominated by contacts with uNA near 0 "
                         "(the compaction case's rule)")
        if fid in ("3b", "7b-hydro", "7b-die") and n_lo:
            notes.append(f"in the walls' box: D / {box_factor(mode, R):.4f} = {m_lo / box_factor(mode, R):.4f}")
        if n_lo == 0:
            vd = MISSING
            lo_txt = missing_text("runs missing or failed")
        else:
            fin_lo = [x for x in lo if math.isfinite(x)]
            lo_txt = fmt_ms(m_lo, se_lo, n_lo, p) + f"; seeds {min(fin_lo):.4g}..{max(fin_lo):.4g}"
        tag = {"dev_un_ratio_of_means": "rom", "dev_un_mean_ratio": "mor"}.get(extra if isinstance(extra, str) else "", "")
        label = ("netsolve" if extra == "net" else "DEM") + (f" at {fin.split('at D = ')[1].split()[0].rstrip(':')}"
                                                              if "at D = " in fin else "")
        rows.append((fid, fin, paper, band, lo_txt, "—" if extra == "net" else fmt_ms(m_hi, se_hi, n_hi, p),
                     f"{inb} / {n_lo}", vd if vd is not None else "n/a", "; ".join(notes), tag, label))
    rows.append(("8d", "closed die frictionless: initial peak of ⟨|uT−uTA|⟩/⟨uNA⟩", "initial peak ~14 (3.3, Fig 8b)",
                 "7..28", missing_text("demsolve writes no tangential deviation column, and netsolve has no "
                                         "converged frictionless die path from the deposition"),
                 "—", "—", MISSING, "", "", "DEM"))
    return rows, per_seed



# ------------------------------------------------------------------------------------------ figures
def make_figures(mode, R, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    figs = []

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for k, s in enumerate(mode["seeds"]):
        c = colours[k % len(colours)]
        for I, ls in ((I_lo, "-"), (I_hi, "--")):
            n = dem_name(s, "hydro", "mu0", I)
            if ok(R, n):
                ax.plot(R[n].h["D"], -R[n].h["S22"], ls, color=c, lw=1,
                        label=f"DEM I = {I:g}" if k == 0 else None)
        n = f"net/s{s}"
        if R[n].ok:
            ax.plot(R[n].h["D"], -R[n].h["S22"], "o", ms=3, color=c, label="netsolve from the jammed state" if k == 0 else None)
        if R[f"aff/s{s}"].ok and ok(R, dem_name(s, "hydro", "mu0", I_hi)):
            a = Affine(R[f"aff/s{s}"], R[dem_name(s, "hydro", "mu0", I_hi)].k)
            d = np.linspace(R[f"aff/s{s}"].h["D"][0], R[dem_name(s, "hydro", "mu0", I_hi)].h["D"][-1], 200)
            ax.plot(d, [-a.at("S22", x) for x in d], ":", color=c, lw=1, label="affine (die's box, same strain)" if k == 0 else None)
    ax.set_xlabel("relative density D (the die's box at equal strain)")
    ax.set_ylabel("−S22 / σy")
    ax.set_title("hydrostatic, frictionless, walls: seeds " + ", ".join(map(str, mode["seeds"])))
    ax.set_yscale("log")
    ax.set_ylim(1e-4, None)
    ax.legend(fontsize=8)
    fig.tight_layout()
    figs.append(("Hydrostatic S22 (3a, 3b)", "fig_hydro_S22.png"))
    fig.savefig(os.path.join(out, figs[-1][1]), dpi=110)
    plt.close(fig)

    for key, title, col, fname in (("die", "closed die: Z (6a)", "Z", "fig_die_Z.png"),
                                   ("hydro", "hydrostatic: ⟨|uN−uNA|⟩/⟨uNA⟩ (7a)", "dev_un_ratio_of_means",
                                    "fig_hydro_normal_deviation.png"),
                                   ("die", "closed die: ⟨|uN−uNA|⟩/⟨uNA⟩ (7a)", "dev_un_ratio_of_means",
                                    "fig_die_normal_deviation.png")):
        fig, ax = plt.subplots(figsize=(7, 4))
        for k, s in enumerate(mode["seeds"]):
            c = colours[k % len(colours)]
            for I, ls in ((I_lo, "-"), (I_hi, "--")):
                n = dem_name(s, key, "mu0", I)
                if ok(R, n):
                    ax.plot(R[n].h["D"], R[n].h[col], ls, color=c, lw=1, label=f"DEM I = {I:g}" if k == 0 else None)
        ax.set_xlabel("relative density D (the die's box at equal strain)")
        ax.set_ylabel(col)
        ax.set_title(f"{title}, frictionless, walls")
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs.append((title, fname))
        fig.savefig(os.path.join(out, fname), dpi=110)
        plt.close(fig)
    return figs


# ------------------------------------------------------------------------------------------- report
def esc(x):
    return str(x).replace("|", "\\|")


def compaction_rows():
    """The same findings' rows of validation/redanz_fleck_compaction/report.md: {id: [(finding, measured, verdict)]}."""
    out = {}
    try:
        text = open(COMPACTION_REPORT, encoding="utf-8").read()
    except OSError:
        return out
    section = False
    for ln in text.splitlines():
        if ln.startswith("## "):
            section = ln.startswith("## Findings")  # the main findings table only
        if not (section and ln.startswith("| ")):
            continue
        c = [x.strip() for x in re.split(r"(?<!\\)\|", ln.strip())[1:-1]]
        if len(c) == 7 and c[0] in ("1c", "3a", "3b", "6a", "7a-hydro", "7b-hydro", "7a-die", "7b-die", "8d"):
            out.setdefault(c[0], []).append((c[1], c[4], c[5].strip("*")))
    return out


def run_table(mode, R, runs):
    L = ["| run | tool | status | D0 → D end | increments not accepted | wall time |", "|---|---|---|---|---|---|"]
    for name, tool, _, _ in prep_runs(mode) + net_runs(mode, runs):
        r = R[name]
        if not r.ok:
            L.append(f"| {name} | {tool} | {r.status} | — | — | — |")
            continue
        un = r.summary.get("solver", {}).get("unconverged_increments", "—") if tool == "netsolve" else "—"
        L.append(f"| {name} | {tool} | {r.status} | {r.h['D'][0]:.4f} → {r.h['D'][-1]:.4f} | {un} | "
                 f"{r.meta.get('wall_s', float('nan')):.0f} s |")
    return L


def write_report(mode, R, runs, out, binaries, cmdline):
    rows, per_seed = evaluate(mode, R)
    figs = make_figures(mode, R, out)
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)
    c = tally([r[7] for r in rows])
    L = ["# Redanz & Fleck's frictionless findings on converged runs with walls", "",
         f"Generated by `{cmdline}`. Issue 28 asks for the paper's frictionless findings (3a, 3b, 6a, 7a) on "
         "converged runs; validation/redanz_fleck_compaction evaluates them on netsolve in the paper's die, where the "
         "frictionless runs do not converge (183-200 of 200 increments) and the drag holds the disks in.", "",
         "**This departs from the paper's boundary.** A converged frictionless packing in the paper's die (the "
         "peripheral layer prescribed) pours out of it (docs/quasistatic.md, \"Frictionless: the die leaks\"). Here the "
         f"same ballistic depositions (W = {mode['width']}, r = R[0.9, 1.1], seeds {', '.join(map(str, mode['seeds']))}) "
         "are compacted between four rigid frictionless walls to D = 0.85:",
         f"* **the DEM limit**: `demsolve compact --boundary walls --friction 0` from the deposition at I = {I_hi:g} and "
         f"{I_lo:g}, hydrostatic and closed die. Lines are graded on the mean over the seeds at I = {I_lo:g}; the column "
         f"at I = {I_hi:g} shows how far the rate still moves them;",
         f"* **the converged network**: netsolve cannot start from the deposition (a frictionless packing below jamming "
         "is a mechanism, its quasi-static stress is zero), so it starts from the DEM's jammed state at D = "
         f"{JAM_D:g} (hydrostatic, every wall loaded) and runs to {TARGET_D:g} with the pseudo-transient iteration;",
         "* **the affine reference** of 3a: netsolve --affine from the same deposition in the die's box (the walls "
         "exclude --affine), taken at the same strain (equal D / D0) and its stress scaled to the walls' box area "
         "(× D0_walls / D0_die, the same disks).", "",
         "Definitions and bands are the compaction case's (validation/redanz_fleck_compaction/run.py), never widened: "
         "Z counts loaded disk-disk contacts; the up-turn is the first window (±0.0025 in D) whose least-squares slope "
         "of |S22| reaches half the final slope (last 0.005); the deviation measures accumulate since each contact "
         "formed (Eq 16). Densities are the walls' box's; the die's box at the same strain is denser by the factor in "
         "the notes. A DEM row is the mean over its output window; a netsolve row the state at the increment's end.", "",
         f"## Findings: {c['PASS']} pass, {c['FAIL']} fail, {c[MISSING]} missing, {c['other']} other", "",
         f"| # | finding | paper | band | measured at I = {I_lo:g}: mean ± se over the seeds | at I = {I_hi:g} | "
         "seeds in band | verdict | notes |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        v = r[7]
        L.append("| " + " | ".join(esc(x) for x in r[:7]) + f" | {'**' + v + '**' if v == 'FAIL' else v} | {esc(r[8])} |")
    old = compaction_rows()
    L += ["", "## Which verdicts moved", "",
          "The same findings in validation/redanz_fleck_compaction/report.md (netsolve in the paper's die, seed 1, "
          "with the drag, unconverged) beside the verdicts above (why they moved: the notes below):", "",
          "| # | finding (compaction report) | measured there | there | here |", "|---|---|---|---|---|"]
    for fid in ("1c", "3a", "3b", "6a", "7a-hydro", "7b-hydro", "7a-die", "7b-die", "8d"):
        for fin, meas, v in old.get(fid, [("—", "—", "—")]):
            tag = "" if not fid.startswith("7") else ("rom" if "⟩/⟨uNA⟩" in fin else "mor")
            here = [f"{r[10]}: {r[7]}" for r in rows if r[0] == fid and r[9] == tag]
            L.append(f"| {fid} | {fin} | {meas} | {v} | {', '.join(here) or '—'} |")
    L += ["", "## Per seed (at I = " + f"{I_lo:g}" + "; netsolve for its line)", ""]
    seeds = mode["seeds"]
    L += ["| # | finding | " + " | ".join(f"s{s}" for s in seeds) + " |", "|---|---|" + "---|" * len(seeds)]
    for (fid, fin), vals in per_seed.items():
        L.append(f"| {fid} | {esc(fin)} | " + " | ".join("—" if not math.isfinite(vals[s][0]) else f"{vals[s][0]:.4g}"
                                                       for s in seeds) + " |")
    L += ["", "## Figures", ""]
    for title, f in figs:
        L += [f"**{title}**", "", f"![{f}]({f})", ""]
    L += ["## Runs", ""] + run_table(mode, R, runs)
    notes = os.path.join(HERE, "notes.md")
    if os.path.isfile(notes) and mode["name"] == "full":
        L += ["", "## Notes (notes.md, written by hand)", "", open(notes, encoding="utf-8").read().strip()]
    L += provenance_lines(provenance(REPO, CASE, binaries), c)
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(L) + "\n")
    print(f"report: {shown_path(os.path.join(out, 'report.md'), REPO)} ({c})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--demsolve", default=os.path.join(REPO, "build", "apps", "demsolve"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--runs", default=None, help="run folders (default: runs/ or runs_quick/ beside this script)")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--only", default="", help="comma list of run-name patterns (e.g. 'dem/*,net/s1')")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--timeout", type=float, default=7200)
    a = ap.parse_args()
    mode = QUICK if a.quick else FULL
    runs = os.path.abspath(a.runs or os.path.join(HERE, "runs_quick" if a.quick else "runs"))
    out = os.path.join(HERE, "quick") if a.quick else HERE
    os.makedirs(out, exist_ok=True)
    only = [p for p in a.only.split(",") if p]
    bins = {"netsolve": a.netsolve, "demsolve": a.demsolve}
    if not a.report_only:
        for b in bins.values():
            if not os.access(b, os.X_OK):
                sys.exit(f"error: binary not found: {b} (build first: cmake --build build)")
        for items in (prep_runs(mode), net_runs(mode, runs)):
            PER.run_all(a.jobs, bins, runs, a.force, a.timeout, [r for r in items if PER.selected(r[0], only)])
    cmdline = "/usr/bin/python3 validation/redanz_fleck_frictionless/run.py" + (" --quick" if a.quick else "")
    write_report(mode, load(mode, runs), runs, out, [a.netsolve, a.demsolve], cmdline)


if __name__ == "__main__":
    main()
