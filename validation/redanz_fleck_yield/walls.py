"""The yield lines that rest on a frictionless precompaction, evaluated between walls (issue 28).

The paper's l.r. boundary prescribes the peripheral layer; without a drag in the answer a
frictionless packing is squeezed out between the peripheral disks, so the l.r. μ = 0 cases of
run.py are unconverged (closed die: stopped at increment 6). Here the same deposition is compacted
between four rigid frictionless walls (nothing prescribed), as validation/redanz_fleck_walls does
for the compaction findings:

* the DEM jams it (`demsolve compact --boundary walls --save-state`, μ = 0 and sticking, each path,
  to D = 0.835 in the walls' box, or 0.004 below the target where the walls' box needs it), since a
  packing below jamming is a mechanism;
* `netsolve yield --state jammed.json --compact-bc walls --iteration pseudo-transient` precompacts
  from there to D = 0.85 / k in the walls' box, i.e. D = 0.85 in the die's box at equal strain
  (k = D0_die / D0_walls of the deposition: the walls enclose the disks that stick out of the
  deposition's lid), unloads and probes between the same walls (walls-walls), or, frictionless,
  affine (walls-affine, Fig 10's l.r.-affine);
* the affine-affine references are run.py's own cases (the same deposition at D = 0.85 in the die's
  box).

This departs from the paper's boundary: the verdicts are the paper's statements about a packing
that is not held by a prescribed layer. Bands are run.py's, never widened.
"""
import csv
import math
import os
import shlex
import subprocess
import time

JAM_D = 0.835      # the walls' box; below the target 0.85 / k (0.8408 for seed 1) and above frictionless jamming
TARGET_DIE = 0.85  # the paper's density, in the die's box
INCREMENTS = 20    # netsolve's precompaction from JAM_D to the target
DIRECTIONS = 8     # probes every 45 degrees, among them both loading directions (225 and 270 degrees) and a
                   # subset of run.py's 24: a frictionless walls probe takes ~6 min (W = 80, about 50
                   # increments of thousands of pseudo-transient iterations each)
MARGIN = 0.004     # the jammed state's density below the target: JAM_D or lower (the quick scale's box
                   # differs more from the die's: k = 1.011 at W = 80, about 1.02 at W = 40)
PATHS = {"hydro": "hydrostatic", "die": "closed-die"}

# name -> (label, precompact, probe-bc, friction, jammed state)
WCASES = {
    "hydro_WW_mu0": ("walls-walls, mu = 0", "hydrostatic", "walls", "0", "jam_hydro_mu0"),
    "hydro_WW_inf": ("walls-walls, sticking", "hydrostatic", "walls", "inf", "jam_hydro_inf"),
    "hydro_WA_mu0": ("walls-affine, mu = 0", "hydrostatic", "affine", "0", "jam_hydro_mu0"),
    "die_WW_mu0": ("walls-walls, mu = 0", "closed-die", "walls", "0", "jam_die_mu0"),
    "die_WW_inf": ("walls-walls, sticking", "closed-die", "walls", "inf", "jam_die_inf"),
}
STYLE = {
    "WW_mu0": dict(color="tab:blue", marker="s"),
    "WW_inf": dict(color="tab:green", marker="^"),
    "WA_mu0": dict(color="tab:orange", marker="D"),
}
LAW = ["--normal-unloading", "reversible"]  # run.py's precompaction law; the jammed state must carry it


def jam_density(runs):
    """JAM_D, or MARGIN below the target where the walls' box makes the target lower (k from the
    deposition: run.py's hydro_AA_mu0 and the walls' box that encloses its disks); None without it."""
    k = deposition_factor(runs)
    return None if k is None else round(min(JAM_D, TARGET_DIE / k - MARGIN), 4)


def jam_args(scale, pre, mu, jam_d):
    return ["compact", "--width", str(scale["width"]), "--seed", "1", "--boundary", "walls", "--friction", mu,
            "--path", PATHS[pre], "--to-density", f"{jam_d:g}", "--save-state", "--snapshots", "", "--quiet"] + LAW


def _rows(path):
    return list(csv.DictReader(line for line in open(path) if not line.startswith("#")))


