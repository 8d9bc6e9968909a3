#!/usr/bin/env python3
"""The cross-check in a periodic cell (issue 29): netsolve's quasi-static answer against the explicit
DEM's limit I -> 0, on periodic packings where nothing leaks and no wall or prescribed layer acts.

usage: /usr/bin/python3 validation/quasistatic_vs_dynamic_periodic/run.py
           [--quick] [--netsolve PATH] [--demsolve PATH] [--jobs 2] [--runs DIR] [--force]
           [--only PATTERN,...] [--report-only] [--timeout S]
       (also: validation/quasistatic_vs_dynamic/run.py --boundary periodic ...)

Packings: `netsolve pack --periodic --n 1600 --seed 1|2|3` (--quick: --n 400, seed 1), each with its
own jammed density D0. Paths: hydrostatic and closed die from D0 to D0 + 0.03; pure shear
(E11, E22, E12) = (1, -1, 0)/sqrt(2) to |E| = 0.02 after hydrostatic precompaction to D0 + 0.015.
Friction mu = inf (sticking), 0.1 and 0. Per combination:
  * `demsolve compact --boundary periodic` at I = 4e-4, 2e-4, 1e-4; the fit sigma = sigma0 + a I
    (least squares) gives sigma0 and its standard error at each comparison point;
  * `netsolve compact --boundary periodic --iteration pseudo-transient` at --regularisation-scale 1
    (the answer compared) and 0.1, 10 (the answer must not move with the regularisation).
Compared at equal D - D0 (5 points, --quick 2) or, in shear, at equal shear strain |E_dev|.
Bands (issue 29, fixed here, never widened): |dSigma_ij| <= 0.02 max(|sigma0_11|, |sigma0_22|) at the
point; Z within +-0.05; a stress line is valid only if se(sigma0) <= 0.005 of the same scale. A
netsolve run with unaccepted increments fails its lines (the note says so). Lines whose runs are
missing are MISSING with the reason.

One folder per run; a run is skipped when its folder holds summary.json and a command.txt with the
same arguments; --force reruns. Simulations run under `nice -n 10`, --jobs at a time, seed 1 first.
"""
import argparse
import concurrent.futures
import fnmatch
import json
import math
import os
import sys
import warnings

import numpy as np
import matplotlib

matplotlib.use("Agg")
warnings.filterwarnings("ignore", message=".*tight_layout.*")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import MISSING, load_module, provenance, provenance_lines, shown_path, tally  # noqa: E402


# the layer/walls case's module (validation/quasistatic_vs_dynamic/run.py): its runner, reader and fit
_qvd = load_module("qvd_layer", os.path.join(REPO, "validation", "quasistatic_vs_dynamic", "run.py"))
Run, fit, fmt, run_one = _qvd.Run, _qvd.fit, _qvd.fmt, _qvd.run_one


def _up_to_date(d, args):
    """As the layer case's, but blind to empty arguments: the tools wrote `--snapshots ''` unquoted into
    command.txt before 2026-12-04 (apps/common/output.cpp shell_command), so such runs compare equal."""
    import shlex
    cmd = os.path.join(d, "command.txt")
    if not (os.path.isfile(os.path.join(d, "summary.json")) and os.path.isfile(cmd)) or \
            os.path.exists(os.path.join(d, ".incomplete")):
        return False
    with open(cmd) as f:
        recorded = [w for w in shlex.split(f.read().strip()) if w not in ("--overwrite", "")]
    return recorded[1:] == [w for w in args if w] + ["--out", d]


_qvd.up_to_date = _up_to_date  # (run_one looks it up in its module)

CASE = "quasistatic_vs_dynamic_periodic"
BOUNDARY = "periodic"           # the compactions' --boundary
FULL = {"name": "full", "n": 1600, "seeds": (1, 2, 3), "dd": (0.006, 0.012, 0.018, 0.024, 0.03),
        "es": (0.004, 0.008, 0.012, 0.016, 0.02)}
