#!/usr/bin/python3
"""demsolve (netdem::dem::DynamicSolver) against LAMMPS gran/hooke/history on the same packing.

Issue #4: particle-steps per CPU-second on a dense, jammed, polydisperse, frictional 2D packing of
N = 300, 3000, 30000 disks, one core, side by side with Debian's LAMMPS (`lmp`, pair style
gran/hooke/history) on the same packing and the same physics (linear spring-dashpot with
tangential history: Luding's law with k1 = k2, k_c = 0, constant T).

    /usr/bin/python3 bench/dem_vs_lammps.py [--bench build-bench/bench/bench_dem] [--n 300,3000,30000]
        [--psteps 3e7] [--reps 3] [--warmup 1000] [--workdir /tmp/dem-vs-lammps] [--out bench/results]

1. `bench_dem` (a private copy) prepares the packings (cached next to the binary in
   `dem_packings/`, see bench/bench_dem.cpp) and writes them as LAMMPS data files.
2. For each repetition and N (interleaved, so slow phases of a shared machine spread over all
   cases): LAMMPS on the data file, then bench_dem with the Linear and Full models.
   LAMMPS: the parameters are ../shared/bench/lammps/params.in (copied to the work folder, not
   modified); the input (written here) reads the data file, sets m = rho pi r^2 h, uses
   `pair_style gran/hooke/history kn kt gamn gamt mu 1` as the shared bench.in and four frictionless
   walls `fix wall/gran hooke/history` at the box faces (boundary f f p: the demsolve walls), then
   runs `--warmup` untimed and max(200, psteps/N) timed steps. Its CPU time = "Loop time" x
   "% CPU use" (the shared REPORT.md found this within 1 % of /proc utime+stime).
   bench_dem: CPU time of its thread around the timed steps (same warm-up and step counts).
   --baseline BINARY: a second bench_dem (e.g. compiled against an older solver.cpp) timed right
   after the first, reported as "baseline" columns (docs/performance.md shows how it was built).
3. Prints the table (medians over the repetitions) and writes OUT/NAME.csv (every run) and
   OUT/NAME.md (the table, machine, load averages).

--dim 3 (issue 16): the same in 3D, spheres (bench_dem --dim 3; packing: a 3D ballistic
deposition, compressed and settled, see bench/bench_dem.cpp), defaults --n 10000,100000
--psteps 2e7 --warmup 300 --name dem_vs_lammps_3d. LAMMPS: `dimension 3`, `boundary f f f`,
mass = rho 4/3 pi r^3 (`set density`), `fix nve/sphere`, six frictionless `fix wall/gran` walls;
dt = t_c/50 and the mass-proportional damping gamn = gn/m12, gamt = gt/m12 of a pair of two a0
SPHERES (params.in's dt, gamn and gamt are those of the 2D disks and are not used).
The 2D mode's behaviour and outputs are unchanged.
"""
import argparse
import csv
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent


sys.path.insert(0, os.path.join(str(REPO), "apps", "scripts"))
from report_paths import shown_path  # noqa: E402


def shown(p):
    """A path for the report (apps/scripts/report_paths.py)."""
    return shown_path(p, REPO)
SHARED = REPO.parent / "shared" / "bench" / "lammps"

