#!/usr/bin/env python3
"""The cross-check with walls from a jammed state (issue 28, "The DEM limit, in walls mode"): netsolve's
quasi-static answer against the explicit DEM's limit I -> 0, both started from the same jammed state.

usage: /usr/bin/python3 validation/quasistatic_vs_dynamic_walls/run.py
           [--quick] [--netsolve PATH] [--demsolve PATH] [--jobs 2] [--runs DIR] [--force]
           [--only PATTERN,...] [--report-only] [--timeout S]

Starts: `demsolve compact --width 80 --seed 1|2|3 --boundary walls --friction F --to-density 0.83
--save-state` (a ballistic deposition compacted hydrostatically between four walls until every wall
carries load; --quick: --width 40, seed 1), one jammed.json per seed and friction (the state holds
the law, so each friction has its own). Paths: hydrostatic and closed die from D0 = 0.83 to 0.85 in 20
increments. Friction mu = inf (sticking), 0.1 and 0. Per combination:
  * `demsolve compact --boundary walls --state jammed.json` at I = 4e-4, 2e-4, 1e-4; the fit
    sigma = sigma0 + a I (least squares) gives sigma0 and its standard error at each comparison point;
  * `netsolve compact --boundary walls --state jammed.json --iteration pseudo-transient` at
    --regularisation-scale 1 (the answer compared) and 0.1, 10 (the answer must not move with it:
    issue 28 "Independence" (a) without instability events, (b) against the spread of the x1 answers
    of five seeds, 1-5, where events occur; seeds 4 and 5 are run at x1 only, for that spread).
Compared at D - D0 = 0.005, 0.01, 0.015, 0.02 (--quick 0.01, 0.02); frictionless only at D - D0 = 0.02
(D = 0.85: below it the frictionless stress is near zero, issue 28 "Independence" (c)). Bands (issue 28,
never widened): |dSigma_ij| <= 0.02 max(|sigma0_11|, |sigma0_22|); Z within +-0.05; a stress line is valid
only if se(sigma0) <= 0.005 of the same scale. A netsolve run with unaccepted increments fails its
lines. The evaluation, figures and runner are the periodic case's (validation/quasistatic_vs_dynamic_periodic/run.py).
"""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))


sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import load_module  # noqa: E402

P = load_module("qvd_periodic", os.path.join(REPO, "validation", "quasistatic_vs_dynamic_periodic", "run.py"))
fmt, MISSING = P.fmt, P.MISSING

JAM_D = 0.83   # the jammed state's density: every wall carries load there (sticking and mu = 0.1)
FULL = {"name": "full", "width": 80, "seeds": (1, 2, 3), "spread": (1, 2, 3, 4, 5), "dd": (0.005, 0.01, 0.015, 0.02)}
QUICK = {"name": "quick", "width": 40, "seeds": (1,), "spread": (), "dd": (0.01, 0.02)}
# issue 28 "Independence": (a) where none of the three runs has an instability event up to the point,
# S11 and S22 within 0.2 % of netsolve's value at x1 and Z within 0.01 over the scales; (b) else the
# spread over the scales no larger than the spread of the x1 answers of the five seeds "spread"
IND_STRESS, IND_Z = 0.002, 0.01
IND_QTY = (("S11", "Σ11"), ("S22", "Σ22"), ("Z", "Z"))


def jam_key(c):
    return f"s{c['seed']}_{c['fk']}"


def jam_dir(runs, c):
    return os.path.join(runs, "jam", jam_key(c))


def jam_args(mode, seed, friction):
    return ["compact", "--width", f"{mode['width']:g}", "--seed", str(seed), "--boundary", "walls", "--friction",
            friction, "--to-density", f"{JAM_D:g}", "--save-state", "--snapshots", "", "--quiet"]


def read_jam(runs, c):
    """The jammed state's summary and its density (the last row of history.csv), or None."""
    d = jam_dir(runs, c)
    try:
        with open(os.path.join(d, "summary.json")) as f:
            s = json.load(f)
        if s.get("status") != "ok" or not os.path.isfile(os.path.join(d, "jammed.json")):
            return None
        with open(os.path.join(d, "history.csv")) as f:
            rows = [ln.strip().split(",") for ln in f if ln.strip()]
        head, last = rows[0], rows[-1]
        s["D0"] = float(last[head.index("D")])
        for k in ("Z", "S11", "S22"):
            s[k + "_0"] = float(last[head.index(k)])
        return s
    except (OSError, ValueError, KeyError, IndexError):
        return None


def start_of(runs, c):
    s = read_jam(runs, c)
    return (None, None) if s is None else (s["D0"], ["--state", os.path.join(jam_dir(runs, c), "jammed.json")])


