#!/usr/bin/env python3
"""Study runner for the long-time sintering grid of Luding, Manetsberger & Muellers (2005), section 4.

usage: /usr/bin/python3 validation/luding_sintering/study.py
           [--quick | --subset] [--demsolve PATH] [--jobs N] [--runs DIR] [--force]
           [--print-commands] [--only SUBSTRING[,SUBSTRING...]] [--timeout S] [--list]

The grid (one folder per run under --runs, default validation/luding_sintering/runs):

* sinter    N in {100, 300}, p in {10, 100}, t_s in {1e-4, 0.01, 0.02, 0.05, 0.1, 1}, seed 1.
            Preparation and heating are identical for every t_s, so per (N, p) the t_s = 1e-4 run is
            made from scratch (`N{N}_p{p}_ts0.0001`) and every other t_s continues from its
            state_heat.txt with `demsolve sinter --state .../state_heat.txt --sinter-time TS`.
* check     `N100_p100_ts0.1_unbranched`: the same run as `N100_p100_ts0.1` without branching
            (the report compares the two state.txt files bit for bit).
* controls  three particles (`--n 3 --arrangement triangle|line`, p = 10 and 100, t_s = 1);
            no thermal expansion (`--param da_T=0`, N = 300, p = 100, t_s = 1);
            investigation (not a default): wall friction 0.5 during preparation (`--mu-wall 0.5`).
* tests     `demsolve compress` (bi-axial, section 4.4.1; strain rate 1/s to 0.1) and `demsolve vibrate`
            (section 4.4.3) on the final state (state_relax.txt) of every grid run; investigation:
            compress at 0.1/s to 0.06 (`*_compress_slow`); skipped with a note when the binary has
            no such subcommand yet.

--quick (= --subset): N = 100 only, t_s in {1e-4, 0.1, 1}; the controls with N = 100 instead of 300.
Quick runs share the folder names with the full grid, so the full grid reuses them.

A run is skipped when its folder already holds summary.json and a command.txt with the same
arguments (the path of the binary is not compared) and no run it depends on is newer; --force reruns
everything. Simulations run under `nice -n 10`, --jobs at a time (default: os.cpu_count()), in
dependency order. --print-commands prints one shell command per run (dependency order: every line
only needs the output of lines above it) instead of running, e.g. for a cluster job array.
Each run folder gets meta.json (return code, wall and CPU time, binary and its sha256) and run.log.
"""
import argparse
import concurrent.futures
import datetime
import hashlib
import json
import os
import shlex
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
DEFAULT_BIN = os.environ.get("DEMSOLVE", os.path.join(REPO, "build", "apps", "demsolve"))

GRID_N = (100, 300)
GRID_P = (10, 100)
GRID_TS = (1e-4, 0.01, 0.02, 0.05, 0.1, 1.0)
QUICK_N = (100,)
QUICK_TS = (1e-4, 0.1, 1.0)
BASE_TS = 1e-4  # the run made from scratch per (N, p); the other t_s branch from its state_heat.txt
COMPRESS = {"strain_rate": 1.0, "max_strain": 0.1}
# investigation: 10 times slower loading (the stress-controlled right wall, m_w = 0.01 kg, rings with a
# period of several ms, comparable with the time to reach eps = 0.005 at 1/s)
COMPRESS_SLOW = {"strain_rate": 0.1, "max_strain": 0.06}
VIBRATE = {"frequency": 100.0, "amplitude": 2e-4, "time": 0.1}
INVESTIGATION_MU_WALL = 0.5
INVESTIGATION_MU_PREPARE = 0.5  # particle friction during the preparation (issue 32; the paper: 0)
FINE_SAMPLES = 12000  # rows of the 0.1 ms runs (t = 0.3..1.5 s)
# issue 32: cool-down times against the walls' relaxation time tau_w = m_wall / gamma_wall (Eq 1)
COOL_SWEEP = (0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0)
COOL_LIGHT_WALL = 0.001  # m_wall of the second wall (tau_w = 5 ms against Table 1's 50 ms)
COOL_LIGHT_SWEEP = (0.001, 0.01, 0.1)


