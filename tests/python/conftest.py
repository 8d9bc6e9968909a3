"""Shared helpers of the module's tests: the executables of the same build (ctest sets
NETDEM_NETSOLVE and NETDEM_DEMSOLVE; else the build next to the imported module) and the
comparison of two run folders."""
import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import netdem
from netdem import _run

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from pvd_check import snapshot_series_errors  # noqa: E402  (tests/pvd_check.py)

# summary.json keys that are not results: wall-clock and CPU times and the command itself
VOLATILE = re.compile(r"^(command|threads_available|timing_s|timings?|timers?(_s)?|(wall|cpu)(_time)?_s|.*_(wall|cpu)_s|.*_per_(cpu_)?s)$")


def executable(tool):
    env = os.environ.get(f"NETDEM_{tool.upper()}")
    if env:
        return env
    build = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(netdem.__file__))))
    return os.path.join(build, "apps", tool)


def run_cli(tool, args, cwd=None):
    """Runs the executable; (exit status, stderr)."""
    p = subprocess.run([executable(tool)] + args, capture_output=True, text=True, cwd=cwd)
    return p.returncode, p.stderr


def assert_same_numbers(a, b, where="summary"):
    """Two JSON values equal, every number exactly (NaN equals NaN), volatile keys skipped."""
    if isinstance(a, dict):
        assert isinstance(b, dict), where
        keys = {k for k in a if not VOLATILE.match(k)}
        other = {k for k in b if not VOLATILE.match(k)}
        assert keys == other, f"{where}: keys differ: {sorted(keys ^ other)}"
        for k in keys:
            assert_same_numbers(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same_numbers(x, y, f"{where}[{k}]")
    elif isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float) and math.isnan(b), where
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def report_lines(text):
    """A report.md without its command line and its timing section (netsolve sinter's)."""
    lines = text.decode().split("\n")
    if "## Timing" in lines:
        lines = lines[:lines.index("## Timing")]
    return [l for l in lines if not (l.startswith("`") and " --out" in l)]


def assert_same_run(cli_dir, result, history="history.csv"):
    """The Python result equals the command line's run folder: every column of its history
    (`history`) exactly, summary.json's numbers, every other JSON file's numbers, report.md without
    the command line and the timings, and every other file byte for byte (but command.txt), in
    subfolders too."""
    cli_history = _run.read_table(os.path.join(cli_dir, history))
    assert list(cli_history) == list(result.history)
    for name, col in cli_history.items():
        assert col.dtype == result.history[name].dtype, name
        assert np.array_equal(col, result.history[name], equal_nan=col.dtype.kind == "f"), name
    with open(os.path.join(cli_dir, "summary.json")) as f:
        assert_same_numbers(json.load(f), result.summary)
    if result.out is not None:
        names = files(cli_dir) - {"command.txt", "summary.json"}
        assert names == files(result.out) - {"command.txt", "summary.json"}
        for n in sorted(names):
            with open(os.path.join(cli_dir, n), "rb") as f, open(os.path.join(result.out, n), "rb") as g:
                a, b = f.read(), g.read()
            if n.endswith(".json") or (n.endswith(".txt") and a.startswith(b"{")):  # JSON, state files too:
                assert_same_numbers(json.loads(a), json.loads(b), n)        # wall-clock times in them
            elif n.endswith(".md"):
                assert report_lines(a) == report_lines(b), n
            else:
                assert a == b, n


def assert_snapshot_series(folder, kinds, tags=None, history=None):
    """`folder`'s snapshots.pvd is the ParaView collection of its snapshot series (tests/pvd_check.py);
    kinds None: the folder holds no .pvd (the run wrote no snapshot)."""
    if kinds is None:
        assert not [n for n in os.listdir(folder) if n.endswith(".pvd")], os.listdir(folder)
        return
    errors = snapshot_series_errors(folder, list(kinds), tags, history)
    assert not errors, "\n".join(errors)


def snapshot_tags(folder):
    """The snapshots listed in `folder`'s snapshots.pvd, in order: TAG of particles_TAG.vtp."""
    root = ET.parse(os.path.join(folder, "snapshots.pvd")).getroot()
    return [re.fullmatch(r"particles_(.+)\.vtp", d.get("file")).group(1) for d in root.iter("DataSet")
            if d.get("part") == "0"]


def files(folder):
    """The files under `folder`, as paths relative to it."""
    return {os.path.relpath(os.path.join(d, f), folder) for d, _, fs in os.walk(folder) for f in fs}


@pytest.fixture
def tmp(tmp_path):
    return str(tmp_path)
