#!/usr/bin/python3
"""How far the drag-regularised compaction is from the rate-independent limit (issue #2).

`netsolve compact` holds every increment with a viscous drag on the non-affine motion, defined
per unit strain (`--viscosity 0.01` at the reference increment `--viscosity-strain 3.57e-4`, the
increment of the 100-increment default run). Refining the increments converges to that fixed
regularised problem (bench/compaction_time_vs_error.py); this script measures what the drag
itself does: it lowers the drag per unit strain by factors of 3 (`--viscosity-strain` 3.57e-4,
1.19e-4, 3.97e-5, ...) and raises the number of increments by the same factor, so that every run
has the same drag per increment (and the same Newton behaviour). S22 at D = 0.85 against the
drag then shows the rate-independent limit (drag -> 0) and the default's distance from it.

Writes <out>/<name>.csv and <out>/<name>.png.

    /usr/bin/python3 bench/drag_regularisation.py --netsolve build/apps/netsolve --seeds 1,2,3 --levels 4
"""
import argparse
import shutil

from bench_common import add_common_args, finish_plot, pyplot, run_compact, setup, write_rows_csv

REF_STRAIN = 3.57e-4  # netsolve's default --viscosity-strain


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", default="1,2,3", help="comma list of deposition seeds")
    ap.add_argument("--levels", type=int, default=4, help="drag levels: 3.57e-4 / 3^k for k = 0 .. levels-1")
    ap.add_argument("--increments", type=int, default=100, help="increments at the default drag (x 3^k at level k)")
    add_common_args(ap, "drag_regularisation", "/tmp/netdem-bench/drag_regularisation")
    a = ap.parse_args()
    workdir, netsolve, nice = setup(a)
    extra = a.extra.split()
    seeds = [int(x) for x in a.seeds.split(",")]
    rows = []
    for seed in seeds:
        for k in range(a.levels):
            vs = REF_STRAIN / 3**k
            n = a.increments * 3**k
            out = workdir / f"seed{seed}_level{k}"
            args = ["--seed", str(seed), "--viscosity-strain", f"{vs:.6g}", "--increments", str(n)]
            res = run_compact(netsolve, out, args + extra, a.reuse, nice, f"seed {seed}, level {k}")
            if res is None:
                continue
            s, t_proc, cpu = res
            rows.append({"seed": seed, "level": k, "viscosity_strain": vs, "increments": n,
                         "drag_per_unit_strain": 0.01 * vs, "S22": s["final"]["S22"], "S11": s["final"]["S11"],
                         "Z": s["final"]["Z"], "unconverged_increments": s["solver"]["unconverged_increments"],
                         "newton_iterations": s["solver"]["newton_iterations"], "process_cpu_s": cpu})
            r = rows[-1]
            print(f"  seed {seed} viscosity-strain {vs:.3g} N {n}: S22 {r['S22']:.5f} Z {r['Z']:.3f} "
                  f"unconverged {r['unconverged_increments']}/{n} cpu {cpu:.1f} s", flush=True)
    shutil.rmtree(netsolve.parent, ignore_errors=True)
    for r in rows:
        base = next(q for q in rows if q["seed"] == r["seed"] and q["level"] == 0)
        r["S22_rel_default"] = r["S22"] / base["S22"]
    cols = ["seed", "level", "viscosity_strain", "increments", "S22", "S22_rel_default", "S11", "Z",
            "unconverged_increments", "newton_iterations", "process_cpu_s"]
    out = write_rows_csv(a.out, a.name, cols, rows)
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    for seed in seeds:
        rr = [r for r in rows if r["seed"] == seed]
        ax.semilogx([r["viscosity_strain"] for r in rr], [-r["S22"] for r in rr], "o-", label=f"seed {seed}")
    ax.axvline(REF_STRAIN, color="k", ls="--", lw=0.8)
    ax.text(REF_STRAIN, ax.get_ylim()[0], " default", rotation=90, va="bottom", fontsize=8)
    ax.set_xlabel("--viscosity-strain (drag per unit strain / (0.01 x mean stiffness))")
    ax.set_ylabel("$-\\Sigma_{22}/\\sigma_y$ at D = 0.85")
    ax.set_title("drag regularisation (W = 80R, sticking, hydrostatic; N x 3 per level)")
    finish_plot(fig, ax, out, a.name)


if __name__ == "__main__":
    main()
