#!/usr/bin/python3
"""Default outputs of every subcommand, for proving a refactor (issue 26): run them with one build,
run them with another, compare.

    /usr/bin/python3 tests/regress/default_outputs.py run BUILD_DIR OUT_DIR [--only NAME,...]
    /usr/bin/python3 tests/regress/default_outputs.py compare OUT_A OUT_B

`run` executes each case below with the binaries of BUILD_DIR (BUILD_DIR/apps/netsolve and
demsolve) in OUT_DIR/<case>/ and writes OUT_DIR/manifest.txt: one line per output file, its
SHA-256 after the normalisation below. `compare` prints the files whose hashes differ (and the
first differing line of each), the files only one side has, and exits 1 if there are any.

Normalisation (what may differ between two runs of the same binary and is not a result):
  * JSON (summary.json, ...): keys that hold wall-clock or CPU times, rates per second, the
    commit, the binary's path, the date or the pid (VOLATILE_KEYS) are removed, at any depth;
  * Markdown reports: sections headed as timings and lines that state a time in seconds or a date
    are dropped;
  * CSV: columns whose header names a wall-clock time (VOLATILE_COLUMNS) are dropped;
  * the absolute paths of the binaries and of the run root (command lines) become <bin>, <root>;
  * state files (state*.txt, *_state.txt, state*.json: the state format changes with issue 26)
    are listed but not compared (marked "state");
  * the run marker .incomplete never survives a finished run and is not listed.
Everything else is compared byte for byte. `run` with the same build twice must compare equal
(`compare` of two such runs is the script's own check: the outputs are deterministic).
"""
import hashlib
import json
import os
import re
import subprocess
import sys
import time

# name -> (tool, args); runs in order, so later cases may read earlier cases' files ({out} is the
# case folder, {root} the OUT_DIR).
CASES = [
    ("netsolve_pack", "netsolve", ["pack"]),
    ("netsolve_pack3d", "netsolve", ["pack", "--dim", "3"]),
    ("netsolve_green", "netsolve", ["pack", "--dim", "3", "--route", "green-body"]),
    ("netsolve_compact", "netsolve", ["compact"]),
    ("netsolve_compact_walls", "netsolve", ["compact", "--boundary", "walls", "--allow-unconverged"]),
    ("netsolve_compact3d", "netsolve", ["compact", "--dim", "3", "--width", "10"]),
    ("netsolve_yield", "netsolve", ["yield", "--jobs", "1"]),
    ("netsolve_sinter_pair", "netsolve", ["sinter-pair"]),
    ("netsolve_sinter", "netsolve", ["sinter"]),
    ("demsolve_prepare", "demsolve", ["prepare"]),
    ("demsolve_prepare3d", "demsolve", ["prepare", "--dim", "3"]),
    ("demsolve_sinter", "demsolve", ["sinter"]),
    ("demsolve_compress", "demsolve", ["compress", "--state", "{root}/demsolve_sinter/state.txt"]),
    ("demsolve_vibrate", "demsolve", ["vibrate", "--state", "{root}/demsolve_sinter/state.txt"]),
    ("demsolve_compact", "demsolve", ["compact"]),
    ("demsolve_compact3d", "demsolve", ["compact", "--dim", "3", "--boundary", "walls", "--width", "5"]),
]

VOLATILE_KEYS = re.compile(
    r"^(timing_s|timings?|timers?(_s)?|wall_s|wall_time_s|cpu_time_s|cpu_s|elapsed_s|seconds|"
    r"particle_steps_per_s|particle_steps_per_cpu_s|steps_per_s|rate_per_s|.*_wall_s|.*_cpu_s|"
    r"commit|git_commit|binary|binaries|executable|date|started|start_time|finished|host|hostname|pid|"
    r"threads_available|run_seconds)$")
VOLATILE_COLUMNS = re.compile(r"^(wall_s|wall_time_s|cpu_s|cpu_time_s|elapsed_s|t_wall|timing_s)$")
VOLATILE_MD = re.compile(r"(\b\d+(\.\d+)?\s*(s|ms|min)\b.*(wall|CPU|cpu|took|time|rate))|"
                         r"((wall|CPU|cpu|took|run time|Run time).*\b\d+(\.\d+)?\s*(s|ms|min)\b)|"
                         r"(\d{4}-\d{2}-\d{2}[ T]\d{2}:\d{2})|(commit [0-9a-f]{7,40})")


def strip_json(v):
    if isinstance(v, dict):
        return {k: strip_json(x) for k, x in v.items() if not VOLATILE_KEYS.match(k)}
    if isinstance(v, list):
        return [strip_json(x) for x in v]
    return v


CASE_NAMES = "|".join(re.escape(c[0]) for c in CASES)
BINARY_PATH = re.compile(rb"[^\s\"'`]*/apps/(netsolve|demsolve)\b")
CASE_PATH = re.compile(rb"[^\s\"'`]*/(" + CASE_NAMES.encode() + rb")/")


