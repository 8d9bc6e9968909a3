#!/usr/bin/python3
"""Robustness campaign of issue 13 (item 6): both tools tried as a hostile new user would.

From a fresh build, about 1,500 bad inputs are generated systematically and each is run once with a
timeout:

* every numeric option of every subcommand (found by parsing each subcommand's --help, plus the
  table EXTRA_OPTIONS below) gets each value of BAD_VALUES: 0, -1, 1e-300, 4.9e-324, 1e300, inf,
  -inf, nan, '', 'abc' and huge integers;
* demsolve's --param NAME=VALUE gets every Table 1 name with a subset of those values;
* the packing reader (netsolve compact/yield --packing, demsolve prepare --packing), netsolve's
  state reader (yield --from-state) and demsolve's state reader (sinter/compress/vibrate --state)
  get mutated copies of valid files written by the tools themselves at the start of the campaign:
  truncation, one field set to each bad value, swapped lines, duplicated lines, binary garbage, a
  directory, a missing file, an empty file;
* the reproducers of issue 13.

Each run is classified (CATEGORIES). The script writes into --out:
  categories.md / categories.csv   counts per tool, subcommand and category
  failures.md / failures.csv       every run in a failure category, with its command line
  runs.csv                         every run: id, tool, subcommand, kind, category, rc, seconds, command
and exits 1 if any crash, hang or NaN-with-exit-0 occurred (0 otherwise; 2 for a bad invocation).

usage:
  /usr/bin/python3 tests/campaign/run_campaign.py --netsolve build/apps/netsolve --demsolve build/apps/demsolve \
      --out results/campaign --jobs 2 [--timeout 20] [--filter REGEX] [--limit N] [--list]

Python standard library only. Runs are small (W = 20 packings, 20-disk DEM samples, short times)
so that the whole campaign takes about 10-15 minutes on 2 cores. Nothing outside --out is written.
"""
import argparse
import concurrent.futures
import csv
import fnmatch
import json
import math
import os
import platform
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import surfaces27  # noqa: E402  (the surfaces of issue 27: sinter, sinter-pair, pack --dim 3, demsolve 3D, run folders)

# ---- the bad values of every numeric option and field -------------------------------------------
BAD_VALUES = ["0", "-1", "1e-300", "4.9e-324", "1e300", "inf", "-inf", "nan", "", "abc",
              "2147483648", "18446744073709551616", "1" + "0" * 40]
# a subset for the many --param names and state-file fields
FIELD_VALUES = ["0", "-1", "1e-300", "4.9e-324", "1e300", "inf", "nan", "abc", ""]
PARAM_VALUES = ["0", "-1", "1e-300", "1e300", "inf", "nan", "abc"]

# numeric options whose --help type is TEXT (a number, or a list of numbers), per tool and subcommand
EXTRA_OPTIONS = {
    ("netsolve", "compact"): ["--friction", "--snapshots"],
    ("netsolve", "yield"): ["--friction"],
    ("netsolve", "sinter-pair"): ["--radii"],
}
# options never varied: output, inputs varied by the file mutations, parallelism (--jobs 0 = all cores)
SKIP_OPTIONS = {"--out", "--help", "-h", "--packing", "--state", "--from-state", "--profile", "--probe-worker",
                "--material", "--set", "--param"}

# Table 1 names of demsolve --param (src/dynamic: kFields)
PARAM_NAMES = ["k2", "k1_ratio", "kc_ratio", "alpha", "gamma_n", "gamma_t", "mu", "mu_wall", "T_melt", "T_var",
               "da_T", "delta_fluid_rel", "t0", "t0_sinter", "a0", "w0", "h", "rho_p", "m_wall", "gamma_wall",
               "T_radius_ref", "stiffness_growth", "sliding_breaks_cohesion", "cooling_stiffness_update",
               "wall_sintering"]

CATEGORIES = [
    ("clear_error", "clear error: exit 1 or 2, one stderr line, no output folder or one marked .incomplete"),
    ("fine", "fine run: exit 0, summary.json present, no NaN/inf in any CSV/JSON/txt output"),
    ("flagged", "untrustworthy run correctly flagged: exit 3 with a status in summary.json"),
    ("crash", "crash: killed by a signal"),
    ("hang", "hang: still running at the timeout"),
    ("nan_exit0", "NaN or inf in the output with exit 0"),
    ("unclear_error", "unclear error: non-zero exit with several stderr lines, raw exception text, or an unmarked folder"),
    ("no_summary", "exit 0 without summary.json"),
    ("exit3_no_status", "exit 3 without a status in summary.json"),
    ("wrong", "wrong result: contradicts the documented answer (exit status, status, a kept file, a refused folder)"),
]
FAILURES = {"crash", "hang", "nan_exit0", "unclear_error", "no_summary", "exit3_no_status", "wrong"}
FATAL = {"crash", "hang", "nan_exit0"}

RAW_EXCEPTION = re.compile(r"bad_alloc|what\(\)|terminate called|std::|basic_string|stoi|stod|Segmentation|Aborted|"
                           r"Assertion|--help for more|Run with --help")
TEXT_KEYS = {"name", "source"}  # JSON strings a user chooses (a material's name, a file name): "nan" there is text
NONFINITE = re.compile(r"(?<![A-Za-z0-9_.])[-+]?(nan|inf|infinity)(?![A-Za-z0-9_])", re.IGNORECASE)

