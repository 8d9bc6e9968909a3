"""The subcommands of issue 33 part 2 against the executables of the same build, bit for bit, on
small scenes: netdem.netsolve.sinter_pair, sinter, yield_merge and netdem.demsolve.prepare, sinter,
compress, vibrate, yield_ (the same words through _run.tokens, so the in-process run is compared
with the executable's); each reports progress up to 1."""
import pytest

import netdem
from netdem import _run
from conftest import assert_same_run, assert_snapshot_series, run_cli


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A green body of 20 spheres (netsolve sinter's packing), a short demsolve sinter's state and a
    small netsolve yield run (yield-merge's input)."""
    d = str(tmp_path_factory.mktemp("inputs"))
    for tool, args in [("netsolve", ["pack", "--dim", "3", "--route", "green-body", "--n", "20", "--quiet"]),
                       ("demsolve", ["sinter", "--n", "30", "--t-heat", "0.01", "--heat-time", "0.01", "--sinter-time",
                                     "0.02", "--cool-time", "0.01", "--relax-time", "0.01", "--quiet"]),
                       ("netsolve", ["yield", "--width", "16", "--directions", "4", "--jobs", "1", "--increments", "5",
                                     "--quiet"])]:
        code, err = run_cli(tool, args + ["--out", f"{d}/{args[0]}"])
        assert code in (0, 3), err
    return d


CASES = [
    ("netsolve", "sinter_pair", "sinter-pair", {"time": 10, "radii": [1e-5, 2e-5], "set": "D_vol0=1.9e-7"}, "pair.csv"),
    ("netsolve", "sinter", "sinter", {"packing": "{d}/pack/packing.csv", "time": 10, "checkpoints": [5], "quiet": True},
     "history.csv"),
    ("demsolve", "prepare", "prepare", {"n": 30, "time": 0.02, "quiet": True}, "timeseries.csv"),
    ("demsolve", "sinter", "sinter", {"n": 30, "t_heat": 0.01, "heat_time": 0.01, "sinter_time": 0.02, "cool_time": 0.01,
                                      "relax_time": 0.01, "param": "k2=2e5", "quiet": True}, "timeseries.csv"),
    ("demsolve", "compress", "compress", {"state": "{d}/sinter/state.txt", "max_strain": 0.01, "quiet": True},
     "compress.csv"),
    ("demsolve", "vibrate", "vibrate", {"state": "{d}/sinter/state.txt", "time": 0.01, "quiet": True}, "timeseries.csv"),
    ("demsolve", "yield_", "yield", {"width": 8, "directions": 2, "probes": [1], "increments": 3, "jobs": 1,
                                     "to_density": 0.8, "max_strain": 0.002, "settle_time": 5, "quiet": True},
     "history.csv"),
]


# the parts of each subcommand's snapshots.pvd (None: no snapshot, no .pvd)
SERIES = {("netsolve", "sinter_pair"): None, ("netsolve", "sinter"): ("particles", "bonds"),
          ("demsolve", "prepare"): ("particles", "contacts"), ("demsolve", "sinter"): ("particles", "contacts"),
          ("demsolve", "compress"): ("particles", "contacts"), ("demsolve", "vibrate"): ("particles", "contacts"),
          ("demsolve", "yield_"): None}


@pytest.mark.parametrize("tool,function,subcommand,options,history", CASES, ids=[f"{c[0]}-{c[2]}" for c in CASES])
def test_subcommand_equals_cli(tmp, inputs, tool, function, subcommand, options, history):
    options = {k: v.format(d=inputs) if isinstance(v, str) else v for k, v in options.items()}
    code, err = run_cli(tool, [subcommand] + _run.tokens(options) + ["--out", f"{tmp}/cli"])
    assert code in (0, 3), err
    seen = []
    r = getattr(getattr(netdem, tool), function)(out=f"{tmp}/py", progress=seen.append, **options)
    assert r.exit_code == code and len(next(iter(r.history.values()))) > 1
    assert seen and seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen)
    assert_same_run(f"{tmp}/cli", r, history)
    assert_snapshot_series(r.out, SERIES[(tool, function)])  # the executable's is the same, byte for byte
    if function in ("vibrate",):
        assert r.clusters and list(r.clusters) == list(_run.read_table(f"{tmp}/cli/clusters.csv"))
    if function == "yield_":
        assert getattr(netdem.demsolve, "yield") is netdem.demsolve.yield_
        assert len(r.yield_points["theta"]) == 1


def test_yield_merge_equals_cli(tmp, inputs):
    code, err = run_cli("netsolve", ["yield-merge", f"{inputs}/yield", "--out", f"{tmp}/cli"])
    assert code == 0, err
    r = netdem.netsolve.yield_merge(f"{inputs}/yield", out=f"{tmp}/py")
    assert r.exit_code == 0 and len(r.yield_points["theta"]) == 4
    cli = _run.read_table(f"{tmp}/cli/yield_points.csv")
    assert list(cli) == list(r.yield_points)
    with open(f"{tmp}/cli/yield_points.csv", "rb") as f, open(f"{tmp}/py/yield_points.csv", "rb") as g:
        assert f.read() == g.read()
    with open(f"{tmp}/cli/scene.toml", "rb") as f, open(f"{tmp}/py/scene.toml", "rb") as g:
        assert f.read() == g.read()


def test_new_subcommand_refuses_a_bad_value(tmp):
    code, err = run_cli("demsolve", ["vibrate", "--state", f"{tmp}/none.txt", "--out", f"{tmp}/cli"])
    with pytest.raises(ValueError) as e:
        netdem.demsolve.vibrate(state=f"{tmp}/none.txt", out=f"{tmp}/py")
    assert code == 2 and str(e.value) == err.strip()
