"""Paths as reports show them (issue 26 item 6): never an absolute path of the machine that ran
the script. Used by validation/*/run.py and bench/*.py."""
import os


def shown_path(p, repo):
    """`p` relative to the repository `repo`; a relative `p` as it is; a file outside the
    repository by its name only."""
    p = str(p)
    if not os.path.isabs(p):
        return p
    r = os.path.relpath(p, str(repo))
    return r if not r.startswith("..") else os.path.join("<outside the repository>", os.path.basename(p))