# small base command lines: each varied option replaces its value here or is appended
BASE = {
    ("netsolve", "pack"): ["pack", "--width", "20"],
    ("netsolve", "compact"): ["compact", "--width", "20", "--increments", "20", "--to-density", "0.84", "--quiet"],
    ("netsolve", "yield"): ["yield", "--width", "20", "--increments", "20", "--to-density", "0.82", "--directions", "2",
                            "--jobs", "1", "--quiet"],
    ("netsolve", "sinter-pair"): ["sinter-pair", "--time", "100", "--quiet"],
    ("demsolve", "prepare"): ["prepare", "--n", "20", "--time", "0.002", "--quiet"],
    ("demsolve", "sinter"): ["sinter", "--state", "{dem_state}", "--t-heat", "0", "--heat-time", "0.001",
                             "--sinter-time", "0.001", "--cool-time", "0.001", "--relax-time", "0.001", "--quiet"],
    ("demsolve", "compress"): ["compress", "--state", "{dem_state}", "--max-strain", "0.002", "--quiet"],
    ("demsolve", "vibrate"): ["vibrate", "--state", "{dem_state}", "--time", "0.001", "--quiet"],
}


def parse_help(text):
    """Numeric options of a CLI11 --help text: [(name, type, default)]."""
    out = []
    for line in text.splitlines():
        m = re.match(r"^\s+(?:-\w,)?(--[\w-]+)(?:\s+(\S+))?(?:\s+\[([^\]]*)\])?", line)
        if not m:
            continue
        name, typ, default = m.group(1), (m.group(2) or ""), (m.group(3) or "")
        if re.search(r"FLOAT|INT|UINT|NUMBER", typ):
            out.append((name, typ, default))
    return out


def with_option(base, name, value):
    """base with --name set to value (replaced if present, else appended)."""
    cmd = list(base)
    if name in cmd:
        k = cmd.index(name)
        if k + 1 < len(cmd) and not cmd[k + 1].startswith("--"):
            cmd[k + 1] = value
            return cmd
        cmd.insert(k + 1, value)
        return cmd
    return cmd + [name, value]


# ---- one run --------------------------------------------------------------------------------------
# JSON nulls written on purpose, per subcommand: patterns (fnmatch) of the dotted keys of walk_json,
# each documented where named. The rule "null in the valid base run" (null_keys) misses the nulls
# that the base run does not produce (a viscosity is infinite only for a vanishing diffusivity).
DOCUMENTED_NULLS = {
    # docs/sintering_pair.md "summary.json": viscosity and viscosity_bouvard_mcmeeking are null when infinite
    ("netsolve", "sinter-pair"): ("at.*.viscosity", "at.*.viscosity_bouvard_mcmeeking", "final.viscosity",
                                  "final.viscosity_bouvard_mcmeeking"),
    # docs/packing.md (green-body route): density.bulk for a window under one diameter,
    # compression.limit_density when the mean overlap never passed --max-overlap
    ("netsolve", "pack --dim 3"): ("density.bulk", "compression.limit_density"),
}


def null_allowed(key, null_ok):
    """A null under `key` is documented: the key is in null_ok, or matches one of its patterns (with '*')."""
    return key in null_ok or any("*" in p and fnmatch.fnmatchcase(key, p) for p in null_ok)


def null_ok_for(nulls, tool, sub):
    """The documented nulls of a run: those of its subcommand's base run (null_keys) and DOCUMENTED_NULLS;
    for the run folders (every tool) all of them."""
    if sub == "run folders":
        return set().union(*nulls.values(), *DOCUMENTED_NULLS.values())
    return nulls.get((tool, sub), set()) | set(DOCUMENTED_NULLS.get((tool, sub), ()))


def scan_outputs(folder, null_ok):
    """Non-finite values in the folder's CSV/JSON/txt files (command.txt excepted): list of 'file: token'."""
    bad = []
    for root, _dirs, files in os.walk(folder):
        for f in sorted(files):
            p = os.path.join(root, f)
            rel = os.path.relpath(p, folder)
            if f == "command.txt" or not f.endswith((".csv", ".json", ".txt")):
                continue
            try:
                with open(p, "r", errors="replace") as fh:
                    text = fh.read(50_000_000)
            except OSError:
                continue
            if f.endswith(".json") or (f.startswith("state") and text.startswith("{")):  # state*.txt: JSON too
                try:
                    j = json.loads(text)
                except ValueError:
                    bad.append(f"{rel}: not valid JSON")
                    continue
                for key, v in walk_json(j):
                    if isinstance(v, float) and not math.isfinite(v):
                        bad.append(f"{rel}: {key} = {v}")
                    elif v is None and not null_allowed(key, null_ok):
                        bad.append(f"{rel}: {key} = null")
                    elif isinstance(v, str) and v.lower() in ("nan", "-nan") and key.split(".")[-1] not in TEXT_KEYS:
                        bad.append(f"{rel}: {key} = '{v}'")
            else:
                lines = text.splitlines()
                status_col = None  # a CSV with a 'status' column: NaN in a row that says why is documented
                if f.endswith(".csv") and lines:
                    head = next(csv.reader([lines[0]]))
                    status_col = head.index("status") if "status" in head else None
                for lineno, line in enumerate(lines, 1):
                    if line.startswith("#"):
                        continue
                    if status_col is not None and lineno > 1:
                        row = next(csv.reader([line]))
                        if len(row) > status_col and row[status_col] not in ("ok", ""):
                            continue
                    m = NONFINITE.search(line)
                    if m:
                        bad.append(f"{rel}:{lineno}: {m.group(0)}")
                        break
    return bad


