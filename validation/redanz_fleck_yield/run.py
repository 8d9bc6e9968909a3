#!/usr/bin/env python3
"""Validation of `netsolve yield` against Redanz & Fleck, Acta Mater. 49 (2001) 4325, section 3.4, Figs 9-10.

usage: /usr/bin/python3 validation/redanz_fleck_yield/run.py
           [--quick] [--netsolve PATH] [--demsolve PATH] [--jobs 2] [--out DIR] [--runs DIR] [--force]
           [--cases LIST] [--report-only]

Runs the yield-surface cases with `netsolve yield` (polydisperse ballistic packing r = R[0.9, 1.1],
W = 80R, seed 1, precompaction to D = 0.85 in 100 increments, 24 probe directions; --quick: W = 40R,
50 increments, 12 directions), one folder per case, then writes figures in the style of Figs 9(a),
9(b) and 10 and report.md (the findings of the issue beside the measured values, each with its band).

A case is skipped when its folder already holds summary.json and a command.txt with the same
arguments (the binary path is not compared); --force reruns every case. Cases run one after the
other under `nice -n 10`, each with --jobs probe processes.

Needs numpy and matplotlib (Debian: /usr/bin/python3 with python3-numpy, python3-matplotlib).
"""
import argparse
import csv
import datetime
import json
import math
import os
import sys
import time

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "apps", "scripts"))
from report_paths import (MISSING, load_module, missing_text, provenance, provenance_lines, tally,  # noqa: E402
                          totals_text, verdict)

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
WL = load_module("rf_yield_walls", os.path.join(HERE, "walls.py"))  # the frictionless lines between walls (issue 28)

FULL = {"width": 80, "increments": 100, "directions": 24}
QUICK = {"width": 40, "increments": 50, "directions": 12}

# name -> (label, precompact, compact-bc, probe-bc, friction)
CASES = {
    "hydro_AA_mu0": ("affine-affine, mu = 0", "hydrostatic", "affine", "affine", "0"),
    "hydro_LL_mu0": ("l.r.-l.r., mu = 0", "hydrostatic", "die", "die", "0"),
    "hydro_LL_inf": ("l.r.-l.r., sticking", "hydrostatic", "die", "die", "inf"),
    "hydro_LA_mu0": ("l.r.-affine, mu = 0", "hydrostatic", "die", "affine", "0"),
    "hydro_AL_mu0": ("affine-l.r., mu = 0", "hydrostatic", "affine", "die", "0"),
    "die_AA_mu0": ("affine-affine, mu = 0", "closed-die", "affine", "affine", "0"),
    "die_LL_mu0": ("l.r.-l.r., mu = 0", "closed-die", "die", "die", "0"),
    "die_LL_inf": ("l.r.-l.r., sticking", "closed-die", "die", "die", "inf"),
    "hydro_AA_inf": ("affine-affine, sticking", "hydrostatic", "affine", "affine", "inf"),
}
# the paper's independence from the un/reloading stiffness (its 10^3 x the loading stiffness, our default):
# die_LL_inf again at 10^2 and 10^4 (netsolve yield --unload-ratio; issue 32)
UNLOAD = {"die_LL_inf_ur100": 100, "die_LL_inf_ur10000": 10000}
KINDS = (("curv", "max curvature"), ("off", "0.1% offset"))
STYLE = {
    "AA_mu0": dict(color="black", marker="o"),
    "AA_inf": dict(color="dimgray", marker="x"),
    "LL_mu0": dict(color="tab:blue", marker="s"),
    "LL_inf": dict(color="tab:green", marker="^"),
    "LA_mu0": dict(color="tab:orange", marker="D"),
    "AL_mu0": dict(color="tab:purple", marker="v"),
}


def case_args(name, scale, jobs):
    _, pre, cbc, pbc, mu = CASES[name]
    a = ["yield", "--width", str(scale["width"]), "--increments", str(scale["increments"]),
         "--directions", str(scale["directions"]), "--precompact", pre, "--compact-bc", cbc,
         "--probe-bc", pbc, "--friction", mu, "--to-density", "0.85", "--normal-unloading", "reversible",
         "--iteration", "legacy-drag", "--jobs", str(jobs), "--quiet"]  # one iteration for all (the die's default)
    if mu == "0":
        # frictionless precompactions are studied unconverged on purpose (exit 3 otherwise); the
        # status stays in summary.json
        a.append("--allow-unconverged")
    return a


