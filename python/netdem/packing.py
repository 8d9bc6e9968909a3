"""Packings as numpy arrays: make one (`deposit`, as `netsolve pack`), read and write packing
files (`id,x,y[,z],r` with '# box', docs/packing.md) with the library's reader and writer."""
import os

import numpy as np

from . import _netdem


class Packing:
    """Disks (dim 2) or spheres (dim 3): x, y, z (None in 2D), r as numpy arrays; box (x_min,
    y_min, x_max, y_max), in 3D (x_min, y_min, z_min, x_max, y_max, z_max); seed (0: unknown);
    periodic and cell ('# periodic', '# cell'); comments (the other '# ...' lines)."""

    def __init__(self, x, y, r, box, z=None, dim=None, seed=0, comments=(), periodic=False, cell=()):
        self.x = np.asarray(x, dtype=np.float64)
        self.y = np.asarray(y, dtype=np.float64)
        self.z = None if z is None else np.asarray(z, dtype=np.float64)
        self.r = np.asarray(r, dtype=np.float64)
        self.dim = dim if dim is not None else (2 if z is None else 3)
        self.box = tuple(float(b) for b in box)
        self.seed = int(seed)
        self.comments = list(comments)
        self.periodic = bool(periodic)
        self.cell = np.asarray(cell, dtype=np.float64)

    def __len__(self):
        return len(self.r)

    def __repr__(self):
        return f"Packing({len(self)} {'spheres' if self.dim == 3 else 'disks'}, box={self.box})"


def read(path):
    """The packing of a packing CSV file (ValueError with the reader's message if it is refused)."""
    d = _netdem.read_packing(os.fspath(path))
    return Packing(d["x"], d["y"], d["r"], d["box"], z=d["z"], dim=d["dim"], seed=d["seed"], comments=d["comments"],
                   periodic=d["periodic"], cell=d["cell"])


def write(p, path):
    """Writes Packing `p` as a packing CSV file (every number to 17 digits: read() gives it back)."""
    _netdem.write_packing({"x": p.x, "y": p.y, "z": p.z, "r": p.r, "dim": p.dim, "box": p.box, "seed": p.seed,
                           "comments": p.comments, "periodic": p.periodic, "cell": p.cell}, os.fspath(path))


def deposit(**options):
    """A new packing by `netsolve pack` with these options (width=80, r_min=0.9, r_max=1.1, seed=1,
    dim=2, ...: `netsolve pack --help`), run in a temporary folder; the Packing of its packing.csv."""
    from . import netsolve
    return netsolve.pack(**options).packing