def walk_json(j, key=""):
    if isinstance(j, dict):
        for k, v in j.items():
            yield from walk_json(v, f"{key}.{k}" if key else k)
    elif isinstance(j, list):
        for v in j:
            yield from walk_json(v, key + "[]")
    else:
        yield key, j


def run_one(task):
    """task: dict(id, tool, sub, kind, exe, args, out, timeout, null_ok). Returns the result dict."""
    out = task["out"]
    args = [a.replace("{out}", out) for a in task["args"]]
    if task.get("add_out", True):
        args = args + ["--out", out]
    cmd = [task["exe"]] + args
    t0 = time.monotonic()
    res = dict(id=task["id"], tool=task["tool"], sub=task["sub"], kind=task["kind"], cmd=cmd)
    mem = task["mem_bytes"]
    ctx = surfaces27.before_run(task)

    def limits():  # own session (killed as a group), and an address-space cap that protects the machine
        if mem:
            resource.setrlimit(resource.RLIMIT_AS, (mem, mem))

    p = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         cwd=task["cwd"], start_new_session=True, preexec_fn=limits)
    try:
        _stdout, stderr = p.communicate(timeout=task["timeout"])
        rc = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)  # the session's children (yield probe workers) go too
        _stdout, stderr = p.communicate()
        rc = None
    res["seconds"] = round(time.monotonic() - t0, 3)
    res["rc"] = rc
    err = stderr.decode("utf-8", "replace")
    chk = task.get("out_check", out).replace("{out}", out)  # the --out of the run
    exists0 = os.path.exists(chk)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    res["stderr"] = (lines[0][:300] if lines else "") + (f" (+{len(lines) - 1} lines)" if len(lines) > 1 else "")
    res["stderr_bytes"] = len(stderr)
    exists = os.path.exists(chk)
    marked = exists and os.path.exists(os.path.join(chk, ".incomplete"))
    status = None
    if exists and os.path.isfile(os.path.join(chk, "summary.json")):
        try:
            with open(os.path.join(chk, "summary.json")) as fh:
                status = json.load(fh).get("status", "(no status)")
        except (ValueError, OSError, AttributeError):
            status = "(unreadable summary.json)"
    res["status"] = status
    wrong = surfaces27.after_run(task, res, ctx, err)
    exists = exists and not res["untouched"]  # a prepared --out the run left as it was is not its folder
    detail = ""
    if rc is None:
        cat = "hang"
        detail = f"timeout {task['timeout']} s"
    elif rc < 0:
        cat = "crash"
        detail = f"signal {-rc}"
    elif rc == 0:
        bad = scan_outputs(chk, task["null_ok"]) if exists0 and os.path.isdir(chk) else []
        if bad:
            cat = "nan_exit0"
            detail = "; ".join(bad[:3])
        elif status is None:
            cat = "no_summary"
        else:
            cat = "fine"
    elif rc == 3:
        # "unreachable": pack --route green-body's documented exit 3 (README, docs/packing.md)
        cat = "flagged" if status in ("unconverged", "unstable", "incomplete", "unreachable") else "exit3_no_status"
    elif rc in (1, 2):
        why = []
        if len(lines) != 1:
            why.append(f"{len(lines)} stderr lines")
        if RAW_EXCEPTION.search(err):
            why.append("raw exception/parser text")
        if len(stderr) > 600:
            why.append(f"{len(stderr)} bytes on stderr")
        if any(ord(c) < 32 and c not in "\n\t" for c in err):
            why.append("control characters on stderr")
        if exists and not marked and rc == 2:
            why.append("output folder written for a refused command line")
        if exists and not marked and rc == 1 and not os.path.isfile(os.path.join(chk, "summary.json")):
            why.append("unmarked partial output folder")
        cat = "unclear_error" if why else "clear_error"
        detail = ", ".join(why)
    else:
        cat = "unclear_error"
        detail = f"exit status {rc}"
    if wrong and cat in ("clear_error", "fine", "flagged"):
        cat, detail = "wrong", "; ".join(wrong)
    res["category"] = cat
    res["detail"] = detail
    if cat in ("clear_error", "fine", "flagged") and os.path.isdir(out) and not task.get("keep"):
        shutil.rmtree(out, ignore_errors=True)  # keep the disk small; failures keep their folder
    return res


# ---- the valid files the mutations start from --------------------------------------------------------
def must_run(cmd, cwd, what, timeout=300, ok=(0,)):
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    if p.returncode not in ok:
        sys.exit(f"run_campaign: the base run for {what} failed (exit {p.returncode}): {' '.join(cmd)}\n"
                 f"{p.stderr.decode(errors='replace')[-2000:]}")
    return p


