#!/usr/bin/python3
"""Run time against error for both solvers on the default compaction (issue 12 section 6).

The scene: `netsolve compact` / `demsolve compact` with no options (1639 disks, W = 80 R ballistic
deposition seed 1, sticking friction, hydrostatic, peripheral-layer ("die") boundary, D0 = 0.8081 ->
D = 0.85). The error of a run is its relative error in Sigma22 at D = 0.85 against the DEM limit
sigma0 (I -> 0):

    SIGMA0_REF = -0.58265 +- 0.00016   (docs/dynamic.md, "Measured on the default scene": least-squares
                 fit S22 = sigma0 + a I of demsolve compact at I = 4.5e-4, 1.5e-4, 5e-5, 1.667e-5,
                 nominal I, a = -24.4 +- 0.7)

The script also recomputes sigma0 from its own demsolve runs at the default time step (the same
linear fit over its spc-50 runs with I <= --fit-inertial-max; standard error from the residuals)
and reports both; the errors use SIGMA0_REF (columns err, err_end) and the recomputed value (err_fit).

Sigma22 at D = 0.85 (the definition of validation/quasistatic_vs_dynamic/run.py): a demsolve row is a
mean over its window (the last of 100 windows ends at D = 0.85), a netsolve row is the state at the
end of its increment, so netsolve is taken as its window mean: at 100 increments the mean of its
last two rows; at N increments the mean of its piecewise-linear S22 over the DEM's last window
(column S22; S22_end is netsolve's last row, S22_last_inc the mean of its last two rows).

Runs (one at a time, under nice; netsolve with OMP_THREAD_LIMIT=1):
  * netsolve: --increments 25,50,100,200,400 (default tol and drag); --tol x10 and /10 at 100
    increments; --viscosity default/3 and /9 at 100 increments (--allow-unconverged: the number of
    unconverged increments is recorded and plotted with an open marker);
  * demsolve: --inertial-number 1.5e-3, 1e-3, 4.5e-4, 1.5e-4, 5e-5 (and 1.667e-5 with --slow) at the
    default --steps-per-contact 50, and --steps-per-contact 25, 100 at the default I (the time
    integration: dt against dt/2); a second, cheaper DEM front at --steps-per-contact 25 (--alt-spc)
    over I = 1.5e-3, 1e-3, 4.5e-4 (--alt-inertial) and the default I, for a second speed-up column. demsolve's default scene ends with exit 3, "unstable" (5-6 disks
    squeezed out of the die between the peripheral disks; docs/dynamic.md): accepted when history.csv
    and summary.json were written, the status is recorded.

x = the solver wall time (summary.json timing_s.wall; packing and output excluded; --time cpu: the
process CPU time, user + sys, which is recorded too), y = |relative error| (log-log).

Speed-up at equal error: for a netsolve run with error e and time t_n, t_d(e) is the DEM time at
the same error by log-log interpolation along the DEM's Pareto front over I (default time step);
speed-up = t_d(e) / t_n. An e above the front's error range is extrapolated from its two fastest
points and flagged; an e below it gets the most accurate DEM run's time, a lower bound (flagged).
Secondary: each solver against its own limit (netsolve against its finest default run, the DEM
against sigma0), the same interpolation (column speedup_self).

    /usr/bin/python3 bench/time_vs_error_both.py --netsolve /tmp/bench6bin/netsolve \
        --demsolve /tmp/bench6bin/demsolve [--slow]          # the runs of 2026-12-01
    /usr/bin/python3 bench/time_vs_error_both.py --reuse      # re-plot the run folders that exist

Writes <out>/<name>.csv, .png and .md (default bench/results/time_vs_error_both.*); run folders in
--workdir (default /tmp/netdem-bench/tve_both). The binaries are copied to a temporary folder
first, so rebuilding them meanwhile is harmless.
"""
import argparse
import csv
import json
import math
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

import bench_common
from bench_common import REPO, add_common_args, pyplot, run_compact, setup, write_rows_csv

