"""What every generated report shares (issues 26 and 32). Used by validation/*/run.py,
validation/status.py and bench/*.py.

* Paths as reports show them (issue 26 item 6): never an absolute path of the machine that ran the
  script (`shown_path`).
* Verdicts and totals (issue 32 item 2, "no silent omissions"): a line is PASS, FAIL, MISSING (it
  could not be evaluated; the reason is written in the line) or anything else ("n/a", "INVALID",
  "report", ...: counted as other). `verdict`, `MISSING`, `missing_text`, `tally`, `totals_text`.
* Provenance (issue 32 item 3, "no stale reports"): the commit the report was made from, whether the
  tracked sources were modified, the git object id of every source path the case measures (so that a
  run on a modified tree that is committed afterwards is still recognised) and the SHA-256 of every
  binary it ran (`provenance`, `provenance_lines`). The machine-readable line is
  `<!-- netdem-report: {json} -->`; `read_meta` reads it back, `count_verdicts` counts a report's
  result columns, `unaffected_by` reads the hand-written `<!-- unaffected-by: COMMIT REASON -->` lines.
"""
import datetime
import hashlib
import json
import os
import re
import subprocess
import tempfile

MISSING = "MISSING"
META_TAG = "netdem-report:"
VERDICT_HEADERS = ("result", "pass/fail", "verdict")

# the sources each validation case measures (paths relative to the repository; folders are compared as
# a whole). A case's own folder is represented by its inputs (scripts, material and profile files), not by
# its outputs (report.md, figures), which change with every regeneration.
COMMON_SOURCES = ("CMakeLists.txt", "src", "apps/CMakeLists.txt", "apps/common", "apps/scripts/report_paths.py")
CASE_SOURCES = {
    "redanz_fleck_compaction": ("apps/netsolve", "validation/redanz_fleck_compaction/run.py"),
    "redanz_fleck_yield": ("apps/netsolve", "apps/demsolve", "validation/redanz_fleck_yield/run.py",
                           "validation/redanz_fleck_yield/analytic_surface.py", "validation/redanz_fleck_yield/walls.py"),
    "luding_sintering": ("apps/demsolve", "validation/luding_sintering/run.py", "validation/luding_sintering/study.py",
                         "validation/luding_sintering/analysis.py", "validation/luding_sintering/figures.py"),
    "sintering_pair": ("apps/netsolve", "validation/sintering_pair/run.py",
                       "validation/sintering_pair/exponent_material.txt"),
    "quasistatic_vs_dynamic": ("apps/netsolve", "apps/demsolve", "validation/quasistatic_vs_dynamic/run.py",
                               "validation/quasistatic_vs_dynamic/notes.md",
                               "validation/quasistatic_vs_dynamic/notes_quick.md"),
    "quasistatic_vs_dynamic_periodic": ("apps/netsolve", "apps/demsolve",
                                        "validation/quasistatic_vs_dynamic/run.py",
                                        "validation/quasistatic_vs_dynamic_periodic/run.py",
                                        "validation/quasistatic_vs_dynamic_periodic/notes.md"),
    "quasistatic_vs_dynamic_walls": ("apps/netsolve", "apps/demsolve",
                                     "validation/quasistatic_vs_dynamic/run.py",
                                     "validation/quasistatic_vs_dynamic_periodic/run.py",
                                     "validation/quasistatic_vs_dynamic_walls/run.py",
                                     "validation/quasistatic_vs_dynamic_walls/notes.md"),
    "redanz_fleck_walls": ("apps/netsolve", "apps/demsolve", "validation/quasistatic_vs_dynamic/run.py",
                           "validation/quasistatic_vs_dynamic_periodic/run.py",
                           "validation/redanz_fleck_compaction/run.py", "validation/redanz_fleck_walls/run.py",
                           "validation/redanz_fleck_walls/frictional.py", "validation/redanz_fleck_walls/notes.md"),
    "compaction_3d": ("apps/netsolve", "apps/demsolve", "validation/quasistatic_vs_dynamic/run.py",
                      "validation/quasistatic_vs_dynamic_periodic/run.py", "validation/compaction_3d/run.py",
                      "validation/compaction_3d/notes.md"),
    "literature_3d": ("apps/netsolve", "validation/quasistatic_vs_dynamic/run.py",
                      "validation/quasistatic_vs_dynamic_periodic/run.py", "validation/literature_3d/run.py",
                      "validation/literature_3d/notes.md"),
    "ivannikov_staggered": ("apps/netsolve", "validation/ivannikov_staggered/run.py",
                            "validation/ivannikov_staggered/ti_two_phase_synthetic.txt",
                            "validation/ivannikov_staggered/synthetic_profile.csv"),
}