def cool_name(n, p, cool, m_wall=None):
    return sinter_name(n, p, 1.0, (f"_mw{m_wall:g}" if m_wall is not None else "") + f"_cool{cool:g}")


def ts_str(ts):
    return f"{ts:g}" if ts >= 1e-3 else f"{ts:.4f}".rstrip("0")


def sinter_name(n, p, ts, suffix=""):
    return f"N{n}_p{p:g}_ts{ts_str(ts)}{suffix}"


class Run:
    """One demsolve invocation: args excludes the binary and includes --out."""

    def __init__(self, name, kind, args, deps=(), info=None):
        self.name, self.kind, self.args, self.deps = name, kind, list(args), list(deps)
        self.info = dict(info or {})

    @property
    def dir(self):
        return self.args[self.args.index("--out") + 1]


def build_runs(runs_dir, quick=False, tests=("compress", "vibrate", "compress_slow")):
    """The study in dependency order (every run's dependencies come before it)."""
    runs_dir = os.path.abspath(runs_dir)
    ns = QUICK_N if quick else GRID_N
    tss = QUICK_TS if quick else GRID_TS
    ctl_n = 100 if quick else 300
    out = []

    def d(name):
        return os.path.join(runs_dir, name)

    grid = []
    for n in ns:
        for p in GRID_P:
            base = sinter_name(n, p, BASE_TS)
            out.append(Run(base, "sinter",
                           ["sinter", "--n", str(n), "--pressure", f"{p:g}", "--sinter-time", ts_str(BASE_TS),
                            "--out", d(base), "--quiet"],
                           info=dict(n=n, p=p, ts=BASE_TS, role="grid", base=base)))
            grid.append(out[-1])
            for ts in tss:
                if ts == BASE_TS:
                    continue
                name = sinter_name(n, p, ts)
                out.append(Run(name, "sinter",
                               ["sinter", "--state", os.path.join(d(base), "state_heat.txt"), "--sinter-time",
                                ts_str(ts), "--out", d(name), "--quiet"],
                               deps=[base], info=dict(n=n, p=p, ts=ts, role="grid", base=base)))
                grid.append(out[-1])
    # branching check: unbranched twin of a branched run
    name = sinter_name(100, 100, 0.1, "_unbranched")
    out.append(Run(name, "sinter", ["sinter", "--n", "100", "--pressure", "100", "--sinter-time", "0.1",
                                    "--out", d(name), "--quiet"],
                   info=dict(n=100, p=100, ts=0.1, role="check", twin=sinter_name(100, 100, 0.1))))
    # three-particle controls
    for arr in ("triangle", "line"):
        for p in GRID_P:
            name = f"N3_{arr}_p{p:g}_ts1"
            out.append(Run(name, "sinter", ["sinter", "--n", "3", "--arrangement", arr, "--pressure", f"{p:g}",
                                            "--sinter-time", "1", "--out", d(name), "--quiet"],
                           info=dict(n=3, p=p, ts=1.0, role="three", arrangement=arr)))
    # no thermal expansion
    name = sinter_name(ctl_n, 100, 1.0, "_daT0")
    out.append(Run(name, "sinter", ["sinter", "--n", str(ctl_n), "--pressure", "100", "--sinter-time", "1",
                                    "--param", "da_T=0", "--out", d(name), "--quiet"],
                   info=dict(n=ctl_n, p=100, ts=1.0, role="daT0", twin=sinter_name(ctl_n, 100, 1.0))))
    # investigation: wall friction during the preparation
    name = sinter_name(ctl_n, 100, 1.0, f"_muw{INVESTIGATION_MU_WALL:g}")
    out.append(Run(name, "sinter", ["sinter", "--n", str(ctl_n), "--pressure", "100", "--sinter-time", "1",
                                    "--mu-wall", f"{INVESTIGATION_MU_WALL:g}", "--out", d(name), "--quiet"],
                   info=dict(n=ctl_n, p=100, ts=1.0, role="investigation", twin=sinter_name(ctl_n, 100, 1.0),
                             what=f"mu_w = {INVESTIGATION_MU_WALL:g} during the preparation [investigation]")))
    # investigation (issue 32): particle friction during the preparation, both pressures
    for p in GRID_P:
        name = sinter_name(ctl_n, p, 1.0, f"_mup{INVESTIGATION_MU_PREPARE:g}")
        out.append(Run(name, "sinter", ["sinter", "--n", str(ctl_n), "--pressure", f"{p:g}", "--sinter-time", "1",
                                        "--mu-prepare", f"{INVESTIGATION_MU_PREPARE:g}", "--out", d(name), "--quiet"],
                       info=dict(n=ctl_n, p=p, ts=1.0, role="investigation", twin=sinter_name(ctl_n, p, 1.0),
                                 what=f"mu = {INVESTIGATION_MU_PREPARE:g} during the preparation [investigation]")))
    # issue 32: the sintering of the t_s = 1 runs again, sampled every 0.1 ms (12000 rows over
    # t = 0.3..1.5), branched from the grid's state_heat.txt (bit-identical to the unbranched run)
    for p in GRID_P:
        base = sinter_name(ctl_n, p, BASE_TS)
        name = sinter_name(ctl_n, p, 1.0, "_fine")
        out.append(Run(name, "sinter", ["sinter", "--state", os.path.join(d(base), "state_heat.txt"),
                                        "--sinter-time", "1", "--samples", str(FINE_SAMPLES), "--out", d(name),
                                        "--quiet"],
                       deps=[base], info=dict(n=ctl_n, p=p, ts=1.0, role="fine", twin=sinter_name(ctl_n, p, 1.0))))
    # issue 32: the cool-down time against the walls' relaxation time, from the reference's
    # state_sinter.txt (t = 1.3); the reference itself is the 0.1 s point of Table 1's wall
    for p in GRID_P:
        ref = sinter_name(ctl_n, p, 1.0)
        sweeps = [(None, c) for c in COOL_SWEEP if c != 0.1]
        if p == 100:
            sweeps += [(COOL_LIGHT_WALL, c) for c in COOL_LIGHT_SWEEP]
        for mw, c in sweeps:
            name = cool_name(ctl_n, p, c, mw)
            extra = ["--param", f"m_wall={mw:g}"] if mw is not None else []
            out.append(Run(name, "sinter", ["sinter", "--state", os.path.join(d(ref), "state_sinter.txt"),
                                            "--sinter-time", "1", "--cool-time", f"{c:g}", *extra, "--out", d(name),
                                            "--quiet"],
                           deps=[ref], info=dict(n=ctl_n, p=p, ts=1.0, role="coolsweep", twin=ref, cool=c,
                                                 m_wall=mw)))
    # experiments of issue 15 (t_s = 1): seeds, size, thermal expansion, footnote 5, wall creep,
    # the cooling stiffness update; the switches branch from the grid's state_heat.txt
    exp_n = ctl_n
    for p in GRID_P:
        for seed in (2, 3):
            name = sinter_name(exp_n, p, 1.0, f"_seed{seed}")
            out.append(Run(name, "sinter", ["sinter", "--n", str(exp_n), "--pressure", f"{p:g}", "--sinter-time", "1",
                                            "--seed", str(seed), "--out", d(name), "--quiet"],
                           info=dict(n=exp_n, p=p, ts=1.0, role="experiment", twin=sinter_name(exp_n, p, 1.0),
                                     what=f"seed {seed}")))
        if not quick:
            name = sinter_name(1000, p, 1.0)
            out.append(Run(name, "sinter", ["sinter", "--n", "1000", "--pressure", f"{p:g}", "--sinter-time", "1",
                                            "--out", d(name), "--quiet"],
                           info=dict(n=1000, p=p, ts=1.0, role="experiment", twin=sinter_name(exp_n, p, 1.0),
                                     what="N = 1000")))
        for tag, par, what in (("_daT0", "da_T=0", "da_T = 0 (no thermal expansion)"),
                               ("_daT2.5e-4", "da_T=2.5e-4", "da_T = 2.5e-4 (the text's '1 % over 80-120 C')")):
            name = sinter_name(exp_n, p, 1.0, tag)
            if any(r.name == name for r in out):
                out[[r.name for r in out].index(name)].info["what"] = what
                continue
            out.append(Run(name, "sinter", ["sinter", "--n", str(exp_n), "--pressure", f"{p:g}", "--sinter-time", "1",
                                            "--param", par, "--out", d(name), "--quiet"],
                           info=dict(n=exp_n, p=p, ts=1.0, role="experiment", twin=sinter_name(exp_n, p, 1.0),
                                     what=what)))
        base = sinter_name(exp_n, p, BASE_TS)
        for tag, par, what in (("_nofn5", "sliding_breaks_cohesion=0", "footnote 5 off (cohesion kept when sliding)"),
                               ("_wallcold", "wall_sintering=0", "wall contacts do not creep (cold k1)"),
                               ("_k2kept", "cooling_stiffness_update=0", "k2' kept on cooling (before issue 15)")):
            name = sinter_name(exp_n, p, 1.0, tag)
            out.append(Run(name, "sinter", ["sinter", "--state", os.path.join(d(base), "state_heat.txt"),
                                            "--sinter-time", "1", "--param", par, "--out", d(name), "--quiet"],
                           deps=[base], info=dict(n=exp_n, p=p, ts=1.0, role="experiment",
                                                  twin=sinter_name(exp_n, p, 1.0), what=what)))
        ref = sinter_name(exp_n, p, 1.0)
        for tag, cool, what in (("_quench", "0.001", "cool-down in 1 ms instead of 0.1 s (from the reference at t = 1.3)"),
                                ("_slowcool", "1", "cool-down in 1 s instead of 0.1 s (from the reference at t = 1.3)")):
            if tag == "_slowcool" and p != 100:
                continue
            name = sinter_name(exp_n, p, 1.0, tag)
            out.append(Run(name, "sinter", ["sinter", "--state", os.path.join(d(ref), "state_sinter.txt"),
                                            "--sinter-time", "1", "--cool-time", cool, "--out", d(name), "--quiet"],
                           deps=[ref], info=dict(n=exp_n, p=p, ts=1.0, role="experiment", twin=ref, what=what)))
        name = sinter_name(exp_n, p, 1.0, "_gw20")
        out.append(Run(name, "sinter", ["sinter", "--state", os.path.join(d(ref), "state_sinter.txt"),
                                        "--sinter-time", "1", "--param", "gamma_wall=20", "--out", d(name), "--quiet"],
                       deps=[ref], info=dict(n=exp_n, p=p, ts=1.0, role="experiment", twin=ref,
                                             what="wall damping 100 x (20 kg/s) during the cool-down")))
    # three-particle controls with wall contacts that do not creep
    for arr in ("triangle", "line"):
        for p in GRID_P:
            name = f"N3_{arr}_p{p:g}_ts1_wallcold"
            out.append(Run(name, "sinter", ["sinter", "--n", "3", "--arrangement", arr, "--pressure", f"{p:g}",
                                            "--sinter-time", "1", "--param", "wall_sintering=0", "--out", d(name),
                                            "--quiet"],
                           info=dict(n=3, p=p, ts=1.0, role="three_wallcold", arrangement=arr)))
    # material tests on the final states
    for g in grid:
        state = os.path.join(g.dir, "state_relax.txt")
        for role, par in (("compress", COMPRESS), ("compress_slow", COMPRESS_SLOW)):
            if role not in tests:
                continue
            name = f"{g.name}_{role}"
            out.append(Run(name, "compress",
                           ["compress", "--state", state, "--strain-rate", f"{par['strain_rate']:g}",
                            "--max-strain", f"{par['max_strain']:g}", "--out", d(name), "--quiet"],
                           deps=[g.name], info=dict(g.info, role=role, sample=g.name)))
        if "vibrate" in tests:
            name = g.name + "_vibrate"
            out.append(Run(name, "vibrate",
                           ["vibrate", "--state", state, "--frequency", f"{VIBRATE['frequency']:g}",
                            "--amplitude", f"{VIBRATE['amplitude']:g}", "--time", f"{VIBRATE['time']:g}",
                            "--out", d(name), "--quiet"],
                           deps=[g.name], info=dict(g.info, role="vibrate", sample=g.name)))
    return out


