"""A worker process of a run started from Python (netsolve yield --jobs: one probe per worker).
The worker pool starts the interpreter with `-c` code that imports this module, then the tool's
command line: it runs that command in process and exits with its status."""
import sys

from . import _netdem


def main():
    code, lines, _ = _netdem.run(sys.argv[1], sys.argv[2:])
    for line in lines:
        print(line, file=sys.stderr)
    sys.exit(code)
