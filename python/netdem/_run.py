"""Runs a subcommand in process (the extension _netdem) and reads its run folder back."""
import csv
import json
import os
import shutil
import sys
import tempfile

import numpy as np

from . import _netdem

# worker processes (netsolve yield --jobs) are this interpreter running netdem._worker
_netdem.set_worker_program([sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv.pop(1)); "
                            "from netdem import _worker; _worker.main()",
                            os.path.dirname(os.path.dirname(os.path.abspath(__file__)))])

class Result:
    """A finished run: `history` (history.csv, or timeseries.csv, as a dict of numpy arrays named
    as its columns), `summary` (summary.json), `status` (the summary's "status": "ok",
    "unconverged", "unstable", "incomplete", ...), `exit_code` (the command line's: 0 or 3),
    `messages` (the error or warning lines the command printed), `summary_line` (the closing line
    the command line prints on stdout, which the module returns instead of printing) and `out` (the
    run folder if kept, else None)."""

    def __init__(self, history, summary, exit_code, messages, out):
        self.history = history
        self.summary = summary
        self.status = summary.get("status", "ok" if exit_code == 0 else "unknown")
        self.exit_code = exit_code
        self.messages = messages
        self.out = out
        self.summary_line = ""

    def __repr__(self):
        rows = len(next(iter(self.history.values()))) if self.history else 0
        return f"Result(status={self.status!r}, exit_code={self.exit_code}, {rows} history rows)"


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple, np.ndarray)):
        return ",".join(_value(x) for x in v)
    if isinstance(v, (float, np.floating)):
        return repr(float(v))  # the shortest text that reads back as the same double
    return str(v)


def tokens(kwargs):
    """The command-line words of keyword arguments: name -> --name (with '_' -> '-', a trailing
    '_' dropped); True is a flag, False and None leave the option out."""
    words = []
    for name, v in kwargs.items():
        option = "--" + name.rstrip("_").replace("_", "-")
        if v is None or v is False:
            continue
        if v is True:
            words.append(option)
        elif _value(v) == "":  # an empty list or text: its own word, as `--snapshots ""` on the command
            words += [option, ""]  # line ("--snapshots=" would take the next word as its value)
        else:
            words.append(f"{option}={_value(v)}")
    return words


def read_table(path):
    """A CSV file of a run (header line, '#' lines skipped) as a dict of numpy arrays."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    table = {}
    for k, name in enumerate(header):
        col = [r[k] if k < len(r) else "nan" for r in body]
        try:
            table[name] = np.array([float(v) if v != "" else np.nan for v in col], dtype=np.float64)
        except ValueError:
            table[name] = np.array(col)
    return table


def read_run(folder, exit_code, messages, keep, history_files=("history.csv", "timeseries.csv")):
    """The Result of the run folder `folder`; its history is the first of `history_files` there."""
    summary = {}
    path = os.path.join(folder, "summary.json")
    if os.path.exists(path):
        with open(path) as f:
            summary = json.load(f)
    history = {}
    for name in history_files:
        if os.path.exists(os.path.join(folder, name)):
            history = read_table(os.path.join(folder, name))
            break
    return Result(history, summary, exit_code, messages, folder if keep else None)


def reader(history_files=("history.csv", "timeseries.csv"), **tables):
    """A reader for run(): the Result of read_run with its history from the first of
    `history_files`, and an attribute per keyword, the table of that CSV file (`yield_points=
    "yield_points.csv"`) or an empty dict if the run did not write it."""

    def read(folder, code, messages, keep):
        r = read_run(folder, code, messages, keep, history_files)
        for attribute, name in tables.items():
            path = os.path.join(folder, name)
            setattr(r, attribute, read_table(path) if os.path.exists(path) else {})
        return r

    return read


def run(tool, subcommand, kwargs, out=None, progress=None, reader=read_run, positional=()):
    """Runs `tool subcommand` with the options of `kwargs` (and the words `positional` before
    them) in process; `reader(folder, exit_code, messages, keep)` makes the result. ValueError for
    a refused command line (exit 2), RuntimeError for a run error (exit 1), both with the command's
    one-line message."""
    if "out" in kwargs:
        raise TypeError("out is the keyword argument of the run folder, not an option")
    tmp = None
    if out is None:
        tmp = tempfile.mkdtemp(prefix="netdem-")
        folder = os.path.join(tmp, "run")
    else:
        folder = os.fspath(out)
    try:
        words = [subcommand] + [os.fspath(w) for w in positional] + tokens(kwargs) + [f"--out={folder}"]
        code, lines, printed = _netdem.run(tool, words, progress)
        message = lines[-1] if lines else f"{tool} {subcommand}: exit status {code}"
        if code == 2:
            raise ValueError(message)
        if code not in (0, 3):
            raise RuntimeError(message)
        result = reader(folder, code, list(lines), tmp is None)
        result.summary_line = printed[-1] if printed else ""
        return result
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
