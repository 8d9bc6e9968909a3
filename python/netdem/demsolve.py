"""demsolve's subcommands (README.md "demsolve"): keyword arguments are the long options of
`demsolve SUBCOMMAND --help` with '-' -> '_' and the same defaults; see netdem.__doc__."""
from . import _run


def compact(*, out=None, progress=None, **options):
    """`demsolve compact`: netsolve's compaction scene with the explicit DEM and the same contact
    law (docs/dynamic.md "demsolve compact"). Returns a Result (netdem.Result)."""
    return _run.run("demsolve", "compact", options, out, progress)


def prepare(*, out=None, progress=None, **options):
    """`demsolve prepare`: random disks (or spheres, dim=3) compressed by stress-controlled walls
    (Luding et al. 2005 section 4.1). Returns a Result whose `history` is timeseries.csv's columns."""
    return _run.run("demsolve", "prepare", options, out, progress)


def sinter(*, out=None, progress=None, **options):
    """`demsolve sinter`: the whole sintering protocol of section 4.1 (prepare, heat, sinter, cool,
    relax; Fig 7). Returns a Result whose `history` is timeseries.csv's columns."""
    return _run.run("demsolve", "sinter", options, out, progress)


def compress(*, out=None, progress=None, **options):
    """`demsolve compress state=FILE`: the bi-axial compression test of section 4.4.1 on a saved
    state. Returns a Result whose `history` is compress.csv's columns."""
    return _run.run("demsolve", "compress", options, out, progress, _run.reader(("compress.csv",)))


def vibrate(*, out=None, progress=None, **options):
    """`demsolve vibrate state=FILE`: the vibration test of section 4.4 on a saved state. Returns a
    Result whose `history` is timeseries.csv's and `clusters` clusters.csv's columns."""
    return _run.run("demsolve", "vibrate", options, out, progress, _run.reader(clusters="clusters.csv"))


def yield_(*, out=None, progress=None, **options):
    """`demsolve yield`: netsolve yield's probes with the explicit DEM (docs/dynamic.md "demsolve
    yield"). Returns a Result whose `history` is the precompaction's and `yield_points`
    yield_points.csv's columns. Also reachable as getattr(netdem.demsolve, "yield")."""
    return _run.run("demsolve", "yield", options, out, progress, _run.reader(yield_points="yield_points.csv"))


globals()["yield"] = yield_  # `yield` is a Python keyword
