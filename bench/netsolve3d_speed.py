#!/usr/bin/env python3
"""Speed of `netsolve compact --dim 3` (issue 30): wall time, its split and the peak memory.

usage: /usr/bin/python3 bench/netsolve3d_speed.py [--n 10000] [--netsolve build/apps/netsolve]
           [--work DIR] [--out bench/results/netsolve3d_speed.md] [--cases green_die,green_affine,periodic]

Packings (made once in --work, reused): the green body of `netsolve pack --dim 3 --route green-body
--n N --target-density 0.58` (lengths in metres) and the periodic packing of `netsolve pack --dim 3
--periodic --n N`. Runs, each hydrostatic to |E| = 0.1 in 100 increments on one thread
(OMP_NUM_THREADS=1, --threads 1):
  green_die      the green body in the die of the peripheral layer, the default iteration (legacy drag);
  green_die_pt   the same with --iteration pseudo-transient (true equilibrium; the 3D die leaks);
  green_affine   the green body, every centre affine;
  periodic       the periodic packing in its cell (pseudo-transient, the default there; since issue 30
                 part 3 the kept factor, --factor-reuse 20, is the 3D default);
  periodic_reuse the same with --factor-reuse 20 given explicitly;
  periodic_fresh the same with a factorisation per fresh tangent (--factor-reuse 0);
  periodic_full  the periodic case with the factor of the whole matrix as the preconditioner
                 (--preconditioner full; the 3D default since issue 30 part 5 is the translations').
A case may be listed more than once (interleaved repetitions); each run is a row.
Writes a Markdown table: wall time, the solver's split (assembly, neighbours, analysis, factorisation,
solve), Newton iterations, factorisations, peak resident memory (GNU time), the run status.
Measure on an idle machine; this is a benchmark, not a test.
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import time

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

CASES = {
    "green_die": ("green", []),
    "green_die_pt": ("green", ["--iteration", "pseudo-transient"]),
    "green_affine": ("green", ["--affine"]),
    "periodic": ("periodic", ["--boundary", "periodic"]),
    "periodic_reuse": ("periodic", ["--boundary", "periodic", "--factor-reuse", "20"]),
    "periodic_fresh": ("periodic", ["--boundary", "periodic", "--factor-reuse", "0"]),
    "periodic_full": ("periodic", ["--boundary", "periodic", "--preconditioner", "full"]),
}


def run(cmd, env=None):
    t0 = time.time()
    timer = ["/usr/bin/time", "-f", "MAXRSS %M"] if os.path.exists("/usr/bin/time") else []  # Debian: package time
    p = subprocess.run(timer + cmd, capture_output=True, text=True, env=env)
    wall = time.time() - t0
    rss = next((int(l.split()[1]) for l in p.stderr.splitlines() if l.startswith("MAXRSS")), None)
    return p.returncode, wall, rss, p.stderr


def cpu_name():
    try:
        for l in open("/proc/cpuinfo"):
            if l.startswith("model name"):
                return l.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=10000)
    ap.add_argument("--netsolve", default=os.path.join(REPO, "build", "apps", "netsolve"))
    ap.add_argument("--work", default=os.path.join(REPO, "results", "bench_netsolve3d"))
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results", "netsolve3d_speed.md"))
    ap.add_argument("--cases", default=",".join(CASES))
    a = ap.parse_args()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    os.makedirs(a.work, exist_ok=True)
    packs = {"green": ["pack", "--dim", "3", "--route", "green-body", "--n", str(a.n), "--target-density", "0.58",
                       "--quiet"],
             "periodic": ["pack", "--dim", "3", "--periodic", "--n", str(a.n), "--quiet"]}
    prep = {}
    for key in sorted({CASES[c][0] for c in a.cases.split(",")}):
        d = os.path.join(a.work, f"pack_{key}_{a.n}")
        if not os.path.isfile(os.path.join(d, "packing.csv")):
            rc, wall, _, err = run([a.netsolve] + packs[key] + ["--overwrite", "--out", d], env)
            if rc != 0:
                sys.exit(f"error: {key} packing failed (exit {rc}): {err.strip()[-300:]}")
            print(f"packing {key}: {wall:.1f} s", flush=True)
        prep[key] = os.path.join(d, "packing.csv")
    rows = []
    load0 = os.getloadavg()
    for c in a.cases.split(","):
        key, extra = CASES[c]
        d = os.path.join(a.work, c)
        cmd = [a.netsolve, "compact", "--dim", "3", "--packing", prep[key], "--to-strain", "0.1", "--increments", "100",
               "--threads", "1", "--snapshots", "", "--quiet", "--allow-unconverged", "--overwrite", "--out", d] + extra
        rc, wall, rss, err = run(cmd, env)
        if not os.path.isfile(os.path.join(d, "summary.json")):
            sys.exit(f"error: {c} wrote no summary.json (exit {rc}): {err.strip()[-300:]}")
        s = json.load(open(os.path.join(d, "summary.json")))
        t, so = s["timing_s"], s["solver"]
        with open(os.path.join(d, "history.csv")) as f:
            hdr = f.readline().strip().split(",")
            col = hdr.index("linear_iterations")
            gmres = sum(int(line.split(",")[col]) for line in f if line.strip())
        so = dict(so, gmres=gmres)
        rows.append((c, s["particles"], s["initial_density"], s["final"]["D"], wall, t, so, rss, s["status"], rc,
                     s["final"]["S33"]))
        print(f"{c}: {wall:.1f} s, {rss / 1e6 if rss else 0:.2f} GB, {s['status']}", flush=True)
    L = [f"# netsolve compact --dim 3: speed (bench/netsolve3d_speed.py --n {a.n})", "",
         f"Machine: {cpu_name()}, {os.cpu_count()} logical CPUs; one thread (OMP_NUM_THREADS=1, --threads 1). "
         "Hydrostatic to |E| = 0.1 in 100 increments. Times in seconds (the solver's own split from summary.json). "
         f"Load average before the first run: {load0[0]:.2f}, {load0[1]:.2f}, {load0[2]:.2f}.", "",
         "| case | preconditioner | spheres | D0 → D | wall | assembly | neighbours | analysis | factorisation | solve | "
         "Newton it. | GMRES it. | factorisations | peak RSS | S33/σ_y at the end | status |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c, n, d0, d1, wall, t, so, rss, st, rc, s3 in rows:
        L.append(f"| {c} | {so.get('preconditioner', '—')} | {n} | {d0:.4f} → {d1:.4f} | {wall:.1f} | {t['assemble']:.1f} | "
                 f"{t['neighbours']:.1f} | {t['analyse']:.1f} | {t['factorise']:.1f} | {t['solve']:.1f} | "
                 f"{so['newton_iterations']} | {so['gmres']} | {so['factorisations']} | "
                 f"{rss / 1e6 if rss else float('nan'):.2f} GB | {s3:.6f} | {st} (exit {rc}) |")
    with open(a.out, "w") as f:
        f.write("\n".join(L) + "\n")
    print(f"wrote {os.path.relpath(a.out, REPO)}")


if __name__ == "__main__":
    main()
