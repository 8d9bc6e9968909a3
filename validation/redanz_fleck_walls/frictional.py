"""The paper's compaction findings with friction (2, 4, 6b, 6c, 6d, 7c, 8a-8c; 1a beside them) on the
DEM between walls (8a-8c from demsolve's Figs 7-8 columns, written since 2026-12-07), from the same depositions as the frictionless lines (issue 32: "each unexplained line
measured on converged runs and on the DEM"). Imported by run.py, which runs and reports them.

Runs per seed: `demsolve compact --boundary walls` from the deposition, hydrostatic and closed die, with
mu = 0.1, sticking, and sticking without rotation, at I = 1.5e-4 (seeds 1-8: the graded mean) and at
I = 5e-5 for seeds 1-2 (the rate check: the same seeds' values at both rates, paired).
"""
import math

import numpy as np

I_GRADED, I_CHECK = 1.5e-4, 5e-5
TARGET_D = 0.85  # the end density of the compaction case (run.py TARGET_D), in the die's box
# (path key, --path, friction key, --friction, no rotation)
CONFIGS = (("hydro", "hydrostatic", "inf", "inf", False), ("hydro", "hydrostatic", "mu0.1", "0.1", False),
           ("hydro", "hydrostatic", "inf_norot", "inf", True), ("die", "closed-die", "inf", "inf", False),
           ("die", "closed-die", "mu0.1", "0.1", False), ("die", "closed-die", "inf_norot", "inf", True))


def check_seeds(mode):
    return mode["seeds"][:2]


def layer_name(seed, pk, fk, I=I_GRADED):
    """A DEM run in the paper's die (netsolve's layer mode: the peripheral layer prescribed)."""
    return f"dem/s{seed}_layer_{pk}_{fk}_I{I:g}"


def _runs(mode, dem_args, boundary):
    """(seed, rate, path key, friction key, args) of the frictional DEM runs with the given --boundary: every
    configuration at I_GRADED, and at I_CHECK for the check seeds."""
    for s in mode["seeds"]:
        for I in (I_GRADED, I_CHECK):
            if I == I_CHECK and s not in check_seeds(mode):
                continue
            for pk, pv, fk, fv, norot in CONFIGS:
                a = dem_args(mode, s, pv, fv, I)
                a[a.index("walls")] = boundary
                if norot:
                    a = a[:-1] + ["--no-rotation", a[-1]]
                yield s, I, pk, fk, a


def layer_runs(mode, dem_args):
    """The frictional DEM runs in the paper's die: the DEM with the paper's boundary, the compaction case's
    netsolve runs' own (densities in the same box)."""
    return [(layer_name(s, pk, fk, I), "demsolve", a, (6 if I == I_GRADED else 7, s))
            for s, I, pk, fk, a in _runs(mode, dem_args, "layer")]


def runs(mode, dem_name, dem_args):
    """(name, tool, args, priority) of the frictional DEM runs between walls (hydro_inf at I_GRADED is
    run.py's already)."""
    return [(dem_name(s, pk, fk, I), "demsolve", a, (4 if I == I_CHECK else 5, s))
            for s, I, pk, fk, a in _runs(mode, dem_args, "walls") if (pk, fk, I) != ("hydro", "inf", I_GRADED)]


END_TOL = 1e-6  # a run "reaches" D = 0.85 when its last row is within this (the DEM stops at 0.85000012)


def layer_ok(R, n):
    """A run in the paper's die that reached its end: status ok, or "unstable" only for disks that left the
    die between the peripheral disks (the DEM's die leaks: counted in the section, the run is still used),
    with a final Z of at least 2 (not a mechanism)."""
    r = R.get(n)
    if r is None or not r.ok or float(r.h["D"][-1]) < TARGET_D - END_TOL:
        return False
    if r.status == "ok":
        return True
    reasons = [x for x in str(r.summary.get("status_reason", "")).split(";") if x.strip()]
    return (r.status == "unstable" and bool(reasons) and all("left the box" in x for x in reasons)
            and float(r.summary.get("final", {}).get("Z", 0.0)) >= 2.0)