def points(mode, c):
    return mode["dd"][-1:] if c["fk"] == "mu0" else mode["dd"]


def all_seeds(mode):
    return sorted(set(mode["seeds"]) | set(mode["spread"]))


def prep_runs(mode):
    return [(f"jam/s{s}_{fk}", "demsolve", jam_args(mode, s, fv), (s, k))
            for s in all_seeds(mode) for k, (fk, fv) in enumerate(P.FRICTIONS)]


def read_preps(mode, runs):
    return {(s, fk): read_jam(runs, dict(seed=s, fk=fk)) for s in all_seeds(mode) for fk, _ in P.FRICTIONS}


_base_compact_runs = P.compact_runs


def compact_runs(mode, runs, scales=P.SCALES):
    """The periodic case's runs for the compared seeds, and netsolve at x1 for the seeds that only
    give the seed-to-seed spread of criterion (b)."""
    out = _base_compact_runs(mode, runs, scales)
    for seed in mode["spread"]:
        if seed in mode["seeds"]:
            continue
        for ip, (pk, pv) in enumerate(P.PATHS):
            for iff, (fk, fv) in enumerate(P.FRICTIONS):
                c = dict(seed=seed, pk=pk, path=pv, fk=fk, friction=fv)
                d0, start = start_of(runs, c)
                if d0 is not None:
                    out.append((f"net/s{seed}_{pk}_{fk}/x1", "netsolve", P.net_args(c, start, d0, 1),
                                (seed, ip, iff, 0, False)))
    return out


def events_to(r, x, d0):
    """Instability events (history.csv `instability`) in the increments up to the one that reaches
    D0 + x, or None for a run without that column."""
    if r is None or not r.ok or "instability" not in r.h:
        return None
    D = r.h["D"]
    idx = np.nonzero(D >= d0 + x - 1e-12)[0]
    j = int(idx[0]) if len(idx) else len(D) - 1
    return int(np.sum(r.h["instability"][1:j + 1] > 0.5))


def drag_rows_of(R, mode, runs, name, c, x, scale, d0):
    """Issue 28's independence lines of combination c at the point x, per quantity: criterion (a) where
    the three scales' runs have no instability event up to the point, else criterion (b)."""
    pk, fk = c["pk"], c["fk"]
    nets = {s: R.get(f"net/{name}/x{s:g}") for s in P.SCALES}
    uas = [P.unaccepted(nets[s]) if nets[s] is not None else None for s in P.SCALES]
    have = d0 is not None and all(nets[s] is not None and nets[s].ok for s in P.SCALES)
    evs = [events_to(nets[s], x, d0) for s in P.SCALES] if have else []
    seeds = {}
    for sd in mode["spread"]:
        cs = dict(seed=sd, pk=pk, fk=fk)
        ds, _ = start_of(runs, cs)
        r = R.get(f"net/s{sd}_{pk}_{fk}/x1")
        if ds is not None and r is not None and r.ok:
            seeds[sd] = r, ds
    out = []
    for col, label in IND_QTY:
        vals = [P.value(nets[s], col, x, pk, d0) if nets[s] is not None else float("nan") for s in P.SCALES]
        row = dict(case=name, x=x, col=label, vals=vals, events=evs, crit="—", spread=float("nan"),
                   bound=float("nan"), note="")
        if not have:
            row.update(verdict=f"{MISSING} (netsolve runs at {len(P.SCALES)} scales not all there)")
        elif not all(np.isfinite(vals)) or any(e is None for e in evs):
            row.update(verdict="invalid", note="point not reached or no instability column")
        else:
            spread = max(vals) - min(vals)
            conv = all(u is not None and u[0] == 0 for u in uas)
            unconv = "" if conv else "unaccepted increments: " + " / ".join(str(u[0]) if u else "?" for u in uas)
            if sum(evs) == 0:
                bound = IND_Z if col == "Z" else IND_STRESS * abs(vals[0])
                row.update(crit="(a)", spread=spread, bound=bound, note=unconv,
                           verdict="PASS" if spread <= bound and conv else "FAIL")
            elif len(seeds) < len(mode["spread"]) or not mode["spread"]:
                row.update(crit="(b)", spread=spread, note=unconv, verdict=f"{MISSING} (x1 runs of "
                           f"{len(seeds)} of {len(mode['spread']) or 5} seeds for the seed-to-seed spread)")
            else:
                sv = [P.value(r, col, x, pk, ds) for r, ds in seeds.values()]
                bad = [sd for sd, (r, _) in seeds.items() if (P.unaccepted(r) or (1, 0))[0] > 0]
                bound = max(sv) - min(sv) if all(np.isfinite(sv)) else float("nan")
                seeds_note = f"seeds {', '.join(map(str, bad))} with unaccepted increments" if bad else ""
                row.update(crit="(b)", spread=spread, bound=bound, note="; ".join(t for t in (unconv, seeds_note) if t),
                           verdict="invalid" if not np.isfinite(bound) else
                           "PASS" if spread <= bound and conv else "FAIL")
        out.append(row)
    return out


