#!/usr/bin/env python3
"""The 3D cross-check (issue 30): `netsolve compact --dim 3` against the explicit DEM's limit I -> 0 on
periodic sphere packings, where nothing leaks and no wall or prescribed layer acts.

usage: /usr/bin/python3 validation/compaction_3d/run.py
           [--quick] [--netsolve PATH] [--demsolve PATH] [--jobs 2] [--runs DIR] [--force]
           [--only PATTERN,...] [--report-only] [--timeout S]

Packings: `netsolve pack --dim 3 --periodic --n 2000 --seed 1|2|3` (--quick: --n 500, seed 1), each at
its own jammed density D0. Paths: hydrostatic and closed die (along z) from D0 to D0 + 0.03 in 30
increments. Friction mu = inf (sticking) and 0.1. Per combination:
  * `demsolve compact --dim 3 --boundary periodic` at I = 4e-4, 2e-4, 1e-4; the fit sigma = sigma0 + a I
    (least squares) gives sigma0 and its standard error at each comparison point;
  * `netsolve compact --dim 3 --boundary periodic --iteration pseudo-transient` at
    --regularisation-scale 1 (the answer compared) and 0.1, 10 (the answer must not move with it).
Compared at equal D - D0 (5 points, --quick 2), netsolve's rows as window means (a DEM row is the
mean over its window). Bands (issue 30: "as in the 2D periodic mode; Z within +-0.1"; fixed here
before the first run, never widened): |dSigma_ii| <= 0.02 max_i |sigma0_ii| at the point; Z within
+-0.1; a stress line is valid only if se(sigma0) <= 0.005 of the same scale; the spread of netsolve's
Sigma_33 over the regularisation scales <= 0.005 of the scale. A netsolve run with unaccepted
increments fails its lines. Lines whose runs are missing are MISSING with the reason.

One folder per run; a run is skipped when its folder holds summary.json and a command.txt with the
same arguments; --force reruns. Simulations run under `nice -n 10`, --jobs at a time, seed 1 first.
"""
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

# the 2D periodic case: its runner (the layer case's), reader, fit and report pieces
P = load_module("qvd_periodic", os.path.join(REPO, "validation", "quasistatic_vs_dynamic_periodic", "run.py"))
Run, fit, fmt = P.Run, P.fit, P.fmt

CASE = "compaction_3d"
FULL = {"name": "full", "n": 2000, "seeds": (1, 2, 3), "dd": (0.006, 0.012, 0.018, 0.024, 0.03)}
QUICK = {"name": "quick", "n": 500, "seeds": (1,), "dd": (0.015, 0.03)}
INERTIAL = (4e-4, 2e-4, 1e-4)
SCALES = (1, 0.1, 10)
DD, INC = 0.03, 30
PATHS = (("hydro", "hydrostatic"), ("die", "closed-die"))
FRICTIONS = (("inf", "inf"), ("mu0.1", "0.1"))
STRESS_BAND, SE_VALID, Z_BAND, DRAG_BAND = 0.02, 0.005, 0.1, 0.005
QTY = (("S11", "Σ11"), ("S22", "Σ22"), ("S33", "Σ33"), ("Z", "Z"))
WINDOW_MEANS = ("S11", "S22", "S33", "Z")


def combos(mode):
    for seed in mode["seeds"]:
        for pk, pv in PATHS:
            for fk, fv in FRICTIONS:
                yield f"s{seed}_{pk}_{fk}", dict(seed=seed, pk=pk, path=pv, fk=fk, friction=fv)


def pack_dir(runs, seed):
    return os.path.join(runs, "pack", f"s{seed}")


def read_d0(runs, seed):
    s = P.read_preps({"seeds": (seed,)}, runs)
    return None if not s.get(seed) or s[seed].get("status") != "ok" else float(s[seed]["density"])


def target(d0):
    return float(f"{d0 + DD:.6f}")


def compact_args(tool, c, pack, d0, extra):
    return (["compact", "--dim", "3", "--boundary", "periodic", "--packing", pack, "--friction", c["friction"],
             "--path", c["path"], "--to-density", f"{target(d0):.6f}", "--increments", str(INC)] + extra
            + ["--snapshots", "", "--quiet"])


def prep_runs(mode):
    return [(f"pack/s{s}", "netsolve", ["pack", "--dim", "3", "--periodic", "--n", str(mode["n"]), "--seed", str(s),
                                        "--quiet"], (s,)) for s in mode["seeds"]]


def compact_runs(mode, runs):
    out = []
    for name, c in combos(mode):
        d0 = read_d0(runs, c["seed"])
        if d0 is None:
            continue
        pack = os.path.join(pack_dir(runs, c["seed"]), "packing.csv")
        pr = (c["seed"], [p for p, _ in PATHS].index(c["pk"]), [f for f, _ in FRICTIONS].index(c["fk"]))
        for I in INERTIAL:
            out.append((f"dem/{name}/I{I:g}", "demsolve",
                        compact_args("demsolve", c, pack, d0, ["--inertial-number", f"{I:g}"]), pr + (1, I)))
        for s in SCALES:
            out.append((f"net/{name}/x{s:g}", "netsolve",
                        compact_args("netsolve", c, pack, d0, ["--iteration", "pseudo-transient", "--regularisation-scale",
                                                               f"{s:g}", "--allow-unconverged"]), pr + (0, s != 1)))
    return out