def lines(R, h, layer=False):
    """(id, finding, paper, band, test of a value or None for information, value of a seed at a rate[, (text,
    value of a seed at a rate) for the notes]). layer: the runs in the paper's die (I_GRADED only).
    h: run.py's helpers (dem_name, ok, early_z, peak) and the compaction case's EVAL_D."""
    def dem(s, pk, fk, I):
        if layer:
            n = layer_name(s, pk, fk, I)
            return R[n] if layer_ok(R, n) else None
        n = h.dem_name(s, pk, fk, I)
        return R[n] if h.ok(R, n) else None

    def at(s, pk, fk, I, f):
        r = dem(s, pk, fk, I)
        return float("nan") if r is None else f(r)

    def pair(s, I, a, b, f):  # f of two runs of seed s
        ra, rb = dem(s, "hydro" if a[0] == "h" else "die", a[1], I), dem(s, "hydro" if b[0] == "h" else "die", b[1], I)
        return float("nan") if ra is None or rb is None else f(ra, rb)

    def late_max(r, col):
        m = (r.h["D"] >= 0.815) & (r.h["D"] <= TARGET_D + END_TOL)
        return float(np.max(r.h[col][m])) if m.any() else float("nan")

    def aniso(r, D):
        return r.at("S22", D) / r.at("S11", D) - 1

    L = []
    for D in h.EVAL_D:
        L.append(("1c", f"hydrostatic S22/S11 − 1 at D = {D:g}: sticking minus frictionless (paired by seed)",
                  "difference even smaller for frictionless (3.1)", "> 0 (frictionless smaller), by 2 se", lambda v: v > 0,
                  lambda s, I, D=D: pair(s, I, ("h", "inf"), ("h", "mu0"), lambda a, b: aniso(a, D) - aniso(b, D)),
                  ("frictionless S22/S11 − 1", lambda s, I, D=D: at(s, "hydro", "mu0", I, lambda r: aniso(r, D)))))
    # (every line: id, finding, paper, band, test, value, note or None, deviation column or None)
    for D in h.EVAL_D:
        L.append(("1a", f"S22/S11, hydrostatic, sticking, at D = {D:g}", "S22 ~15 % above S11 (3.1, Fig 4)", "1.05..1.25",
                  lambda v: 1.05 <= v <= 1.25, lambda s, I, D=D: at(s, "hydro", "inf", I, lambda r: r.at("S22", D) / r.at("S11", D))))
    def in_box(D, by):  # (layer) the same line at equal density of the disks left inside the die
        return ((f"at D_in_box = {D:g} (the disks left in the die)", by) if layer else None)

    for D in h.EVAL_D:
        f2 = (lambda D, by="D": lambda s, I: pair(s, I, ("h", "mu0.1"), ("h", "inf"),
                                                  lambda a, b: 1 - a.at("S22", D, by=by) / b.at("S22", D, by=by)))
        L.append(("2", f"hydrostatic S22: 1 − S22(μ = 0.1) / S22(sticking) at D = {D:g}", "drops by only 10 % (3.1, Fig 5a)",
                  "0.05..0.15", lambda v: 0.05 <= v <= 0.15, f2(D), in_box(D, f2(D, "D_in_box"))))
    for D in h.EVAL_D:
        f4 = (lambda D, by="D": lambda s, I: pair(s, I, ("h", "inf_norot"), ("h", "inf"),
                                                  lambda a, b: a.at("S22", D, by=by) / b.at("S22", D, by=by) - 1))
        L.append(("4", f"hydrostatic sticking S22: no rotation / free rotation − 1 at D = {D:g}",
                  "stiffer by about 10 % (3.1, Fig 5a)", "0.05..0.15", lambda v: 0.05 <= v <= 0.15, f4(D),
                  in_box(D, f4(D, "D_in_box"))))
    L.append(("6b", "closed die sticking: mean Z over the first 20 % of the D range", "Z about 3.0, sticking (3.2, Fig 6b)",
              "2.7..3.3", lambda v: 2.7 <= v <= 3.3, lambda s, I: at(s, "die", "inf", I, lambda r: h.early_z(r)[0])))
    L.append(("6c", "closed die sticking: early Z, no rotation minus free rotation",
              "additional slight drop with no rotation (3.2, Fig 6b)", "−0.3 ≤ dZ < 0", lambda v: -0.3 <= v < 0,
              lambda s, I: pair(s, I, ("d", "inf_norot"), ("d", "inf"), lambda a, b: h.early_z(a)[0] - h.early_z(b)[0])))
    L.append(("6d", "closed die μ = 0.1: early Z (information)", "between 3.5 and 3.0 (3.2)", "-", None,
              lambda s, I: at(s, "die", "mu0.1", I, lambda r: h.early_z(r)[0])))
    for pk, where in (("hydro", "hydrostatic"), ("die", "closed die")):
        for fk, what in (("mu0.1", "μ = 0.1"), ("inf", "sticking"), ("inf_norot", "sticking, no rotation")):
            for col, sym in (("dev_un_ratio_of_means", "⟨|uN−uNA|⟩/⟨uNA⟩"), ("dev_un_mean_ratio", "⟨|uN−uNA|/uNA⟩")):
                L.append((f"7c-{pk}", f"{where}, {what}: max of {sym} over the run", "< 50 % for μ ≥ 0.1 (3.3, Fig 7)",
                          "< 0.5", lambda v: v < 0.5,
                          lambda s, I, pk=pk, fk=fk, col=col: at(s, pk, fk, I, lambda r: h.peak(r, col)[0]),
                          ("max over D ≥ 0.815 (the compaction case's note)",
                           lambda s, I, pk=pk, fk=fk, col=col: at(s, pk, fk, I, lambda r: late_max(r, col))), col))
    def plateau(r, col):  # the compaction case's plateau: the median over 0.83 <= D <= the end density
        if col not in r.h:  # (a run of a demsolve older than its Figs 7-8 columns)
            return float("nan")
        m = (r.h["D"] >= 0.83) & (r.h["D"] <= TARGET_D + END_TOL)
        return float(np.median(r.h[col][m])) if m.any() else float("nan")

    for fid, pk, fk, what, paper, lo, hi in (
            ("8a", "hydro", "inf", "hydrostatic, sticking", "plateau ~0.5 (3.3, Fig 8a)", 0.3, 0.7),
            ("8b", "die", "mu0.1", "closed die, μ = 0.1", "plateau ~1.5 (3.3, Fig 8b)", 1.0, 2.0),
            ("8c", "die", "inf", "closed die, sticking", "plateau ~1.5 (3.3, Fig 8b)", 1.0, 2.0)):
        L.append((fid, f"{what}: plateau of ⟨|uT−uTA|⟩/⟨uNA⟩ (median over D ≥ 0.83; uT of Eq 5, with the rotations)",
                  paper, f"{lo}..{hi}", lambda v, lo=lo, hi=hi: lo <= v <= hi,
                  lambda s, I, pk=pk, fk=fk: at(s, pk, fk, I, lambda r: plateau(r, "dev_ut_rotations")),
                  ("the centres only (dev_ut_centres)",
                   lambda s, I, pk=pk, fk=fk: at(s, pk, fk, I, lambda r: plateau(r, "dev_ut_centres")))))
    return [x + (None,) * (8 - len(x)) for x in L]