# ------------------------------------------------------------------------------------------ running
def available_subcommands(binary):
    """Subcommands listed by `demsolve --help`, and whether each accepts --quiet."""
    try:
        txt = subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return {}
    subs = {}
    in_subs = False
    for line in txt.splitlines():
        if line.strip().startswith("Subcommands"):
            in_subs = True
            continue
        if in_subs and line.strip():
            subs[line.split()[0]] = False
    for sc in list(subs):
        try:
            h = subprocess.run([binary, sc, "--help"], capture_output=True, text=True, timeout=30).stdout
            subs[sc] = "--quiet" in h
        except (OSError, subprocess.SubprocessError):
            pass
    return subs


def adapt_to_binary(runs, binary):
    """Drops tests the binary cannot run (returned as notes) and --quiet where a test does not accept it."""
    subs = available_subcommands(binary)
    kept, notes = [], []
    for r in runs:
        if r.kind != "sinter":
            if r.args[0] not in subs:
                notes.append(f"{r.name}: `demsolve {r.args[0]}` not available in {binary}")
                continue
            if not subs[r.args[0]] and "--quiet" in r.args:
                r.args.remove("--quiet")
        kept.append(r)
    return kept, notes


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def recorded_args(run_dir):
    p = os.path.join(run_dir, "command.txt")
    if not os.path.isfile(p):
        return None
    with open(p) as f:
        return [w for w in shlex.split(f.read().strip())[1:] if w != "--overwrite"]