def drag_section(drag_rows):
    """The independence table (issue 28 "Independence" (a) and (b))."""
    L = ["", "## The regularisation does not move netsolve's answer", "",
         f"netsolve at `--regularisation-scale` {' / '.join(f'{s:g}' for s in P.SCALES)}, per quantity (issue 28 "
         "\"Independence\", bands set by the issue):",
         f"* **(a)** where none of the three runs has an instability event (history.csv `instability`) in the "
         f"increments up to the point: the spread over the scales ≤ {100 * IND_STRESS:g} % of netsolve's value at ×1 "
         f"(Σ11, Σ22), ≤ {IND_Z:g} (Z);",
         "* **(b)** elsewhere: the spread over the scales ≤ the spread of netsolve's ×1 answers over the five seeds "
         "1-5 (each from its own jammed state; seeds 4 and 5 are run at ×1 only, for this spread);",
         "* both: every increment of the three runs accepted.", "",
         "| case | point D − D0 | quantity | ×1 / ×0.1 / ×10 | instability events ×1 / ×0.1 / ×10 | criterion | "
         "spread over scales | bound | result | note |", "|---|---|---|---|---|---|---|---|---|---|"]
    for d in drag_rows:
        ev = " / ".join(str(e) for e in d["events"]) if d["events"] else "—"
        L.append(f"| {d['case']} | {d['x']:g} | {d['col']} | {' / '.join(fmt(v) for v in d['vals'])} | {ev} | "
                 f"{d['crit']} | {fmt(d['spread'])} | {fmt(d['bound'])} | {d['verdict']} | {d['note']} |")
    return L


def report_head(mode, preps):
    L = [f"# Validation: the cross-check with walls from a jammed state ({mode['name']} mode)", "",
         "Generated by `validation/quasistatic_vs_dynamic_walls/run.py" + (" --quick" if mode["name"] == "quick" else "")
         + "`; what it measures and why: README.md of this folder. Both solvers start from the same jammed state "
         "(`jammed.json` of `demsolve compact --save-state`, contact histories included): netsolve (`compact "
         "--boundary walls --state jammed.json --iteration pseudo-transient`, regularisation ×1) against the DEM's "
         f"limit σ = σ₀ + a·I (I = {', '.join(f'{I:g}' for I in P.INERTIAL)}). Band: |Δ| ≤ 2 % of max(|σ₀,11|, "
         "|σ₀,22|) at the point (\"scale\"); Z ±0.05; a stress line is valid if se(σ₀) ≤ 0.5 % of the scale. A "
         "netsolve run with increments it did not accept fails its lines.", "", "## Jammed states", "",
         f"`demsolve compact --width {mode['width']} --boundary walls --to-density {JAM_D:g} --save-state` (hydrostatic, "
         "I = 1.5e-4, the command's defaults); the values are the DEM's at its last window (moving, not the state at rest).", "",
         "| seed | friction | particles | D0 | Z | Σ11 | Σ22 | status |", "|---|---|---|---|---|---|---|---|"]
    for (seed, fk), s in preps.items():
        s = s or {}
        L.append(f"| {seed} | {fk} | {s.get('particles', '—')} | {fmt(s.get('D0'), 4)} | {fmt(s.get('Z_0'), 3)} | "
                 f"{fmt(s.get('S11_0'))} | {fmt(s.get('S22_0'))} | {s.get('status', 'missing')} |")
    return L


def configure():
    """The periodic case's machinery with this case's starts, paths and report."""
    P.CASE, P.BOUNDARY, P.HERE = "quasistatic_vs_dynamic_walls", "walls", HERE
    P.FULL, P.QUICK = FULL, QUICK
    P.PATHS = tuple(p for p in P.PATHS if p[0] != "shear")
    P.DD, P.INC = 0.02, 20
    P.start_of, P.points, P.prep_runs, P.read_preps = start_of, points, prep_runs, read_preps
    P.report_head = report_head
    P.compact_runs, P.drag_rows_of, P.drag_section = compact_runs, drag_rows_of, drag_section
    P.yield_runs = lambda mode, runs: []
    P.yield_section = lambda R, mode: ([], [])
    P.__doc__ = __doc__


if __name__ == "__main__":
    configure()
    sys.exit(P.main())

