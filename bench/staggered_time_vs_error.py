#!/usr/bin/env python3
"""Run time against error of the staggered scheme's two time-marching strategies (issue 17, "Strategy 1 against
strategy 2 at equal accuracy").

usage: /usr/bin/python3 bench/staggered_time_vs_error.py PACKING.csv [--bench build/bench/bench_staggered]
           [--time 1000] [--eps1 1e-4,1e-5,1e-6] [--eps2 1e-4,...,1e-7] [--dt-max 10,1] [--ref-eps 1e-10] [--ref-dt-max 0.25] [--out bench/results/staggered_time_vs_error]

Every run sinters the same packing (Cu set, 1293 K, new contacts on). The reference is strategy 2 at --ref-eps and a
small --ref-dt-max: the error of a run is then both its integration error (eps_lim) and its staggering error (the
coupling of the contacts through the network once per global step). The error is that of the mean shrinkage (the three axes' average) and of the mean neck at --time, relative
to the reference. Writes OUT.csv and OUT.md (with the machine). One run per setting: the run times are single
measurements (this machine varies by about 10 %).
"""
import argparse
import os
import platform
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(str(REPO), "apps", "scripts"))
from report_paths import shown_path  # noqa: E402


def shown(p):
    """A path for the report (apps/scripts/report_paths.py)."""
    return shown_path(p, REPO)


def run(bench, packing, strategy, eps, t_end, dt_max=10.0):
    out = subprocess.run([bench, packing, "--strategy", str(strategy), "--eps-lim", str(eps), "--time", str(t_end),
                          "--dt-max", str(dt_max)], check=True, capture_output=True, text=True).stdout
    sh = [float(v) for v in re.search(r"shrink (\S+) (\S+) (\S+)", out).groups()]
    neck = float(re.search(r"neck (\S+)", out).group(1))
    wall = float(re.search(r"wall (\S+) s", out).group(1))
    steps = int(re.search(r"steps (\d+)", out).group(1))
    sub = int(re.search(r"substeps (\d+)", out).group(1))
    return {"shrink": sum(sh) / 3, "neck": neck, "wall": wall, "steps": steps, "substeps": sub}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("packing")
    ap.add_argument("--bench", default=os.path.join(REPO, "build", "bench", "bench_staggered"))
    ap.add_argument("--time", type=float, default=1000.0)
    ap.add_argument("--eps1", default="1e-4,1e-5,1e-6", help="eps_lim of the strategy-1 runs")
    ap.add_argument("--eps2", default="1e-4,1e-5,1e-6,1e-7", help="eps_lim of the strategy-2 runs")
    ap.add_argument("--dt-max", default="10,1", help="dt_max of the strategy-2 runs [s] (strategy 1: the first)")
    ap.add_argument("--ref-eps", type=float, default=1e-10)
    ap.add_argument("--ref-dt-max", type=float, default=0.25,
                    help="dt_max of the reference: small, so that the staggering (coupling) error is small too")
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results", "staggered_time_vs_error"))
    a = ap.parse_args()
    ref = run(a.bench, a.packing, 2, a.ref_eps, a.time, a.ref_dt_max)
    print(f"reference: {ref['wall']:.2f} s, {ref['steps']} steps", flush=True)
    dts = [float(x) for x in a.dt_max.split(",")]
    configs = [(1, float(e), dts[0]) for e in a.eps1.split(",")]
    configs += [(2, float(e), d) for d in dts for e in a.eps2.split(",")]
    rows = []
    for s_, e, d in configs:
        r = run(a.bench, a.packing, s_, e, a.time, d)
        r.update(strategy=s_, eps=e, dt_max=d, err_shrink=abs(r["shrink"] / ref["shrink"] - 1),
                 err_neck=abs(r["neck"] / ref["neck"] - 1))
        rows.append(r)
        print(f"strategy {s_} eps {e:g} dt_max {d:g}: {r['wall']:.2f} s, error {r['err_shrink']:.2e} (shrink) "
              f"{r['err_neck']:.2e} (neck)", flush=True)
    with open(a.out + ".csv", "w") as f:
        f.write("strategy,eps_lim,dt_max,wall_s,steps,substeps,shrink_mean,neck_mean,rel_error_shrink,rel_error_neck\n")
        for r in rows:
            f.write(f"{r['strategy']},{r['eps']:g},{r['dt_max']:g},{r['wall']:.3f},{r['steps']},{r['substeps']},{r['shrink']:.9e},"
                    f"{r['neck']:.9e},{r['err_shrink']:.3e},{r['err_neck']:.3e}\n")
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    with open(a.out + ".md", "w") as f:
        f.write(f"# Staggered scheme: run time against error of strategies 1 and 2\n\n"
                f"`{' '.join(['bench/staggered_time_vs_error.py', shown(a.packing), '--time', str(a.time)])}`; "
                f"machine: {cpu}, one core. Reference: strategy 2 at eps_lim = {a.ref_eps:g}, dt_max = {a.ref_dt_max:g} s "
                f"({ref['wall']:.2f} s, {ref['steps']} steps; shrinkage {ref['shrink']:.9e}, neck {ref['neck']:.9e}).\n\n"
                "| strategy | eps_lim | dt_max [s] | run time [s] | steps | sub-steps | error of the mean shrinkage | error of the mean neck |\n"
                "|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['strategy']} | {r['eps']:g} | {r['dt_max']:g} | {r['wall']:.2f} | {r['steps']} | {r['substeps']} | {r['err_shrink']:.2e} | "
                    f"{r['err_neck']:.2e} |\n")


if __name__ == "__main__":
    main()