def evaluate(mode, R, h, layer=False):
    """Rows (id, finding, paper, band, graded mean, rate check, seeds in band, verdict, notes); layer: the
    runs in the paper's die (no rate check; 1c needs a frictionless run there, which leaks: MISSING)."""
    seeds, chk = mode["seeds"], check_seeds(mode)
    rows = []
    for fid, fin, paper, band, test, fn, note, col in lines(R, h, layer):
        if layer and fid == "1c":
            rows.append((fid, fin, paper, band, h.missing_text("not run: the frictionless DEM pours out of the paper's "
                                                               "die (docs/quasistatic.md)"), "—", "—", h.MISSING, ""))
            continue
        v = [fn(s, I_GRADED) for s in seeds]
        m, se, n = h.stats(v)
        lo = [fn(s, I_CHECK) for s in chk]
        hi = [fn(s, I_GRADED) for s in chk]
        g = (lambda x: f"{x:.3g}" if abs(x) >= 1000 else f"{x:.3f}")
        check = "; ".join(f"s{s}: {g(a)} (at {I_GRADED:g}: {g(b)})" for s, a, b in zip(chk, lo, hi)
                          if math.isfinite(a) and math.isfinite(b)) or "—"
        fin_v = [x for x in v if math.isfinite(x)]
        notes = []
        if note:
            what, note_fn = note
            notes.append(f"{what}: {h.fmt_ms(*h.stats([note_fn(s, I_GRADED) for s in seeds]))}")
        if n == 0:
            rows.append((fid, fin, paper, band, h.missing_text("runs missing or failed"), check, "—", h.MISSING, ""))
            continue
        if n < len(seeds):
            notes.append("seeds left out (a run missing, failed or not at its end): "
                         + ", ".join(str(s) for s, x in zip(seeds, v) if not math.isfinite(x)))
        ill = col == "dev_un_mean_ratio" and m > 100  # the compaction case's rule, applied to the mean
        if ill:
            notes.append("ill-conditioned: the mean of ratios is dominated by contacts with uNA near 0 (the compaction "
                         "case's rule)")
        vd = "INVALID" if ill else (h.verdict(test(m)) if test else "n/a")
        if fid == "1c":  # a sign of a paired difference: graded where the mean is 2 se from zero
            vd = "PASS" if m - 2 * se > 0 else ("FAIL" if m + 2 * se < 0 else "UNRESOLVED")
            notes.append("PASS / FAIL only where the mean paired difference is more than 2 se from 0")
        inb = f"{sum(1 for x in fin_v if test(x))} / {n}" if test else "—"
        rows.append((fid, fin, paper, band, h.fmt_ms(m, se, n) + f"; seeds {min(fin_v):.4g}..{max(fin_v):.4g}", check, inb,
                     vd, "; ".join(notes)))
    return rows