def deposition_factor(runs):
    """k = D0_die / D0_walls of the deposition: the die's box is the deposition's, the walls' box
    encloses every disk (apps/common/setup.hpp walls_box: the disks above the lid stick out); from
    run.py's hydro_AA_mu0 (its packing.csv), None without it."""
    f = os.path.join(runs, "hydro_AA_mu0", "packing.csv")
    if not os.path.exists(f):
        return None
    box, disks = None, []
    for line in open(f):
        if line.startswith("# box"):
            box = [float(v) for v in line.split()[2:6]]
        elif line[:1].isdigit():
            _, x, y, r = (float(v) for v in line.split(",")[:4])
            disks.append((x, y, r))
    if box is None or not disks:
        return None
    lo_x = min([box[0]] + [x - r for x, _, r in disks])
    lo_y = min([box[1]] + [y - r for _, y, r in disks])
    hi_x = max([box[2]] + [x + r for x, _, r in disks])
    hi_y = max([box[3]] + [y + r for _, y, r in disks])
    return (hi_x - lo_x) * (hi_y - lo_y) / ((box[2] - box[0]) * (box[3] - box[1]))


def not_runnable(runs, name):
    """Why a walls yield case cannot run (its jammed state missing, or at or past the target), or ""."""
    jam = WCASES[name][4]
    k = deposition_factor(runs)
    if k is None or not os.path.exists(os.path.join(runs, jam, "jammed.json")):
        return f"no jammed state {jam} (or no hydro_AA_mu0 for the box factor)"
    d = float(_rows(os.path.join(runs, jam, "history.csv"))[-1]["D"])
    if not d < TARGET_DIE / k - 1e-4:
        return f"the jammed state {jam} (D = {d:.4f}) is not below the target {TARGET_DIE / k:.4f} in the walls' box"
    return ""


def yield_args(name, scale, runs, jobs):
    _, pre, pbc, mu, jam = WCASES[name]
    k = deposition_factor(runs)
    return ["yield", "--state", os.path.join(runs, jam, "jammed.json"), "--compact-bc", "walls", "--probe-bc", pbc,
            "--precompact", pre, "--friction", mu, "--to-density", f"{TARGET_DIE / k:.6f}", "--increments",
            str(INCREMENTS), "--iteration", "pseudo-transient", "--directions", str(min(DIRECTIONS, scale["directions"])),
            "--jobs", str(jobs), "--allow-unconverged", "--quiet"] + LAW


