#!/usr/bin/env python3
"""Redanz & Fleck's compaction findings between walls: the frictionless ones (3a, 3b, 6a, 7a/7b, 8d; issue 28)
on the explicit DEM at two rates and on netsolve from a DEM jammed state, and those with friction (1a, 1c, 2,
4, 6b-6d, 7c, 8a-8c; issue 32, frictional.py) on the DEM.

usage: /usr/bin/python3 validation/redanz_fleck_walls/run.py
           [--quick] [--netsolve PATH] [--demsolve PATH] [--jobs 2] [--runs DIR] [--force]
           [--only PATTERN,...] [--report-only] [--timeout S]

The paper's die (a prescribed peripheral layer) does not hold a frictionless packing without the drag in
the answer: the disks are extruded through it (docs/quasistatic.md, "Frictionless: the die leaks"). This
case departs from the paper's boundary: four rigid frictionless walls around the same ballistic
depositions (W = 80, seeds 1-8; --quick: W = 40, seeds 1-2), driven hydrostatically or as a closed die to
D = 0.85 in the walls' box. Runs per seed:
  * `demsolve compact --boundary walls --friction 0` from the deposition, hydrostatic and closed die, at
    I = 1.5e-4 (the tool's default) and 5e-5 (graded; the other rate shows how far the rate moves a line);
  * `demsolve compact ... --to-density 0.84 --save-state` (hydrostatic, mu = 0, I = 1.5e-4: every wall
    loaded) and from its jammed.json `netsolve compact --boundary walls --iteration pseudo-transient` to
    0.85 (a frictionless packing below jamming is a mechanism, so netsolve cannot start from the deposition);
  * `netsolve compact --affine --friction 0` from the same deposition (the affine reference of 3a; the
    walls exclude --affine, so it runs in the die's box and is compared at the same strain, its stress
    scaled to the walls' box area);
  * frictional.py's runs: mu = 0.1, sticking and sticking without rotation, both paths.
Densities are converted to the die's box at equal strain (the paper's). The findings' definitions and
bands are validation/redanz_fleck_compaction/run.py's (never widened); each is evaluated per seed and
graded on the mean over the seeds.
"""
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
FR = load_module("rf_walls_frictional", os.path.join(HERE, "frictional.py"))
PER = load_module("qvd_periodic", os.path.join(REPO, "validation", "quasistatic_vs_dynamic_periodic", "run.py"))

CASE = "redanz_fleck_walls"
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
            "--affine", "--friction", "0", "--to-density", f"{AFFINE_TO_D:g}", "--increments", "200", "--snapshots", "",
            "--quiet"], (3, s)))
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
# the compaction report's lines this case evaluates again (frictionless here, with friction in frictional.py)
COMPARED = ("1a", "1c", "2", "3a", "3b", "4", "6a", "6b", "6c", "6d", "7a-hydro", "7b-hydro", "7a-die", "7b-die",
            "7c-hydro", "7c-die", "8a", "8b", "8c", "8d")


def all_runs(mode, runs):
    return prep_runs(mode) + net_runs(mode, runs) + FR.runs(mode, dem_name, dem_args) + FR.layer_runs(mode, dem_args)


def seed_of(name):
    return int(name.split("/")[1].split("_")[0][1:])