def load_module(name, path):
    """The Python file `path` (a sibling case's run.py, say) as a module named `name`."""
    import importlib.util
    spec = importlib.util.spec_from_file_location(name, path)
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def shown_path(p, repo):
    """`p` relative to the repository `repo`; a relative `p` as it is; a file outside the
    repository by its name only."""
    p = str(p)
    if not os.path.isabs(p):
        return p
    r = os.path.relpath(p, str(repo))
    return r if not r.startswith("..") else os.path.join("<outside the repository>", os.path.basename(p))


# ------------------------------------------------------------------------------------------ verdicts
def verdict(ok):
    """PASS / FAIL for a graded line, n/a for an information line (ok is None)."""
    return "n/a" if ok is None else ("PASS" if ok else "FAIL")


def missing_text(reason):
    """The measured cell of a line that could not be evaluated."""
    return f"not evaluated: {reason}"


def classify(v):
    """PASS, FAIL, MISSING or other, for a verdict cell as written (bold markers ignored)."""
    v = str(v).strip().strip("*").strip()
    if v in ("PASS", "FAIL"):
        return v
    return MISSING if v.startswith(MISSING) else "other"


def tally(verdicts):
    """{'PASS': n, 'FAIL': n, 'MISSING': n, 'other': n} of an iterable of verdict cells."""
    c = {"PASS": 0, "FAIL": 0, MISSING: 0, "other": 0}
    for v in verdicts:
        c[classify(v)] += 1
    return c


def totals_text(c):
    return f"{c['PASS']} PASS, {c['FAIL']} FAIL, {c[MISSING]} MISSING, {c['other']} other"


def _cells(line):
    return [x.strip() for x in re.split(r"(?<!\\)\|", line.strip())[1:-1]]


def count_verdicts(text):
    """Counts of the verdict column ('result', 'pass/fail' or 'verdict') of every table of a report."""
    lines = text.splitlines()
    verdicts = []
    i = 0
    while i < len(lines):
        if lines[i].startswith("|") and i + 1 < len(lines) and re.match(r"^\|[-| :]+\|\s*$", lines[i + 1]):
            head = [h.lower() for h in _cells(lines[i])]
            col = next((head.index(h) for h in VERDICT_HEADERS if h in head), None)
            i += 2
            while i < len(lines) and lines[i].startswith("|"):
                row = _cells(lines[i])
                if col is not None and col < len(row):
                    verdicts.append(row[col])
                i += 1
        else:
            i += 1
    return tally(verdicts)


# ---------------------------------------------------------------------------------------- provenance
def _git(repo, *args, env=None):
    r = subprocess.run(["git", "-C", str(repo)] + list(args), capture_output=True, text=True, timeout=60,
                       env=env)
    if r.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)}: {r.stderr.strip()}")
    return r.stdout


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def case_sources(case):
    return list(COMMON_SOURCES) + list(CASE_SOURCES.get(case, ("apps", f"validation/{case}/run.py")))