QUICK = {"name": "quick", "n": 400, "seeds": (1,), "dd": (0.015, 0.03), "es": (0.01, 0.02)}
INERTIAL = (4e-4, 2e-4, 1e-4)
SCALES = (1, 0.1, 10)           # netsolve --regularisation-scale; 1 is the answer compared
DD, INC = 0.03, 30              # hydrostatic and closed die: D0 -> D0 + DD in INC increments
PRE_DD, PRE_INC = 0.015, 15     # pure shear: hydrostatic precompaction to D0 + PRE_DD, then
SHEAR_E, SHEAR_INC = 0.02, 20   # pure shear to |E| = SHEAR_E
PATHS = (("hydro", "hydrostatic"), ("die", "closed-die"), ("shear", "1,-1,0"))
FRICTIONS = (("inf", "inf"), ("mu0.1", "0.1"), ("mu0", "0"))
STRESS_BAND = 0.02      # |dSigma| <= 0.02 max(|sigma0_11|, |sigma0_22|)
SE_VALID = 0.005        # valid if se(sigma0) <= 0.005 of the same scale
Z_BAND = 0.05
DRAG_BAND = 0.005       # the spread of netsolve's answer over the scales 0.1 ... 10, of the same scale
YIELD_DIRECTIONS, YIELD_PROBES = 8, (3, 4, 5, 6)  # theta = 135, 180, 225, 270 deg
YIELD_BAND = 0.03       # |S_dem - S_net| / |S_loading| (issue 29, "Yield in the periodic cell")
QTY = {"hydro": (("S11", "Σ11"), ("S22", "Σ22"), ("Z", "Z")),
       "die": (("S11", "Σ11"), ("S22", "Σ22"), ("Z", "Z")),
       "shear": (("Sdev", "Σ11 − Σ22"), ("S12", "Σ12"), ("Z", "Z"))}


def combos(mode):
    for seed in mode["seeds"]:
        for pk, pv in PATHS:
            for fk, fv in FRICTIONS:
                yield f"s{seed}_{pk}_{fk}", dict(seed=seed, pk=pk, path=pv, fk=fk, friction=fv)


def pack_args(mode, seed):
    return ["pack", "--periodic", "--n", str(mode["n"]), "--seed", str(seed), "--quiet"]


def target(d0):
    """The end density of the hydrostatic and die runs (and the yield precompaction) as the commands get
    it: D0 + DD to 6 decimals; the last comparison point is this density."""
    return float(f"{d0 + DD:.6f}")


def path_args(c, d0):
    if c["pk"] == "shear":
        return ["--path", c["path"], "--precompact-density", f"{d0 + PRE_DD:.6f}", "--precompact-increments",
                str(PRE_INC), "--to-strain", f"{SHEAR_E:g}", "--increments", str(SHEAR_INC)]
    return ["--path", c["path"], "--to-density", f"{target(d0):.6f}", "--increments", str(INC)]


def dem_args(c, start, d0, I):
    return (["compact", "--boundary", BOUNDARY] + start + ["--friction", c["friction"]]
            + path_args(c, d0) + ["--inertial-number", f"{I:g}", "--snapshots", "", "--quiet"])


def net_args(c, start, d0, scale):
    return (["compact", "--boundary", BOUNDARY] + start + ["--friction", c["friction"]]
            + path_args(c, d0) + ["--iteration", "pseudo-transient", "--regularisation-scale", f"{scale:g}",
                                  "--snapshots", "", "--allow-unconverged", "--quiet"])


