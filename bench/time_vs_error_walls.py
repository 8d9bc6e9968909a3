#!/usr/bin/python3
"""Run time against error for both solvers in walls mode from a jammed state (issue 28, "Speed").

The scene is validation/quasistatic_vs_dynamic_walls's: W = 80 ballistic packings jammed by
`demsolve compact --boundary walls --to-density 0.83 --save-state` (that case's runs/jam/s<seed>_<mu>/
jammed.json; run its run.py first), then both tools from the same state to D = 0.85 in 20
increments, hydrostatic or closed die. The error of a run is |S22 - sigma0| / |sigma0| at D = 0.85,
sigma0 the DEM's quasi-static limit: the least-squares line S22 = sigma0 + a I through this script's
own DEM runs (a DEM row is its window's mean; netsolve is taken through the mean of its last two
rows, the same window, as in the validation case).

Runs, one at a time (OMP_THREAD_LIMIT=1, nice), per seed, path and friction:
  * demsolve compact at I = 8e-4, 4e-4, 2e-4, 1e-4 (5e-5 with --slow);
  * netsolve compact --iteration pseudo-transient at 20 increments (the default regularisation),
    and at 40 increments and at --tol 1e-3 (20 increments).
x = the solver's wall time (summary.json timing_s.wall), y = the error. The DEM's front (time and
error over I) is interpolated log-log at each netsolve run's error: speed-up = t_DEM(e) / t_net. An
error below the front's range gets the most accurate DEM run's time (a lower bound, flagged); above
it, the front is extrapolated from its two fastest points (flagged). Also t_DEM at 1 % error.

    /usr/bin/python3 bench/time_vs_error_walls.py [--seeds 1,2,3] [--paths hydrostatic,closed-die]
        [--frictions inf] [--slow] [--workdir DIR] [--reuse]

--workdir defaults to netdem-bench/tve_walls in the system's temporary folder. --reuse takes a run
whose folder in --workdir already holds summary.json and history.csv as it is
(the same binaries are assumed: say so when you use it).

Writes bench/results/time_vs_error_walls.{csv,md}.
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "apps", "scripts"))
from report_paths import load_module  # noqa: E402

JAM = os.path.join(REPO, "validation", "quasistatic_vs_dynamic_walls", "runs", "jam")
INERTIAL = (8e-4, 4e-4, 2e-4, 1e-4)
NET_RUNS = (("20 inc", ["--increments", "20"]), ("40 inc", ["--increments", "40"]),
            ("20 inc, tol 1e-3", ["--increments", "20", "--tol", "1e-3"]))


def run(cmd, out, reuse=False):
    if not (reuse and os.path.exists(os.path.join(out, "summary.json"))):
        launch(cmd, out)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    return s, rows


def launch(cmd, out):
    env = dict(os.environ, OMP_THREAD_LIMIT="1")
    r = subprocess.run(["nice"] + cmd + ["--snapshots", "", "--quiet", "--overwrite", "--out", out],
                       capture_output=True, text=True, env=env)
    if r.returncode not in (0, 3):
        raise SystemExit(f"time_vs_error_walls: exit {r.returncode}: {' '.join(cmd)}: {r.stderr.strip()}")


# validation/quasistatic_vs_dynamic/run.py as a module: its least-squares fit of the DEM's limit
_qvd = load_module("qvd_layer", os.path.join(REPO, "validation", "quasistatic_vs_dynamic", "run.py"))


def fit(points):
    """sigma = s0 + a I by least squares over [(I, sigma)]: (s0, se(s0)), the validation cases' fit."""
    s0, se, _, _ = _qvd.fit([i for i, _ in points], [v for _, v in points])
    return s0, se


