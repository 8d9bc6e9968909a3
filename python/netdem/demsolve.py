"""demsolve's subcommands (README.md "demsolve"): keyword arguments are the long options of
`demsolve SUBCOMMAND --help` with '-' -> '_' and the same defaults; see netdem.__doc__."""
from . import _run


def compact(*, out=None, progress=None, **options):
    """`demsolve compact`: netsolve's compaction scene with the explicit DEM and the same contact
    law (docs/dynamic.md "demsolve compact"). Returns a Result (netdem.Result)."""
    return _run.run("demsolve", "compact", options, out, progress)