def yield_args(tool, pack, d0, probing="periodic"):
    """Yield after periodic hydrostatic precompaction to D0 + DD, sticking, seed 1; netsolve probes with
    its pseudo-transient iteration. probing: "periodic" (the cell relaxed) or "affine" (every centre
    follows the cell from the unloading on, the spins free: --probe-bc affine)."""
    a = ["yield", "--packing", pack, "--compact-bc", "periodic", "--to-density", f"{target(d0):.6f}",
         "--directions", str(YIELD_DIRECTIONS), "--probes", ",".join(map(str, YIELD_PROBES)), "--quiet",
         "--allow-unconverged"]
    if probing == "affine":
        a += ["--probe-bc", "affine"]
    return a + (["--jobs", "1"] if tool == "demsolve" else ["--iteration", "pseudo-transient"])


YIELD_PROBINGS = ("periodic", "affine")


def yield_runs(mode, runs):
    seed = mode["seeds"][0]
    d0 = read_d0(runs, seed)
    if d0 is None:
        return []
    pack = os.path.join(pack_dir(runs, seed), "packing.csv")
    return [(f"yield/{t[:3]}_{pr}", t, yield_args(t, pack, d0, pr), (0, 2 * j + k))
            for j, pr in enumerate(YIELD_PROBINGS) for k, t in enumerate(("demsolve", "netsolve"))]


def pack_dir(runs, seed):
    return os.path.join(runs, "pack", f"s{seed}")


def read_d0(runs, seed):
    try:
        with open(os.path.join(pack_dir(runs, seed), "summary.json")) as f:
            s = json.load(f)
        return float(s["density"]) if s.get("status") == "ok" else None
    except (OSError, ValueError, KeyError):
        return None


def start_of(runs, c):
    """(D0, the arguments that start a compaction of combination c from its prepared packing), or
    (None, None) while the packing is not there."""
    d0 = read_d0(runs, c["seed"])
    return (None, None) if d0 is None else (d0, ["--packing", os.path.join(pack_dir(runs, c["seed"]), "packing.csv")])


def points(mode, c):
    """The comparison points of combination c: D - D0, or |E_dev| in shear."""
    return mode["es"] if c["pk"] == "shear" else mode["dd"]


def prep_runs(mode):
    """The runs that prepare the starts: one periodic packing per seed."""
    return [(f"pack/s{s}", "netsolve", pack_args(mode, s), (s,)) for s in mode["seeds"]]


def read_preps(mode, runs):
    """The summaries of the preparations, for the report's first table."""
    packs = {}
    for s in mode["seeds"]:
        try:
            with open(os.path.join(pack_dir(runs, s), "summary.json")) as f:
                packs[s] = json.load(f)
        except (OSError, ValueError):
            packs[s] = None
    return packs


def compact_runs(mode, runs, scales=SCALES):
    """(name, tool, args, priority) of every compaction run whose packing exists."""
    out = []
    for name, c in combos(mode):
        d0, pack = start_of(runs, c)
        if d0 is None:
            continue
        pr = (c["seed"], [p for p, _ in PATHS].index(c["pk"]), [f for f, _ in FRICTIONS].index(c["fk"]))
        for I in INERTIAL:
            out.append((f"dem/{name}/I{I:g}", "demsolve", dem_args(c, pack, d0, I), pr + (1, I)))
        for s in scales:
            out.append((f"net/{name}/x{s:g}", "netsolve", net_args(c, pack, d0, s), pr + (0, s != 1)))
    return out


# ---------------------------------------------------------------------------------------- reading
def shear_strain(h):
    """|E_dev| = sqrt((E11 - E22)^2 / 2 + 2 E12^2), the equivalent strain of the shear leg."""
    return np.sqrt(0.5 * (h["E11"] - h["E22"]) ** 2 + 2.0 * h["E12"] ** 2)