LAMMPS_IN = r"""# bench_lammps.in -- written by netdem bench/dem_vs_lammps.py: the demsolve scene in LAMMPS
# usage: lmp -in bench_lammps.in -var data pack_N3000.data -var nsteps 10000 -var nwarm 1000
include         params.in
variable        nsteps index 20000
variable        nwarm  index 1000
units           si
dimension       2
boundary        f f p
atom_style      sphere
atom_modify     map array
comm_modify     vel yes
read_data       ${data}
# mass = rho pi r^2 h as prep.in: a disc density per area of rho h
set             group all density/disc $(v_rho*v_h)
pair_style      gran/hooke/history ${kn} ${kt} ${gamn} ${gamt} ${mu} 1
pair_coeff      * *
# the four demsolve walls at the box faces, frictionless (mu_w = 0, Table 1)
fix             wx all wall/gran hooke/history ${kn} ${kt} ${gamn} ${gamt} 0.0 1 xplane $(xlo) $(xhi)
fix             wy all wall/gran hooke/history ${kn} ${kt} ${gamn} ${gamt} 0.0 1 yplane $(ylo) $(yhi)
neighbor        ${skin} bin
neigh_modify    delay 0 every 1 check yes
timestep        ${dt}
fix             nve all nve/sphere disc
fix             e2d all enforce2d
compute         pv all pressure NULL virial
compute         zc all contact/atom
compute         Z all reduce ave c_zc
thermo_style    custom step atoms c_pv c_Z ke cpu
thermo_modify   norm no
thermo          ${nwarm}
run             ${nwarm}
thermo          ${nsteps}
run             ${nsteps}
print           "BENCH N=$(atoms) steps=${nsteps} P=$(c_pv) Z=$(c_Z) KE=$(ke)"
"""

LAMMPS_IN3 = r"""# bench_lammps3d.in -- written by netdem bench/dem_vs_lammps.py --dim 3: the bench_dem 3D scene
# usage: lmp -in bench_lammps3d.in -var data pack3d_N10000.data -var nsteps 2000 -var nwarm 300
include         params.in
variable        nsteps index 2000
variable        nwarm  index 300
# 3D: spheres of mass rho 4/3 pi r^3; dt = t_c/50 and the mass-proportional damping of
# gran/hooke/history matched to gn, gt for a pair of two a0 spheres (params.in: the 2D disks)
variable        m0s    equal ${rho}*4.0/3.0*PI*${a0}^3
variable        m12s   equal ${m0s}/2.0
variable        eta0s  equal ${gn}/(2.0*${m12s})
variable        tcs    equal PI/sqrt(${kn}/${m12s}-${eta0s}^2)
variable        dts    equal ${tcs}/50.0
variable        gamns  equal ${gn}/${m12s}
variable        gamts  equal ${gt}/${m12s}
units           si
dimension       3
boundary        f f f
atom_style      sphere
atom_modify     map array
comm_modify     vel yes
read_data       ${data}
set             group all density ${rho}
pair_style      gran/hooke/history ${kn} ${kt} ${gamns} ${gamts} ${mu} 1
pair_coeff      * *
# the six bench_dem walls at the box faces, frictionless
fix             wx all wall/gran hooke/history ${kn} ${kt} ${gamns} ${gamts} 0.0 1 xplane $(xlo) $(xhi)
fix             wy all wall/gran hooke/history ${kn} ${kt} ${gamns} ${gamts} 0.0 1 yplane $(ylo) $(yhi)
fix             wz all wall/gran hooke/history ${kn} ${kt} ${gamns} ${gamts} 0.0 1 zplane $(zlo) $(zhi)
neighbor        ${skin} bin
neigh_modify    delay 0 every 1 check yes
timestep        ${dts}
fix             nve all nve/sphere
compute         pv all pressure NULL virial
compute         zc all contact/atom
compute         Z all reduce ave c_zc
thermo_style    custom step atoms c_pv c_Z ke cpu
thermo_modify   norm no
thermo          ${nwarm}
run             ${nwarm}
thermo          ${nsteps}
run             ${nsteps}
print           "BENCH N=$(atoms) steps=${nsteps} P=$(c_pv) Z=$(c_Z) KE=$(ke) dt=${dts}"
"""

LOOP = re.compile(r"^Loop time of ([\d.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")
CPU = re.compile(r"^([\d.]+)% CPU use")
BENCH = re.compile(r"^BENCH N=(\d+) steps=(\d+) P=(\S+) Z=(\S+) KE=(\S+)")
SECT = re.compile(r"^(Pair|Neigh|Comm|Modify|Other)\s*\|")
NEIGHS = re.compile(r"^Ave neighs/atom = ([\d.eE+-]+)")
NBUILDS = re.compile(r"^Neighbor list builds = (\d+)")


