#!/usr/bin/python3
"""Scaling of the default compaction with the box width (issue #2: W = 80, 160, 320, 640 R).

For each W runs `netsolve compact --width W --increments 100` (polydisperse, seed 1, sticking,
hydrostatic, D0 -> 0.85, die boundary conditions) and records the number of particles, the solver
wall time (summary.json timing_s.wall: packing generation and output excluded), the process wall
time (including the deposition and the output), the time per increment and the
assemble / analyse / factorise / solve / neighbours split from summary.json timing_s.
W = 640 is run only if W = 320 took less than --max-seconds-before-640 (default 600 s); use
--widths to choose the widths explicitly.

Writes <out>/<name>.csv and <out>/<name>.png (--name, default scaling).

    /usr/bin/python3 bench/scaling.py
    /usr/bin/python3 bench/scaling.py --widths 80,160 --increments 20
"""
import argparse
import csv
import math
import shutil
import sys
from pathlib import Path

from bench_common import add_common_args, run_compact, setup
PARTS = ("assemble", "analyse", "factorise", "solve", "neighbours")


def run(netsolve, width, n, workdir, extra, reuse, nice):
    out = workdir / f"W{width}_N{n}"
    res = run_compact(netsolve, out, ["--width", str(width), "--increments", str(n)] + extra, reuse, nice,
                      f"W = {width}")
    if res is None:
        return None
    s, t_proc, cpu = res
    t = s["timing_s"]
    r = {
        "W": width,
        "particles": s["particles"],
        "free_dofs": s["solver"].get("free_dofs", ""),
        "increments": s["increments"],
        "wall_s": t["wall"],
        "process_wall_s": t_proc,
        "process_cpu_s": cpu,
        "per_increment_s": t["wall"] / s["increments"],
        "analyses": s["solver"]["analyses"],
        "factorisations": s["solver"]["factorisations"],
        "newton_iterations": s["solver"]["newton_iterations"],
        "unconverged_increments": s["solver"]["unconverged_increments"],
        "max_residual": s["solver"]["max_residual"],
        "S22": s["final"]["S22"],
        "Z": s["final"]["Z"],
    }
    for k in PARTS:
        r[k + "_s"] = t.get(k, 0.0)
    r["other_s"] = t["wall"] - sum(r[k + "_s"] for k in PARTS)
    r["factorise_per_call_ms"] = 1e3 * r["factorise_s"] / max(r["factorisations"], 1)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--widths", default="80,160,320,640")
    ap.add_argument("--increments", type=int, default=100)
    ap.add_argument("--max-seconds-before-640", type=float, default=600.0,
                    help="run W = 640 only if W = 320 took less than this (process wall time)")
    add_common_args(ap, "scaling", "/tmp/netdem-bench/scaling")
    a = ap.parse_args()
    workdir, netsolve, nice = setup(a)
    widths = [int(x) for x in a.widths.split(",")]

    rows, skipped = [], []
    for w in widths:
        if w == 640:
            r320 = next((r for r in rows if r["W"] == 320), None)
            if r320 is None or r320["process_wall_s"] >= a.max_seconds_before_640:
                why = "W = 320 did not run" if r320 is None else f"W = 320 took {r320['process_wall_s']:.0f} s"
                print(f"W = 640 not run: {why} (limit {a.max_seconds_before_640:.0f} s)", flush=True)
                skipped.append(w)
                continue
        print(f"W = {w}", flush=True)
        r = run(netsolve, w, a.increments, workdir, a.extra.split(), a.reuse, nice)
        if r is None:
            skipped.append(w)
            continue
        rows.append(r)
        print(f"  {r['particles']} particles: {r['wall_s']:.1f} s ({1e3 * r['per_increment_s']:.0f} ms/increment;"
              f" assemble {r['assemble_s']:.1f}, analyse {r['analyse_s']:.1f}, factorise {r['factorise_s']:.1f},"
              f" solve {r['solve_s']:.1f}, other {r['other_s']:.1f} s; {r['factorisations']} factorisations,"
              f" {r['factorise_per_call_ms']:.1f} ms each)", flush=True)
    shutil.rmtree(netsolve.parent, ignore_errors=True)

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    cols = ["W", "particles", "free_dofs", "increments", "wall_s", "process_wall_s", "process_cpu_s", "per_increment_s"] + \
           [k + "_s" for k in PARTS] + ["other_s", "analyses", "factorisations", "factorise_per_call_ms",
                                        "newton_iterations", "unconverged_increments", "max_residual", "S22", "Z"]
    with open(out / f"{a.name}.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(cols)
        for r in rows:
            wr.writerow([f"{r[c]:.6g}" if isinstance(r[c], float) else r[c] for c in cols])
        for w in skipped:
            wr.writerow([w] + ["not run"] + [""] * (len(cols) - 2))
    print("wrote", out / f"{a.name}.csv")
    if len(rows) >= 2:
        n0, n1 = rows[-2]["particles"], rows[-1]["particles"]
        p = math.log(rows[-1]["wall_s"] / rows[-2]["wall_s"]) / math.log(n1 / n0)
        est = rows[-1]["wall_s"] * (1.0e5 / n1) ** p
        print(f"last exponent t ~ N^{p:.2f}; extrapolated 100k particles, {a.increments} increments: {est:.0f} s")

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not available: no plot", file=sys.stderr)
        return
    if not rows:
        return
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.4))
    n = [r["particles"] for r in rows]
    for k, st in (("wall", "o-"), ("assemble", "s--"), ("analyse", "^--"), ("factorise", "v--"), ("solve", "d--"),
                  ("other", "x:")):
        ax1.loglog(n, [1e3 * r[k + "_s"] / r["increments"] for r in rows], st, label=k)
    ax1.set_xlabel("particles")
    ax1.set_ylabel("time per increment [ms]")
    ax1.set_title(f"netsolve compact, {a.increments} increments to D = 0.85")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)
    ax2.loglog(n, [r["wall_s"] for r in rows], "o-", label="solver wall time")
    ax2.loglog(n, [r["process_cpu_s"] for r in rows], "s--", label="process CPU time (user+sys)")
    ax2.axhline(120.0, color="k", ls="--", lw=0.8)
    ax2.axvline(1.0e5, color="k", ls=":", lw=0.8)
    ax2.text(n[0], 120.0, "target: 100k particles < 2 min", va="bottom", fontsize=8)
    ax2.set_xlabel("particles")
    ax2.set_ylabel(f"total time, {a.increments} increments [s]")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / f"{a.name}.png", dpi=130)
    print("wrote", out / f"{a.name}.png")


if __name__ == "__main__":
    main()