def prepare(r, pk):
    """Adds the derived columns: Sdev = S11 - S22 and, for the shear path, the axis Es of the shear leg
    (the rows of the leg, from the last row of the precompaction)."""
    if not r.ok:
        return r
    for h in {id(r.h): r.h, id(r.hw): r.hw}.values():
        if "S11" in h and "S22" in h:
            h["Sdev"] = h["S11"] - h["S22"]
        if pk == "shear" and "E11" in h:
            es = shear_strain(h)
            if "leg" in h:
                first = int(np.argmax(h["leg"] > 0.5)) if np.any(h["leg"] > 0.5) else len(es)
                es[:max(first - 1, 0)] = np.nan  # the precompaction rows, except the leg's start
            h["Es"] = es
    if r.tool == "netsolve":  # window means of the derived columns too
        for k in ("Sdev", "S12"):
            if k in r.h:
                v = r.h[k]
                w = v.copy()
                w[1:] = 0.5 * (v[1:] + v[:-1])
                r.hw[k] = w
    return r


def value(r, col, x, pk, d0):
    """The value at the point x (D - D0, or |E_dev| in shear), at most at target(d0)."""
    if not r.ok:
        return float("nan")
    if pk == "shear":
        return r.at(col, x, by="Es")
    return r.at(col, min(d0 + x, target(d0)), by="D")


def unaccepted(r):
    """Increments not accepted by netsolve (column `converged` == 0), and their count."""
    if not r.ok or "converged" not in r.h:
        return None
    return int(np.sum(r.h["converged"][1:] < 0.5)), len(r.h["converged"]) - 1


# ------------------------------------------------------------------------------------------ evaluate
def evaluate(R, mode, runs):
    rows, drag_rows = [], []
    for name, c in combos(mode):
        d0, _ = start_of(runs, c)
        pk = c["pk"]
        pts = points(mode, c)
        dem = [(I, R.get(f"dem/{name}/I{I:g}")) for I in INERTIAL]
        dem = [(I, r) for I, r in dem if r is not None and r.ok]
        nets = {s: R.get(f"net/{name}/x{s:g}") for s in SCALES}
        n0 = nets[1]
        for x in pts:
            fits = {}
            for col in ("S11", "S22", "Sdev", "S12", "Z"):
                fits[col] = fit([I for I, _ in dem], [value(r, col, x, pk, d0) for _, r in dem])
            scale = max(abs(fits["S11"][0]), abs(fits["S22"][0]))
            for col, label in QTY[pk]:
                s0, se, a, n = fits[col]
                nv = value(n0, col, x, pk, d0) if n0 is not None else float("nan")
                row = dict(case=name, c=c, x=x, col=col, label=label, net=nv, s0=s0, se=se, scale=scale, n=n)
                if d0 is None:
                    row.update(verdict=MISSING, note="no packing")
                elif n0 is None or not n0.ok:
                    why = "netsolve run missing" if n0 is None or not n0.meta else \
                        f"netsolve run failed (exit {n0.meta.get('returncode')})"
                    row.update(verdict=f"{MISSING} ({why})", note="")
                elif len(dem) < len(INERTIAL):
                    row.update(verdict=f"{MISSING} (DEM runs at {len(dem)} of {len(INERTIAL)} inertial numbers)", note="")
                elif not (np.isfinite(nv) and np.isfinite(s0) and np.isfinite(scale)):
                    row.update(verdict="invalid", note="point not reached")
                else:
                    ua = unaccepted(n0)
                    conv = ua is not None and ua[0] == 0
                    unconv = "" if conv else f"netsolve unconverged: {ua[0]} of {ua[1]} increments not accepted"
                    if col == "Z":
                        ok, dist = abs(nv - s0) <= Z_BAND, f"{nv - s0:+.3f}"
                        valid = True
                    else:
                        ok = abs(nv - s0) <= STRESS_BAND * scale
                        dist = f"{nv - s0:+.4f} ({100 * (nv - s0) / scale:+.2f} % of scale)"
                        valid = se <= SE_VALID * scale
                    if not valid:
                        verdict = "invalid"
                        note = f"se(σ₀) = {100 * se / scale:.2f} % of scale > 0.5 %"
                    else:
                        verdict = "PASS" if ok and conv else "FAIL"
                        note = ""
                    row.update(verdict=verdict, note="; ".join(t for t in (dist, note, unconv) if t))
                rows.append(row)
            drag_rows += drag_rows_of(R, mode, runs, name, c, x, scale, d0)
    return rows, drag_rows