def make_bases(a, work):
    """Valid inputs written by the tools themselves; returns a dict of paths."""
    b = {}
    base = os.path.join(work, "base")
    os.makedirs(base, exist_ok=True)
    if a.netsolve:
        must_run([a.netsolve, "pack", "--width", "20", "--out", os.path.join(base, "pack")], work, "the W20 packing")
        b["packing"] = os.path.join(base, "pack", "packing.csv")
        must_run([a.netsolve, "compact", "--width", "20", "--increments", "20", "--to-density", "0.82", "--quiet",
                  "--save-state", "--out", os.path.join(base, "compact")], work,
                 "the netsolve state")
        b["ns_state"] = os.path.join(base, "compact", "state.txt")
        with open(os.path.join(base, "profile.csv"), "w") as fh:
            fh.write("time,T\n0,1000\n100,1200\n")
        b["profile"] = os.path.join(base, "profile.csv")
    if a.demsolve:
        must_run([a.demsolve, "prepare", "--n", "20", "--time", "0.002", "--quiet", "--out",
                  os.path.join(base, "prepare")], work, "the demsolve state", ok=(0, 3))
        cand = [f for f in os.listdir(os.path.join(base, "prepare")) if f.startswith("state") and f.endswith(".txt")]
        if not cand:
            sys.exit("run_campaign: demsolve prepare wrote no state*.txt")
        b["dem_state"] = os.path.join(base, "prepare", "state.txt" if "state.txt" in cand else sorted(cand)[0])
    return surfaces27.make_bases(a, work, b, must_run)