SIGMA0_REF = -0.58265      # S22 at D = 0.85, DEM I -> 0 (docs/dynamic.md, "Measured on the default scene")
SIGMA0_REF_SE = 0.00016
A_REF = -24.4              # slope dS22/dI of the same fit
# docs/dynamic.md's run at I = 1.667e-5 (not rerun without --slow: 333 s CPU); marked "docs" in the table
DOCS_I_SLOW = {"I": 1.667e-5, "S22": -0.58319, "cpu_s": 333.3}
D_END = 0.85
NET_DEFAULT = {"increments": 100, "tol": 3e-3, "viscosity": 0.01}   # netsolve compact --help
DEM_DEFAULT = {"I": 1.5e-4, "spc": 50.0}                            # demsolve compact --help


def read_history(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]
    return [{k: float(v) for k, v in r.items() if v not in (None, "")} for r in rows]


def priv_copy(binary, tmp):
    dst = Path(tmp) / Path(binary).name
    shutil.copy2(binary, dst)
    return dst


def run_dem(demsolve, out, args, reuse, nice):
    """demsolve compact ARGS --out OUT; exit 0 or 3 (unstable) accepted when summary.json and
    history.csv exist. Returns (summary, process wall s, process CPU s, exit code) or None."""
    summ, hist = out / "summary.json", out / "history.csv"
    if not (reuse and summ.exists() and hist.exists() and not (out / ".incomplete").exists()):
        cmd = ([] if nice is None else ["nice", "-n", str(nice)]) + [str(demsolve), "compact"] + args + [
            "--snapshots", "", "--quiet", "--overwrite", "--out", str(out)]
        print("  " + " ".join(cmd), flush=True)
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=bench_common.ENV)
        t_proc = time.perf_counter() - t0
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
        if p.returncode not in (0, 3) or not (summ.exists() and hist.exists()):
            print(f"  demsolve failed ({p.returncode}) after {t_proc:.1f} s: {p.stderr.strip()[-300:]}",
                  file=sys.stderr)
            return None
        (out / "process_wall_s.txt").write_text(f"{t_proc:.4f}\n")
        (out / "process_cpu_s.txt").write_text(f"{cpu:.4f}\n")
        (out / "exit_code.txt").write_text(f"{p.returncode}\n")

    def read(name):
        f = out / name
        return float(f.read_text()) if f.exists() else float("nan")

    return json.loads(summ.read_text()), read("process_wall_s.txt"), read("process_cpu_s.txt"), read("exit_code.txt")


def s22_end(hist, window_mean, dem_windows=100):
    """S22 at D = 0.85 from the last row (NaN if the run did not reach it).

    window_mean (netsolve): the mean of netsolve's piecewise-linear S22 over the DEM's last window,
    i.e. of its value at the end (D = 0.85) and at the strain fraction (dem_windows - 1)/dem_windows
    (both solvers take equal strain steps), linear in the row index. At netsolve's default 100
    increments this is exactly the mean of its last two rows, the definition of
    validation/quasistatic_vs_dynamic/run.py; at other N it compares over the same density window
    as the DEM row (the mean of the last two rows at N = 25 would be centred 0.0006 lower in D,
    worth ~0.9 % in S22 there)."""
    if not hist or abs(hist[-1]["D"] - D_END) > 1e-6:
        return float("nan")
    if window_mean:
        n = len(hist) - 1                      # rows 0..N
        x = n * (dem_windows - 1) / dem_windows
        k = min(int(math.floor(x)), n - 1)
        f = x - k
        s_w = (1 - f) * hist[k]["S22"] + f * hist[k + 1]["S22"]
        return 0.5 * (s_w + hist[-1]["S22"])
    return hist[-1]["S22"]


def s22_last_increment(hist):
    """netsolve: the mean of its last two rows (its own last increment), for reference."""
    if not hist or abs(hist[-1]["D"] - D_END) > 1e-6:
        return float("nan")
    return 0.5 * (hist[-1]["S22"] + hist[-2]["S22"])


def linfit(xs, ys):
    """Least squares y = s0 + a x: (s0, se(s0), a, se(a)); se NaN below 3 points."""
    n = len(xs)
    if n < 2:
        return (float("nan"),) * 4
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    a = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    s0 = my - a * mx
    if n < 3:
        return s0, float("nan"), a, float("nan")
    s2 = sum((y - s0 - a * x) ** 2 for x, y in zip(xs, ys)) / (n - 2)
    return s0, math.sqrt(s2 * (1.0 / n + mx * mx / sxx)), a, math.sqrt(s2 / sxx)