def run_one(binary, name, args, runs, force, after=None):
    """Runs `binary args --out runs/name` unless that folder holds a finished run of the same
    arguments newer than the file `after` (its input); exit 3 (finished, untrustworthy) is kept and
    shown by the report. Returns "" or why the run failed (the report's MISSING line says it)."""
    out = os.path.join(runs, name)
    cmd_file = os.path.join(out, "command.txt")
    summ = os.path.join(out, "summary.json")
    done = os.path.exists(summ) and not os.path.exists(os.path.join(out, ".incomplete"))
    if done and after and os.path.exists(after) and os.path.getmtime(after) > os.path.getmtime(summ):
        done = False  # its input was made again
    if not force and done and os.path.exists(cmd_file):
        old = [w for w in open(cmd_file).read().split()[1:] if w != "--overwrite"]
        if old[:-2] == [shlex.quote(a) for a in args] or old[:-2] == args:
            print(f"  {name}: up to date")
            return ""
    t0 = time.time()
    exists = any(os.path.exists(os.path.join(out, f)) for f in ("command.txt", "summary.json", ".incomplete"))
    cmd = ["nice", "-n", "10", binary] + args + (["--overwrite"] if exists else []) + ["--out", out]
    print("  " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode == 3:
        print(f"    {name}: exit 3 (finished, untrustworthy): {r.stderr.strip()[-300:]}", flush=True)
    elif r.returncode != 0:
        why = f"exit {r.returncode}: {r.stderr.strip()[-300:]}"
        print(f"    {name} failed: {why}", flush=True)
        return why
    print(f"    {r.stdout.strip()} ({time.time() - t0:.0f} s)", flush=True)
    return ""


def run_all(netsolve, demsolve, scale, runs, jobs, force):
    """The DEM's jammed states, then netsolve's yield surfaces from them (run.py's hydro_AA_mu0 first:
    its deposition density gives k)."""
    jam_d = jam_density(runs)
    if jam_d is None:
        print("  walls cases: skipped (they need run.py's hydro_AA_mu0 for the box factor)")
        return
    for pre in PATHS:
        for mu in ("0", "inf"):
            run_one(demsolve, f"jam_{pre}_{'mu0' if mu == '0' else 'inf'}", jam_args(scale, pre, mu, jam_d), runs, force)
    for name in WCASES:
        why = not_runnable(runs, name)
        if why:
            print(f"  {name}: skipped ({why})")
            continue
        run_one(netsolve, name, yield_args(name, scale, runs, jobs), runs, force,
                after=os.path.join(runs, WCASES[name][4], "jammed.json"))


def have(runs):
    return {n for n in WCASES if os.path.exists(os.path.join(runs, n, "yield_points.csv"))}


def load_all(R, runs, directions):
    """The walls cases (run.py's load), their probes keyed as run.py's: probe k of `directions`
    directions at the same angle, so that run.py's ratio functions pair them by angle."""
    W = {}
    for n in have(runs):
        c = R.load(runs, n)
        keyed = {}
        for p in c["points"].values():
            k = p["theta"] * directions / 360.0
            if abs(k - round(k)) > 1e-6:
                raise ValueError(f"{n}: probe angle {p['theta']} is not one of the {directions} reference directions")
            keyed[round(k) % directions] = p
        c["points"] = keyed
        W[n] = c
    return W


def subset(C, keys):
    """C with only the probes `keys` (the reference on the walls runs' directions)."""
    return dict(C, points={k: p for k, p in C["points"].items() if k in keys})


def findings(R, C, W, add, miss, reason):
    """The walls lines beside run.py's: R is run.py (its ratio functions), C its loaded cases, W the
    loaded walls cases; add(finding, measured, band, ok, note), miss(finding, band, why, note)."""
    def load_norm(c):
        p = c["summary"]["precompaction"]
        return math.hypot(p["S11"], p["S22"])

    def ratio(finding, A, B, names, lo, hi, note="", unit=""):
        """The size ratio A / B for both yield-point definitions (`finding` has a {kl} field)."""
        band = f"{lo:g}-{hi:g}"
        for kind, kl in R.KINDS:
            if A and B:
                r, n = R.size_ratio(A, B, kind)
                add(finding.format(kl=kl), f"{r:.2f} (median of {n}{unit})", band, lo <= r <= hi, note)
            else:
                miss(finding.format(kl=kl), band, reason(*names), note)

    for pre in PATHS:
        pname = "hydrostatic" if pre == "hydro" else "closed die"
        aa, ww, wi = C.get(f"{pre}_AA_mu0"), W.get(f"{pre}_WW_mu0"), W.get(f"{pre}_WW_inf")
        ratio(pname + ", between walls: walls-walls μ=0 surface / affine-affine size ({kl}; the paper's l.r.-l.r. line)",
              ww, aa, (f"{pre}_AA_mu0", f"{pre}_WW_mu0"), 0.4, 0.6, unit=" directions")
        for kind, kl in R.KINDS:
            fin = (f"{pname}, between walls: kink angle at the loading point, affine-affine vs walls-walls μ=0 ({kl})")
            note = "the paper: a vertex for affine-affine, rounded for l.r.-l.r. (smaller angle = smoother)"
            if aa and ww:  # the reference on the same directions: secants of equal span
                add(fin, f"{R.kink_angle(subset(aa, ww['points'].keys()), kind):.0f}° vs {R.kink_angle(ww, kind):.0f}°",
                    "-", None, note + f"; both on the walls runs' {len(ww['points'])} directions")
            else:
                miss(fin, "-", reason(f"{pre}_AA_mu0", f"{pre}_WW_mu0"), note)
        ratio(pname + ", between walls: sticking / frictionless size, walls-walls ({kl})", wi, ww,
              (f"{pre}_WW_mu0", f"{pre}_WW_inf"), 1.6, 2.4)
        ratio(pname + ", between walls: sticking walls-walls / affine-affine size ({kl})", wi, aa,
              (f"{pre}_WW_inf", f"{pre}_AA_mu0"), 0.8, 1.2,
              note="band chosen here (run.py's): the issue says 'close to affine size'")
        fin = f"{pname}, between walls: loading-point |Σ| ratios walls μ=0 / affine, sticking / μ=0 (information)"
        note = "the yield-surface ratios above follow these precompaction ratios (validation/redanz_fleck_walls: 3a, 2)"
        if aa and ww and wi:
            add(fin, f"{load_norm(ww) / load_norm(aa):.2f}, {load_norm(wi) / load_norm(ww):.2f}", "-", None, note)
        else:
            miss(fin, "-", reason(f"{pre}_AA_mu0", f"{pre}_WW_mu0", f"{pre}_WW_inf"), note)
    aa, wa = C.get("hydro_AA_mu0"), W.get("hydro_WA_mu0")
    ratio("Fig 10, between walls: walls-affine / affine-affine size, hydrostatic μ=0 ({kl}; the paper's l.r.-affine)",
          wa, aa, ("hydro_AA_mu0", "hydro_WA_mu0"), 0.4, 0.6)
    for kind, kl in R.KINDS:
        miss(f"Fig 10, between walls: affine-walls / affine-affine size, hydrostatic μ=0 ({kl}; the paper's affine-l.r.)",
             "0.4-0.6", "not run: an affinely compacted state has no walls to be probed between (netsolve yield "
             "refuses --compact-bc affine --probe-bc walls: the disks at the box faces would start inside the walls)")


def equilibrium_text(c):
    """The iteration record of a walls run: unaccepted precompaction increments, and the probes'."""
    p = c["summary"]["precompaction"]
    rows = list(csv.DictReader(open(os.path.join(c["dir"], "yield_points.csv"))))
    un = sum(int(r["unconverged"] or 0) for r in rows)
    inc = sum(int(r["increments"] or 0) for r in rows)
    return f"{p.get('unconverged_increments')} of {p.get('increments')} / {un} of {inc}"


def runs_table(runs, W, R):
    lines = ["", "## Runs between walls", "",
             "The DEM's jammed states (walls' box) and netsolve's walls runs from them: D in the walls' box (the die's "
             "box in brackets), the precompaction's and the probes' increments not accepted by the pseudo-transient "
             "iteration's criterion (undragged residual RMS ≤ --tol, max ≤ 10 × --tol).", "",
             "| case | start | D walls (die) | Z | loading point S11, S22 | precompaction / probes | probes ok | status |",
             "|---|---|---|---|---|---|---|---|"]
    for n, (lab, pre, _, mu, jam) in WCASES.items():
        k = deposition_factor(runs)
        if n not in W or k is None:
            why = not_runnable(runs, n) or R.no_points_reason(runs, n)
            lines.append(f"| {n} ({lab}, {pre}) | {jam} | no yield points: {why} | | | | | |")
            continue
        s = W[n]["summary"]
        p = s["precompaction"]
        jh = _rows(os.path.join(runs, jam, "history.csv"))[-1]
        lines.append(f"| {n} ({lab}, {pre}) | {jam}: D {float(jh['D']):.4f}, Z {float(jh['Z']):.2f} | {p['D']:.4f} "
                     f"({p['D'] * k:.4f}) | {p['Z']:.3f} | {p['S11']:.3f}, {p['S22']:.3f} | {equilibrium_text(W[n])} | "
                     f"{s['probes']['ok']}/{s['probes']['run']} | {s['status']} |")
    return lines


def fig(R, runs, C, W, pre, path, outdir):
    import matplotlib.pyplot as plt
    names = [n for n in (f"{pre}_WW_mu0", f"{pre}_WW_inf", f"{pre}_WA_mu0") if n in W]
    aa = C.get(f"{pre}_AA_mu0")
    if not names or not aa:
        return False
    f, ax = plt.subplots(figsize=(6.2, 6.2))
    R.plot_surface(ax, aa, "affine-affine, mu = 0 (die's box)", R.STYLE["AA_mu0"])
    for n in names:
        R.plot_surface(ax, W[n], WCASES[n][0], STYLE[n.split("_", 1)[1]])
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$\Sigma_{11}/\sigma_y$")
    ax.set_ylabel(r"$\Sigma_{22}/\sigma_y$")
    ax.set_title(f"Between walls: {PATHS[pre]} precompaction to D = 0.85 (die's box)", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    f.tight_layout()
    f.savefig(os.path.join(outdir, path), dpi=130)
    plt.close(f)
    return True
