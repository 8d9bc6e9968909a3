"""netdem.packing: the deposition of netsolve pack, and packing files round trip exactly."""
import numpy as np
import pytest

import netdem
from conftest import run_cli


def same(a, b):
    assert a.dim == b.dim and len(a) == len(b) and a.box == b.box and a.seed == b.seed
    for k in ("x", "y", "r") + (("z",) if a.dim == 3 else ()):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert a.periodic == b.periodic and a.comments == b.comments and np.array_equal(a.cell, b.cell)


def test_deposit_equals_netsolve_pack(tmp):
    code, _ = run_cli("netsolve", ["pack", "--width", "20", "--seed", "7", "--out", f"{tmp}/cli"])
    assert code == 0
    p = netdem.packing.deposit(width=20, seed=7)
    same(netdem.packing.read(f"{tmp}/cli/packing.csv"), p)
    assert p.dim == 2 and p.z is None and p.seed == 7 and len(p) > 50
    assert np.all((p.r >= 0.9) & (p.r <= 1.1))


@pytest.mark.parametrize("options", [{"width": 20, "r_min": 0.5, "r_max": 1.5}, {"dim": 3, "width": 6}])
def test_write_then_read_is_exact(tmp, options):
    p = netdem.packing.deposit(**options)
    netdem.packing.write(p, f"{tmp}/p.csv")
    q = netdem.packing.read(f"{tmp}/p.csv")
    same(p, q)
    # numbers the deposition does not make: every bit of them too
    rng = np.random.default_rng(3)
    p.x = p.x + rng.standard_normal(len(p)) * 1e-9
    p.r = p.r * (1 + 1e-15)
    netdem.packing.write(p, f"{tmp}/p2.csv")
    same(p, netdem.packing.read(f"{tmp}/p2.csv"))


def test_bad_packings_raise(tmp):
    p = netdem.packing.deposit(width=10)
    p.r = p.r[:-1]
    with pytest.raises(ValueError, match="same length"):
        netdem.packing.write(p, f"{tmp}/bad.csv")
    with open(f"{tmp}/broken.csv", "w") as f:
        f.write("id,x,y,r\n0,1,2,notanumber\n")
    with pytest.raises(ValueError, match="broken.csv"):
        netdem.packing.read(f"{tmp}/broken.csv")
    code, err = run_cli("netsolve", ["pack", "--width", "0", "--out", f"{tmp}/cli"])
    with pytest.raises(ValueError) as e:
        netdem.packing.deposit(width=0)
    assert code == 2 and str(e.value) == err.strip()