def drag_rows_of(R, mode, runs, name, c, x, scale, d0):
    """The regularisation lines of combination c at the point x: netsolve's S22 (Sdev in shear) at the
    scales 0.1, 1, 10 must lie within DRAG_BAND of the scale, every increment accepted."""
    pk = c["pk"]
    nets = {s: R.get(f"net/{name}/x{s:g}") for s in SCALES}
    col = "Sdev" if pk == "shear" else "S22"
    vals = [value(nets[s], col, x, pk, d0) if nets[s] is not None else float("nan") for s in SCALES]
    uas = [unaccepted(nets[s]) if nets[s] is not None else None for s in SCALES]
    if d0 is None or any(nets[s] is None or not nets[s].ok for s in SCALES):
        v, note = f"{MISSING} (netsolve runs at {len(SCALES)} scales not all there)", ""
    elif not all(np.isfinite(vals)) or not np.isfinite(scale):
        v, note = "invalid", "point not reached or no DEM scale"
    else:
        spread = max(vals) - min(vals)
        conv = all(u is not None and u[0] == 0 for u in uas)
        v = "PASS" if spread <= DRAG_BAND * scale and conv else "FAIL"
        note = f"{100 * spread / scale:.3f} % of scale" + ("" if conv else "; unaccepted increments: " + " / ".join(
            str(u[0]) if u else "?" for u in uas))
    return [dict(case=name, x=x, col=col, vals=vals, verdict=v, note=note)]


def evaluate_yield(R, mode):
    """Rows of the yield table: per probing (periodic, affine), probe and definition, the distance of the
    two solvers' points relative to netsolve's loading stress."""
    rows = []
    for probing in YIELD_PROBINGS:
        rd, rn = R.get(f"yield/dem_{probing}"), R.get(f"yield/net_{probing}")
        yd = _qvd.read_yield(rd.dir) if rd is not None and rd.ok else {}
        yn = _qvd.read_yield(rn.dir) if rn is not None and rn.ok else {}
        ln = rn.summary.get("precompaction", {}) if rn is not None and rn.ok else {}
        scale = math.hypot(_qvd.num(ln.get("S11")), _qvd.num(ln.get("S22")))
        for k in YIELD_PROBES:
            for kind, sfx in (("curvature", ""), ("offset", "_offset")):
                a = tuple(_qvd.num(yd.get(k, {}).get(c + sfx)) for c in ("S11", "S22"))
                b = tuple(_qvd.num(yn.get(k, {}).get(c + sfx)) for c in ("S11", "S22"))
                dist = (math.hypot(a[0] - b[0], a[1] - b[1]) / scale if all(map(np.isfinite, a + b + (scale,)))
                        else float("nan"))
                if not (yd and yn):
                    v = f"{MISSING} ({probing} yield runs not there)"
                elif not np.isfinite(dist):
                    v = "invalid"
                else:
                    v = "PASS" if dist <= YIELD_BAND else "FAIL"
                rows.append(dict(probe=k, theta=360.0 * k / YIELD_DIRECTIONS, kind=kind, probing=probing, dem=a, net=b,
                                 dist=dist, verdict=v,
                                 st=(yd.get(k, {}).get("status", "—"), yn.get(k, {}).get("status", "—"))))
    return rows