def load(mode, runs):
    """The runs, and {seed: k}. Every walls run's density column is converted to the die's box at equal
    strain, D × k with k = D0 (die's box: the affine run's first row) / D0 (walls' box: the first row of
    a run from the deposition), the paper's box, in which the compaction case's findings and bands are
    stated; the raw walls density is kept as column D_walls. A seed without k (its affine run or every
    run from its deposition missing) gets D = nan: its lines drop it, and the report names it."""
    R = {name: Q.Run(os.path.join(runs, name), tool) for name, tool, _, _ in all_runs(mode, runs)}
    K = {}
    for s in mode["seeds"]:
        a = R[f"aff/s{s}"]
        d0w = next((float(r.h["D"][0]) for n, r in R.items()
                    if r.ok and n.startswith(("dem/", "jam/")) and "_layer_" not in n and seed_of(n) == s), float("nan"))
        K[s] = float(a.h["D"][0]) / d0w if a.ok else float("nan")
        for name, r in R.items():
            if r.ok and not name.startswith("aff/") and "_layer_" not in name and seed_of(name) == s:
                r.k = K[s]
                for h in {id(r.h): r.h, id(r.hw): r.hw}.values():
                    h["D_walls"] = h["D"].copy()
                    h["D"] = h["D"] * K[s]
    return R, K


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
    m = r.h["D"] <= TARGET_D + FR.END_TOL
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
    """The largest value of a column over increments 1.. up to D = TARGET_D in the die's box (where the
    compaction case's runs end), and its density."""
    m = (np.arange(len(r.h["D"])) > 0) & (r.h["D"] <= TARGET_D + FR.END_TOL)
    y, d = r.h[col][m], r.h["D"][m]
    if len(y) == 0:
        return float("nan"), float("nan")
    k = int(np.argmax(y))
    return float(y[k]), float(d[k])


# --------------------------------------------------------------------------------------- findings
def measures(R):
    """The frictionless lines: (id, finding, paper, band text, test of a value (None: information), the
    value of a seed at an inertial number (None for netsolve's line), the deviation column of 7a/7b or
    None), and the DEM's and netsolve's 3a ratio functions (for the netsolve line's notes)."""
    def dem(s, pk, I):
        n = dem_name(s, pk, "mu0", I)
        return R[n] if ok(R, n) else None

    def ratio(s, I, D):
        r, a = dem(s, "hydro", I), R.get(f"aff/s{s}")
        if r is None or a is None or not a.ok:
            return float("nan")
        return r.at("S22", D) / Affine(a, r.k).at("S22", D)

    def net_ratio(s):
        """netsolve's ratio at the end of its run, for a run that accepts every increment."""
        n, a = R.get(f"net/s{s}"), R.get(f"aff/s{s}")
        if not (ok(R, f"net/s{s}") and a.ok) or n.summary.get("solver", {}).get("unconverged_increments", 1) != 0:
            return float("nan")
        D = float(n.h["D"][-1])
        return n.at("S22", D, window=False) / Affine(a, n.k).at("S22", D)

    def of(pk, f):
        return lambda s, I: float("nan") if dem(s, pk, I) is None else f(dem(s, pk, I))

    L = []
    for D in C.EVAL_D:
        L.append(("3a", f"hydrostatic S22: frictionless / affine at D = {D:g} (DEM)",
                  "at most half that for affine (3.1, Fig 5a)", "≤ 0.6", lambda v: v <= 0.6,
                  lambda s, I, D=D: ratio(s, I, D), None))
    L.append(("3a", "hydrostatic S22: frictionless / affine at the end of netsolve's runs from the jammed state "
                    f"(D = {TARGET_D:g} in the walls' box; information: past the paper's densities)",
              "at most half that for affine (3.1, Fig 5a)", "≤ 0.6", None, None, None))
    L.append(("3b", "hydrostatic frictionless: up-turn density, first D where d|S22|/dD ≥ half its final value",
              "sharp up-turn at D = 0.825 (3.1, Fig 5a)", "0.815..0.835", lambda v: 0.815 <= v <= 0.835,
              of("hydro", lambda r: upturn(r)[0]), None))
    L.append(("6a", "closed die frictionless: mean Z over the first 20 % of the D range",
              "Z about 3.5, frictionless (3.2, Fig 6b)", "3.2..3.8", lambda v: 3.2 <= v <= 3.8,
              of("die", lambda r: early_z(r)[0]), None))
    for path, where in (("hydro", "hydrostatic"), ("die", "closed die")):
        for col, sym in (("dev_un_mean_ratio", "⟨|uN−uNA|/uNA⟩ (the paper's)"), ("dev_un_ratio_of_means", "⟨|uN−uNA|⟩/⟨uNA⟩")):
            L.append((f"7a-{path}", f"{where} frictionless: peak of {sym}", "> 200 % in the initial stages (3.3, Fig 7)",
                      "> 2.0", lambda v: v > 2.0, of(path, lambda r, c=col: peak(r, c)[0]), col))
            L.append((f"7b-{path}", f"{where} frictionless: density of the peak of {sym}", "peak at D ~ 0.83 (3.3, Fig 7)",
                      "0.82..0.84", lambda v: 0.82 <= v <= 0.84, of(path, lambda r, c=col: peak(r, c)[1]), col))
    # Fig 8b on the DEM (demsolve's Figs 7-8 columns, since 2026-12-07; netsolve has no frictionless die path
    # from the deposition: a mechanism until it jams)
    L.append(("8d", "closed die frictionless: initial peak of ⟨|uT−uTA|⟩/⟨uNA⟩ (uT of Eq 5, with the rotations; DEM)",
              "initial peak ~14 (3.3, Fig 8b)", "7..28", lambda v: 7 <= v <= 28,
              of("die", lambda r: peak(r, "dev_ut_rotations")[0] if "dev_ut_rotations" in r.h else float("nan")), None))
    return L, ratio, net_ratio


