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
