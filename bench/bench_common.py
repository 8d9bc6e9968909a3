"""Shared set-up of the netsolve benchmark scripts (time_vs_error, scaling)."""
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
ENV = dict(os.environ)


def add_common_args(ap, name, workdir):
    """Options every benchmark script has."""
    ap.add_argument("--netsolve", default=str(REPO / "build-bench" / "apps" / "netsolve"))
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--name", default=name, help="base name of the .csv and .png in --out")
    ap.add_argument("--workdir", default=workdir, help="run folders")
    ap.add_argument("--reuse", action="store_true", help="reuse run folders that already hold summary.json")
    ap.add_argument("--nice", type=int, default=5, help="nice level of the runs (-1: none)")
    ap.add_argument("--omp-thread-limit", type=int, default=0,
                    help="set OMP_THREAD_LIMIT for netsolve (CHOLMOD 3 runs 4 OpenMP threads in its supernodal "
                         "factorisation whatever OMP_NUM_THREADS says; 1 = truly serial). 0: inherit the environment")
    ap.add_argument("--extra", default="", help="extra netsolve compact arguments, space separated")


def setup(a):
    """Applies the common options: returns (workdir, private copy of netsolve, nice level or None)."""
    if a.omp_thread_limit > 0:
        ENV["OMP_THREAD_LIMIT"] = str(a.omp_thread_limit)
    workdir = Path(a.workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    netsolve = Path(tempfile.mkdtemp(prefix="netsolve-")) / "netsolve"
    shutil.copy2(a.netsolve, netsolve)  # later rebuilds must not change the binary under the runs
    return workdir, netsolve, (None if a.nice < 0 else a.nice)


def run_compact(netsolve, out, args, reuse, nice, label):
    """Runs `netsolve compact ARGS --out OUT` (unless reuse finds its summary) and returns
    (summary dict, process wall s, process CPU s), or None if netsolve failed."""
    summ = out / "summary.json"
    if not (reuse and summ.exists() and not (out / ".incomplete").exists()):
        # a coarse run is unconverged on purpose (time vs error): --allow-unconverged keeps exit 0,
        # summary.json keeps the status; a rerun replaces the old run's files (--overwrite)
        held = any((out / f).exists() for f in ("command.txt", "summary.json", ".incomplete"))
        cmd = ([] if nice is None else ["nice", "-n", str(nice)]) + [
            str(netsolve), "compact"] + args + ["--snapshots", "", "--quiet", "--allow-unconverged"] + (
            ["--overwrite"] if held else []) + ["--out", str(out)]
        print("  " + " ".join(cmd), flush=True)
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=ENV)
        t_proc = time.perf_counter() - t0
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
        if p.returncode != 0:
            print(f"  {label}: netsolve failed ({p.returncode}) after {t_proc:.1f} s: {p.stderr.strip()[-300:]}",
                  file=sys.stderr)
            return None
        (out / "process_wall_s.txt").write_text(f"{t_proc:.4f}\n")
        (out / "process_cpu_s.txt").write_text(f"{cpu:.4f}\n")

    def read(name):
        f = out / name
        return float(f.read_text()) if f.exists() else float("nan")

    return json.loads(summ.read_text()), read("process_wall_s.txt"), read("process_cpu_s.txt")


def write_rows_csv(out, name, cols, rows):
    """Writes rows (dicts) as <out>/<name>.csv with the header cols (floats to 6 digits)."""
    import csv
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / f"{name}.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            w.writerow([f"{r[c]:.6g}" if isinstance(r[c], float) else r[c] for c in cols])
    print("wrote", out / f"{name}.csv")
    return out


def pyplot():
    """matplotlib.pyplot with the Agg backend, or None (with a message) if matplotlib is missing."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not available: no plot", file=sys.stderr)
        return None
    return plt


def finish_plot(fig, ax, out, name):
    """Legend, log grid, tight layout; saves <out>/<name>.png."""
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(Path(out) / f"{name}.png", dpi=130)
    print("wrote", Path(out) / f"{name}.png")