def dem_time_at(front, e):
    """front: [(error, time)] over I; the DEM time at error e, log-log; flag '<' (lower bound) or '>'."""
    f = sorted(front)  # by error, ascending (slowest first)
    if e <= f[0][0]:
        return f[0][1], "lower bound"
    for (e0, t0), (e1, t1) in zip(f, f[1:]):
        if e0 <= e <= e1:
            w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), ""
    (e0, t0), (e1, t1) = f[-2], f[-1]
    w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
    return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), "extrapolated"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--demsolve", default=os.path.join(REPO, "build", "apps", "demsolve"))
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--paths", default="hydrostatic,closed-die")
    ap.add_argument("--frictions", default="inf")
    ap.add_argument("--reuse", action="store_true", help="take finished runs in --workdir as they are")
    ap.add_argument("--slow", action="store_true", help="add the DEM at I = 5e-5")
    ap.add_argument("--workdir", default=os.path.join(tempfile.gettempdir(), "netdem-bench", "tve_walls"))
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results", "time_vs_error_walls"))
    a = ap.parse_args()
    inertial = INERTIAL + ((5e-5,) if a.slow else ())
    bins = tempfile.mkdtemp(prefix="tve-walls-bin-")
    net, dem = shutil.copy(a.netsolve, bins), shutil.copy(a.demsolve, bins)  # rebuilding meanwhile is harmless
    rows, summary = [], []
    for seed in a.seeds.split(","):
        for mu in a.frictions.split(","):
            state = os.path.join(JAM, f"s{seed}_{'inf' if mu == 'inf' else 'mu' + mu}", "jammed.json")
            if not os.path.exists(state):
                raise SystemExit(f"time_vs_error_walls: no jammed state {os.path.relpath(state, REPO)} "
                                 "(run validation/quasistatic_vs_dynamic_walls/run.py first)")
            for path in a.paths.split(","):
                case = f"s{seed}_{path}_{mu}"
                common = ["compact", "--boundary", "walls", "--state", state, "--friction", mu, "--path", path,
                          "--to-density", "0.850000"]
                front, pts = [], []
                for I in inertial:
                    s, h = run([dem] + common + ["--increments", "20", "--inertial-number", f"{I:g}"],
                               os.path.join(a.workdir, case, f"dem_I{I:g}"), a.reuse)
                    pts.append((I, float(h[-1]["S22"]), s["timing_s"]["wall"], s["status"]))
                s0, se = fit([(I, v) for I, v, _, _ in pts])
                for I, v, t, st in pts:
                    err = abs(v - s0) / abs(s0)
                    front.append((err, t))
                    rows.append(dict(case=case, solver="demsolve", setting=f"I={I:g}", S22=v, err=err, time_s=t,
                                     status=st, speedup="", flag=""))
                t1, f1 = dem_time_at(front, 0.01)
                for name, extra in NET_RUNS:
                    s, h = run([net] + common + ["--iteration", "pseudo-transient", "--allow-unconverged"] + extra,
                               os.path.join(a.workdir, case, "net_" + name.replace(" ", "_").replace(",", "")), a.reuse)
                    v = 0.5 * (float(h[-1]["S22"]) + float(h[-2]["S22"]))
                    err = abs(v - s0) / abs(s0)
                    td, flag = dem_time_at(front, err)
                    t = s["timing_s"]["wall"]
                    un = s.get("solver", {}).get("unconverged_increments", "")
                    rows.append(dict(case=case, solver="netsolve", setting=name, S22=v, err=err, time_s=t,
                                     status=f"{s['status']} (unaccepted {un})", speedup=td / t, flag=flag))
                summary.append((case, s0, se, t1, f1))
                print(f"{case}: sigma0 {s0:.5f} +- {se:.1e}; DEM at 1 %: {t1:.1f} s {f1}", flush=True)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    rev = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout
    md = [f"# Time against error in walls mode from a jammed state (issue 28)\n",
          f"`bench/time_vs_error_walls.py` at commit {rev.strip()}, one run at a time (OMP_THREAD_LIMIT=1). "
          "Error: |S22 − σ₀| / |σ₀| at D = 0.85, σ₀ the DEM's limit over its own runs "
          f"(I = {', '.join(f'{I:g}' for I in inertial)}). Speed-up: the DEM's time at netsolve's error "
          "(log-log along the DEM's front) over netsolve's time.\n",
          "A case is valid when se(σ₀) ≤ 0.5 % of |σ₀| (the validation cases' rule): otherwise the DEM's own "
          "limit is not known to 1 %, and its errors and speed-ups are not evaluated (invalid).\n",
          "| case | σ₀ (se) | valid | DEM time at 1 % error [s] |", "|---|---|---|---|"]
    md += [f"| {c} | {s0:.5f} ({se:.1e}) | {'yes' if se <= 0.005 * abs(s0) else 'no (invalid)'} | "
           f"{t1:.1f}{' (' + f1 + ')' if f1 else ''} |" for c, s0, se, t1, f1 in summary]
    md += ["", "| case | solver | setting | S22 | error | wall [s] | speed-up | status |", "|---|---|---|---|---|---|---|---|"]
    valid = {c: se <= 0.005 * abs(s0) for c, s0, se, _, _ in summary}
    for r in rows:
        if not valid[r["case"]] and r["speedup"] != "":
            r["flag"] = "invalid: se(σ₀) > 0.5 %"
        sp = f"{r['speedup']:.1f}{' (' + r['flag'] + ')' if r['flag'] else ''}" if r["speedup"] != "" else ""
        md.append(f"| {r['case']} | {r['solver']} | {r['setting']} | {r['S22']:.5f} | {100 * r['err']:.3f} % | "
                  f"{r['time_s']:.2f} | {sp} | {r['status']} |")
    with open(a.out + ".md", "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