def table_rows(rows, esc):
    """Markdown rows of (id, finding, paper, band, measured, other, in band, verdict, notes); FAIL in bold."""
    return ["| " + " | ".join(esc(x) for x in r[:7]) + f" | {'**' + r[7] + '**' if r[7] == 'FAIL' else r[7]} | "
            f"{esc(r[8])} |" for r in rows]


def leaks(mode, R):
    """Text: the disks outside the paper's die at the end of the layer runs, per configuration."""
    out = []
    for pk, _, fk, _, _ in CONFIGS:
        n = [R[layer_name(s, pk, fk)].summary.get("centres_outside_box") for s in mode["seeds"]
             if layer_ok(R, layer_name(s, pk, fk))]
        n = [x for x in n if x is not None]
        if n:
            out.append(f"{pk} {fk}: {min(n)}..{max(n)} (mean {np.mean(n):.1f}, {len(n)} runs)")
    return "; ".join(out) or "no run"


def layer_section(mode, R, rows, esc):
    """The report's section of the frictional lines on the DEM in the paper's die."""
    L = ["", f"### With friction (issue 32): the DEM in the paper's die, I = {I_GRADED:g}", "",
         "The same depositions and laws, `demsolve compact --boundary layer` (the peripheral layer prescribed, as in the "
         "paper and in validation/redanz_fleck_compaction's netsolve runs; densities in the same box, no conversion). "
         "The DEM's die leaks too: disk centres outside the box at the end, " + leaks(mode, R) + ". Such runs end "
         "\"unstable\" (exit 3) and are used here with that caveat. Graded on the mean over seeds "
         f"{', '.join(map(str, mode['seeds']))} at I = {I_GRADED:g}; the rate check gives seeds "
         f"{', '.join(map(str, check_seeds(mode)))} at I = {I_CHECK:g} beside their own values at {I_GRADED:g}.", "",
         "| # | finding | paper | band | measured: mean ± se over the seeds | rate check | seeds in band | verdict | notes |",
         "|---|---|---|---|---|---|---|---|---|"]
    return L + table_rows(rows, esc)


def section(mode, rows, esc):
    """The report's section of the frictional lines."""
    L = ["", f"### With friction (issue 32): the DEM between walls, I = {I_GRADED:g}", "",
         f"The same depositions, `demsolve compact --boundary walls` with μ = 0.1, sticking and sticking without rotation, "
         f"hydrostatic and closed die. Graded on the mean over seeds {', '.join(map(str, mode['seeds']))} at I = {I_GRADED:g}; "
         f"the rate check gives seeds {', '.join(map(str, check_seeds(mode)))} at I = {I_CHECK:g} beside their own values at "
         f"{I_GRADED:g}. Definitions and bands: the compaction case's; new here are the grading on the mean over the seeds "
         "and 1c's sign rule (2 se).", "",
         "| # | finding | paper | band | measured: mean ± se over the seeds | rate check | seeds in band | verdict | notes |",
         "|---|---|---|---|---|---|---|---|---|"]
    return L + table_rows(rows, esc)