# ------------------------------------------------------------------------------------------ figures
def make_figures(R, mode, runs, out):
    figs = []
    seed = mode["seeds"][0]
    for pk, col, ylab, xl in (("hydro", "S22", "Σ22", "D − D0"), ("die", "S22", "Σ22", "D − D0"),
                              ("shear", "Sdev", "Σ11 − Σ22", "|E_dev| of the shear leg")):
        if pk not in [p for p, _ in PATHS]:
            continue
        fig, axs = plt.subplots(1, 3, figsize=(13, 3.8), sharey=False)
        drawn = False
        for ax, (fk, fv) in zip(axs, FRICTIONS):
            name = f"s{seed}_{pk}_{fk}"
            d0, _ = start_of(runs, dict(seed=seed, pk=pk, fk=fk))
            if d0 is None:
                continue
            for k, I in enumerate(INERTIAL):
                r = R.get(f"dem/{name}/I{I:g}")
                if r is not None and r.ok and col in r.h:
                    xs = r.h["Es"] if pk == "shear" else r.h["D"] - d0
                    ax.plot(xs, r.h[col], "-", color=f"C{k}", lw=1, label=f"DEM I = {I:g}")
                    drawn = True
            for s, st in ((1, "k-"), (0.1, "k:"), (10, "k--")):
                r = R.get(f"net/{name}/x{s:g}")
                if r is not None and r.ok and col in r.hw:
                    xs = r.hw["Es"] if pk == "shear" else r.hw["D"] - d0
                    ax.plot(xs, r.hw[col], st, lw=1.2, label=f"netsolve ×{s:g} (window means)")
                    drawn = True
            pts = points(mode, dict(pk=pk, fk=fk))
            dem = [(I, R.get(f"dem/{name}/I{I:g}")) for I in INERTIAL]
            dem = [(I, r) for I, r in dem if r is not None and r.ok]
            if len(dem) >= 2:
                s0 = [fit([I for I, _ in dem], [value(r, col, x, pk, d0) for _, r in dem])[0] for x in pts]
                ax.plot(pts, s0, "rs", ms=5, label="DEM σ₀ (I → 0)")
            ax.set_title(f"seed {seed}, {pk}, μ = {fv}")
            ax.set_xlabel(xl)
            ax.set_ylabel(ylab + " [σ_y]")
        if drawn:
            axs[0].legend(fontsize=7)
            fig.tight_layout()
            fn = f"fig_{pk}_{col}.png"
            fig.savefig(os.path.join(out, fn), dpi=110)
            figs.append(fn)
        plt.close(fig)
    return figs


# ------------------------------------------------------------------------------------------- report
def unaccepted_substeps(r):
    """Sub-increments netsolve committed without accepting them (history.csv `unconverged_substeps`,
    the damped path of a cut increment; docs/quasistatic.md "Cut increments"), or None for a run
    older than that column."""
    if not r.ok or "unconverged_substeps" not in r.h:
        return None
    return int(np.sum(r.h["unconverged_substeps"][1:]))


def run_table(R, names):
    lines = ["| run | status | wall time [s] | unaccepted increments | unaccepted sub-increments | instability events |",
             "|---|---|---|---|---|---|"]
    for n in names:
        r = R[n]
        ua = unaccepted(r) if r.tool == "netsolve" else None
        us = unaccepted_substeps(r) if r.tool == "netsolve" else None
        ev = int(np.sum(r.h["instability"][1:] > 0.5)) if r.tool == "netsolve" and r.ok and "instability" in r.h else None
        wall = r.meta.get("wall_s")
        lines.append(f"| `{n}` | {r.status if r.ok else 'missing'} | {fmt(wall, 1) if wall is not None else '—'} | "
                     f"{'—' if ua is None else f'{ua[0]} of {ua[1]}'} | {'—' if us is None else us} | "
                     f"{'—' if ev is None else ev} |")
    return lines