def normalised(path):
    name = os.path.basename(path)
    data = open(path, "rb").read()
    # the binaries' and the run root's absolute paths (in command.txt, summary.json, reports)
    data = CASE_PATH.sub(rb"<root>/\1/", BINARY_PATH.sub(rb"<bin>/\1", data))
    if name.endswith(".json"):
        try:
            return json.dumps(strip_json(json.loads(data)), sort_keys=True).encode()
        except ValueError:
            return data
    if name.endswith(".md"):
        out, skip = [], False
        for l in data.decode(errors="replace").splitlines():
            if l.startswith("#"):  # a section on timings is dropped whole, to the next heading
                skip = re.search(r"timing|run time|speed|performance", l, re.I) is not None
            elif l.startswith("!["):
                skip = False
            if not skip and not VOLATILE_MD.search(l):
                out.append(l)
        return "\n".join(out).encode()
    if name.endswith(".csv"):
        lines = data.decode(errors="replace").splitlines()
        head = next((i for i, l in enumerate(lines) if l and not l.startswith("#")), None)
        if head is None:
            return data
        cols = lines[head].split(",")
        drop = {i for i, c in enumerate(cols) if VOLATILE_COLUMNS.match(c.strip())}
        if not drop:
            return data
        out = lines[:head]
        for l in lines[head:]:
            if l.startswith("#"):
                out.append(l)
                continue
            f = l.split(",")
            out.append(",".join(x for i, x in enumerate(f) if i not in drop))
        return "\n".join(out).encode()
    return data


def is_state(name):
    return re.match(r"^(.*_)?state.*\.(txt|json|cbor)$", name) is not None


def run(build, root, only):
    root = os.path.abspath(root)
    os.makedirs(root, exist_ok=True)
    tools = {t: os.path.join(os.path.abspath(build), "apps", t) for t in ("netsolve", "demsolve")}
    for t, p in tools.items():
        if not os.access(p, os.X_OK):
            sys.exit(f"default_outputs: no executable {p}")
    log = open(os.path.join(root, "runs.txt"), "a")
    for name, tool, args in CASES:
        if only and name not in only:
            continue
        out = os.path.join(root, name)
        if os.path.exists(os.path.join(out, "command.txt")) or os.path.exists(os.path.join(out, ".incomplete")):
            args_over = ["--overwrite"]
        else:
            args_over = []
        argv = [tools[tool]] + [a.format(out=out, root=root) for a in args] + ["--out", name] + args_over
        t0 = time.time()
        r = subprocess.run(argv, cwd=root, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        dt = time.time() - t0
        msg = f"{name}: exit {r.returncode} in {dt:.1f} s"
        print(msg, file=sys.stderr)
        log.write(msg + "\n")
        if r.returncode not in (0, 3):
            log.write(r.stderr[-2000:] + "\n")
            print(r.stderr[-2000:], file=sys.stderr)
    log.close()
    write_manifest(root)


def write_manifest(root):
    rows = []
    for case in sorted(os.listdir(root)):
        d = os.path.join(root, case)
        if not os.path.isdir(d):
            continue
        for base, _, files in os.walk(d):
            for f in sorted(files):
                if f == ".incomplete":
                    continue
                p = os.path.join(base, f)
                rel = os.path.relpath(p, root)
                h = "state" if is_state(f) else hashlib.sha256(normalised(p)).hexdigest()
                rows.append(f"{h}  {rel}")
    with open(os.path.join(root, "manifest.txt"), "w") as m:
        m.write("\n".join(sorted(rows, key=lambda r: r.split("  ", 1)[1])) + "\n")
    print(f"default_outputs: {len(rows)} files in {root}/manifest.txt", file=sys.stderr)


def load(root):
    m = {}
    for line in open(os.path.join(root, "manifest.txt")):
        h, rel = line.rstrip("\n").split("  ", 1)
        m[rel] = h
    return m


def first_diff(a, b):
    la, lb = a.decode(errors="replace").splitlines(), b.decode(errors="replace").splitlines()
    for i, (x, y) in enumerate(zip(la, lb)):
        if x != y:
            return f"line {i + 1}:\n    A: {x[:200]}\n    B: {y[:200]}"
    return f"lengths {len(la)} and {len(lb)} lines"


def compare(ra, rb):
    a, b = load(ra), load(rb)
    bad = 0
    for rel in sorted(set(a) | set(b)):
        if rel not in a or rel not in b:
            print(f"only in {'A' if rel in a else 'B'}: {rel}")
            bad += 1
        elif a[rel] != b[rel]:
            print(f"differs: {rel}: " + first_diff(normalised(os.path.join(ra, rel)), normalised(os.path.join(rb, rel))))
            bad += 1
    same = sum(1 for r in a if r in b and a[r] == b[r] and a[r] != "state")
    print(f"default_outputs: {same} files identical, {bad} different or missing, "
          f"{sum(1 for r in a if a[r] == 'state')} state files not compared")
    return 1 if bad else 0


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "run":
        only = set()
        if "--only" in sys.argv:
            only = set(sys.argv[sys.argv.index("--only") + 1].split(","))
        run(sys.argv[2], sys.argv[3], only)
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