def run_case(binary, name, scale, runs, jobs, force):
    """One case (walls.run_one: skipped when its folder holds a finished run of the same arguments);
    a failed case stops the script. An UNLOAD case is die_LL_inf at its un/reloading stiffness."""
    args = (case_args("die_LL_inf", scale, jobs) + ["--unload-ratio", f"{UNLOAD[name]:g}"] if name in UNLOAD
            else case_args(name, scale, jobs))
    why = WL.run_one(binary, name, args, runs, force)
    if why:
        sys.exit(f"{name} failed: {why}")


def load(runs, name):
    d = os.path.join(runs, name)
    rows = list(csv.DictReader(open(os.path.join(d, "yield_points.csv"))))
    f = lambda r, k: float(r[k]) if r[k] not in ("", "nan") else math.nan  # noqa: E731
    pts = {}
    for r in rows:
        pts[int(r["probe"])] = {k: f(r, k) if k in r else math.nan
                                for k in ("theta", "S11", "S22", "S11_offset", "S22_offset", "S11_analytic",
                                          "S22_analytic", "S11_fabric", "S22_fabric")} | {"status": r["status"]}
    summ = json.load(open(os.path.join(d, "summary.json")))
    return {"points": pts, "summary": summ, "dir": d}


def no_points_reason(runs, name):
    """Why a case has no yield points: its summary.json status, or no run."""
    sp = os.path.join(runs, name, "summary.json")
    if not os.path.exists(sp):
        return "no run"
    sj = json.load(open(sp))
    return f"{sj.get('status', '?')}: {sj.get('status_reason', '')}"


def radius(p, kind):
    a, b = (p["S11"], p["S22"]) if kind == "curv" else (p["S11_offset"], p["S22_offset"])
    return math.hypot(a, b)


def analytic_curve(summ, n=721, z0=None):
    """The affine analytic surface of the run (numpy port of docs/yield_analytic.md, elementary forms),
    with the run's measured Z0 or the given one."""
    sys.path.insert(0, HERE)
    from analytic_surface import closed_form  # noqa: E402
    a = summ["setup"]["analytic"]
    d0, d = a["D0"], a["D"]
    z0 = a["Z0"] if z0 is None else z0
    tr = math.log(d / d0)  # -(E11 + E22)
    E11, E22 = (-tr / 2, -tr / 2) if a["dir11"] == a["dir22"] else (0.0, -tr)
    th = np.linspace(0, 2 * math.pi, n)
    return np.array([closed_form(t, E11, E22, d, z0) for t in th])


def size_ratio(A, B, kind, min_frac=0.1):
    """Median over common probes (both found, analytic |S| >= min_frac x vertex) of |S_A| / |S_B|."""
    vert = max(math.hypot(p["S11_analytic"], p["S22_analytic"]) for p in B["points"].values())
    rs = []
    for k, pa in A["points"].items():
        pb = B["points"].get(k)
        if pb is None or math.hypot(pa["S11_analytic"], pa["S22_analytic"]) < min_frac * vert:
            continue
        ra, rb = radius(pa, kind), radius(pb, kind)
        if math.isfinite(ra) and math.isfinite(rb) and rb > 0:
            rs.append(ra / rb)
    return (float(np.median(rs)), len(rs)) if rs else (math.nan, 0)


def analytic_ratios(A, kind, min_frac=0.1, ref="analytic"):
    """(probe, theta, |S_measured| / |S_ref|) for the probes whose reference |S| is at least
    min_frac x its vertex value; ref = "analytic" (App. A, isotropic) or "fabric" (the
    fabric-resolved affine bound of the run's own contacts)."""
    vert = max(math.hypot(p[f"S11_{ref}"], p[f"S22_{ref}"]) for p in A["points"].values())
    out = []
    for k, p in sorted(A["points"].items()):
        ra = math.hypot(p[f"S11_{ref}"], p[f"S22_{ref}"])
        if not (ra >= min_frac * vert):
            continue
        out.append((k, p["theta"], radius(p, kind) / ra))
    return out