def pareto(points):
    """points (t, e): the front sorted by time, each point with a smaller error than every faster one."""
    front = []
    for t, e in sorted(points):
        if not front or e < front[-1][1]:
            front.append((t, e))
    return front


def t_at_error(front, e):
    """DEM time at error e by log-log interpolation along the front (errors decrease with time).
    Returns (t, flag): flag '' inside the front's error range; 'extrapolated' above it (larger error than
    the fastest DEM run: log-log extrapolation of the first two points); 'lower bound' below it (the
    time of the most accurate DEM run, so the speed-up is a lower bound)."""
    if len(front) < 2 or not (e > 0):
        return float("nan"), "no front"
    pts = [(math.log(t), math.log(err)) for t, err in front]
    # the front is ordered by increasing t and decreasing e
    if e < front[-1][1]:
        # below the most accurate DEM run: the DEM needs at least that run's time (lower bound)
        return front[-1][0], "lower bound"
    flag = "" if e <= front[0][1] else "extrapolated"
    le = math.log(e)
    if le >= pts[0][1]:
        (t0, e0), (t1, e1) = pts[0], pts[1]
    elif le <= pts[-1][1]:
        (t0, e0), (t1, e1) = pts[-2], pts[-1]
    else:
        k = next(i for i in range(len(pts) - 1) if pts[i][1] >= le >= pts[i + 1][1])
        (t0, e0), (t1, e1) = pts[k], pts[k + 1]
    w = (le - e0) / (e1 - e0)
    return math.exp(t0 + w * (t1 - t0)), flag


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--demsolve", default=str(REPO / "build-bench" / "apps" / "demsolve"))
    ap.add_argument("--increments", default="25,50,100,200,400", help="netsolve increments (default tol, drag)")
    ap.add_argument("--tols", default="3e-2,3e-4", help="netsolve --tol values at 100 increments (default 3e-3 is in --increments)")
    ap.add_argument("--drag-divisors", default="3,9", help="netsolve --viscosity = 0.01 / these, at 100 increments")
    ap.add_argument("--inertial", default="1.5e-3,1e-3,4.5e-4,1.5e-4,5e-5", help="demsolve --inertial-number values (spc 50)")
    ap.add_argument("--slow", action="store_true", help="also demsolve at I = 1.667e-5 (about 330 s CPU)")
    ap.add_argument("--spcs", default="25,100", help="demsolve --steps-per-contact values at the default I (50 is the default)")
    ap.add_argument("--alt-spc", type=float, default=25.0,
                    help="a second DEM front at this --steps-per-contact (0: none); its I values: --alt-inertial")
    ap.add_argument("--alt-inertial", default="1.5e-3,1e-3,4.5e-4",
                    help="demsolve --inertial-number values at --alt-spc (the default I comes from --spcs)")
    ap.add_argument("--fit-inertial-max", type=float, default=4.5e-4,
                    help="the recomputed sigma0 fits the spc-50 DEM runs with I <= this (the docs' range)")
    ap.add_argument("--time", choices=("wall", "cpu"), default="wall",
                    help="x axis and speed-up: solver wall time (summary.json timing_s.wall) or process CPU time")
    add_common_args(ap, "time_vs_error_both", "/tmp/netdem-bench/tve_both")
    ap.set_defaults(omp_thread_limit=1)
    a = ap.parse_args()
    workdir, netsolve, nice = setup(a)
    demsolve = priv_copy(a.demsolve, netsolve.parent) if Path(a.demsolve).exists() else None

    # ---------------------------------------------------------------- the runs (one at a time)
    rows = []
    net_cases = [("increments", n, NET_DEFAULT["tol"], NET_DEFAULT["viscosity"]) for n in map(int, a.increments.split(","))]
    net_cases += [("tol", 100, float(t), NET_DEFAULT["viscosity"]) for t in a.tols.split(",") if t]
    net_cases += [("drag", 100, NET_DEFAULT["tol"], NET_DEFAULT["viscosity"] / float(d)) for d in a.drag_divisors.split(",") if d]
    for knob, n, tol, visc in net_cases:
        out = workdir / f"net_N{n}_tol{tol:g}_visc{visc:.4g}"
        args = ["--increments", str(n), "--tol", repr(tol), "--viscosity", repr(visc)]
        res = run_compact(netsolve, out, args, a.reuse, nice, f"netsolve N={n} tol={tol:g} visc={visc:.4g}")
        if res is None:
            continue
        s, pw, pc = res
        h = read_history(out / "history.csv")
        unc = s["solver"]["unconverged_increments"]
        rows.append({"solver": "netsolve", "knob": knob, "increments": n, "tol": tol, "viscosity": visc,
                     "I": float("nan"), "steps_per_contact": float("nan"),
                     "wall_s": float(s["timing_s"]["wall"]), "process_wall_s": pw, "process_cpu_s": pc,
                     "S22": s22_end(h, True), "S22_end": s22_end(h, False), "S22_last_inc": s22_last_increment(h),
                     "status": s["status"],
                     "unconverged": unc, "outside": s.get("centres_outside_box", float("nan")),
                     "steps": s["solver"]["newton_iterations"], "source": "run"})
    dem_cases = [("I", float(i), DEM_DEFAULT["spc"]) for i in a.inertial.split(",")]
    dem_cases += [("dt", DEM_DEFAULT["I"], float(c)) for c in a.spcs.split(",") if c]
    if a.alt_spc > 0:
        dem_cases += [("I_alt", float(i), a.alt_spc) for i in a.alt_inertial.split(",") if i]
    if a.slow:  # last: the longest run
        dem_cases.append(("I", DOCS_I_SLOW["I"], DEM_DEFAULT["spc"]))
    for knob, I, spc in dem_cases:
        out = workdir / f"dem_I{I:.4g}_spc{spc:g}"
        args = ["--inertial-number", repr(I), "--steps-per-contact", f"{spc:g}"]
        if demsolve is None:
            if not (a.reuse and (out / "summary.json").exists()):
                print(f"  no demsolve binary ({a.demsolve}) and no run folder {out}: skipped", file=sys.stderr)
                continue
        res = run_dem(demsolve, out, args, a.reuse, nice)
        if res is None:
            continue
        s, pw, pc, rc = res
        h = read_history(out / "history.csv")
        rows.append({"solver": "demsolve", "knob": knob, "increments": s.get("increments", 100), "tol": float("nan"),
                     "viscosity": float("nan"), "I": I, "steps_per_contact": spc,
                     "wall_s": float(s["timing_s"]["wall"]), "process_wall_s": pw, "process_cpu_s": pc,
                     "S22": s22_end(h, False), "S22_end": s22_end(h, False), "S22_last_inc": s22_end(h, False),
                     "status": f"{s['status']} (exit {rc:.0f})", "unconverged": float("nan"),
                     "outside": s.get("centres_outside_box", float("nan")), "steps": s.get("steps", float("nan")),
                     "source": "run"})
    shutil.rmtree(netsolve.parent, ignore_errors=True)
    have_slow = any(r["solver"] == "demsolve" and abs(r["I"] - DOCS_I_SLOW["I"]) < 1e-9 for r in rows)
    if not have_slow:
        # docs/dynamic.md's number (CPU time on this machine; wall not recorded there): marked "docs"
        rows.append({"solver": "demsolve", "knob": "I", "increments": 100, "tol": float("nan"), "viscosity": float("nan"),
                     "I": DOCS_I_SLOW["I"], "steps_per_contact": DEM_DEFAULT["spc"], "wall_s": DOCS_I_SLOW["cpu_s"],
                     "process_wall_s": float("nan"), "process_cpu_s": DOCS_I_SLOW["cpu_s"], "S22": DOCS_I_SLOW["S22"],
                     "S22_end": DOCS_I_SLOW["S22"], "S22_last_inc": DOCS_I_SLOW["S22"], "status": "unstable (docs/dynamic.md)", "unconverged": float("nan"),
                     "outside": float("nan"), "steps": 2766244.0, "source": "docs"})

    # ---------------------------------------------------------------- sigma0, errors, dt, speed-up
    dem_main = sorted([r for r in rows if r["solver"] == "demsolve" and r["knob"] == "I"
                       and math.isfinite(r["S22"])], key=lambda r: -r["I"])
    # the recomputed sigma0: this script's own runs only (the docs' I = 1.667e-5 row is not used)
    fit_pts = [r for r in dem_main if r["I"] <= a.fit_inertial_max * (1 + 1e-9) and r["source"] == "run"]
    s0, s0_se, slope, slope_se = linfit([r["I"] for r in fit_pts], [r["S22"] for r in fit_pts])
    own = [r for r in dem_main if r["source"] == "run"]
    s0_all, s0_all_se, slope_all, slope_all_se = linfit([r["I"] for r in own], [r["S22"] for r in own])
    for r in rows:
        r["err"] = abs(r["S22"] - SIGMA0_REF) / abs(SIGMA0_REF)
        r["err_end"] = abs(r["S22_end"] - SIGMA0_REF) / abs(SIGMA0_REF)
        r["err_fit"] = abs(r["S22"] - s0) / abs(s0) if math.isfinite(s0) else float("nan")
        r["t"] = r["process_cpu_s"] if a.time == "cpu" else r["wall_s"]

    def dem_at(I, spc):
        return next((r for r in rows if r["solver"] == "demsolve" and r["source"] == "run" and abs(r["I"] - I) < 1e-12
                     and r["steps_per_contact"] == spc), None)

    base = dem_at(DEM_DEFAULT["I"], DEM_DEFAULT["spc"])
    dt_lines = []
    for spc in sorted({r["steps_per_contact"] for r in rows if r["solver"] == "demsolve" and r["knob"] == "dt"}):
        o = dem_at(DEM_DEFAULT["I"], spc)
        if base and o:
            ch = (o["S22"] - base["S22"]) / abs(base["S22"])
            dt_lines.append((spc, o["S22"], ch))

    front_pts = [(r["t"], r["err"]) for r in dem_main if r["source"] == "run" or a.time == "cpu"]
    front = pareto(front_pts)
    # secondary: each solver against its own limit. netsolve's "self" error is against its finest
    # default run (most increments, default tol and drag), which is not shown to be converged; the
    # DEM's own limit is sigma0, so its self error is err.
    finest = max((r for r in rows if r["solver"] == "netsolve" and r["knob"] == "increments"),
                 key=lambda r: r["increments"], default=None)
    alt = sorted([r for r in rows if r["solver"] == "demsolve" and a.alt_spc > 0 and r["steps_per_contact"] == a.alt_spc
                  and math.isfinite(r["S22"])], key=lambda r: -r["I"])
    front_alt = pareto([(r["t"], r["err"]) for r in alt])
    for r in rows:
        r["dem_t_at_err"], r["speedup"], r["speedup_flag"] = float("nan"), float("nan"), ""
        r["speedup_alt"], r["speedup_alt_flag"] = float("nan"), ""
        if r["solver"] == "netsolve" and len(front_alt) >= 2:
            td, flag = t_at_error(front_alt, r["err"])
            r["speedup_alt"], r["speedup_alt_flag"] = td / r["t"], flag
        r["err_self"], r["dem_t_at_err_self"], r["speedup_self"], r["speedup_self_flag"] = (
            r["err"], float("nan"), float("nan"), "")
        if r["solver"] == "netsolve":
            td, flag = t_at_error(front, r["err"])
            r["dem_t_at_err"], r["speedup"], r["speedup_flag"] = td, td / r["t"], flag
            r["err_self"] = float("nan")
            if finest is not None and r is not finest:
                r["err_self"] = abs(r["S22"] - finest["S22"]) / abs(finest["S22"])
                td, flag = t_at_error(front, r["err_self"])
                r["dem_t_at_err_self"], r["speedup_self"], r["speedup_self_flag"] = td, td / r["t"], flag

    cols = ["solver", "knob", "increments", "tol", "viscosity", "I", "steps_per_contact", "wall_s", "process_wall_s",
            "process_cpu_s", "S22", "S22_end", "S22_last_inc", "err", "err_end", "err_fit", "status", "unconverged", "outside",
            "steps", "dem_t_at_err", "speedup", "speedup_flag", "speedup_alt", "speedup_alt_flag", "err_self", "dem_t_at_err_self", "speedup_self",
            "speedup_self_flag", "source"]
    out = write_rows_csv(a.out, a.name, cols, rows)

    # ---------------------------------------------------------------- report (.md)
    tname = "CPU" if a.time == "cpu" else "solver wall"
    L = []
    w = L.append
    w(f"# Run time against error, both solvers (bench/time_vs_error_both.py)\n")
    w(f"Default scene (1639 disks, W = 80R, seed 1, sticking, hydrostatic, die/layer, D0 -> 0.85). Error = "
      f"|S22(0.85) − σ₀| / |σ₀| with σ₀ = {SIGMA0_REF} ± {SIGMA0_REF_SE} (docs/dynamic.md). demsolve S22 = its last window "
      f"mean (D from 0.8496 to 0.85); netsolve S22 = the mean of its piecewise-linear S22 over that same window (at N = 100 "
      f"exactly the mean of its last two rows, the definition of validation/quasistatic_vs_dynamic/run.py); "
      f"'S22 end value' = netsolve's last row. "
      f"Time for the speed-up: {tname} time.\n")
    w("| solver | knob | setting | solver wall [s] | process CPU [s] | S22 (0.85) | S22 end value | error [%] | status | "
      f"DEM time at this error [s] | speed-up | speed-up vs DEM at spc {a.alt_spc:g} | error vs own finest run [%] | "
      "speed-up at that error |")
    w("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if r["solver"] == "netsolve":
            setting = f"N = {r['increments']}, tol = {r['tol']:g}, drag = {r['viscosity']:.4g}"
            st = r["status"] + (f", {r['unconverged']}/{r['increments']} unconverged" if r["unconverged"] else "")
            st += f", {r['outside']} outside" if r["outside"] else ""
            su = ("> " if r["speedup_flag"] == "lower bound" else "") + f"{r['speedup']:.2f}" + (
                " (extrapolated)" if r["speedup_flag"] == "extrapolated" else "")
            td = f"{r['dem_t_at_err']:.1f}"
            sa = "" if not math.isfinite(r["speedup_alt"]) else (
                ("> " if r["speedup_alt_flag"] == "lower bound" else "") + f"{r['speedup_alt']:.2f}" + (
                    " (extrapolated)" if r["speedup_alt_flag"] == "extrapolated" else ""))
            es = "(reference)" if not math.isfinite(r["err_self"]) else f"{100 * r['err_self']:.3f}"
            ss = "" if not math.isfinite(r["speedup_self"]) else (
                ("> " if r["speedup_self_flag"] == "lower bound" else "") + f"{r['speedup_self']:.0f}" + (
                    " (extrapolated)" if r["speedup_self_flag"] == "extrapolated" else ""))
        else:
            setting = f"I = {r['I']:.4g}, spc = {r['steps_per_contact']:g}"
            st = r["status"] + (f", {r['outside']:.0f} outside" if math.isfinite(r["outside"]) else "")
            su, td, sa, es, ss = "", "", "", "", ""
        wall = "—" if r["source"] == "docs" else f"{r['wall_s']:.1f}"
        w(f"| {r['solver']} | {r['knob']} | {setting} | {wall} | {r['process_cpu_s']:.1f} | {r['S22']:.5f} | "
          f"{r['S22_end']:.5f} | {100 * r['err']:.3f} | {st} | {td} | {su} | {sa} | {es} | {ss} |")
    w("")
    w(f"σ₀ recomputed from these DEM runs (spc 50, I ≤ {a.fit_inertial_max:g}: "
      f"{', '.join(format(r['I'], 'g') for r in fit_pts)}): "
      f"{s0:.5f} ± {s0_se:.5f}, a = {slope:.2f} ± {slope_se:.2f}; reference {SIGMA0_REF} ± {SIGMA0_REF_SE}, a = {A_REF}. "
      f"Over all I of these runs ({', '.join(format(r['I'], 'g') for r in own)}): {s0_all:.5f} ± {s0_all_se:.5f}, a = {slope_all:.2f} ± {slope_all_se:.2f}.\n")
    if base:
        for spc, s, ch in dt_lines:
            w(f"Time step at I = {DEM_DEFAULT['I']:g}: S22(0.85) = {s:.5f} at spc {spc:g} against {base['S22']:.5f} at spc 50: "
              f"change {100 * ch:+.3f} %.")
        w("")
    if finest is not None:
        w(f"'error vs own finest run': netsolve against its N = {finest['increments']} run (S22 = {finest['S22']:.5f}; "
          "not shown to be converged), the DEM against σ₀; the speed-up in the last column compares the two "
          "solvers each at that distance from its own limit (secondary; the headline is the speed-up against σ₀).\n")
    w("DEM Pareto front (time, error %): " + ", ".join(f"({t:.1f} s, {100 * e:.3f})" for t, e in front) + "\n")
    if front_alt:
        w(f"DEM front at spc {a.alt_spc:g} (time, error %): " + ", ".join(f"({t:.1f} s, {100 * e:.3f})" for t, e in front_alt) + "\n")
    (Path(out) / f"{a.name}.md").write_text("\n".join(L) + "\n")
    print("\n".join(L))
    print("wrote", Path(out) / f"{a.name}.md")

    # ---------------------------------------------------------------- plot
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7.2, 5.0))
    dm = [r for r in dem_main]
    ax.loglog([r["t"] for r in dm], [100 * r["err"] for r in dm], "s-", color="k", label="demsolve, I (spc 50)")
    for r in dm:
        ax.annotate(f"I={r['I']:.3g}" + (" (docs, CPU)" if r["source"] == "docs" else ""), (r["t"], 100 * r["err"]),
                    textcoords="offset points", xytext=(4, 4), fontsize=7)
    if alt:
        ax.loglog([r["t"] for r in alt], [100 * r["err"] for r in alt], "s--", color="0.5", mfc="none",
                  label=f"demsolve, I (spc {a.alt_spc:g})")
    dd = [r for r in rows if r["solver"] == "demsolve" and r["knob"] == "dt"]
    if dd:
        ax.loglog([r["t"] for r in dd], [100 * r["err"] for r in dd], "D", color="0.5", mfc="none", ls="none",
                  label=f"demsolve, I = {DEM_DEFAULT['I']:g}, spc 25/100")
        for r in dd:
            ax.annotate(f"spc={r['steps_per_contact']:g}", (r["t"], 100 * r["err"]), textcoords="offset points",
                        xytext=(4, -10), fontsize=7)
    styles = {"increments": ("o-", "C0", "netsolve, increments"), "tol": ("^:", "C1", "netsolve, --tol (N = 100)"),
              "drag": ("v:", "C2", "netsolve, drag (N = 100)")}
    for knob, (st, col, lab) in styles.items():
        rr = [r for r in rows if r["solver"] == "netsolve" and r["knob"] == knob]
        if not rr:
            continue
        ax.plot([r["t"] for r in rr], [100 * r["err"] for r in rr], st, color=col, label=lab)
        for j, r in enumerate(rr):
            if r["unconverged"]:
                ax.plot(r["t"], 100 * r["err"], "o", ms=12, mfc="none", color="r")
            if r["outside"]:
                ax.plot(r["t"], 100 * r["err"], "x", ms=14, color="m")
            txt = {"increments": f"N={r['increments']}", "tol": f"tol={r['tol']:g}",
                   "drag": f"drag={r['viscosity']:.3g}"}[knob]
            off = (-8, 8 + 8 * (j % 3)) if knob == "increments" else (6, -12)
            ax.annotate(txt, (r["t"], 100 * r["err"]), textcoords="offset points", xytext=off, fontsize=6.5, color=col)
    ax.plot([], [], "o", ms=12, mfc="none", color="r", label="netsolve with unconverged increments")
    ax.plot([], [], "x", ms=10, color="m", label="netsolve with disk centres outside the box")
    ax.axhline(100 * SIGMA0_REF_SE / abs(SIGMA0_REF), color="k", ls=":", lw=0.8)
    ax.text(ax.get_xlim()[0], 100 * SIGMA0_REF_SE / abs(SIGMA0_REF), " σ₀ standard error", va="bottom", fontsize=7)
    ax.set_ylim(top=12)
    ax.set_xlabel("process CPU time [s]" if a.time == "cpu" else "solver wall time (summary.json timing_s.wall) [s]")
    ax.set_ylabel("|Σ22(0.85) − σ₀| / |σ₀| [%]")
    ax.set_title("default compaction, one core: netsolve vs demsolve (σ₀ = DEM I → 0)", fontsize=10)
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(Path(out) / f"{a.name}.png", dpi=130)
    print("wrote", Path(out) / f"{a.name}.png")


if __name__ == "__main__":
    main()