def load_run(d, tool):
    r = Run(d, tool)
    if r.ok and tool == "netsolve":  # window means of every compared column (Run does S11, S22, Z)
        for k in WINDOW_MEANS:
            if k in r.h:
                v = r.h[k]
                w = v.copy()
                w[1:] = 0.5 * (v[1:] + v[:-1])
                r.hw[k] = w
    return r


def value(r, col, x, d0):
    return float("nan") if r is None or not r.ok else r.at(col, min(d0 + x, target(d0)), by="D")


def evaluate(R, mode, runs):
    rows, drag = [], []
    for name, c in combos(mode):
        d0 = read_d0(runs, c["seed"])
        dem = [(I, R.get(f"dem/{name}/I{I:g}")) for I in INERTIAL]
        dem = [(I, r) for I, r in dem if r is not None and r.ok]
        nets = {s: R.get(f"net/{name}/x{s:g}") for s in SCALES}
        n0 = nets[1]
        for x in mode["dd"]:
            if d0 is None:
                for col, label in QTY:
                    rows.append(dict(case=name, x=x, label=label, net=np.nan, s0=np.nan, se=np.nan, scale=np.nan,
                                     verdict=f"{MISSING} (no packing)", note=""))
                continue
            fits = {col: fit([I for I, _ in dem], [value(r, col, x, d0) for _, r in dem]) for col, _ in QTY}
            scale = max(abs(fits[k][0]) for k in ("S11", "S22", "S33"))
            ua = P.unaccepted(n0) if n0 is not None else None
            for col, label in QTY:
                s0, se = fits[col][0], fits[col][1]
                nv = value(n0, col, x, d0)
                row = dict(case=name, x=x, label=label, net=nv, s0=s0, se=se, scale=scale)
                if n0 is None or not n0.ok:
                    row.update(verdict=f"{MISSING} (netsolve run missing or failed)", note="")
                elif len(dem) < len(INERTIAL):
                    row.update(verdict=f"{MISSING} (DEM runs at {len(dem)} of {len(INERTIAL)} inertial numbers)", note="")
                elif not (np.isfinite(nv) and np.isfinite(s0) and np.isfinite(scale)):
                    row.update(verdict="invalid", note="point not reached")
                else:
                    conv = ua is not None and ua[0] == 0
                    unconv = "" if conv else f"netsolve: {ua[0]} of {ua[1]} increments not accepted"
                    if col == "Z":
                        ok, valid, dist = abs(nv - s0) <= Z_BAND, True, f"{nv - s0:+.3f}"
                    else:
                        ok, valid = abs(nv - s0) <= STRESS_BAND * scale, se <= SE_VALID * scale
                        dist = f"{nv - s0:+.5f} ({100 * (nv - s0) / scale:+.2f} % of scale)"
                    why = "" if valid else f"se(σ₀) = {100 * se / scale:.2f} % of scale > 0.5 %"
                    row.update(verdict="invalid" if not valid else ("PASS" if ok and conv else "FAIL"),
                               note="; ".join(t for t in (dist, why, unconv) if t))
                rows.append(row)
            vals = [value(nets[s], "S33", x, d0) for s in SCALES]
            uas = [P.unaccepted(nets[s]) if nets[s] is not None else None for s in SCALES]
            if any(nets[s] is None or not nets[s].ok for s in SCALES):
                v, note = f"{MISSING} (netsolve runs at {len(SCALES)} scales not all there)", ""
            elif not (all(np.isfinite(vals)) and np.isfinite(scale)):
                v, note = "invalid", "point not reached or no DEM scale"
            else:
                spread = max(vals) - min(vals)
                conv = all(u is not None and u[0] == 0 for u in uas)
                v = "PASS" if spread <= DRAG_BAND * scale and conv else "FAIL"
                note = f"{100 * spread / scale:.3f} % of scale" + ("" if conv else "; unaccepted increments: " + " / ".join(
                    str(u[0]) if u else "?" for u in uas))
            drag.append(dict(case=name, x=x, col="S33", vals=vals, verdict=v, note=note))
    return rows, drag