def write_rows(out_dir, name, rows):
    """OUT_DIR/NAME.csv with one line per run (the keys of the first row as the header); returns OUT_DIR."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / f"{name}.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    return out


def loadavg():
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def parse_lammps(log):
    lines = Path(log).read_text(errors="replace").splitlines()
    idx = max(i for i, l in enumerate(lines) if LOOP.match(l))
    m = LOOP.match(lines[idx])
    r = dict(wall=float(m.group(1)), steps=int(m.group(3)), N=int(m.group(4)), cpu_pct=100.0)
    for l in lines[idx + 1:]:
        if (c := CPU.match(l)):
            r["cpu_pct"] = float(c.group(1))
        if SECT.match(l):
            parts = [p.strip() for p in l.split("|")]
            r["sec_" + parts[0]] = float(parts[2]) if parts[2] else 0.0
        if (b := BENCH.match(l)):
            r.update(P=float(b.group(3)), Z=float(b.group(4)), KE=float(b.group(5)))
        if (nb := NEIGHS.match(l)):
            r["neighs"] = float(nb.group(1))
        if (nb := NBUILDS.match(l)):
            r["nbuilds"] = int(nb.group(1))
    r["cpu"] = r["wall"] * r["cpu_pct"] / 100.0
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=str(REPO / "build-bench" / "bench" / "bench_dem"))
    ap.add_argument("--cache", default="", help="packing cache (default: dem_packings/ next to --bench)")
    ap.add_argument("--lammps", default="lmp")
    ap.add_argument("--params", default=str(SHARED / "params.in"), help="the shared LAMMPS parameters")
    ap.add_argument("--dim", type=int, default=2, choices=[2, 3], help="2: disks (issue 4); 3: spheres (issue 16)")
    ap.add_argument("--n", default=None, help="default 300,3000,30000 (--dim 3: 10000,100000)")
    ap.add_argument("--psteps", type=float, default=None, help="particle-steps per timed run (default 3e7; 3D 2e7)")
    ap.add_argument("--warmup", type=int, default=None, help="default 1000 (3D: 300)")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--models", default="linear,full", help="bench_dem models (linear,full,full_linparams)")
    ap.add_argument("--baseline", default="", help="another bench_dem binary (e.g. built from an older solver) timed "
                    "the same way, reported as 'baseline' columns")
    ap.add_argument("--workdir", default=os.path.join(tempfile.gettempdir(), "dem-vs-lammps"))
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--name", default=None, help="default dem_vs_lammps (3D: dem_vs_lammps_3d)")
    a = ap.parse_args()
    d3 = a.dim == 3
    if a.n is None:
        a.n = "10000,100000" if d3 else "300,3000,30000"
    if a.psteps is None:
        a.psteps = 2e7 if d3 else 3e7
    if a.warmup is None:
        a.warmup = 300 if d3 else 1000
    if a.name is None:
        a.name = "dem_vs_lammps_3d" if d3 else "dem_vs_lammps"
    if d3:
        return main3(a)

    ns = [int(x) for x in a.n.split(",")]
    models = a.models.split(",")
    work = Path(a.workdir)
    work.mkdir(parents=True, exist_ok=True)
    bench = work / "bench_dem"
    shutil.copy2(a.bench, bench)  # rebuilding meanwhile is harmless
    benches = [("demsolve_", bench)]
    if a.baseline:
        shutil.copy2(a.baseline, work / "bench_dem_baseline")
        benches.append(("baseline_", work / "bench_dem_baseline"))
    cache = a.cache or str(Path(a.bench).resolve().parent / "dem_packings")
    shutil.copy2(a.params, work / "params.in")
    (work / "bench_lammps.in").write_text(LAMMPS_IN)
    env = dict(os.environ, OMP_NUM_THREADS="1")

    # 1) packings (untimed; cached) and the LAMMPS data files
    t0 = time.time()
    subprocess.run([str(bench), "--n", a.n, "--models", "none", "--cache", cache, "--lammps-data", str(work)],
                   check=True, stdout=subprocess.DEVNULL, env=env)
    print(f"packings ready ({time.time() - t0:.0f} s)", file=sys.stderr)

    rows = []
    for rep in range(1, a.reps + 1):
        for n in ns:
            steps = max(200, int(a.psteps / n))
            # LAMMPS
            log = work / f"lammps_N{n}_r{rep}.log"
            la0 = loadavg()
            subprocess.run([a.lammps, "-in", "bench_lammps.in", "-var", "data", f"pack_N{n}.data", "-var", "nsteps",
                            str(steps), "-var", "nwarm", str(a.warmup), "-log", str(log), "-screen", "none"],
                           cwd=work, check=True, env=env)
            r = parse_lammps(log)
            rows.append(dict(code="lammps_hooke_history", N=n, rep=rep, steps=r["steps"], cpu_s=r["cpu"],
                             wall_s=r["wall"], psteps_per_cpu_s=n * r["steps"] / r["cpu"],
                             psteps_per_wall_s=n * r["steps"] / r["wall"], contacts_per_particle=r.get("Z", ""),
                             pressure=r.get("P", ""), load_before=la0, load_after=loadavg(),
                             note=f"pair {r.get('sec_Pair', 0):.3g} s, modify {r.get('sec_Modify', 0):.3g} s, "
                                  f"neigh {r.get('sec_Neigh', 0):.3g} s, {r['cpu_pct']:.1f}% CPU"))
            print(f"rep {rep} N={n} lammps: {rows[-1]['psteps_per_cpu_s']:.4g} p-steps/CPU-s", file=sys.stderr)
            for prefix, binary in benches:  # demsolve (and the baseline binary)
                la0 = loadavg()
                p = subprocess.run([str(binary), "--n", str(n), "--models", ",".join(models), "--psteps",
                                    str(a.psteps), "--warmup", str(a.warmup), "--cache", cache], check=True,
                                   capture_output=True, text=True, env=env)
                la1 = loadavg()
                for d in csv.DictReader(p.stdout.splitlines()):
                    rows.append(dict(code=prefix + d["model"], N=n, rep=rep, steps=int(d["steps"]),
                                     cpu_s=float(d["cpu_s"]), wall_s=float(d["wall_s"]),
                                     psteps_per_cpu_s=float(d["psteps_per_cpu_s"]),
                                     psteps_per_wall_s=float(d["psteps_per_wall_s"]),
                                     contacts_per_particle=float(d["contacts_per_particle"]),
                                     pressure=0.5 * (float(d["sxx_N_per_m"]) + float(d["syy_N_per_m"])),
                                     load_before=la0, load_after=la1,
                                     note=f"rebuilds {d['rebuilds']}, table/particle {d['table_per_particle']}, "
                                          f"nu {d['nu']}"))
                    print(f"rep {rep} N={n} {prefix}{d['model']}: {float(d['psteps_per_cpu_s']):.4g} "
                          "p-steps/CPU-s", file=sys.stderr)

    out = write_rows(a.out, a.name, rows)

    def med(code, n):
        v = [r["psteps_per_cpu_s"] for r in rows if r["code"] == code and r["N"] == n]
        return statistics.median(v) if v else float("nan")

    def rng(code, n):
        v = [r["psteps_per_cpu_s"] for r in rows if r["code"] == code and r["N"] == n]
        return f"{min(v) / 1e6:.2f}-{max(v) / 1e6:.2f}" if v else ""

    has_full = "full" in models
    has_base = bool(a.baseline)
    head = ("| N | LAMMPS gran/hooke/history (Mp-steps/CPU-s) | demsolve Linear | ratio Linear/LAMMPS |"
            + (" demsolve Full (Table 1, 80 °C) |" if has_full else "")
            + (" baseline Linear | baseline Full |" if has_base else ""))
    sep = "|---|---|---|---|" + ("---|" if has_full else "") + ("---|---|" if has_base else "")
    lines = [head, sep]
    for n in ns:
        lm, li = med("lammps_hooke_history", n), med("demsolve_linear", n)
        line = (f"| {n} | {lm / 1e6:.2f} ({rng('lammps_hooke_history', n)}) | {li / 1e6:.2f} "
                f"({rng('demsolve_linear', n)}) | **{li / lm:.2f}** |")
        if has_full:
            line += f" {med('demsolve_full', n) / 1e6:.2f} ({rng('demsolve_full', n)}) |"
        if has_base:
            line += (f" {med('baseline_linear', n) / 1e6:.2f} ({rng('baseline_linear', n)}) |"
                     f" {med('baseline_full', n) / 1e6:.2f} ({rng('baseline_full', n)}) |")
        lines.append(line)
    table = "\n".join(lines)

    def first(code, n, key):
        v = [r[key] for r in rows if r["code"] == code and r["N"] == n and r[key] != ""]
        return statistics.median(v) if v else float("nan")

    check = ["| N | contacts/particle LAMMPS (walls excluded) | demsolve Linear (walls excluded) | LAMMPS virial "
             "pressure (walls excluded, N/m) | demsolve Linear contact stress (walls included, N/m) |",
             "|---|---|---|---|---|"]
    for n in ns:
        check.append(f"| {n} | {first('lammps_hooke_history', n, 'contacts_per_particle'):.3f} | "
                     f"{first('demsolve_linear', n, 'contacts_per_particle'):.3f} | "
                     f"{first('lammps_hooke_history', n, 'pressure'):.1f} | "
                     f"{first('demsolve_linear', n, 'pressure'):.1f} |")
    table += "\n\nScene check (end of the timed runs, medians):\n\n" + "\n".join(check)
    cpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = next((l.split(":", 1)[1].strip() for l in cpu.splitlines() if l.startswith("Model name")), "?")
    loads = sorted({r["load_before"] for r in rows} | {r["load_after"] for r in rows})
    md = [f"# demsolve vs LAMMPS ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())})", "",
          f"Machine: {os.cpu_count()} cores, {model}; load averages seen (1/5/15 min): "
          f"{loads[0]} ... {loads[-1]}", "",
          f"Command: `/usr/bin/python3 bench/dem_vs_lammps.py {' '.join(shown(x) for x in sys.argv[1:])}`", "",
          f"Median over {a.reps} repetitions (min-max in brackets), millions of particle-steps per CPU-second; "
          f"timed runs of max(200, {a.psteps:.3g}/N) steps after {a.warmup} warm-up steps.", "", table, ""]
    (out / f"{a.name}.md").write_text("\n".join(md))
    print("\n".join(md))



def main3(a):
    """--dim 3: the 3D benchmark (see the module docstring)."""
    ns = [int(x) for x in a.n.split(",")]
    models = a.models.split(",")
    work = Path(a.workdir)
    work.mkdir(parents=True, exist_ok=True)
    bench = work / "bench_dem"
    shutil.copy2(a.bench, bench)
    benches = [("demsolve_", bench)]
    if a.baseline:
        shutil.copy2(a.baseline, work / "bench_dem_baseline")
        benches.append(("baseline_", work / "bench_dem_baseline"))
    cache = a.cache or str(Path(a.bench).resolve().parent / "dem_packings")
    shutil.copy2(a.params, work / "params.in")
    (work / "bench_lammps3d.in").write_text(LAMMPS_IN3)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    uptime0 = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()

    t0 = time.time()
    subprocess.run([str(bench), "--dim", "3", "--n", a.n, "--models", "none", "--cache", cache, "--lammps-data",
                    str(work)], check=True, stdout=subprocess.DEVNULL, env=env)
    print(f"packings ready ({time.time() - t0:.0f} s)", file=sys.stderr)

    rows = []
    for rep in range(1, a.reps + 1):
        for n in ns:
            steps = max(200, int(a.psteps / n))
            log = work / f"lammps3d_N{n}_r{rep}.log"
            la0 = loadavg()
            subprocess.run([a.lammps, "-in", "bench_lammps3d.in", "-var", "data", f"pack3d_N{n}.data", "-var",
                            "nsteps", str(steps), "-var", "nwarm", str(a.warmup), "-log", str(log), "-screen",
                            "none"], cwd=work, check=True, env=env)
            r = parse_lammps(log)
            rows.append(dict(code="lammps_hooke_history", N=n, rep=rep, steps=r["steps"], cpu_s=r["cpu"],
                             wall_s=r["wall"], psteps_per_cpu_s=n * r["steps"] / r["cpu"],
                             psteps_per_wall_s=n * r["steps"] / r["wall"], contacts_per_particle=r.get("Z", ""),
                             pressure=r.get("P", ""), listed_per_particle=r.get("neighs", ""),
                             rebuilds=r.get("nbuilds", ""), ekin=r.get("KE", ""), load_before=la0,
                             load_after=loadavg(),
                             note=f"pair {r.get('sec_Pair', 0):.3g} s, modify {r.get('sec_Modify', 0):.3g} s, "
                                  f"neigh {r.get('sec_Neigh', 0):.3g} s, comm {r.get('sec_Comm', 0):.3g} s, "
                                  f"other {r.get('sec_Other', 0):.3g} s, {r['cpu_pct']:.1f}% CPU"))
            print(f"rep {rep} N={n} lammps: {rows[-1]['psteps_per_cpu_s']:.4g} p-steps/CPU-s", file=sys.stderr)
            for prefix, binary in benches:
                la0 = loadavg()
                p = subprocess.run([str(binary), "--dim", "3", "--n", str(n), "--models", ",".join(models),
                                    "--psteps", str(a.psteps), "--warmup", str(a.warmup), "--cache", cache],
                                   check=True, capture_output=True, text=True, env=env)
                la1 = loadavg()
                for d in csv.DictReader(p.stdout.splitlines()):
                    rows.append(dict(code=prefix + d["model"], N=n, rep=rep, steps=int(d["steps"]),
                                     cpu_s=float(d["cpu_s"]), wall_s=float(d["wall_s"]),
                                     psteps_per_cpu_s=float(d["psteps_per_cpu_s"]),
                                     psteps_per_wall_s=float(d["psteps_per_wall_s"]),
                                     contacts_per_particle=float(d["contacts_per_particle"]),
                                     pressure=(float(d["sxx_Pa"]) + float(d["syy_Pa"]) + float(d["szz_Pa"])) / 3.0,
                                     listed_per_particle=float(d["table_per_particle"]), rebuilds=int(d["rebuilds"]),
                                     ekin=float(d["ekin_J"]), load_before=la0, load_after=la1,
                                     note=f"wall contacts {d['wall_contacts']}, nu {d['nu']}"))
                    print(f"rep {rep} N={n} {prefix}{d['model']}: {float(d['psteps_per_cpu_s']):.4g} "
                          "p-steps/CPU-s", file=sys.stderr)
    uptime1 = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()

    out = write_rows(a.out, a.name, rows)

    def vals(code, n, key="psteps_per_cpu_s"):
        return [r[key] for r in rows if r["code"] == code and r["N"] == n and r[key] != ""]

    def med(code, n, key="psteps_per_cpu_s"):
        v = vals(code, n, key)
        return statistics.median(v) if v else float("nan")

    def cell(code, n):
        v = vals(code, n)
        return f"{statistics.median(v) / 1e6:.2f} ({min(v) / 1e6:.2f}-{max(v) / 1e6:.2f})" if v else ""

    def ratio(code, n):  # median of the per-repetition ratios (each against the LAMMPS run just before)
        rs = []
        for rep in range(1, a.reps + 1):
            lm = [r["psteps_per_cpu_s"] for r in rows if r["code"] == "lammps_hooke_history" and r["N"] == n
                  and r["rep"] == rep]
            us = [r["psteps_per_cpu_s"] for r in rows if r["code"] == code and r["N"] == n and r["rep"] == rep]
            if lm and us:
                rs.append(us[0] / lm[0])
        return statistics.median(rs) if rs else float("nan")

    has_full = "full" in models
    has_base = bool(a.baseline)
    head = ("| N | LAMMPS gran/hooke/history (Mp-steps/CPU-s) | netdem Linear | ratio Linear/LAMMPS (median of "
            "ratio of medians / of per-rep ratios) |" + (" netdem Full (Table 1, 80 °C) | ratio Full/LAMMPS |"
                                                         if has_full else "")
            + (" baseline Linear | ratio baseline Linear/LAMMPS |" if has_base else ""))
    lines = [head, "|---|---|---|---|" + ("---|---|" if has_full else "") + ("---|---|" if has_base else "")]
    for n in ns:
        lm = med("lammps_hooke_history", n)
        line = (f"| {n} | {cell('lammps_hooke_history', n)} | {cell('demsolve_linear', n)} | "
                f"**{med('demsolve_linear', n) / lm:.2f}** / {ratio('demsolve_linear', n):.2f} |")
        if has_full:
            line += f" {cell('demsolve_full', n)} | {med('demsolve_full', n) / lm:.2f} |"
        if has_base:
            line += f" {cell('baseline_linear', n)} | {med('baseline_linear', n) / lm:.2f} |"
        lines.append(line)
    table = "\n".join(lines)
    check = ["| N | contacts/particle LAMMPS (pairs) | netdem Linear (pairs) | listed pairs/particle LAMMPS "
             "(half list) | netdem Linear (Verlet table) | list builds in timed run LAMMPS / netdem | LAMMPS virial "
             "pressure (pairs, Pa) | netdem Linear contact stress (pairs + walls, Pa) | KE at end LAMMPS / netdem (J) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for n in ns:
        L, D = "lammps_hooke_history", "demsolve_linear"
        check.append(f"| {n} | {med(L, n, 'contacts_per_particle'):.3f} | {med(D, n, 'contacts_per_particle'):.3f} | "
                     f"{med(L, n, 'listed_per_particle'):.2f} | {med(D, n, 'listed_per_particle'):.2f} | "
                     f"{med(L, n, 'rebuilds'):.0f} / {med(D, n, 'rebuilds'):.0f} | "
                     f"{med(L, n, 'pressure'):.4g} | {med(D, n, 'pressure'):.4g} | "
                     f"{med(L, n, 'ekin'):.2e} / {med(D, n, 'ekin'):.2e} |")
    table += "\n\nScene check (end of the timed runs, medians over the repetitions):\n\n" + "\n".join(check)
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    keep = ("Architecture", "CPU(s)", "Model name", "Thread(s) per core", "Core(s) per socket", "Socket(s)",
            "L1d cache", "L2 cache", "L3 cache", "Hypervisor vendor", "Virtualization type")
    lscpu_short = "\n".join(l for l in lscpu.splitlines() if l.split(":")[0].strip() in keep)
    lmp_ver = ""
    logs = sorted(work.glob("lammps3d_N*_r1.log"))
    if logs:
        lmp_ver = Path(logs[0]).read_text(errors="replace").splitlines()[0]
    md = [f"# netdem DynamicSolver3 vs LAMMPS in 3D ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())})", "",
          f"Command: `/usr/bin/python3 bench/dem_vs_lammps.py {' '.join(shown(x) for x in sys.argv[1:])}`", "",
          f"LAMMPS: `{a.lammps}` ({lmp_ver}), `pair_style gran/hooke/history`, one process, OMP_NUM_THREADS=1; "
          "netdem: bench_dem --dim 3 (one thread).", "",
          f"Median over {a.reps} interleaved repetitions (per repetition and N: LAMMPS, then netdem Linear and Full "
          f"in one process), min-max in brackets, millions of particle-steps per CPU-second; timed runs of "
          f"max(200, {a.psteps:.3g}/N) steps after {a.warmup} untimed warm-up steps from the same packing at rest "
          "(fresh tangential histories in both codes).", "",
          "**Load:** the machine has 2 cores and was shared: other engineers compiled on the other core during this "
          "run (CPU time, not wall time, is the measure; LAMMPS: Loop time x % CPU).", "",
          f"- `uptime` before: `{uptime0}`", f"- `uptime` after: `{uptime1}`",
          f"- 1/5/15-min load averages seen at the starts/ends of the runs: "
          f"{min(r['load_before'] for r in rows)} ... {max(r['load_after'] for r in rows)}", "",
          table, "", "Machine (`lscpu`, abridged):", "", "```", lscpu_short, "```", ""]
    (out / f"{a.name}.md").write_text("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
