"""netsolve's subcommands (README.md "netsolve"): keyword arguments are the long options of
`netsolve SUBCOMMAND --help` with '-' -> '_' and the same defaults; see netdem.__doc__."""
from . import _run
from . import packing as _packing


def compact(*, out=None, progress=None, **options):
    """`netsolve compact`: the network solver's compaction (default: the ballistic deposition of
    W = 80 R, hydrostatic, sticking friction, to D = 0.85). Returns a Result (netdem.Result)."""
    return _run.run("netsolve", "compact", options, out, progress)


def pack(*, out=None, **options):
    """`netsolve pack`: a packing (ballistic deposition; --dim 3, --route green-body, --periodic).
    Returns a Result whose `packing` is the netdem.packing.Packing of packing.csv."""

    def reader(folder, code, messages, keep):
        r = _run.read_run(folder, code, messages, keep)
        r.packing = _packing.read(f"{folder}/packing.csv")
        return r

    return _run.run("netsolve", "pack", options, out, None, reader)


def yield_(*, out=None, progress=None, **options):
    """`netsolve yield`: compaction, elastic unloading and strain probes in `directions` directions
    (docs/yield.md); `jobs` worker processes (0, the default: one per core) are this interpreter.
    Returns a Result whose `history` is the precompaction's and `yield_points` yield_points.csv's
    columns (numpy arrays; NaN where a probe found no point, text columns as arrays of str).
    Also reachable as getattr(netdem.netsolve, "yield")."""

    def reader(folder, code, messages, keep):
        r = _run.read_run(folder, code, messages, keep)
        r.yield_points = _run.read_table(f"{folder}/yield_points.csv")
        return r

    return _run.run("netsolve", "yield", options, out, progress, reader)


def yield_merge(*dirs, out=None, **options):
    """`netsolve yield-merge DIR...`: yield_points.csv assembled from the probe files of the yield
    run folders `dirs`. Returns a Result whose `yield_points` is yield_points.csv's columns."""
    return _run.run("netsolve", "yield-merge", options, out, None, _run.reader(yield_points="yield_points.csv"), dirs)


def sinter_pair(*, out=None, progress=None, **options):
    """`netsolve sinter-pair`: one two-particle sintering contact against time (SI units; default:
    Cu at 1293 K, docs/sintering_pair.md). Returns a Result whose `history` is pair.csv's columns."""
    return _run.run("netsolve", "sinter-pair", options, out, progress, _run.reader(("pair.csv",)))


def sinter(*, out=None, progress=None, **options):
    """`netsolve sinter`: the staggered sintering scheme of Ivannikov et al. in 3D (docs/staggered.md;
    default: the Cu benchmark). Returns a Result whose `history` is history.csv's and `steps`
    steps.csv's columns."""
    return _run.run("netsolve", "sinter", options, out, progress, _run.reader(steps="steps.csv"))


globals()["yield"] = yield_  # `yield` is a Python keyword: netdem.netsolve.yield_ or getattr(..., "yield")