def net_notes(R, seeds, dem_ratio, net_ratio):
    """The netsolve line: its value and notes (the runs' iteration record, the DEM at the same density)."""
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)
    runs = [(s, R[f"net/s{s}"]) for s in seeds if ok(R, f"net/s{s}")]
    if not runs:
        return [], ["no netsolve run finished"]
    sv = [r.summary.get("solver", {}) for _, r in runs]
    rng = (lambda k, p=2: f"{min(x.get(k, float('nan')) for x in sv):.{p}g}..{max(x.get(k, float('nan')) for x in sv):.{p}g}")
    vals = [net_ratio(s) for s in seeds]
    ends = [float(r.h["D"][-1]) for s, r in runs if math.isfinite(net_ratio(s))]
    used = [(s, float(r.h["D"][-1])) for s, r in runs if math.isfinite(net_ratio(s))]
    notes = [f"{sum(1 for x in sv if x.get('unconverged_increments', 1) == 0)} of {len(runs)} runs accept every "
             f"increment (the others are left out); every increment is an instability event (instability_events "
             f"{rng('instability_events')}; cut increments {rng('cut_increments')}; unaccepted sub-increments committed "
             f"{rng('unconverged_substeps')}; drag_work_fraction {rng('drag_work_fraction')}; max_residual "
             f"{rng('max_residual', 3)} against 10 × tol = 0.03): equilibrium end states on a damped path the drag selects"]
    if used:
        for I in (I_lo, I_hi):
            d = stats([dem_ratio(s, I, D) for s, D in used])
            diff = stats([net_ratio(s) - dem_ratio(s, I, D) for s, D in used])
            notes.append(f"the DEM at the same D (I = {I:g}): {fmt_ms(*d)}, netsolve − DEM {fmt_ms(*diff)}")
        notes.append(f"D = {min(ends):.4f}..{max(ends):.4f} in the die's box; netsolve starts from the DEM's jammed state "
                     f"at I = {I_hi:g} (walls' box {JAM_D:g}, die's {min(float(r.h['D'][0]) for _, r in runs):.4f}..), "
                     f"which the I = {I_lo:g} runs reach on their own path")
    return vals, notes


def helpers():
    """The functions frictional.py evaluates with."""
    import types
    return types.SimpleNamespace(dem_name=dem_name, ok=ok, early_z=early_z, peak=peak, stats=stats, fmt_ms=fmt_ms,
                                 verdict=verdict, missing_text=missing_text, MISSING=MISSING, EVAL_D=C.EVAL_D)