def source_ids(repo, paths, modified):
    """{path: git object id of its content in the work tree} (a tree id for a folder, a blob id for a
    file, "absent" if it does not exist). A clean tree reads HEAD; a modified one is written to a
    temporary index (the real index is not touched; the blobs go to the object store)."""
    tree = "HEAD"
    if modified:
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, GIT_INDEX_FILE=os.path.join(tmp, "index"))
            _git(repo, "read-tree", "HEAD", env=env)
            _git(repo, "add", "-u", "--", *paths, env=env)
            tree = _git(repo, "write-tree", env=env).strip()
    out = {}
    for p in paths:
        r = subprocess.run(["git", "-C", str(repo), "rev-parse", "--verify", "-q", f"{tree}:{p}"],
                           capture_output=True, text=True, timeout=60)
        out[p] = r.stdout.strip() if r.returncode == 0 else "absent"
    return out


def provenance(repo, case, binaries=(), reused=None):
    """The provenance of a report of `case` made now from the work tree of `repo`, with the SHA-256 of
    each binary in `binaries` (paths; missing files are recorded as such). `reused`: which runs the
    report read from earlier run folders instead of running them (text, e.g. "all (--report-only)"),
    so that the binaries are not claimed to have made them; None if every run ran now."""
    paths = case_sources(case)
    try:
        commit = _git(repo, "rev-parse", "HEAD").strip()
        changed = [ln[3:] for ln in _git(repo, "status", "--porcelain", "--untracked-files=no", "--",
                                         *paths).splitlines() if ln.strip()]
        sources = source_ids(repo, paths, bool(changed))
    except (OSError, RuntimeError, subprocess.SubprocessError) as e:
        commit, changed, sources = None, [], {}
        print(f"provenance: git unavailable ({e}); the report will be listed as 'no provenance'")
    bins = {}
    for b in binaries:
        if b:
            bins[shown_path(os.path.abspath(b), repo)] = sha256_file(b) if os.path.isfile(b) else "missing"
    return {"case": case, "commit": commit, "modified": bool(changed), "modified_files": changed,
            "sources": sources, "binaries": bins, **({"reused": reused} if reused else {}),
            "generated": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}


def provenance_lines(prov, counts):
    """Markdown lines for the end of a report: a readable provenance and totals, and the one
    machine-readable line validation/status.py reads."""
    meta = dict(prov, counts=counts)
    commit = (prov.get("commit") or "unknown")[:12]
    tree = "work tree modified: " + ", ".join(prov["modified_files"]) if prov.get("modified") else "work tree clean"
    bins = "; ".join(f"`{k}` sha256 {v}" for k, v in sorted(prov.get("binaries", {}).items())) or "none"
    if prov.get("reused"):
        bins += (f" (runs reused from earlier run folders, not run by these binaries: {prov['reused']}; the "
                 "sources they measure are unchanged since, or declared unaffected in the report)")
    return ["", "## Provenance", "",
            f"Commit {commit} ({tree}); generated {prov.get('generated', '?')}. Binaries run: {bins}. "
            f"Totals: {totals_text(counts)} (MISSING: a line that could not be evaluated, with the reason in the "
            "line). `validation/status.py` says whether the sources this report measures changed since.", "",
            f"<!-- {META_TAG} {json.dumps(meta, sort_keys=True, ensure_ascii=True)} -->"]


def read_meta(text):
    """The machine-readable line of a report, or None for a report without provenance."""
    m = re.search(r"<!-- " + re.escape(META_TAG) + r" (\{.*\}) -->", text)
    if not m:
        return None
    try:
        return json.loads(m.group(1))
    except json.JSONDecodeError:
        return None


def unaffected_by(text):
    """[(commit prefix, reason)] of the `<!-- unaffected-by: COMMIT REASON -->` lines of a report."""
    return [(m.group(1).lower(), m.group(2).strip())
            for m in re.finditer(r"<!--\s*unaffected-by:\s*([0-9a-fA-F]{7,40})\s+(.*?)\s*-->", text)]
