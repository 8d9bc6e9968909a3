#!/usr/bin/python3
"""The explicit DEM on two threads against one (issue 31), with LAMMPS on one and two beside it.

    /usr/bin/python3 bench/dem_threads.py [--bench build/bench/bench_dem] [--dim 2|3] [--n 30000]
        [--threads 2] [--reps 3] [--psteps 3e7] [--warmup 1000] [--cache DIR] [--name NAME]

The scene, packings and LAMMPS inputs are bench/dem_vs_lammps.py's (the linear law against
gran/hooke/history; --dim 3: spheres). Per repetition and N, interleaved: bench_dem --threads 1,
bench_dem --threads T, LAMMPS serial, LAMMPS on T MPI ranks (`mpirun -np T`); Debian 12's LAMMPS
has no OPENMP package, so LAMMPS on threads is not measured. All rates are particle-steps per WALL second (a
threaded run's CPU time is not its cost). The packings are prepared with --threads T (the same
packing as with one: the DEM's results do not depend on the thread count). Writes
OUT/NAME.md and OUT/NAME.csv; measure on an idle machine (the load averages are recorded).
"""
import argparse
import csv
import importlib.util
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("dem_vs_lammps", HERE / "dem_vs_lammps.py")
DVL = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(DVL)


def run_bench(binary, dim, n, threads, a, cache):
    p = subprocess.run([str(binary), "--dim", str(dim), "--n", str(n), "--models", "linear", "--psteps", str(a.psteps),
                        "--warmup", str(a.warmup), "--cache", cache, "--threads", str(threads)],
                       check=True, capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    d = next(csv.DictReader(p.stdout.splitlines()))
    return dict(steps=int(d["steps"]), wall_s=float(d["wall_s"]), rate=float(d["psteps_per_wall_s"]),
                contacts=float(d["contacts_per_particle"]))


def run_lammps(a, work, infile, data, n, steps, mode, threads):
    log = work / f"lammps_{mode}_N{n}.log"
    cmd = [a.lammps, "-in", infile, "-var", "data", data, "-var", "nsteps", str(steps), "-var", "nwarm",
           str(a.warmup), "-log", str(log), "-screen", "none"]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    if mode == "mpi":
        cmd = ["mpirun", "-np", str(threads), "--oversubscribe", "--allow-run-as-root", "--bind-to", "none"] + cmd
    subprocess.run(cmd, cwd=work, check=True, env=env, stdout=subprocess.DEVNULL)
    r = DVL.parse_lammps(log)
    return dict(steps=r["steps"], wall_s=r["wall"], rate=n * r["steps"] / r["wall"], contacts=r.get("Z", ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=str(HERE.parent / "build" / "bench" / "bench_dem"))
    ap.add_argument("--dim", type=int, default=2, choices=[2, 3])
    ap.add_argument("--n", default=None, help="default 30000 (3D: 100000)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--psteps", type=float, default=None, help="default 3e7 (3D 2e7)")
    ap.add_argument("--warmup", type=int, default=None, help="default 1000 (3D 300)")
    ap.add_argument("--cache", default="", help="packing cache (default: dem_packings/ next to --bench)")
    ap.add_argument("--lammps", default="lmp")
    ap.add_argument("--params", default=str(DVL.SHARED / "params.in"))
    ap.add_argument("--workdir", default=os.path.join(tempfile.gettempdir(), "dem-threads"))
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--name", default=None, help="default dem_threads_2d / dem_threads_3d")
    a = ap.parse_args()
    d3 = a.dim == 3
    a.n = a.n or ("100000" if d3 else "30000")
    a.psteps = a.psteps or (2e7 if d3 else 3e7)
    a.warmup = a.warmup if a.warmup is not None else (300 if d3 else 1000)
    a.name = a.name or f"dem_threads_{a.dim}d"
    ns = [int(x) for x in a.n.split(",")]
    work = Path(a.workdir)
    work.mkdir(parents=True, exist_ok=True)
    bench = work / "bench_dem"
    shutil.copy2(a.bench, bench)
    cache = a.cache or str(Path(a.bench).resolve().parent / "dem_packings")
    shutil.copy2(a.params, work / "params.in")
    infile = "bench_lammps3d.in" if d3 else "bench_lammps.in"
    (work / infile).write_text(DVL.LAMMPS_IN3 if d3 else DVL.LAMMPS_IN)
    t0 = time.time()
    subprocess.run([str(bench), "--dim", str(a.dim), "--n", a.n, "--models", "none", "--cache", cache, "--lammps-data",
                    str(work), "--threads", str(a.threads)], check=True, stdout=subprocess.DEVNULL)
    print(f"packings ready ({time.time() - t0:.0f} s, {a.threads} threads)", file=sys.stderr)
    rows = []
    codes = [("netdem_1", None), (f"netdem_{a.threads}", None), ("lammps_1", "serial"),
             (f"lammps_mpi_{a.threads}", "mpi")]
    for rep in range(1, a.reps + 1):
        for n in ns:
            steps = max(200, int(a.psteps / n))
            data = f"pack3d_N{n}.data" if d3 else f"pack_N{n}.data"
            for code, mode in codes:
                la0 = DVL.loadavg()
                if mode is None:
                    r = run_bench(bench, a.dim, n, 1 if code == "netdem_1" else a.threads, a, cache)
                else:
                    r = run_lammps(a, work, infile, data, n, steps, mode, a.threads)
                rows.append(dict(code=code, N=n, rep=rep, load_before=la0, load_after=DVL.loadavg(), **r))
                print(f"rep {rep} N={n} {code}: {r['rate'] / 1e6:.3f} Mp-steps/wall-s", file=sys.stderr)
    out = DVL.write_rows(a.out, a.name, rows)

    def rates(code, n):
        return [r["rate"] for r in rows if r["code"] == code and r["N"] == n]

    def per_rep_ratio(num, den, n):
        return [x / y for x, y in zip(rates(num, n), rates(den, n))]

    T = a.threads
    lines = [f"| N | netdem 1 thread | netdem {T} threads | **netdem {T} / 1** (per repetition) | LAMMPS serial | "
             f"LAMMPS {T} MPI ranks | LAMMPS {T} / 1 | netdem 1 / LAMMPS 1 | netdem {T} / LAMMPS {T} |",
             "|---|---|---|---|---|---|---|---|---|"]
    for n in ns:
        med = {c: statistics.median(rates(c, n)) for c, _ in codes}
        sp = per_rep_ratio(f"netdem_{T}", "netdem_1", n)
        lines.append(f"| {n} | {med['netdem_1'] / 1e6:.2f} | {med[f'netdem_{T}'] / 1e6:.2f} | "
                     f"**{statistics.median(sp):.2f}** ({', '.join(f'{x:.2f}' for x in sp)}) | "
                     f"{med['lammps_1'] / 1e6:.2f} | {med[f'lammps_mpi_{T}'] / 1e6:.2f} | "
                     f"{med[f'lammps_mpi_{T}'] / med['lammps_1']:.2f} | {med['netdem_1'] / med['lammps_1']:.2f} | "
                     f"{med[f'netdem_{T}'] / med[f'lammps_mpi_{T}']:.2f} |")
    cpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = next((ln.split(":", 1)[1].strip() for ln in cpu.splitlines() if ln.startswith("Model name")), "?")
    loads = sorted({r["load_before"] for r in rows} | {r["load_after"] for r in rows})
    md = [f"# netdem's DEM on {T} threads ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())})", "",
          f"Machine: {os.cpu_count()} cores, {model}; load averages seen (1/5/15 min): {loads[0]} ... {loads[-1]}", "",
          f"Command: `/usr/bin/python3 bench/dem_threads.py {' '.join(DVL.shown(x) for x in sys.argv[1:])}`", "",
          f"{a.dim}D, the linear law; medians over {a.reps} interleaved repetitions, millions of particle-steps per "
          f"wall-clock second; timed runs of max(200, {a.psteps:.3g}/N) steps after {a.warmup} warm-up steps.", "",
          "\n".join(lines), ""]
    (out / f"{a.name}.md").write_text("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