def null_keys(a, work, bases):
    """JSON keys that are null in a valid run of each subcommand: documented nulls, not NaN."""
    keys = {}
    runs = list(BASE.items())
    if "ns_state" in bases:  # yield from a state file: no precompaction, its keys are null
        runs.append((("netsolve", "yield"), ["yield", "--directions", "2", "--jobs", "1", "--quiet", "--from-state",
                                             bases["ns_state"]]))
    runs += [((t, s), args) for t, s, args in surfaces27.null_runs(bases)]
    for n, ((tool, sub), base) in enumerate(runs):
        exe = getattr(a, tool)
        if not exe:
            continue
        out = os.path.join(work, "base", f"null_{n}")
        cmd = [exe] + [x.format(**bases) for x in base] + ["--out", out]
        subprocess.run(cmd, cwd=work, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
        ks = set()
        for root, _d, files in os.walk(out) if os.path.isdir(out) else []:
            for f in files:
                if f.endswith(".json") or (f.startswith("state") and f.endswith(".txt")):
                    try:
                        with open(os.path.join(root, f)) as fh:
                            ks |= {k for k, v in walk_json(json.load(fh)) if v is None}
                    except (ValueError, OSError):
                        pass
        keys[(tool, sub)] = keys.get((tool, sub), set()) | ks
    return keys


# ---- mutations of a text file -------------------------------------------------------------------------
def split_fields(line):
    """(separator, fields) of a data line: comma- or space-separated."""
    if "," in line:
        return ",", line.split(",")
    return " ", line.split(" ")


def field_mutations(name, lines, li, limit, values):
    """Copies of `lines` with each of the first `limit` (None: all) numeric fields of line li set to each value."""
    sep, f = split_fields(lines[li])
    idx = [k for k in range(len(f)) if re.fullmatch(r"[-+0-9.eE]+", f[k].strip())][:limit]
    out = []
    for k in idx:
        for v in values:
            g = list(f)
            g[k] = v
            m = list(lines)
            m[li] = sep.join(g)
            out.append((f"{name}: line {li + 1} field {k + 1} = '{v}'", ("\n".join(m) + "\n").encode()))
    return out


def mutate_text(text, name, lines_to_vary, fields_per_line, values, rng):
    """Mutated copies of `text`: [(label, bytes)]."""
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    body = "\n".join(lines) + "\n"
    muts = []
    n = len(body)
    for frac in (0.0, 0.01, 0.1, 0.5, 0.9, 0.999):
        muts.append((f"{name}: truncated at {frac:.1%} of its bytes", body[: int(n * frac)].encode()))
    muts.append((f"{name}: last line cut in the middle", body[: n - max(2, len(lines[-1]) // 2)].encode()))
    for li in lines_to_vary:
        if li >= len(lines):
            continue
        muts += field_mutations(name, lines, li, fields_per_line, values)
    data = [k for k, ln in enumerate(lines) if ln and ln[0].isdigit()]
    first = data[0] if data else 1
    pairs = [(0, 1), (0, first), (first, first + 1), (first, len(lines) - 1)]
    for i, j in pairs:
        if i < len(lines) and j < len(lines) and i != j:
            m = list(lines)
            m[i], m[j] = m[j], m[i]
            muts.append((f"{name}: lines {i + 1} and {j + 1} swapped", ("\n".join(m) + "\n").encode()))
    for i in sorted({0, 1, first, first + 1, len(lines) - 1}):
        if i < len(lines):
            m = list(lines)
            m.insert(i, lines[i])
            muts.append((f"{name}: line {i + 1} duplicated", ("\n".join(m) + "\n").encode()))
    m = list(lines)
    m[first:first] = lines[first:first + 5]
    muts.append((f"{name}: 5 data lines duplicated", ("\n".join(m) + "\n").encode()))
    muts.append((f"{name}: 4 kB of random bytes", bytes(rng.randrange(256) for _ in range(4096))))
    muts.append((f"{name}: a 5 MB binary first line", bytes(rng.randrange(1, 256) for _ in range(5_000_000)) + b"\n" + body.encode()))
    muts.append((f"{name}: NUL bytes inside a data line",
                 ("\n".join(lines[:first]) + "\n").encode() + lines[first].encode()[:3] + b"\0\0\0" +
                 lines[first].encode()[3:] + b"\n" + ("\n".join(lines[first + 1:]) + "\n").encode()))
    muts.append((f"{name}: random bytes appended", body.encode() + bytes(rng.randrange(256) for _ in range(512))))
    muts.append((f"{name}: Windows line ends", body.replace("\n", "\r\n").encode()))
    muts.append((f"{name}: no final newline", body[:-1].encode()))
    muts.append((f"{name}: empty file", b""))
    muts.append((f"{name}: only the header", ("\n".join(lines[:first]) + "\n").encode()))
    muts.append((f"{name}: blank lines between the data lines", body.replace("\n", "\n\n").encode()))
    return muts


def packing_reproducers(text):
    """The packing reproducers of issue 13: [(label, bytes)]."""
    lines = text.rstrip("\n").split("\n")
    hdr = [ln for ln in lines if not (ln and ln[0].isdigit())]
    data = [ln.split(",") for ln in lines if ln and ln[0].isdigit()]
    box_i = next(k for k, ln in enumerate(hdr) if ln.startswith("# box"))
    out = []

    def build(h, rows):
        return ("\n".join(h) + "\n" + "\n".join(",".join(r) for r in rows) + "\n").encode()

    for v in ("1e-300", "4.9e-324", "0", "1e300"):
        out.append((f"packing: every radius = {v}", build(hdr, [r[:3] + [v] for r in data])))
    rows = [list(r) for r in data]
    rows[len(rows) // 2][3] = "4.9e-324"
    out.append(("packing: one radius = 4.9e-324 (issue: hang in peripheral_layer)", build(hdr, rows)))
    h = list(hdr)
    h[box_i] = "# box 0 0 2e300 2e300"
    out.append(("packing: box 2e300, coordinates x 1e299 (issue: SIGSEGV)",
                build(h, [[r[0], repr(float(r[1]) * 1e299), repr(float(r[2]) * 1e299), r[3]] for r in data])))
    out.append(("packing: 99 unit disks stacked 1e-9 apart",
                build(["# box 0 0 10 200", "id,x,y,r"], [[str(k), "5", repr(1.0 + k * 1e-9), "1"] for k in range(99)])))
    rng = random.Random(7)
    near = [[str(k), repr(10 + rng.uniform(0, 1e-10)), repr(10 + rng.uniform(0, 1e-10)), "1"] for k in range(100000)]
    out.append(("packing: 1e5 disks within 1e-10 of each other (issue: hang)", build(["# box 0 0 20 20", "id,x,y,r"], near)))
    out.append(("packing: one disk far outside the box", build(hdr, data[:-1] + [[data[-1][0], "1e6", "1e6", data[-1][3]]])))
    out.append(("packing: r_max/r_min = 1e6", build(hdr, [data[0][:3] + ["1e-6"]] + data[1:])))
    out.append(("packing: box of zero size", build(["# box 0 0 0 0"], data)))
    return out


def dem_state_reproducers(text):
    """The state-file reproducers of issue 13 for demsolve (the state archive, docs/dynamic.md): [(label, bytes)]."""
    good = json.loads(text)

    def mutated(label, edit):
        j = json.loads(json.dumps(good))
        edit(j)
        return (label, (json.dumps(j, separators=(",", ":")) + "\n").encode())

    def wall_mass_zero(j):
        for w in j["moving_walls"]:
            if w["mode"] == "stress":
                w["mass"] = 0.0

    def same_position(j):
        p = j["particles"]
        p["x"][1], p["y"][1] = p["x"][0], p["y"][0]

    def column(name, value):
        def edit(j):
            j["particles"][name][0] = value
        return edit

    return [mutated("dem state: stress-controlled wall with mass 0", wall_mass_zero),
            mutated("dem state: two particles at the same position", same_position),
            mutated("dem state: a particle far outside the box", column("x", 1e3)),
            mutated("dem state: radius 1e300", column("radius", 1e300)),
            mutated("dem state: velocity vx 1e300", column("vx", 1e300))]


# ---- the task list ------------------------------------------------------------------------------------
def build_tasks(a, work, bases):
    tasks = []
    inputs = os.path.join(work, "inputs")
    os.makedirs(inputs, exist_ok=True)
    rng = random.Random(13)
    nulls = null_keys(a, work, bases)

    def add(tool, sub, kind, args, add_out=True, timeout=None):
        exe = getattr(a, tool)
        if not exe:
            return None
        tid = len(tasks)
        ok = null_ok_for(nulls, tool, sub)
        tasks.append(dict(id=tid, tool=tool, sub=sub, kind=kind, exe=exe, args=args, add_out=add_out,
                          out=os.path.join(work, "runs", f"{tid:05d}"), timeout=timeout or a.timeout, cwd=work,
                          mem_bytes=int(a.mem_limit_gb * 2**30), null_ok=ok))
        return tasks[-1]

    # 1. every numeric option of every subcommand x BAD_VALUES
    for (tool, sub), base in BASE.items():
        exe = getattr(a, tool)
        if not exe:
            continue
        base = [x.format(**bases) for x in base]
        h = subprocess.run([exe, sub, "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=30)
        opts = [o for o, _t, _d in parse_help(h.stdout.decode(errors="replace")) if o not in SKIP_OPTIONS]
        opts += [o for o in EXTRA_OPTIONS.get((tool, sub), []) if o not in opts]
        add(tool, sub, "base run", base)
        for o in opts:
            for v in BAD_VALUES:
                add(tool, sub, f"option {o}", with_option(base, o, v))
        if tool == "demsolve" and sub in ("prepare", "compress"):
            for pn in PARAM_NAMES:
                for v in PARAM_VALUES if sub == "prepare" else PARAM_VALUES[::2]:
                    add(tool, sub, "option --param", base + ["--param", f"{pn}={v}"])

    # 2. the readers: mutated copies of valid files
    written = [0]

    def write(label, data):
        written[0] += 1
        p = os.path.join(inputs, f"{written[0]:05d}.txt")
        with open(p, "wb") as fh:
            fh.write(data)
        return p

    special = [("a directory", inputs), ("a missing file", os.path.join(inputs, "no_such_file.csv")),
               ("/dev/null", "/dev/null")]
    if "packing" in bases:
        with open(bases["packing"]) as fh:
            ptext = fh.read()
        plines = ptext.rstrip("\n").split("\n")
        first = next(k for k, ln in enumerate(plines) if ln and ln[0].isdigit())
        vary = [k for k, ln in enumerate(plines) if ln.startswith("# box")] + [first, len(plines) - 1]
        muts = mutate_text(ptext, "packing", [], 0, FIELD_VALUES, rng)
        for li in vary:  # '# box a b c d' and two data lines: every numeric field x every value
            muts += field_mutations("packing", plines, li, None, BAD_VALUES)
        muts += packing_reproducers(ptext)
        cbase = ["compact", "--increments", "20", "--to-density", "0.84", "--quiet", "--packing"]
        for label, data in muts:
            add("netsolve", "compact", "packing file", cbase + [write(label, data)])
            tasks[-1]["label"] = label
        for label, p in special:
            add("netsolve", "compact", "packing file", cbase + [p])
            tasks[-1]["label"] = "packing: " + label
        add("netsolve", "compact", "packing file", cbase[:-1] + ["--packing", ""])
        tasks[-1]["label"] = "packing: --packing ''"
        # the same reader through yield and demsolve prepare: a sample of the mutations
        ybase = ["yield", "--increments", "20", "--to-density", "0.82", "--directions", "2", "--jobs", "1", "--quiet",
                 "--packing"]
        dbase = ["prepare", "--time", "0.002", "--quiet", "--packing"]
        for label, data in muts[::6] + packing_reproducers(ptext)[:6]:
            p = write(label, data)
            add("netsolve", "yield", "packing file", ybase + [p])
            tasks[-1]["label"] = label
            add("demsolve", "prepare", "packing file", dbase + [p])
            tasks[-1]["label"] = label
        for label, p in special[:2]:
            add("demsolve", "prepare", "packing file", dbase + [p])
            tasks[-1]["label"] = "packing: " + label
        add("demsolve", "prepare", "packing file", dbase[:-1] + ["--packing", ""])
        tasks[-1]["label"] = "packing: --packing ''"

    # the state archives (one JSON line since issue 26): every member, the first and last particle rows
    if "ns_state" in bases:
        with open(bases["ns_state"]) as fh:
            stext = fh.read()
        sbase = ["yield", "--directions", "2", "--jobs", "1", "--quiet", "--from-state"]
        for label, data in surfaces27.json_mutations(stext, "netsolve state", rng):
            add("netsolve", "yield", "state file", sbase + [write(label, data)])["label"] = label
        for label, p in special[:3]:
            add("netsolve", "yield", "state file", sbase + [p])["label"] = "netsolve state: " + label

    if "dem_state" in bases:
        with open(bases["dem_state"]) as fh:
            dtext = fh.read()
        muts = surfaces27.json_mutations(dtext, "dem state", rng) + dem_state_reproducers(dtext)
        subs = ["compress", "vibrate", "sinter"]
        for n, (label, data) in enumerate(muts):
            base = [x.format(**bases) for x in BASE[("demsolve", subs[n % 3])]]
            add("demsolve", subs[n % 3], "state file", with_option(base, "--state", write(label, data)))["label"] = label
        for sub in subs:
            base = [x.format(**bases) for x in BASE[("demsolve", sub)]]
            for label, p in special[:3]:
                add("demsolve", sub, "state file", with_option(base, "--state", p))["label"] = "dem state: " + label

    # 3. the command-line reproducers of issue 13 and hostile command lines
    st = bases.get("dem_state", "")
    repro = [
        ("netsolve", "other", ["frobnicate"]),
        ("netsolve", "pack", ["pack", "--width", "1e20"]),
        ("netsolve", "pack", ["pack", "--width", "1e308"]),
        ("netsolve", "pack", ["pack", "--width", "1e7"]),
        ("netsolve", "pack", ["pack", "--seed", "-1"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--increments", "10", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--path", "1,-1,0", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--path", "nan,nan,nan", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--path", "0,0,0", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--path", "1,1,0", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--to-density", "0.5", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--normal-unloading", "abc", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--bogus-option", "1", "--quiet"]),
        ("netsolve", "compact", ["compact", "--width", "20", "--quiet", "--out", "/proc/forbidden/x"]),
        ("netsolve", "yield-merge", ["yield-merge", os.path.join(work, "no_such_dir")]),
        ("netsolve", "yield-merge", ["yield-merge", inputs]),
        ("netsolve", "sinter-pair", ["sinter-pair", "--material", "no_such_material", "--quiet"]),
        ("netsolve", "sinter-pair", ["sinter-pair", "--set", "D_vol0=nan", "--quiet"]),
        ("netsolve", "sinter-pair", ["sinter-pair", "--set", "no_such_key=1", "--quiet"]),
        ("netsolve", "sinter-pair", ["sinter-pair", "--paths", "VI", "--quiet"]),
        ("netsolve", "sinter-pair", ["sinter-pair", "--profile", bases.get("profile", ""), "--time", "100", "--quiet"]),
        ("demsolve", "other", ["frobnicate"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--pressure", "1e12", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--pressure", "1e6", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--pressure", "1e5", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--pressure", "1e4", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--param", "gamma_n=100", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--param", "m_wall=1e-9", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--param", "gamma_wall=1e6", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--param", "k2=1e2", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "50", "--time", "0.02", "--param", "k1_ratio=1e-6", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--steps-per-contact", "inf", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--param", "rho_p=1e-300", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--param", "k2=1e300", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--seed", "-1", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--packing", "", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--param", "nonsense=1", "--quiet"]),
        ("demsolve", "prepare", ["prepare", "--n", "20", "--time", "0.002", "--param", "k2", "--quiet"]),
        ("demsolve", "sinter", ["sinter", "--state", st, "--t-heat", "0", "--heat-time", "0.001", "--sinter-time",
                                "0.001", "--cool-time", "0.001", "--relax-time", "0.001", "--T-hot", "1e6", "--quiet"]),
        ("demsolve", "sinter", ["sinter", "--state", st, "--t-heat", "0", "--heat-time", "0.001", "--sinter-time",
                                "0.001", "--cool-time", "0.001", "--relax-time", "0.001", "--T-hot", "-300", "--quiet"]),
        ("demsolve", "sinter", ["sinter", "--state", st, "--n", "7", "--seed", "3", "--t-heat", "0", "--heat-time",
                                "0.001", "--sinter-time", "0.001", "--cool-time", "0.001", "--relax-time", "0.001",
                                "--quiet"]),
        ("demsolve", "compress", ["compress", "--state", st, "--ramp-time", "1e9", "--quiet"]),
        ("demsolve", "compress", ["compress", "--state", st, "--strain-rate", "1e4", "--max-strain", "0.01", "--quiet"]),
        ("demsolve", "vibrate", ["vibrate", "--state", st, "--frequency", "1e12", "--time", "0.001", "--quiet"]),
    ]
    for tool, sub, args in repro:
        add(tool, sub, "reproducer", args, add_out="--out" not in args)
    surfaces27.PARAMS = PARAM_NAMES
    surfaces27.with_option, surfaces27.field_mutations, surfaces27.mutate_text = with_option, field_mutations, mutate_text
    surfaces27.add_tasks(a, work, bases, add, write, rng, BAD_VALUES)
    return tasks


def tally(results):
    rows = {}
    for r in results:
        key = (r["tool"], r["sub"])
        rows.setdefault(key, {c: 0 for c, _ in CATEGORIES})
        rows[key][r["category"]] += 1
    return dict(sorted(rows.items()))


def write_reports(a, results, wall, started):
    os.makedirs(a.out, exist_ok=True)
    rows = tally(results)
    cats = [c for c, _ in CATEGORIES]
    with open(os.path.join(a.out, "categories.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["tool", "subcommand", "inputs"] + cats)
        for (tool, sub), c in rows.items():
            w.writerow([tool, sub, sum(c.values())] + [c[k] for k in cats])
        tot = {k: sum(c[k] for c in rows.values()) for k in cats}
        w.writerow(["all", "all", sum(tot.values())] + [tot[k] for k in cats])
    heads = {"clear_error": "clear error", "fine": "fine", "flagged": "flagged (exit 3)", "crash": "crash",
             "hang": "hang", "nan_exit0": "NaN/inf exit 0", "unclear_error": "unclear error",
             "no_summary": "exit 0, no summary", "exit3_no_status": "exit 3, no status",
             "wrong": "wrong result"}
    md = ["| tool | subcommand | inputs | " + " | ".join(heads[k] for k in cats) + " |",
          "|---|---|---:|" + "---:|" * len(cats)]
    for (tool, sub), c in rows.items():
        md.append(f"| {tool} | {sub} | {sum(c.values())} | " + " | ".join(str(c[k]) for k in cats) + " |")
    for tool in sorted({t for t, _ in rows}):
        tt = {k: sum(c[k] for (t, _s), c in rows.items() if t == tool) for k in cats}
        md.append(f"| **{tool}** | **all** | **{sum(tt.values())}** | " + " | ".join(f"**{tt[k]}**" for k in cats) + " |")
    md.append(f"| **all** | | **{sum(tot.values())}** | " + " | ".join(f"**{tot[k]}**" for k in cats) + " |")
    legend = "\n".join(f"* {heads[c]}: {d}" for c, d in CATEGORIES)
    header = (f"Robustness campaign (tests/campaign/run_campaign.py), started {started}, {len(results)} runs in "
              f"{wall:.0f} s with --jobs {a.jobs}, timeout {a.timeout:g} s, on {platform.node()} "
              f"({platform.machine()}, {os.cpu_count()} cores).\n")
    with open(os.path.join(a.out, "categories.md"), "w") as fh:
        fh.write(header + "\n" + "\n".join(md) + "\n\n" + legend + "\n")
    fails = [r for r in results if r["category"] in FAILURES]
    with open(os.path.join(a.out, "failures.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["id", "tool", "subcommand", "kind", "input", "category", "rc", "seconds", "detail", "stderr", "command"])
        for r in fails:
            w.writerow([r["id"], r["tool"], r["sub"], r["kind"], r.get("label", ""), r["category"], r["rc"], r["seconds"],
                        r["detail"], r["stderr"], " ".join(shell_quote(x) for x in r["cmd"])])
    with open(os.path.join(a.out, "failures.md"), "w") as fh:
        fh.write(f"# Failures: {len(fails)} of {len(results)} runs\n\n")
        for cat in [c for c in cats if c in FAILURES]:
            sel = [r for r in fails if r["category"] == cat]
            if not sel:
                continue
            fh.write(f"## {heads[cat]} ({len(sel)})\n\n")
            for r in sel:
                lab = f" [{r['label']}]" if r.get("label") else ""
                fh.write(f"* {r['tool']} {r['sub']}, {r['kind']}{lab}: rc={r['rc']}, {r['seconds']} s"
                         f"{', ' + r['detail'] if r['detail'] else ''}; stderr: `{r['stderr'][:200]}`\n"
                         f"  `{' '.join(shell_quote(x) for x in r['cmd'])}`\n")
            fh.write("\n")
    with open(os.path.join(a.out, "runs.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["id", "tool", "subcommand", "kind", "input", "category", "rc", "status", "seconds", "detail",
                    "stderr", "command"])
        for r in results:
            w.writerow([r["id"], r["tool"], r["sub"], r["kind"], r.get("label", ""), r["category"], r["rc"],
                        r["status"], r["seconds"], r["detail"], r["stderr"], " ".join(shell_quote(x) for x in r["cmd"])])
    return "\n".join(md)


def shell_quote(s):
    if s == "":
        return "''"
    if re.fullmatch(r"[\w@%+=:,./-]+", s):
        return s
    return "'" + s.replace("'", "'\\''") + "'"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--netsolve", help="netsolve binary (leave out to skip netsolve)")
    ap.add_argument("--demsolve", help="demsolve binary (leave out to skip demsolve)")
    ap.add_argument("--out", default="campaign", help="output folder (runs/ and inputs/ go under it too)")
    ap.add_argument("--jobs", type=int, default=2, help="runs at the same time")
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds before a run counts as a hang")
    ap.add_argument("--mem-limit-gb", type=float, default=4.0,
                    help="address-space limit of each run (RLIMIT_AS; 0: none), so that a runaway run cannot take the machine")
    ap.add_argument("--filter", help="only the runs whose tool/subcommand/kind/label/command matches this regex")
    ap.add_argument("--limit", type=int, help="only the first N runs (after --filter)")
    ap.add_argument("--list", action="store_true", help="print the runs and stop")
    a = ap.parse_args()
    for t in ("netsolve", "demsolve"):
        p = getattr(a, t)
        if p:
            p = os.path.abspath(p)
            if not (os.path.isfile(p) and os.access(p, os.X_OK)):
                ap.error(f"--{t} {p} is not an executable file")
            setattr(a, t, p)
    if not (a.netsolve or a.demsolve):
        ap.error("give --netsolve and/or --demsolve")
    if a.jobs < 1 or not (a.timeout > 0):
        ap.error("--jobs must be >= 1 and --timeout > 0")
    a.out = os.path.abspath(a.out)
    work = a.out
    for sub in ("runs", "inputs", "base"):
        shutil.rmtree(os.path.join(work, sub), ignore_errors=True)
    os.makedirs(work, exist_ok=True)
    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    t0 = time.monotonic()
    bases = make_bases(a, work)
    tasks = build_tasks(a, work, bases)
    if a.filter:
        rx = re.compile(a.filter)
        tasks = [t for t in tasks if rx.search(" ".join([t["tool"], t["sub"], t["kind"], t.get("label", "")] + t["args"]))]
    if a.limit:
        tasks = tasks[: a.limit]
    if a.list:
        for t in tasks:
            print(t["id"], t["tool"], t["sub"], t["kind"], t.get("label", ""), " ".join(shell_quote(x) for x in t["args"]))
        print(f"{len(tasks)} runs")
        return 0
    os.makedirs(os.path.join(work, "runs"), exist_ok=True)
    print(f"run_campaign: {len(tasks)} runs, --jobs {a.jobs}, timeout {a.timeout:g} s", flush=True)
    results = []
    with concurrent.futures.ProcessPoolExecutor(max_workers=a.jobs) as pool:
        for n, r in enumerate(pool.map(run_one, tasks, chunksize=1), 1):
            results.append(r)
            if r["category"] in FAILURES:
                print(f"  [{n}/{len(tasks)}] {r['category']}: {r['tool']} {r['sub']} {r['kind']} {r.get('label', '')}",
                      flush=True)
            elif n % 100 == 0:
                print(f"  [{n}/{len(tasks)}] {time.monotonic() - t0:.0f} s", flush=True)
    for r, t in zip(results, tasks):
        if "label" in t:
            r["label"] = t["label"]
    wall = time.monotonic() - t0
    md = write_reports(a, results, wall, started)
    print(md)
    bad = sum(r["category"] in FATAL for r in results)
    print(f"run_campaign: {len(results)} runs in {wall:.0f} s; {bad} crashes/hangs/NaN-with-exit-0; reports in {a.out}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
