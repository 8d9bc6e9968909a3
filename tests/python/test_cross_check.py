"""The two solvers on the same scene: netsolve's quasi-static network and the DEM's dynamics, in affine
motion (every centre follows the strain, the rotations are free), closed die, sticking friction, W = 20.

Redanz & Fleck's Figs 7-8 measure the tangential deviation from the affine field,
<|u_T - u_T^a|>/<u_N^a>, with u_T the tangential displacement of the centres (dev_ut_centres) or of
the contact points, the rotations included (Eq 5, dev_ut_rotations), accumulated since each contact
formed. The centres are prescribed, so dev_ut_centres is kinematics: the two solvers must give the
same number up to the DEM's window mean (a row is the mean of its window's samples, so it lags the
netsolve row by half an increment). The rotations are the only unknowns: the DEM's limit and
netsolve's undragged equilibrium (the pseudo-transient iteration) must agree on them. Measured when
written: centres within 0.57 %, rotations within 0.83 % (rows 10-40); the legacy drag's rotations
differ by 2-3.7 %.
"""
import numpy as np

import netdem

SCENE = dict(width=20, affine=True, path="closed-die", increments=40, quiet=True)


def test_affine_tangential_deviation_agrees_between_the_solvers():
    net = netdem.netsolve.compact(iteration="pseudo-transient", **SCENE)
    dem = netdem.demsolve.compact(**SCENE)
    assert net.status == "ok" and dem.status == "ok"
    n, d = net.history, dem.history
    assert len(n["D"]) == len(d["D"]) == 41
    k = np.arange(10, 41)
    # the same densities row by row (the strain is prescribed)
    assert np.max(np.abs(d["D"][k] - n["D"][k])) < 1e-4
    # kinematics: the centres' deviation, netsolve's at the middle of the DEM's window
    mid = 0.5 * (n["dev_ut_centres"][k - 1] + n["dev_ut_centres"][k])
    assert np.all(mid > 0)
    assert np.max(np.abs(d["dev_ut_centres"][k] / mid - 1)) < 0.01
    # the rotations: the DEM against the undragged equilibrium
    assert np.all(n["dev_ut_rotations"][k] > 0.3)  # well away from zero: the rotations matter
    assert np.max(np.abs(d["dev_ut_rotations"][k] / n["dev_ut_rotations"][k] - 1)) < 0.015