def yield_section(R, mode):
    """The yield table's lines and verdicts."""
    yrows = evaluate_yield(R, mode)
    L = ["", "## Yield in the periodic cell", "",
          f"Seed {mode['seeds'][0]}, sticking, hydrostatic precompaction to D0 + {DD:g}, probes "
          f"{', '.join(map(str, YIELD_PROBES))} of {YIELD_DIRECTIONS}: `demsolve yield --compact-bc periodic` (its "
          "defaults) and `netsolve yield --compact-bc periodic --iteration pseudo-transient`; probing periodic "
          "(the cell relaxed) or affine (`--probe-bc affine`: every centre follows the cell from the unloading on, "
          "the spins free). Band: the distance of "
          f"the two points ≤ {100 * YIELD_BAND:g} % of netsolve's loading stress |Σ|.", "",
          "| probe | θ [°] | probing | definition | DEM (Σ11, Σ22) | netsolve (Σ11, Σ22) | distance | status DEM / net | result |",
          "|---|---|---|---|---|---|---|---|---|"]
    for y in yrows:
        dist = "—" if not np.isfinite(y["dist"]) else f"{100 * y['dist']:.2f} %"
        L.append(f"| {y['probe']} | {y['theta']:g} | {y['probing']} | {y['kind']} | ({fmt(y['dem'][0])}, {fmt(y['dem'][1])}) | "
                 f"({fmt(y['net'][0])}, {fmt(y['net'][1])}) | "
                 f"{dist} | "
                 f"{y['st'][0]} / {y['st'][1]} | {y['verdict']} |")
    return L, [y["verdict"] for y in yrows]


def report_head(mode, packs):
    """The report's title, its introduction and the table of the prepared packings."""
    L = [f"# Validation: the cross-check in a periodic cell ({mode['name']} mode)", "",
         "Generated by `validation/quasistatic_vs_dynamic_periodic/run.py" + (" --quick" if mode["name"] == "quick" else "")
         + "`; what it measures and why: README.md of this folder. netsolve (`compact --boundary periodic "
         "--iteration pseudo-transient`, regularisation ×1) against the DEM's limit σ = σ₀ + a·I "
         f"(I = {', '.join(f'{I:g}' for I in INERTIAL)}). Band: |Δ| ≤ 2 % of max(|σ₀,11|, |σ₀,22|) at the "
         "point (\"scale\"); Z ±0.05; a stress line is valid if se(σ₀) ≤ 0.5 % of the scale. A netsolve run "
         "with increments it did not accept fails its lines.", "", "## Packings", "",
         "| seed | particles | D0 | Z without rattlers | rattlers | ψ6 global | max overlap / R | status |",
         "|---|---|---|---|---|---|---|---|"]
    for seed in mode["seeds"]:
        p = packs.get(seed) or {}
        L.append(f"| {seed} | {p.get('particles', '—')} | {fmt(p.get('density'), 4)} | "
                 f"{fmt(p.get('coordination_without_rattlers'), 3)} | {fmt(p.get('rattler_fraction'), 3)} | "
                 f"{fmt((p.get('psi6') or {}).get('global'), 2)} | {fmt((p.get('overlap_over_R') or {}).get('max'), 5)} | "
                 f"{p.get('status', 'missing')} |")
    return L



def drag_section(drag_rows):
    """The regularisation table's lines."""
    L = ["", "## The regularisation does not move netsolve's answer", "",
         f"netsolve at `--regularisation-scale` {' / '.join(f'{s:g}' for s in SCALES)}; band: spread ≤ "
         f"{100 * DRAG_BAND:g} % of the scale, every increment accepted (set with the case, before its first run).", "",
         "| case | point | quantity | ×1 / ×0.1 / ×10 | result | note |", "|---|---|---|---|---|---|"]
    for d in drag_rows:
        L.append(f"| {d['case']} | {d['x']:g} | {d['col']} | {' / '.join(fmt(v) for v in d['vals'])} | "
                 f"{d['verdict']} | {d['note']} |")
    return L