def holds_run(run_dir):
    """True if run_dir holds a demsolve run's files (README.md, docs/dynamic.md 'Exit status')."""
    return any(os.path.exists(os.path.join(run_dir, f)) for f in ("command.txt", "summary.json", ".incomplete"))


def up_to_date(run, by_name):
    summ = os.path.join(run.dir, "summary.json")
    if not os.path.isfile(summ) or recorded_args(run.dir) != run.args:
        return False
    if os.path.exists(os.path.join(run.dir, ".incomplete")):  # a failed or killed run keeps it
        return False
    for dname in run.deps:
        if dname not in by_name:
            continue
        dsum = os.path.join(by_name[dname].dir, "summary.json")
        if not os.path.isfile(dsum) or os.path.getmtime(dsum) > os.path.getmtime(summ):
            return False
    return True


def run_one(run, binary, timeout):
    # a rerun replaces the old run's files: demsolve refuses a folder that holds another run unless
    # --overwrite, and then clears it first (so the log is written beside the folder until the end)
    rerun = ["--overwrite"] if holds_run(run.dir) else []
    os.makedirs(os.path.dirname(run.dir) or ".", exist_ok=True)
    cmd = ["nice", "-n", "10", binary] + run.args + rerun
    t0 = time.time()
    tmp_log = run.dir.rstrip("/") + ".run.log.tmp"
    with open(tmp_log, "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        killer = threading.Timer(timeout, proc.kill)
        killer.start()
        _, status, ru = os.wait4(proc.pid, 0)
        killer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.time() - t0
    rc = proc.returncode
    os.makedirs(run.dir, exist_ok=True)
    os.replace(tmp_log, os.path.join(run.dir, "run.log"))
    with open(os.path.join(run.dir, "run.log")) as f:
        out = f.read().strip()
    if rc == 0 and not os.path.isfile(os.path.join(run.dir, "command.txt")):
        with open(os.path.join(run.dir, "command.txt"), "w") as f:  # the binary did not record it
            f.write(shlex.join([binary] + run.args) + "\n")
    meta = {"returncode": rc, "wall_s": wall, "cpu_s": ru.ru_utime + ru.ru_stime, "output": out[-2000:],
            "command": shlex.join(cmd), "binary": os.path.abspath(binary), "binary_sha256": sha256(binary),
            "date": datetime.datetime.now().isoformat(timespec="seconds")}
    with open(os.path.join(run.dir, "meta.json"), "w") as f:
        json.dump(meta, f, indent=2)
    last = out.splitlines()[-1] if out else ""
    return rc == 0 and os.path.isfile(os.path.join(run.dir, "summary.json")), \
        f"rc={rc}, {wall:.1f} s wall, {meta['cpu_s']:.1f} s CPU: {last}"


def execute(runs, binary, jobs, force=False, timeout=7200, log=print):
    """Runs the study in dependency order, --jobs at a time. Returns {name: (ok, message)}."""
    by_name = {r.name: r for r in runs}
    pending = list(runs)
    result = {}
    running = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs)) as ex:
        while pending or running:
            progressed = True
            while progressed:
                progressed = False
                for r in list(pending):
                    bad = [dn for dn in r.deps if dn in result and not result[dn][0]]
                    if bad:
                        result[r.name] = (False, f"not run: {', '.join(bad)} failed")
                        log(f"  {r.name}: {result[r.name][1]}")
                        pending.remove(r)
                        progressed = True
                        continue
                    if not all(dn in result or dn not in by_name for dn in r.deps):
                        continue
                    if not force and up_to_date(r, by_name):
                        result[r.name] = (True, "skipped (up to date)")
                        pending.remove(r)
                        progressed = True
                        continue
                    if len(running) >= max(1, jobs):
                        break
                    log(f"  start {r.name}")
                    running[ex.submit(run_one, r, binary, timeout)] = r
                    pending.remove(r)
                    progressed = True
            if not running:
                if pending:  # unreachable dependencies
                    for r in pending:
                        result[r.name] = (False, "not run: unresolved dependency")
                    pending = []
                break
            done, _ = concurrent.futures.wait(list(running), return_when=concurrent.futures.FIRST_COMPLETED)
            for fut in done:
                r = running.pop(fut)
                try:
                    result[r.name] = fut.result()
                except Exception as e:  # noqa: BLE001
                    result[r.name] = (False, f"error: {e}")
                log(f"  {r.name}: {result[r.name][1]}")
    return result


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", "--subset", action="store_true", dest="quick",
                    help="N = 100, t_s in {1e-4, 0.1, 1} (development)")
    ap.add_argument("--demsolve", default=DEFAULT_BIN, help="the demsolve binary (default: build/apps/demsolve)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="simulations in parallel")
    ap.add_argument("--runs", default=os.path.join(HERE, "runs"), help="folder of the run folders")
    ap.add_argument("--force", action="store_true", help="rerun every run")
    ap.add_argument("--print-commands", action="store_true", help="print the commands instead of running")
    ap.add_argument("--only", default=None, help="comma-separated substrings: run only matching runs "
                                                 "(and nothing else; dependencies must exist)")
    ap.add_argument("--no-tests", action="store_true", help="skip compress and vibrate")
    ap.add_argument("--timeout", type=float, default=7200, help="per-run time limit in seconds")
    ap.add_argument("--list", action="store_true", help="list run names and exit")
    a = ap.parse_args(argv)
    runs = build_runs(a.runs, a.quick, tests=() if a.no_tests else ("compress", "vibrate", "compress_slow"))
    if a.print_commands:
        for r in runs:
            print(shlex.join([a.demsolve] + r.args))
        return 0
    if a.list:
        for r in runs:
            print(r.name, "<-", ",".join(r.deps) or "-")
        return 0
    if not os.access(a.demsolve, os.X_OK):
        print(f"study.py: no executable demsolve at {a.demsolve}", file=sys.stderr)
        return 2
    runs, notes = adapt_to_binary(runs, a.demsolve)
    for n in notes:
        print("  note:", n)
    if a.only:
        keys = a.only.split(",")
        runs = [r for r in runs if any(k in r.name for k in keys)]
    res = execute(runs, a.demsolve, a.jobs, a.force, a.timeout)
    bad = [n for n, (ok, _) in res.items() if not ok]
    print(f"study: {len(res) - len(bad)} of {len(res)} runs ok" + (f"; failed: {', '.join(bad)}" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