def make_figures(R, mode, runs, out):
    figs = []
    seed = mode["seeds"][0]
    d0 = read_d0(runs, seed)
    if d0 is None:
        return figs
    for pk, _ in PATHS:
        fig, axs = plt.subplots(1, len(FRICTIONS), figsize=(10, 3.8))
        for ax, (fk, fv) in zip(axs, FRICTIONS):
            name = f"s{seed}_{pk}_{fk}"
            for k, I in enumerate(INERTIAL):
                r = R.get(f"dem/{name}/I{I:g}")
                if r is not None and r.ok:
                    for col, ls in (("S11", ":"), ("S33", "-")):
                        ax.plot(r.h["D"] - d0, r.h[col], ls, color=f"C{k}", lw=1,
                                label=f"DEM I = {I:g} ({col})" if col == "S33" or k == 0 else None)
            r = R.get(f"net/{name}/x1")
            if r is not None and r.ok:
                for col, ls in (("S11", "k:"), ("S33", "k-")):
                    ax.plot(r.hw["D"] - d0, r.hw[col], ls, lw=1.4, label=f"netsolve ({col}, window means)")
            ax.set_title(f"seed {seed}, {pk}, μ = {fv}")
            ax.set_xlabel("D − D0")
            ax.set_ylabel("Σ [σ_y]")
        axs[0].legend(fontsize=6)
        fig.tight_layout()
        fn = f"fig_{pk}.png"
        fig.savefig(os.path.join(out, fn), dpi=110)
        plt.close(fig)
        figs.append(fn)
    return figs


def run_binaries(R):
    """{tool (as recorded by the runs): sha256} of the binaries that made the runs, from each run's
    meta.json; a tool whose runs used more than one binary lists every sha."""
    shas = {}
    for r in R.values():
        sha = (r.meta or {}).get("binary_sha256")
        if sha:
            shas.setdefault(f"{r.tool} (the runs' meta.json)", set()).add(sha)
    return {k: ", ".join(sorted(v)) for k, v in shas.items()}


def write_report(R, mode, runs, out, binaries):
    rows, drag = evaluate(R, mode, runs)
    figs = make_figures(R, mode, runs, out)
    packs = P.read_preps(mode, runs)
    L = [f"# Validation: netsolve compact --dim 3 against the DEM limit ({mode['name']} mode)", "",
         "Generated by `validation/compaction_3d/run.py" + (" --quick" if mode["name"] == "quick" else "") +
         "`; what it measures and why: README.md of this folder. netsolve (`compact --dim 3 --boundary periodic "
         "--iteration pseudo-transient`, regularisation ×1) against the DEM's limit σ = σ₀ + a·I "
         f"(I = {', '.join(f'{I:g}' for I in INERTIAL)}). Band: |Δ| ≤ 2 % of max_i |σ₀,ii| at the point "
         "(\"scale\"); Z ±0.1; a stress line is valid if se(σ₀) ≤ 0.5 % of the scale. A netsolve run with "
         "increments it did not accept fails its lines.", "", "## Packings", "",
         "| seed | spheres | D0 | Z | Z without rattlers | rattlers | max overlap / R | status |", "|---|---|---|---|---|---|---|---|"]
    for seed in mode["seeds"]:
        p = packs.get(seed) or {}
        L.append(f"| {seed} | {p.get('particles', '—')} | {fmt(p.get('density'), 4)} | {fmt(p.get('coordination'), 3)} | "
                 f"{fmt(p.get('coordination_without_rattlers'), 3)} | {fmt(p.get('rattler_fraction'), 3)} | "
                 f"{fmt((p.get('overlap_over_R') or {}).get('max'), 5)} | {p.get('status', 'missing')} |")
    L += ["", "## netsolve against the DEM limit", "",
          "| case | point | quantity | netsolve | DEM σ₀ ± se | scale | result | note |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        L.append(f"| {r['case']} | D − D0 = {r['x']:g} | {r['label']} | {fmt(r['net'], 5)} | {fmt(r['s0'], 5)} ± "
                 f"{fmt(r['se'], 5)} | {fmt(r['scale'], 5)} | {r['verdict']} | {r['note']} |")
    L += [ln.replace("S22", "S33") for ln in P.drag_section(drag)]
    c = tally([r["verdict"] for r in rows] + [d["verdict"] for d in drag])
    L += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figs]
    L += ["", "## Runs", ""] + P.run_table(R, sorted(R))
    notes = os.path.join(HERE, "notes.md")
    if os.path.isfile(notes):
        L += ["", "## Notes (notes.md, written by hand)", "", open(notes, encoding="utf-8").read().strip()]
    prov = provenance(REPO, CASE, binaries)
    ran = run_binaries(R)
    if ran:  # the binaries that made the runs (their meta.json), not the files at report time
        prov["binaries"] = ran
    L += provenance_lines(prov, c)
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(L) + "\n")
    print(f"report: {shown_path(os.path.join(out, 'report.md'), REPO)} ({c})")


def main():
    a, runs, out, only, bins = P.parse_case_args(__doc__, HERE, "pack/*,*/s1_hydro_*")
    mode = QUICK if a.quick else FULL
    if not a.report_only:
        P.run_all(a.jobs, bins, runs, a.force, a.timeout, [p for p in prep_runs(mode) if P.selected(p[0], only)])
        P.run_all(a.jobs, bins, runs, a.force, a.timeout, [r for r in compact_runs(mode, runs) if P.selected(r[0], only)])
    R = {name: load_run(os.path.join(runs, name), tool) for name, tool, _, _ in compact_runs(mode, runs)}
    write_report(R, mode, runs, out, [a.netsolve, a.demsolve])


if __name__ == "__main__":
    main()
