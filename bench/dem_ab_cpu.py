#!/usr/bin/python3
"""A/B of the explicit DEM between two builds, interleaved, in CPU time (no LAMMPS needed).

    /usr/bin/python3 bench/dem_ab_cpu.py BUILD_A BUILD_B [--reps 8] [--cache DIR] [--only WORD,...] [--big]

Runs, for each repetition, every case with both builds, the order alternating (A B, B A, ...) so
that the slow phases of a shared machine fall on both: `bench_dem` (bench/bench_dem.cpp: 2D
N = 3000 with the linear and the full Luding law, 3D N = 1e4 linear; its CPU time of the timed
steps) and two `demsolve compact` runs of the plastic law (2D and 3D; the CPU time of the process,
set-up and meter included). BUILD_X is a build folder (BUILD_X/bench/bench_dem,
BUILD_X/apps/demsolve). The packings of bench_dem are prepared once in --cache (by build A).
Prints per case the minimum and the median of each build and the speed of B relative to A
(A's time / B's time: above 1, B is faster); on a shared machine the minimum is the steadier.
"""
import argparse
import csv
import os
import resource
import statistics
import subprocess
import tempfile


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--reps", type=int, default=8)
    ap.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "dem-ab-cache"))
    ap.add_argument("--only", default="", help="comma list: run the cases whose name contains one of them")
    ap.add_argument("--big", action="store_true",
                    help="add bench 3D N=1e5 linear (its packing takes about 9 min of CPU to prepare, once)")
    a = ap.parse_args()
    builds = {"A": a.a, "B": a.b}
    work = tempfile.mkdtemp(prefix="dem-ab-")
    c = a.cache
    bench = [("bench 2D N=3000 linear", ["--n", "3000", "--models", "linear", "--psteps", "3e7", "--warmup", "1000"]),
             ("bench 2D N=3000 full", ["--n", "3000", "--models", "full", "--psteps", "3e7", "--warmup", "1000"]),
             ("bench 3D N=1e4 linear",
              ["--dim", "3", "--n", "10000", "--models", "linear", "--psteps", "2e7", "--warmup", "300"])]
    if a.big:
        bench.append(("bench 3D N=1e5 linear",
                      ["--dim", "3", "--n", "100000", "--models", "linear", "--psteps", "2e7", "--warmup", "300"]))
    demsolve = [("demsolve compact 2D plastic", ["compact", "--width", "10", "--to-density", "0.82"]),
                ("demsolve compact 3D plastic",
                 ["compact", "--dim", "3", "--boundary", "walls", "--width", "4", "--to-density", "0.6"])]
    only = [w for w in a.only.split(",") if w]
    cases = [(n, 0, x) for n, x in bench] + [(n, 1, x) for n, x in demsolve]
    cases = [x for x in cases if not only or any(w in x[0] for w in only)]
    for n, kind, args in cases:  # prepare the packings once
        if kind == 0:
            subprocess.run([f"{a.a}/bench/bench_dem"] + args[:args.index("--models")] + ["--models", "none",
                           "--cache", c], check=True, capture_output=True)
    res = {}
    for rep in range(a.reps):
        order = ("A", "B") if rep % 2 == 0 else ("B", "A")
        for name, kind, args in cases:
            for t in order:
                if kind == 1:  # the CPU time of the process
                    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                    subprocess.run([f"{builds[t]}/apps/demsolve"] + args + ["--quiet", "--overwrite", "--out",
                                   os.path.join(work, t)], check=True, capture_output=True)
                    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                    v = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
                else:  # CPU seconds per million particle-steps
                    p = subprocess.run([f"{builds[t]}/bench/bench_dem"] + args + ["--cache", c], check=True,
                                       capture_output=True, text=True)
                    v = 1e6 / float(next(csv.DictReader(p.stdout.splitlines()))["psteps_per_cpu_s"])
                res.setdefault(name, {}).setdefault(t, []).append(v)
            print(f"rep {rep} {name}: A {res[name]['A'][-1]:.4f}, B {res[name]['B'][-1]:.4f} "
                  f"(load {open('/proc/loadavg').read().split()[0]})", flush=True)
    print("\nCPU time (bench_dem: s per million particle-steps; demsolve: s per run); speed of B = A's time / B's")
    print("| case | A min / median | B min / median | speed of B (min) | speed of B (median) |")
    print("|---|---|---|---|---|")
    for name, d in res.items():
        ta, tb = d["A"], d["B"]
        print(f"| {name} | {min(ta):.4f} / {statistics.median(ta):.4f} | {min(tb):.4f} / {statistics.median(tb):.4f} | "
              f"{min(ta) / min(tb):.3f} | {statistics.median(ta) / statistics.median(tb):.3f} |")


if __name__ == "__main__":
    main()
