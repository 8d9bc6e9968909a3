"""Reading a run into ParaView through a .pvd time series.

Every tool that writes snapshots writes snapshots.pvd beside them, a ParaView collection that
gives each snapshot's files their time and a part each. `netdem.netsolve.sinter`'s snapshots
(particles_K.vtp: the spheres with radius and displacement; bonds_K.vtp: the necks as lines) have
the time t; `netdem.netsolve.compact`'s (particles_TAG.vtp, contacts_TAG.vtp, cell_TAG.vtp with
--boundary periodic; TAG initial, D<density>, final) the relative density D; the demsolve
subcommands' the time t of their time series. This script sinters a small green body and compacts
a small packing, checks that each run's .pvd's files exist and parse at the times asked for, and
opens the sintering series with ParaView's Python (`paraview.simple`, e.g. under `pvpython`) when
it is importable: a screenshot of the last time step. Otherwise it prints how to open the file:
`paraview DIR/sinter/snapshots.pvd`, or File > Open in ParaView, then Apply; a "Point Gaussian" or
"Glyph" (sphere, scaled by "radius") representation draws the spheres (on the particles block:
Extract Block, or the block named "particles" of a compact run's series).

    PYTHONPATH=build/python /usr/bin/python3 examples/paraview_series.py [--small] [--out DIR]

--small: 60 spheres, 500 s, 4 snapshots, W = 24 R (about a second); default: 805 spheres, 5000 s,
10 snapshots, W = 80 R (10 s measured).
"""
import argparse
import os
import sys
import xml.etree.ElementTree as ET

import netdem


def pvd_datasets(pvd):
    """The (timestep, part, file path) of a .pvd collection, the paths made absolute."""
    root = ET.parse(pvd).getroot()
    base = os.path.dirname(os.path.abspath(pvd))
    return [(float(d.get("timestep")), int(d.get("part", 0)), os.path.join(base, d.get("file")))
            for d in root.iter("DataSet")]


def check_series(pvd, points=None):
    """Errors of a .pvd: no data sets, a missing or unreadable .vtp, a PolyData without points
    (or, for part 0, not `points` of them)."""
    errors = []
    datasets = pvd_datasets(pvd)
    if not datasets:
        errors.append(f"{pvd}: no data sets")
    for t, part, f in datasets:
        if not os.path.isfile(f):
            errors.append(f"{pvd}: t = {t}: {f} does not exist")
            continue
        piece = ET.parse(f).getroot().find("PolyData/Piece")
        n = int(piece.get("NumberOfPoints")) if piece is not None else 0
        if n == 0 or (part == 0 and points is not None and n != points):
            errors.append(f"{f}: {n} points")
    return errors


def show_in_paraview(pvd, png):
    try:
        import paraview.simple as pv
    except ImportError:
        print(f"paraview.simple is not importable here: open the series with\n    paraview {pvd}\n"
              "(File > Open, Apply; the time steps are the .pvd's; Glyph with a sphere scaled by 'radius'\n"
              f" draws the spheres), or run this script under ParaView's pvpython.")
        return
    reader = pv.PVDReader(FileName=pvd)
    view = pv.GetActiveViewOrCreate("RenderView")
    pv.Show(reader, view)
    view.ViewTime = reader.TimestepValues[-1] if reader.TimestepValues else 0.0
    pv.ResetCamera(view)
    pv.SaveScreenshot(png, view)
    print(f"paraview: {len(reader.TimestepValues)} time steps, wrote {png}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="small runs (the ctest run)")
    ap.add_argument("--out", default="results/examples/paraview_series", help="output folder")
    args = ap.parse_args()
    n, t_end, snaps, width = (60, 500.0, 4, 24) if args.small else (805, 5000.0, 10, 80)
    os.makedirs(args.out, exist_ok=True)
    errors = []

    # netsolve sinter: its own snapshots.pvd
    green = netdem.netsolve.pack(dim=3, route="green-body", n=n, target_density=0.5, quiet=True,
                                 out=os.path.join(args.out, "green"), overwrite=True)
    s = netdem.netsolve.sinter(packing=os.path.join(args.out, "green", "packing.csv"), time=t_end,
                               snapshots=snaps, quiet=True, out=os.path.join(args.out, "sinter"), overwrite=True)
    pvd = os.path.abspath(os.path.join(args.out, "sinter", "snapshots.pvd"))
    datasets = pvd_datasets(pvd)
    times = sorted({t for t, _, _ in datasets})
    print(f"{pvd}: {len(datasets)} files at {len(times)} times {times}")
    if green.status != "ok" or s.status != "ok":
        errors.append(f"statuses: green body {green.status}, sinter {s.status}")
    errors += check_series(pvd, points=n)
    if len(times) != snaps + 1 or times[-1] != t_end:
        errors.append(f"{len(times)} snapshot times ending at {times[-1]}, expected {snaps + 1} ending at {t_end}")

    # netsolve compact: its snapshots.pvd, the time being the relative density D
    asked = [0.82, 0.84, 0.85]
    c = netdem.netsolve.compact(width=width, snapshots=asked, quiet=True, out=os.path.join(args.out, "compact"),
                                overwrite=True)
    compact_pvd = os.path.abspath(os.path.join(args.out, "compact", "snapshots.pvd"))
    densities = sorted({t for t, _, _ in pvd_datasets(compact_pvd)})
    print(f"{compact_pvd}: {len(densities)} densities {densities}")
    # the start, then each density asked for at the first increment at or past it (the last is
    # the end of the run, so no separate final snapshot)
    if c.status != "ok" or len(densities) != len(asked) + 1 or \
            not all(d - 1e-9 <= t < d + 0.01 for d, t in zip(asked, densities[1:])):
        errors.append(f"compact: status {c.status}, densities {densities}, asked for {asked}")
    errors += check_series(compact_pvd, points=c.summary.get("particles"))

    show_in_paraview(pvd, os.path.join(args.out, "paraview.png"))
    for e in errors:
        print(f"check failed: {e}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
