"""netdem from Python: the libraries of netdem through the subcommands of its two tools.

    import netdem
    r = netdem.netsolve.compact(friction=0.1, to_density=0.85)
    r.history["D"], r.history["S11"], r.summary["status"], r.status

Each function takes the long options of its subcommand as keyword arguments, with '-' replaced by
'_' and the same defaults (`netsolve compact --help`): `friction=0.1` is `--friction 0.1`, a flag
is True (`no_rotation=True` is `--no-rotation`), a list is a comma list. `out=DIR` keeps the run
folder the command line writes; without it the run goes to a temporary folder that is removed.
It returns a Result (.history, .summary, .status, .exit_code). A bad value raises ValueError with
the command line's one-line message; a run that finishes untrustworthy returns its status.
`progress=callable(fraction)` is called during the run (at most every 50 ms); Ctrl-C stops it.

Modules: netdem.netsolve (pack, compact, yield_, yield_merge, sinter_pair, sinter), netdem.demsolve
(prepare, sinter, compress, vibrate, compact, yield_), netdem.packing (deposit, read, write).
`config="scene.toml"` reads the options from a scene file (README.md "Scene files"); the keyword
arguments override it.
"""
from . import demsolve, netsolve, packing
from ._run import Result

__all__ = ["Result", "demsolve", "netsolve", "packing"]