def box_factor(K):
    """The mean over the seeds of k = D0 (die's box) / D0 (walls' box) of the same deposition."""
    k = [x for x in K.values() if math.isfinite(x)]
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


def ill(col, mean):
    return col == "dev_un_mean_ratio" and math.isfinite(mean) and mean > 100


def evaluate(mode, R, K):
    """The frictionless rows: (id, finding, paper, band, at I_lo, at I_hi, seeds in band, verdict, notes),
    and the per-seed table {(id, finding): {seed: value at I_lo}}."""
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)
    seeds = mode["seeds"]
    rows, per_seed, invalid = [], {}, set()
    lines, dem_ratio, net_ratio = measures(R)
    no_k = [s for s in seeds if not math.isfinite(K.get(s, float("nan")))]
    for fid, fin, paper, band, test, fn, col in lines:
        notes = []
        if fn is None:  # netsolve's line
            lo, notes = net_notes(R, seeds, dem_ratio, net_ratio)
            hi = []
        else:
            lo, hi = [fn(s, I_lo) for s in seeds], [fn(s, I_hi) for s in seeds]
        per_seed[(fid, fin)] = dict(zip(seeds, lo))
        m_lo, se_lo, n_lo = stats(lo)
        m_hi, se_hi, n_hi = stats(hi)
        p = 4 if fid in ("3b", "7b-hydro", "7b-die") else 3
        vd = (verdict(test(m_lo)) if test else "n/a") if n_lo else MISSING
        inb = f"{sum(1 for a in lo if math.isfinite(a) and test(a))} / {n_lo}" if test else "—"
        if fid.startswith("7a") and ill(col, m_lo):
            invalid.add((fid[3:], col))
        if (fid[3:], col) in invalid:
            vd = "INVALID"
            notes.append("ill-conditioned: the mean of ratios is dominated by contacts with uNA near 0 "
                         "(the compaction case's rule)")
        if fid == "3b" and n_lo:
            notes.append(f"in the walls' own box: {m_lo / box_factor(K):.4f} (D / {box_factor(K):.4f}, mean k): the "
                         "verdict depends on the box convention")
        if fid.startswith("7b") and n_lo:
            notes.append(f"in the walls' box: {m_lo / box_factor(K):.4f}")
        if no_k and fn is not None:
            notes.append("seeds without a box factor (left out): " + ", ".join(map(str, no_k)))
        if n_lo:
            fin_lo = [x for x in lo if math.isfinite(x)]
            lo_txt = fmt_ms(m_lo, se_lo, n_lo, p) + f"; seeds {min(fin_lo):.4g}..{max(fin_lo):.4g}"
        else:
            lo_txt = missing_text("runs missing or failed")
        rows.append((fid, fin, paper, band, lo_txt, fmt_ms(m_hi, se_hi, n_hi, p) if hi else "—", inb, vd,
                     "; ".join(notes)))
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
        if len(c) == 7 and c[0] in COMPARED:
            out.setdefault(c[0], []).append((c[1], c[4], c[5].strip("*")))
    return out


def run_table(mode, R, runs):
    L = ["| run | tool | status | D0 → D end (die's box; affine: its own) | increments not accepted | wall time |",
         "|---|---|---|---|---|---|"]
    for name, tool, _, _ in all_runs(mode, runs):
        r = R[name]
        if not r.ok:
            L.append(f"| {name} | {tool} | {r.status} | — | — | — |")
            continue
        un = r.summary.get("solver", {}).get("unconverged_increments", "—") if tool == "netsolve" else "—"
        L.append(f"| {name} | {tool} | {r.status} | {r.h['D'][0]:.4f} → {r.h['D'][-1]:.4f} | {un} | "
                 f"{r.meta.get('wall_s', float('nan')):.0f} s |")
    return L


def tag_of(fid, fin):
    """What tells apart the lines of one id: the deviation measure (7x) and the case (7c)."""
    if not fid.startswith("7"):
        return ""
    case = fin.split(":")[0].replace("mu =", "μ =") if fid.startswith("7c") else ""
    return case + ("rom" if "⟩/⟨uNA⟩" in fin else "mor")