def kink_angle(A, kind):
    """Angle (deg) between the secants from the yield point of the probe along the loading direction
    to its nearest found neighbours on either side (0 = smooth, large = vertex); nan if missing."""
    pts = A["summary"]["setup"]["analytic"]
    th_load = math.degrees(math.atan2(pts["dir22"], pts["dir11"])) % 360
    P = A["points"]
    key = ("S11", "S22") if kind == "curv" else ("S11_offset", "S22_offset")
    found = sorted(k for k, p in P.items() if math.isfinite(p[key[0]]))
    at = [k for k in found if abs((P[k]["theta"] - th_load + 180) % 360 - 180) < 1e-6]
    if not at:
        return math.nan
    i = found.index(at[0])
    if i == 0 or i == len(found) - 1:
        return math.nan
    xy = [np.array([P[k][key[0]], P[k][key[1]]]) for k in (found[i - 1], found[i], found[i + 1])]
    a, b = xy[1] - xy[0], xy[2] - xy[1]
    c = float(np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def vertex_count(A, kind, tol=0.02):
    L = A["summary"]["precompaction"]
    l11, l22 = L["S11"], L["S22"]
    n = 0
    for p in A["points"].values():
        a, b = (p["S11"], p["S22"]) if kind == "curv" else (p["S11_offset"], p["S22_offset"])
        if math.isfinite(a) and math.hypot(a - l11, b - l22) <= tol * math.hypot(l11, l22):
            n += 1
    return n


def plot_surface(ax, C, label, style, kind="curv", offset_too=True):
    pts = [C["points"][k] for k in sorted(C["points"])]
    s = [(p["S11"], p["S22"]) for p in pts if math.isfinite(p["S11"])]
    if s:
        xy = np.array(s)  # not closed: the paper hand-sketches the part near Σ = 0
        ax.plot(xy[:, 0], xy[:, 1], "-", color=style["color"], marker=style["marker"], ms=4, lw=1.2, label=label)
    if offset_too:
        o = [(p["S11_offset"], p["S22_offset"]) for p in pts if math.isfinite(p["S11_offset"])]
        if o:
            xy = np.array(o)
            ax.plot(xy[:, 0], xy[:, 1], ":", color=style["color"], marker=style["marker"], mfc="none", ms=4, lw=0.8,
                    label=label + " (0.1% offset)")
    L = C["summary"]["precompaction"]
    ax.plot([L["S11"]], [L["S22"]], "*", color=style["color"], ms=10)
    # strain-rate directions at the found points (short arrows, as the paper's)
    for p in pts:
        if math.isfinite(p["S11"]):
            t = math.radians(p["theta"])
            ax.annotate("", xy=(p["S11"] + 0.06 * math.cos(t), p["S22"] + 0.06 * math.sin(t)), xytext=(p["S11"], p["S22"]),
                        arrowprops=dict(arrowstyle="->", color=style["color"], lw=0.6))


def fig(runs, names, title, path, outdir):
    fig_, ax = plt.subplots(figsize=(6.2, 6.2))
    first = load(runs, names[0])
    ana = analytic_curve(first["summary"])
    ax.plot(ana[:, 0], ana[:, 1], "--", color="gray", lw=1.2,
            label=f"analytic affine (App. A), measured Z0 = {first['summary']['setup']['analytic']['Z0']:.2f}")
    ana4 = analytic_curve(first["summary"], z0=4.0)
    ax.plot(ana4[:, 0], ana4[:, 1], ":", color="gray", lw=1.0, label="analytic affine (App. A), Z0 = 4.0")
    aa = next((n for n in names if "_AA_" in n), None)
    if aa:
        fp = [load(runs, aa)["points"][k] for k in sorted(load(runs, aa)["points"])]
        fxy = np.array([(p["S11_fabric"], p["S22_fabric"]) for p in fp if math.isfinite(p["S11_fabric"])])
        if len(fxy):
            ax.plot(fxy[:, 0], fxy[:, 1], "-.", color="black", lw=0.9, marker="+", ms=5,
                    label="fabric-resolved affine bound (own contacts)")
    for n in names:
        C = load(runs, n)
        key = n.split("_", 1)[1]
        plot_surface(ax, C, CASES[n][0], STYLE[key])
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$\Sigma_{11}/\sigma_y$")
    ax.set_ylabel(r"$\Sigma_{22}/\sigma_y$")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    fig_.tight_layout()
    fig_.savefig(os.path.join(outdir, path), dpi=130)
    plt.close(fig_)


def fig_curves(runs, outdir):
    """Reloading curves of a few probes (the knees behind the points)."""
    fig_, axs = plt.subplots(1, 2, figsize=(10, 4))
    for ax, n in zip(axs, ["hydro_AA_mu0", "hydro_LL_mu0"]):
        C = load(runs, n)
        nd = C["summary"]["setup"]["directions"]
        for k in sorted(C["points"]):
            th = C["points"][k]["theta"]
            if th < 120 or th > 300 or (k % max(1, nd // 8)):
                continue
            rows = list(csv.DictReader(open(os.path.join(C["dir"], "probes", f"probe_{k:03d}.csv"))))
            x = [float(r["strain"]) for r in rows]
            y = [float(r["stress"]) for r in rows]
            line, = ax.plot(np.array(x) * 1e3, y, "-", lw=1, label=f"θ = {th:.0f}°")
            p = C["points"][k]
            t = math.radians(th)
            for kind, mk in (("", "o"), ("_offset", "s")):
                a, b = p["S11" + kind], p["S22" + kind]
                if math.isfinite(a):
                    j = json.load(open(os.path.join(C["dir"], "probes", f"probe_{k:03d}.json")))
                    xs = j["strain" if kind == "" else "strain_offset"]
                    ax.plot([xs * 1e3], [a * math.cos(t) + b * math.sin(t)], mk, color=line.get_color(), mfc="none")
        ax.set_xlabel(r"probe strain $|\Delta E|$ (x 1e-3)")
        ax.set_ylabel(r"$\Sigma:\hat{E}/\sigma_y$")
        ax.set_title(CASES[n][0] + ", hydrostatic (o curvature, □ offset)", fontsize=9)
        ax.legend(fontsize=7)
    fig_.tight_layout()
    fig_.savefig(os.path.join(outdir, "reloading_curves.png"), dpi=120)
    plt.close(fig_)


def unload_lines(C, U, add, miss):
    """The paper (section 4): "the yield points are independent of the exact value of the unloading-reloading
    stiffness as long as it is sufficiently high" (10^3 x the loading stiffness there and by default here).
    Closed die, l.r.-l.r., sticking at 10^2 and 10^4 against 10^3: the median size ratio over the directions
    (size_ratio) in the band of this report's other 'same size' lines, with the largest single-direction
    deviation as the note."""
    ref = C.get("die_LL_inf")
    band = "0.9-1.1 (ours; the paper: independent)"
    for kind, kl in KINDS:
        fin = f"Section 4: closed die, l.r.-l.r. sticking, yield points at un/reloading stiffness 10² and 10⁴ / 10³ ({kl})"
        if ref is None or len(U) < len(UNLOAD):
            miss(fin, band, ["die_LL_inf"] + list(UNLOAD))
            continue
        ratios, worst = [], 0.0
        big = max((radius(q, kind) for q in ref["points"].values() if math.isfinite(radius(q, kind))), default=0.0)
        for n in UNLOAD:
            r, m = size_ratio(U[n], ref, kind)
            ratios.append((r, m))
            for k, p in U[n]["points"].items():
                q = ref["points"].get(k)
                if q is not None and math.isfinite(radius(p, kind)) and radius(q, kind) >= 0.5 * big > 0:
                    worst = max(worst, abs(radius(p, kind) / radius(q, kind) - 1))
        ok = all(0.9 <= r <= 1.1 for r, _ in ratios)
        add(fin, ", ".join(f"{r:.2f} (median of {m})" for r, m in ratios), band, ok,
            f"largest deviation in a direction whose yield stress at 10³ is at least half the surface's largest: "
            f"{100 * worst:.1f} %")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--demsolve", default=os.path.join(REPO, "build", "apps", "demsolve"),
                    help="the DEM that jams the packings of the walls cases (walls.py)")
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=None, help="figures and report (default: this folder, or quick/ with --quick)")
    ap.add_argument("--runs", default=None,
                    help="simulation folders (default: results/validation/redanz_fleck_yield[_quick], git-ignored)")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--report-only", action="store_true",
                    help="run nothing: the figures and report.md from the runs there are (a missing run is a MISSING line)")
    ap.add_argument("--cases", default=",".join(list(CASES) + list(UNLOAD) + ["walls"]),
                    help="comma-separated subset; 'walls': the cases between walls (walls.py)")
    a = ap.parse_args()
    scale = QUICK if a.quick else FULL
    outdir = a.out or (os.path.join(HERE, "quick") if a.quick else HERE)
    runs = a.runs or os.path.join(REPO, "results", "validation", "redanz_fleck_yield" + ("_quick" if a.quick else ""))
    os.makedirs(runs, exist_ok=True)
    names = [n for n in a.cases.split(",") if n]
    t0 = time.time()
    for n in names:
        if n != "walls" and not a.report_only:
            run_case(os.path.abspath(a.netsolve), n, scale, runs, a.jobs, a.force)
    if "walls" in names and not a.report_only:
        WL.run_all(os.path.abspath(a.netsolve), os.path.abspath(a.demsolve), scale, runs, a.jobs, a.force)
    have = {n for n in CASES if os.path.exists(os.path.join(runs, n, "yield_points.csv"))}

    # each figure with the runs it draws (a list: the plot order) and its title (None: fig_curves)
    figures = {"fig9a_hydrostatic.png": (["hydro_AA_mu0", "hydro_LL_mu0", "hydro_LL_inf"],
                                         "Fig 9(a): hydrostatic precompaction to D = 0.85"),
               "fig9b_closed_die.png": (["die_AA_mu0", "die_LL_mu0", "die_LL_inf"],
                                        "Fig 9(b): closed-die precompaction to D = 0.85"),
               "fig10_bc_combinations.png": (["hydro_AA_mu0", "hydro_LA_mu0", "hydro_AL_mu0", "hydro_LL_mu0"],
                                             "Fig 10: hydrostatic, mu = 0, compaction-probing boundary conditions"),
               "reloading_curves.png": (["hydro_AA_mu0", "hydro_LL_mu0"], None)}
    drawn = [f_ for f_, (names, _) in figures.items() if set(names) <= have]
    for f_, (names, title) in figures.items():
        if f_ not in drawn:  # a figure of an earlier run whose runs are missing now
            if os.path.exists(os.path.join(outdir, f_)):
                os.remove(os.path.join(outdir, f_))
        elif title is None:
            fig_curves(runs, outdir)
        else:
            fig(runs, names, title, f_, outdir)

    # ---- findings
    rows = []

    def add(finding, measured, band, ok, note=""):
        rows.append((finding, measured, band, verdict(ok), note))

    def why(*names):
        """Why a line resting on these cases cannot be evaluated (their summary.json status)."""
        return "; ".join(f"no yield points for {n}: {no_points_reason(runs, n)}" for n in names if n not in C)

    def miss(finding, band, names, note=""):
        """A line that cannot be evaluated: written as MISSING with the reason, and counted."""
        rows.append((finding, missing_text(why(*names))[:400], band, MISSING, note))

    def load_norm(c):
        p = c["summary"]["precompaction"]
        return math.hypot(p["S11"], p["S22"])

    C = {n: load(runs, n) for n in have}
    for pre in ("hydro", "die"):
        pname = "hydrostatic" if pre == "hydro" else "closed die"
        aa = C.get(f"{pre}_AA_mu0")
        if aa:
            has_fabric = all(math.isfinite(p["S11_fabric"]) for p in aa["points"].values())
            refs = [("analytic", "the analytic surface radially (probes with analytic |Σ| ≥ 0.1 vertex)", "")]
            if has_fabric:
                refs.append(("fabric", "the fabric-resolved affine bound (our check: App. A evaluated on the packing's "
                             "own contacts; probes with |Σ| ≥ 0.1 vertex)",
                             "not a finding of the paper: it separates the solver's probing from the isotropy "
                             "assumption of App. A"))
            for ref, what, note in refs:
                for kind, kl in KINDS:
                    r = analytic_ratios(aa, kind, ref=ref)
                    vals = [x for _, _, x in r if math.isfinite(x)]
                    worst = max((abs(x - 1) for x in vals), default=math.nan)
                    inside = sum(abs(x - 1) <= 0.10 for x in vals)
                    add(f"{pname}: affine-affine μ=0 yield points ({kl}) within 10% of {what}",
                        f"{inside}/{len(r)} within; ratios {min(vals, default=math.nan):.2f}-"
                        f"{max(vals, default=math.nan):.2f}",
                        "every |ratio − 1| ≤ 0.10", len(vals) == len(r) and len(r) > 0 and worst <= 0.10, note)
            for kind, kl in KINDS:
                n = vertex_count(aa, kind)
                add(f"{pname}: vertex at the loading point, affine-affine ({kl})",
                    f"{n} directions within 2% of the loading point", "≥ 2", n >= 2)
        else:  # the fabric-resolved lines need the run too: they are not listed
            for kind, kl in KINDS:
                miss(f"{pname}: affine-affine μ=0 yield points ({kl}) within 10% of the analytic surface radially "
                     "(probes with analytic |Σ| ≥ 0.1 vertex)", "every |ratio − 1| ≤ 0.10", (f"{pre}_AA_mu0",))
            for kind, kl in KINDS:
                miss(f"{pname}: vertex at the loading point, affine-affine ({kl})", "≥ 2", (f"{pre}_AA_mu0",))
        ll = C.get(f"{pre}_LL_mu0")
        for kind, kl in KINDS:
            fin = (f"{pname}: kink angle at the loading point between the secants to the neighbouring yield "
                   f"points, affine-affine vs l.r.-l.r. μ=0 ({kl})")
            note = "the paper: a vertex for affine-affine, rounded for l.r.-l.r. (smaller angle = smoother)"
            if aa and ll:
                add(fin, f"{kink_angle(aa, kind):.0f}° vs {kink_angle(ll, kind):.0f}°", "-", None, note)
            else:
                miss(fin, "-", (f"{pre}_AA_mu0", f"{pre}_LL_mu0"), note)
        for kind, kl in KINDS:
            fin = f"{pname}: l.r.-l.r. μ=0 surface / affine-affine size ({kl})"
            if aa and ll:
                r, n = size_ratio(ll, aa, kind)
                add(fin, f"{r:.2f} (median of {n} directions)", "0.4-0.6", 0.4 <= r <= 0.6)
            else:
                miss(fin, "0.4-0.6", (f"{pre}_AA_mu0", f"{pre}_LL_mu0"))
        ai = C.get(f"{pre}_AA_inf")
        if f"{pre}_AA_inf" in CASES:  # run for the hydrostatic precompaction only
            note = "section 3.4 citing [2, 7]: friction has only a minor effect when affine deformation is imposed"
            for kind, kl in KINDS:
                fin = f"{pname}: affine-affine sticking / frictionless size ({kl})"
                if aa and ai:
                    r, n = size_ratio(ai, aa, kind)
                    add(fin, f"{r:.2f} (median of {n})", "0.9-1.1 (ours)", 0.9 <= r <= 1.1, note)
                else:
                    miss(fin, "0.9-1.1 (ours)", (f"{pre}_AA_mu0", f"{pre}_AA_inf"), note)
        li = C.get(f"{pre}_LL_inf")
        for kind, kl in KINDS:
            fin = f"{pname}: sticking / frictionless size, l.r.-l.r. ({kl})"
            if ll and li:
                r, n = size_ratio(li, ll, kind)
                add(fin, f"{r:.2f} (median of {n})", "1.6-2.4", 1.6 <= r <= 2.4)
            else:
                miss(fin, "1.6-2.4", (f"{pre}_LL_mu0", f"{pre}_LL_inf"))
        note = "band chosen here: the issue says 'close to affine size'"
        for kind, kl in KINDS:
            fin = f"{pname}: sticking l.r.-l.r. / affine-affine size ({kl})"
            if li and aa:
                r, n = size_ratio(li, aa, kind)
                add(fin, f"{r:.2f} (median of {n})", "0.8-1.2", 0.8 <= r <= 1.2, note)
            else:
                miss(fin, "0.8-1.2", (f"{pre}_LL_inf", f"{pre}_AA_mu0"), note)
        # information: the surfaces inherit the precompaction stress (validation/redanz_fleck_compaction)
        fin = f"{pname}: loading-point |Σ| ratios l.r. μ=0 / affine, sticking / μ=0 (information)"
        note = "the yield-surface ratios above follow these precompaction ratios"
        if aa and ll and li:
            add(fin, f"{load_norm(ll) / load_norm(aa):.2f}, {load_norm(li) / load_norm(ll):.2f}", "-", None, note)
        else:
            miss(fin, "-", (f"{pre}_AA_mu0", f"{pre}_LL_mu0", f"{pre}_LL_inf"), note)
    unload_lines(C, {n: load(runs, n) for n in UNLOAD if os.path.exists(os.path.join(runs, n, "yield_points.csv"))},
                 add, miss)
    aa = C.get("hydro_AA_mu0")
    for n, lab in (("hydro_LA_mu0", "l.r.-affine"), ("hydro_AL_mu0", "affine-l.r.")):
        for kind, kl in KINDS:
            fin = f"Fig 10: {lab} / affine-affine size, hydrostatic μ=0 ({kl})"
            if aa and n in C:
                r, m = size_ratio(C[n], aa, kind)
                add(fin, f"{r:.2f} (median of {m})", "0.4-0.6", 0.4 <= r <= 0.6)
            else:
                miss(fin, "0.4-0.6", ("hydro_AA_mu0", n))

    # ---- the same lines between walls (walls.py), a table of their own
    W = WL.load_all(sys.modules[__name__], runs, scale["directions"])
    wrows = []

    def wadd(finding, measured, band, ok, note=""):
        wrows.append((finding, measured, band, verdict(ok), note))

    def wmiss(finding, band, why_text, note=""):
        wrows.append((finding, missing_text(why_text)[:400], band, MISSING, note))

    def wreason(*names):
        return "; ".join(f"no yield points for {n}: {(WL.not_runnable(runs, n) if n in WL.WCASES else '') or no_points_reason(runs, n)}"
                         for n in names if n not in C and n not in W)

    WL.findings(sys.modules[__name__], C, W, wadd, wmiss, wreason)
    wfigs = [f for pre, f in (("hydro", "fig_walls_hydrostatic.png"), ("die", "fig_walls_closed_die.png"))
             if WL.fig(sys.modules[__name__], runs, C, W, pre, f, outdir)]

    # ---- report
    counts = tally(r[3] for r in rows + wrows)
    lines = ["# netsolve yield vs Redanz & Fleck (2001) section 3.4, Figs 9-10", "",
             f"Generated {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC by "
             f"`validation/redanz_fleck_yield/run.py{' --quick' if a.quick else ''}`: "
             f"W = {scale['width']}R, seed 1, r = R[0.9, 1.1], D = 0.85 in {scale['increments']} increments, "
             f"{scale['directions']} probe directions. Algorithm and definitions: docs/yield.md.", "",
             "Size ratios are medians over the probe directions found in both runs whose analytic affine stress is at "
             "least 0.1 of the vertex value; 'max curvature' is the paper's definition, '0.1% offset' the second one.",
             "", f"Totals: {totals_text(counts)}. MISSING: a line that could not be evaluated (the reason is in "
             "its measured column); it counts as neither PASS nor FAIL.",
             "", "| finding | measured | band | result | note |", "|---|---|---|---|---|"]
    for r in rows:
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in r) + " |")
    lines += ["", "## Between walls (issue 28)", "", WL.__doc__.split("\n\n", 1)[1].strip(), "",
              f"Probes: {min(WL.DIRECTIONS, scale['directions'])} directions, paired with the affine-affine probes at "
              "the same angle. Totals above count both tables.", "",
              "| finding | measured | band | result | note |", "|---|---|---|---|---|"]
    for r in wrows:
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in r) + " |")
    lines += WL.runs_table(runs, W, sys.modules[__name__])
    lines += [""] + [f"![{f_}]({f_})" for f_ in wfigs]
    lines += ["", "## Runs", "", "| case | D | Z | loading point S11, S22 | unloading | probes ok | time total (compaction / unloading / probes) s |",
              "|---|---|---|---|---|---|---|"]
    labels = {n: f"{CASES[n][0]}, {CASES[n][1]}" for n in CASES}
    labels |= {n: f"{CASES['die_LL_inf'][0]}, {CASES['die_LL_inf'][1]}, --unload-ratio {r:g}" for n, r in UNLOAD.items()}
    for n, label in labels.items():
        got = C.get(n) or (load(runs, n) if n in UNLOAD and os.path.exists(os.path.join(runs, n, "yield_points.csv"))
                           else None)
        if not got:
            # a case without yield points: say why (its summary.json status), not a silent gap
            reason_text = no_points_reason(runs, n)
            lines.append(f"| {n} ({label}) | no yield points: {reason_text} | | | | | |")
            continue
        s = got["summary"]
        p = s["precompaction"]
        u = s["unloading"]
        t = s["timing_s"]
        lines.append(f"| {n} ({label}) | {p['D']:.4f} | {p['Z']:.3f} | {p['S11']:.3f}, {p['S22']:.3f} | "
                     f"\\|Σ\\| = {u['stress_norm']:.1e} in {u['increments']} | {s['probes']['ok']}/{s['probes']['run']} | "
                     f"{t['total']:.1f} ({t['compaction']:.1f} / {t['unloading']:.1f} / {t['probes']:.1f}) |")
    lines += ["", f"Times are wall seconds of the runs of this report (`--jobs {a.jobs}`: cases run one after another, "
              f"each with --jobs {a.jobs} probe processes) on a 2-core machine that may be shared; they vary by up to 2-3x "
              "between repetitions. The speed target is measured separately (docs/performance.md).", "", "## Per-direction ratios to the analytic affine surface (affine-affine, μ = 0)", ""]
    for pre in ("hydro", "die"):
        aa = C.get(f"{pre}_AA_mu0")
        if not aa:
            continue
        lines += [f"{pre}: θ (deg): |Σ| curvature / analytic, offset / analytic", ""]
        rc = analytic_ratios(aa, "curv")
        ro = {k: x for k, _, x in analytic_ratios(aa, "off")}
        lines.append(", ".join(f"{th:.0f}: {x:.2f} / {ro[k]:.2f}" for k, th, x in rc))
        lines.append("")
        if all(math.isfinite(p["S11_fabric"]) for p in aa["points"].values()):
            lines += [f"{pre}: θ (deg): |Σ| curvature / fabric-resolved bound, offset / fabric-resolved bound, "
                      f"fabric-resolved bound / analytic", ""]
            fc = analytic_ratios(aa, "curv", ref="fabric")
            fo = {k: x for k, _, x in analytic_ratios(aa, "off", ref="fabric")}
            fa = {k: math.hypot(p["S11_fabric"], p["S22_fabric"]) / math.hypot(p["S11_analytic"], p["S22_analytic"])
                  for k, p in aa["points"].items() if math.hypot(p["S11_analytic"], p["S22_analytic"]) > 0}
            lines.append(", ".join(f"{th:.0f}: {x:.2f} / {fo.get(k, math.nan):.2f} / {fa.get(k, math.nan):.2f}"
                                   for k, th, x in fc))
            lines.append("")
    for f_ in drawn:
        lines.append(f"![{f_}]({f_})")
    lines.append("")
    lines.append("Written with --report-only from the runs there were (each run's time is in the tables above)."
                 if a.report_only else f"Total time of this script: {time.time() - t0:.0f} s.")
    lines += provenance_lines(provenance(REPO, "redanz_fleck_yield", [a.netsolve, a.demsolve]), counts)
    open(os.path.join(outdir, "report.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines[:len(rows) + 10]))


if __name__ == "__main__":
    main()