def write_report(R, mode, runs, out, binaries, packs):
    rows, drag_rows = evaluate(R, mode, runs)
    figs = make_figures(R, mode, runs, out)
    L = report_head(mode, packs)
    L += ["", "## netsolve against the DEM limit", "",
          "| case | point | quantity | netsolve | DEM σ₀ ± se | scale | result | note |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        pt = f"E = {r['x']:g}" if r["c"]["pk"] == "shear" else f"D − D0 = {r['x']:g}"
        L.append(f"| {r['case']} | {pt} | {r['label']} | {fmt(r['net'])} | {fmt(r['s0'])} ± {fmt(r['se'])} | "
                 f"{fmt(r['scale'])} | {r['verdict']} | {r['note']} |")
    L += drag_section(drag_rows)
    ylines, yverdicts = yield_section(R, mode)
    L += ylines
    c = tally([r["verdict"] for r in rows] + [d["verdict"] for d in drag_rows] + yverdicts)
    L += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figs]
    L += ["", "## Runs", ""] + run_table(R, sorted(R))
    notes = os.path.join(HERE, "notes.md")
    if os.path.isfile(notes):
        L += ["", "## Notes (notes.md, written by hand)", "", open(notes, encoding="utf-8").read().strip()]
    L += provenance_lines(provenance(REPO, CASE, binaries), c)
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(L) + "\n")
    print(f"report: {shown_path(os.path.join(out, 'report.md'), REPO)} ({c})")


# ------------------------------------------------------------------------------------------- driver
def run_all(jobs, binaries, runs, force, timeout, items):
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as ex:
        futs = [ex.submit(run_one, name, binaries[tool], args, os.path.join(runs, name), force, timeout)
                for name, tool, args, _ in sorted(items, key=lambda t: t[3])]
        for f in concurrent.futures.as_completed(futs):
            name, msg = f.result()
            print(f"{name}: {msg}", flush=True)


def selected(name, only):
    return not only or any(fnmatch.fnmatch(name, p) for p in only)


def parse_case_args(doc, here, only_example):
    """The command line of a case that runs both tools (this one, redanz_fleck_walls): the parsed arguments,
    the run folder, the report folder, the --only patterns and the binaries (checked unless --report-only)."""
    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--demsolve", default=os.path.join(REPO, "build", "apps", "demsolve"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--runs", default=None, help="run folders (default: runs/ or runs_quick/ beside this script)")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--only", default="", help=f"comma list of run-name patterns (e.g. '{only_example}')")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--timeout", type=float, default=7200)
    a = ap.parse_args()
    runs = os.path.abspath(a.runs or os.path.join(here, "runs_quick" if a.quick else "runs"))
    out = os.path.join(here, "quick") if a.quick else here
    os.makedirs(out, exist_ok=True)
    only = [p for p in a.only.split(",") if p]
    bins = {"netsolve": a.netsolve, "demsolve": a.demsolve}
    if not a.report_only:
        for b in bins.values():
            if not os.access(b, os.X_OK):
                sys.exit(f"error: binary not found: {b} (build first: cmake --build build)")
    return a, runs, out, only, bins


def main():
    a, runs, out, only, bins = parse_case_args(__doc__, HERE, "pack/*,*/s1_hydro_*")
    mode = QUICK if a.quick else FULL
    if not a.report_only:
        packs = prep_runs(mode)
        run_all(a.jobs, bins, runs, a.force, a.timeout, [p for p in packs if selected(p[0], only)])
        rs = [r for r in yield_runs(mode, runs) + compact_runs(mode, runs) if selected(r[0], only)]
        run_all(a.jobs, bins, runs, a.force, a.timeout, rs)
    R = {}
    for name, tool, _, _ in yield_runs(mode, runs):
        R[name] = Run(os.path.join(runs, name), tool)
    for name, tool, _, _ in compact_runs(mode, runs):
        pk = name.split("/")[1].split("_")[1]
        R[name] = prepare(Run(os.path.join(runs, name), tool), pk)
    packs = read_preps(mode, runs)
    write_report(R, mode, runs, out, [a.netsolve, a.demsolve], packs)


if __name__ == "__main__":
    main()