def label_of(r):
    who = "netsolve" if r[1].find("netsolve") >= 0 else "DEM"
    return who + (f" at {r[1].split('at D = ')[1].split()[0].rstrip(':')}" if "at D = " in r[1] else "")


def write_report(mode, R, K, runs, out, binaries, cmdline, reused=None):
    rows, per_seed = evaluate(mode, R, K)
    fr_rows = FR.evaluate(mode, R, helpers())
    layer_rows = FR.evaluate(mode, R, helpers(), layer=True)
    figs = make_figures(mode, R, out)
    I_lo, I_hi = min(INERTIAL), max(INERTIAL)
    c = tally([r[7] for r in rows + fr_rows + layer_rows])
    ks = [x for x in K.values() if math.isfinite(x)]
    krange = f"{min(ks):.4f}..{max(ks):.4f} over the seeds" if ks else "none: no seed has its affine run"
    L = ["# Redanz & Fleck's compaction findings between walls: the DEM at two rates, and netsolve from a jammed state", "",
         f"Generated by `{cmdline}`. validation/redanz_fleck_compaction evaluates the paper's findings on netsolve in the "
         "paper's die with the legacy drag; its frictionless runs do not converge (183-200 of 200 increments). Issue 28 "
         "asks for the frictionless findings (3a, 3b, 6a, 7a) on converged runs and on the DEM limit; issue 32 for the "
         "unexplained lines with friction on the DEM.", "",
         "**This departs from the paper's boundary.** Without the drag in the answer a frictionless packing in the paper's "
         "die (the peripheral layer prescribed) pours out of it (docs/quasistatic.md, \"Frictionless: the die leaks\"). "
         f"Here the same ballistic depositions (W = {mode['width']}, r = R[0.9, 1.1], seeds "
         f"{', '.join(map(str, mode['seeds']))}) are compacted between four rigid frictionless walls to D = {TARGET_D:g} in "
         "the walls' box:",
         f"* **the DEM**: `demsolve compact --boundary walls --friction 0` from the deposition at I = {I_hi:g} and "
         f"{I_lo:g}, hydrostatic and closed die. The frictionless lines are graded on the mean over the seeds at "
         f"I = {I_lo:g}; the column at I = {I_hi:g} shows how far the rate still moves them (several lines still move: "
         "they are the DEM at these rates, not an extrapolated limit);",
         "* **netsolve** cannot start from the deposition (a frictionless packing below jamming is a mechanism), so it "
         f"starts from the DEM's jammed state (I = {I_hi:g}, walls' box D = {JAM_D:g}, every wall loaded) and runs to "
         f"{TARGET_D:g} in the walls' box with the pseudo-transient iteration: past the paper's densities, so its line is "
         "information;",
         "* **the affine reference** of 3a: netsolve --affine from the same deposition in the die's box (the walls "
         "exclude --affine), compared at the same strain, its stress scaled to the walls' box area (÷ k). Between walls "
         "an affine motion would also press the disks touching the walls into them, a few per cent of the stress that "
         "this reference leaves out.", "",
         "**Densities are the die's box's** (the paper's: the cylinders' area over the container's): every walls run's D "
         f"is converted at equal strain, D × k with k = D0_die / D0_walls of the same deposition ({krange}); the walls' "
         "own values are in the notes where a verdict depends on the box. Definitions and bands are the compaction case's (validation/redanz_fleck_compaction/"
         "run.py), never widened: Z counts loaded disk-disk contacts (the paper's Z also counts the network's unloaded "
         "elements); the up-turn is the first window (±0.0025 in D) whose least-squares slope of |S22| reaches half the "
         "final slope (the last 0.005 before D = 0.85); the deviation measures accumulate since each contact formed "
         "(Eq 16), over loaded contacts, and their peaks are taken up to D = 0.85. A DEM row is the mean over its output "
         "window; a netsolve row the state at the increment's end. Counts are of lines, not findings (3a has three).", "",
         f"## Findings: {c['PASS']} pass, {c['FAIL']} fail, {c[MISSING]} missing, {c['other']} other (all three tables)", "",
         "### Without friction (issue 28)", "",
         f"| # | finding | paper | band | measured at I = {I_lo:g}: mean ± se over the seeds | at I = {I_hi:g} | "
         "seeds in band | verdict | notes |", "|---|---|---|---|---|---|---|---|---|"]
    L += FR.table_rows(rows, esc)
    L += FR.section(mode, fr_rows, esc)
    L += FR.layer_section(mode, R, layer_rows, esc)
    old = compaction_rows()
    L += ["", "## Which verdicts moved", "",
          "The same findings in validation/redanz_fleck_compaction/report.md (netsolve in the paper's die, seed 1, "
          "legacy drag) beside the verdicts here (why they moved: the notes below):", "",
          "| # | finding (compaction report) | measured there | there | here |", "|---|---|---|---|---|"]
    for fid in COMPARED:
        for fin, meas, v in old.get(fid, [("—", "—", "—")]):
            here = []
            for rs, who in ((rows, f"I = {I_lo:g}"), (fr_rows, f"walls, I = {FR.I_GRADED:g}"),
                            (layer_rows, f"die, I = {FR.I_GRADED:g}")):
                here += [f"{label_of(r)} ({who if 'netsolve' not in r[1] else 'from the jammed state'}): {r[7]}"
                         for r in rs if r[0] == fid and tag_of(fid, r[1]) == tag_of(fid, fin)
                         and not (rs is layer_rows and r[7] == MISSING)]
            L.append(f"| {fid} | {fin} | {meas} | {v} | {', '.join(here) or '—'} |")
    L += ["", "## Per seed (at I = " + f"{I_lo:g}" + "; netsolve for its line)", ""]
    seeds = mode["seeds"]
    L += ["| # | finding | " + " | ".join(f"s{s}" for s in seeds) + " |", "|---|---|" + "---|" * len(seeds)]
    for (fid, fin), vals in per_seed.items():
        L.append(f"| {fid} | {esc(fin)} | " + " | ".join("—" if not math.isfinite(vals.get(s, float("nan")))
                                                       else f"{vals[s]:.4g}" for s in seeds) + " |")
    L += ["", "## Figures", ""]
    for title, f in figs:
        L += [f"**{title}**", "", f"![{f}]({f})", ""]
    L += ["## Runs", ""] + run_table(mode, R, runs)
    notes = os.path.join(HERE, "notes.md")
    if os.path.isfile(notes) and mode["name"] == "full":
        L += ["", "## Notes (notes.md, written by hand)", "", open(notes, encoding="utf-8").read().strip()]
    L += provenance_lines(provenance(REPO, CASE, binaries, reused), c)
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(L) + "\n")
    print(f"report: {shown_path(os.path.join(out, 'report.md'), REPO)} ({c})")


def main():
    a, runs, out, only, bins = PER.parse_case_args(__doc__, HERE, "dem/*,net/s1")
    mode = QUICK if a.quick else FULL
    if not a.report_only:
        for items in (prep_runs(mode), net_runs(mode, runs), FR.runs(mode, dem_name, dem_args),
                      FR.layer_runs(mode, dem_args)):
            PER.run_all(a.jobs, bins, runs, a.force, a.timeout, [r for r in items if PER.selected(r[0], only)])
    cmdline = "/usr/bin/python3 validation/redanz_fleck_walls/run.py" + (" --quick" if a.quick else "")
    R, K = load(mode, runs)
    write_report(mode, R, K, runs, out, [a.netsolve, a.demsolve], cmdline,
                 "all (--report-only)" if a.report_only else None)


if __name__ == "__main__":
    main()
