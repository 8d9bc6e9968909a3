#!/usr/bin/python3
"""Picture of a 3D packing file (`netsolve pack --dim 3`): the spheres seen from an oblique
direction, drawn back to front as shaded discs (an orthographic projection keeps a sphere's outline
a circle of its radius), coloured by height.

    /usr/bin/python3 apps/scripts/plot_packing3d.py PACKING.csv OUT.png [--azimuth 35] [--elevation 25]
"""
import argparse
import csv
import math
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402


def read_packing3d(path):
    box, dim, rows = None, 2, []
    with open(path, newline="") as f:
        lines = [l for l in f if l.strip()]
    body = []
    for l in lines:
        if l.startswith("#"):
            w = l[1:].split()
            if w and w[0] == "box":
                box = [float(v) for v in w[1:]]
            elif w and w[0] == "dim":
                dim = int(w[1])
        else:
            body.append(l)
    if dim != 3 or box is None or len(box) != 6:
        sys.exit(f"{path}: not a 3D packing file (needs '# dim 3' and a 6-number box line)")
    for r in csv.DictReader(body):
        rows.append((float(r["x"]), float(r["y"]), float(r["z"]), float(r["r"])))
    return np.array(rows), box


def draw(P, box, out, azimuth=35.0, elevation=25.0, title=None):
    """The picture of the spheres P (rows x, y, z, r) in box [x0, y0, z0, x1, y1, z1] into out (PNG);
    title: the plot's title (default: the count, the box and the density)."""
    az, el = math.radians(azimuth), math.radians(elevation)
    # view basis: d points from the scene to the viewer; u (right) and v (up) span the screen
    d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    u = np.cross([0.0, 0.0, 1.0], d)
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    X = P[:, :3]
    sx, sy, depth = X @ u, X @ v, X @ d
    order = np.argsort(depth)  # far first
    zmin, zmax = box[2], box[5]
    cmap = plt.get_cmap("viridis")
    fig, ax = plt.subplots(figsize=(7, 6.5), dpi=130)
    for k in order:
        x, y, r = sx[k], sy[k], P[k, 3]
        c = np.array(cmap((P[k, 2] - zmin) / max(zmax - zmin, 1e-12))[:3])
        ax.add_patch(Circle((x, y), r, facecolor=0.55 * c, edgecolor="none"))
        # a highlight towards the light (upper left): two smaller, lighter discs
        ax.add_patch(Circle((x - 0.15 * r, y + 0.15 * r), 0.78 * r, facecolor=0.8 * c, edgecolor="none"))
        ax.add_patch(Circle((x - 0.3 * r, y + 0.3 * r), 0.45 * r, facecolor=np.minimum(1.0, 0.4 + 0.8 * c),
                            edgecolor="none"))
    # the box edges
    xs, ys, zs = (box[0], box[3]), (box[1], box[4]), (box[2], box[5])
    corners = np.array([[x, y, z] for x in xs for y in ys for z in zs])
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(corners[i] != corners[j]) == 1:
                p, q = corners[i], corners[j]
                ax.plot([p @ u, q @ u], [p @ v, q @ v], color="0.6", lw=0.6, zorder=0)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.axis("off")
    n = len(P)
    dens = np.sum(4.0 / 3.0 * np.pi * P[:, 3] ** 3) / ((box[3] - box[0]) * (box[4] - box[1]) * (box[5] - box[2]))
    if title is None:
        title = (f"{n} spheres, box {box[3] - box[0]:g} x {box[4] - box[1]:g} x {box[5] - box[2]:g}, "
                 f"density {dens:.3f} (colour: height)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("packing")
    ap.add_argument("out")
    ap.add_argument("--azimuth", type=float, default=35.0, help="view direction about z [deg]")
    ap.add_argument("--elevation", type=float, default=25.0, help="view elevation above the x-y plane [deg]")
    a = ap.parse_args()
    P, box = read_packing3d(a.packing)
    draw(P, box, a.out, a.azimuth, a.elevation)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
