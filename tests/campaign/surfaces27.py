"""The surfaces of issue 27 for the robustness campaign (imported by run_campaign.py).

* netsolve sinter (3D staggered sintering): every numeric option x the 13 bad values on a 27-sphere
  lattice (both strategies), on --generate cu and on --restart; the 3D packing reader; the state
  archive of --restart (every member, every field of the first and last particle and contact rows,
  removed members, wrong lengths and types, truncation, garbage, the issue's reproducers);
* the material files (--material FILE, key = value text) and --set KEY=VALUE of sinter and
  sinter-pair; the temperature profiles (--profile) of both;
* sinter-pair: every numeric option with each of the other integrators (rk4, cvode, arkode),
  --radii pairs;
* pack --dim 3: ballistic (walls, periodic) and the green-body route;
* demsolve in 3D: prepare --dim 3 (with --param), sinter and compress on a 3D state, compact --dim 3
  (affine and walls), the 3D packing reader, and the state archive (2D and 3D) mutated as above;
* the run folders: --out a file, under a file, not writable, a folder with a user's file, a finished
  run with and without --overwrite, a stale .incomplete of a dead pid or of a reused pid, a folder
  held by a live run (a real run in the background) with and without --overwrite.

Some runs carry an expectation (the documented answer: the exit status, a status, a kept file, a
refused folder); a run that contradicts it is a wrong result ("wrong").
"""
import copy
import json
import os
import random
import re
import signal
import socket
import subprocess
import time

JSON_VALUES = [("0", "0"), ("-1", "-1"), ("1e-300", "1e-300"), ("4.9e-324", "4.9e-324"), ("1e300", "1e300"),
               ("inf", '"inf"'), ("-inf", '"-inf"'), ("nan", '"nan"'), ("NaN", "NaN"), ("''", '""'), ("abc", '"abc"'),
               ("2147483648", "2147483648"), ("18446744073709551616", "18446744073709551616"),
               ("1e40", "1" + "0" * 40), ("null", "null")]
SENTINEL = "@@hostile@@"
HERE = os.path.dirname(os.path.abspath(__file__))
MATERIALS = os.path.join(HERE, "..", "..", "src", "contact", "materials")


# ---- bases ------------------------------------------------------------------------------------------
def lattice_text(n=3, r=25e-6, s=49.95e-6):
    L = 2 * r + (n - 1) * s
    out = [f"# box 0 0 0 {L!r} {L!r} {L!r}", "# dim 3", "# seed 7", "id,x,y,z,r"]
    k = 0
    for i in range(n):
        for j in range(n):
            for m in range(n):
                out.append(f"{k},{r + i * s!r},{r + j * s!r},{r + m * s!r},{r!r}")
                k += 1
    return "\n".join(out) + "\n"


def make_bases(a, work, b, must_run):
    base = os.path.join(work, "base")
    if a.netsolve:
        b["lattice"] = os.path.join(base, "lattice.csv")
        with open(b["lattice"], "w") as fh:
            fh.write(lattice_text())
        must_run([a.netsolve, "sinter", "--packing", b["lattice"], "--time", "100", "--quiet", "--out",
                  os.path.join(base, "sinter")], work, "the netsolve sinter state")
        b["sn_state"] = os.path.join(base, "sinter", "state.txt")
        b["sn_summary"] = os.path.join(base, "sinter", "summary.json")
        with open(b["sn_state"]) as fh:  # a state without a record of origin (apps/scripts/convert_state.py
            j = json.load(fh)            # writes null for an old state without its summary.json)
        j["origin"] = None
        b["sn_state_no_origin"] = os.path.join(base, "state_no_origin.txt")
        with open(b["sn_state_no_origin"], "w") as fh:
            fh.write(dump(j))
        must_run([a.netsolve, "pack", "--dim", "3", "--width", "5", "--out", os.path.join(base, "pack3")], work,
                 "the 3D packing")
        b["packing3"] = os.path.join(base, "pack3", "packing.csv")
        with open(os.path.join(base, "profile_sn.csv"), "w") as fh:
            fh.write("time,T\n0,1293\n50,1300\n100,1300\n")
        b["profile_sn"] = os.path.join(base, "profile_sn.csv")
        for m in ("cu", "ti"):
            src = os.path.join(MATERIALS, f"{m}.txt")
            if os.path.isfile(src):
                b[f"mat_{m}"] = src
    if a.demsolve:
        must_run([a.demsolve, "prepare", "--dim", "3", "--n", "20", "--time", "0.002", "--quiet", "--out",
                  os.path.join(base, "prepare3")], work, "the 3D demsolve state", ok=(0, 3))
        b["dem3_state"] = os.path.join(base, "prepare3", "state.txt")
    return b


SINTER_T = ["--t-heat", "0", "--heat-time", "0.001", "--sinter-time", "0.001", "--cool-time", "0.001",
            "--relax-time", "0.001", "--quiet"]
# (tool, sub-label, the real subcommand, base, which options: None = all numeric ones of --help, or a list)
BASES = [
    ("netsolve", "sinter", "sinter", ["sinter", "--packing", "{lattice}", "--time", "100", "--quiet"], None),
    ("netsolve", "sinter", "sinter", ["sinter", "--packing", "{lattice}", "--time", "100", "--strategy", "1",
                                      "--quiet"], None),
    ("netsolve", "sinter", "sinter", ["sinter", "--generate", "cu", "--time", "10", "--quiet"],
     ["--green-density", "--seed"]),
    ("netsolve", "sinter", "sinter", ["sinter", "--restart", "{sn_state}", "--time", "150", "--quiet"],
     ["--time", "--snapshots", "--max-steps", "--checkpoints"]),
    ("netsolve", "sinter-pair", "sinter-pair", ["sinter-pair", "--time", "100", "--integrator", "rk4", "--quiet"], None),
    ("netsolve", "sinter-pair", "sinter-pair", ["sinter-pair", "--time", "100", "--integrator", "cvode", "--quiet"], None),
    ("netsolve", "sinter-pair", "sinter-pair", ["sinter-pair", "--time", "100", "--integrator", "arkode", "--quiet"], None),
    ("netsolve", "pack --dim 3", "pack", ["pack", "--dim", "3", "--width", "5"],
     ["--width", "--r-min", "--r-max", "--seed", "--dim"]),
    ("netsolve", "pack --dim 3", "pack", ["pack", "--dim", "3", "--width", "5", "--lateral", "periodic"],
     ["--width", "--r-min", "--r-max", "--seed"]),
    ("netsolve", "pack --dim 3", "pack", ["pack", "--dim", "3", "--route", "green-body", "--n", "30",
                                          "--target-density", "0.4", "--quiet"], None),
    ("demsolve", "prepare --dim 3", "prepare", ["prepare", "--dim", "3", "--n", "20", "--time", "0.002", "--quiet"], None),
    ("demsolve", "sinter --dim 3", "sinter", ["sinter", "--dim", "3", "--state", "{dem3_state}"] + SINTER_T, None),
    ("demsolve", "compress --dim 3", "compress", ["compress", "--state", "{dem3_state}", "--max-strain", "0.002",
                                                  "--quiet"], None),
    ("demsolve", "compact --dim 3", "compact", ["compact", "--dim", "3", "--width", "4", "--affine", "--increments", "5",
                                                "--to-density", "0.6", "--inertial-number", "1e-3", "--quiet"], None),
    ("demsolve", "compact --dim 3", "compact", ["compact", "--dim", "3", "--width", "4", "--boundary", "walls",
                                                "--increments", "5", "--to-density", "0.6", "--inertial-number", "1e-3",
                                                "--quiet"], None),
]
EXTRA = {("netsolve", "sinter"): ["--checkpoints"], ("netsolve", "sinter-pair"): ["--radii"],
         ("netsolve", "pack --dim 3"): ["--lateral"], ("demsolve", "compact --dim 3"): ["--path"]}


def null_runs(bases):
    """(tool, sub, args) of the valid base runs whose JSON nulls are documented."""
    runs = [(t, s, [x.format(**bases) for x in args]) for t, s, _sub, args, _o in BASES
            if all(k in bases for k in re.findall(r"\{(\w+)\}", " ".join(args)))]
    if "lattice" in bases:  # --planes spheres: the state's plane_origin is null (docs/staggered.md)
        runs.append(("netsolve", "sinter", ["sinter", "--packing", bases["lattice"], "--time", "100", "--planes",
                                            "spheres", "--quiet"]))
        runs.append(("netsolve", "sinter", ["sinter", "--restart", bases["sn_state_no_origin"], "--time", "150",
                                            "--quiet"]))  # seed and restart.packing unknown: null
    return runs


# ---- mutations of the JSON state archives ---------------------------------------------------------
def json_leaves(j, path=()):
    """Paths of the scalar members: every member of a dict; of a list its first and last element (the
    first only of a list of lists or objects)."""
    if isinstance(j, dict):
        for k, v in j.items():
            yield from json_leaves(v, path + (k,))
    elif isinstance(j, list):
        for i in sorted({0, len(j) - 1}) if j else []:
            if i > 0 and isinstance(j[i], (list, dict)):
                continue
            yield from json_leaves(j[i], path + (i,))
    else:
        yield path


def json_set(j, path, value):
    j = copy.deepcopy(j)
    node = j
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return j


def json_del(j, path):
    j = copy.deepcopy(j)
    node = j
    for k in path[:-1]:
        node = node[k]
    del node[path[-1]]
    return j


def dump(j, token=None):
    s = json.dumps(j, separators=(",", ":"))
    return (s.replace(f'"{SENTINEL}"', token) if token is not None else s) + "\n"


def json_mutations(text, name, rng, values=JSON_VALUES, every=1):
    """Mutated copies of a one-line JSON state: [(label, bytes)]."""
    good = json.loads(text)
    out = []
    body = text if text.endswith("\n") else text + "\n"
    for frac in (0.0, 0.01, 0.1, 0.5, 0.9, 0.999):
        out.append((f"{name}: truncated at {frac:.1%} of its bytes", body[: int(len(body) * frac)].encode()))
    leaves = list(json_leaves(good))[::every]
    for path in leaves:
        p = "/" + "/".join(str(k) for k in path)
        for label, tok in values:
            out.append((f"{name}: {p} = {label}", dump(json_set(good, path, SENTINEL), tok).encode()))
    for k, v in good.items():  # every member removed; every column shortened and lengthened
        out.append((f"{name}: member /{k} removed", dump(json_del(good, (k,))).encode()))
        if isinstance(v, dict):
            for k2, v2 in v.items():
                out.append((f"{name}: member /{k}/{k2} removed", dump(json_del(good, (k, k2))).encode()))
                if isinstance(v2, list) and v2:
                    out.append((f"{name}: /{k}/{k2} one element short", dump(json_set(good, (k, k2), v2[:-1])).encode()))
                    out.append((f"{name}: /{k}/{k2} one element long", dump(json_set(good, (k, k2), v2 + v2[-1:])).encode()))
                    out.append((f"{name}: /{k}/{k2} a number, not a list", dump(json_set(good, (k, k2), 1.0)).encode()))
            out.append((f"{name}: /{k} a list, not an object", dump(json_set(good, (k,), [])).encode()))
    out.append((f"{name}: /extra member added", dump(dict(good, extra=1)).encode()))
    out.append((f"{name}: pretty-printed over many lines", (json.dumps(good, indent=1) + "\n").encode()))
    out.append((f"{name}: a member given twice", ('{"version":1,' + dump(good)[1:]).encode()))
    out.append((f"{name}: a second document appended", (dump(good) + dump(good)).encode()))
    out.append((f"{name}: a member nested 100000 deep", dump(json_set(good, ("version",), SENTINEL),
                                                               "[" * 100000 + "]" * 100000).encode()))
    out.append((f"{name}: only {{}}", b"{}\n"))
    out.append((f"{name}: only null", b"null\n"))
    out.append((f"{name}: 4 kB of random bytes", bytes(rng.randrange(256) for _ in range(4096))))
    out.append((f"{name}: a 5 MB binary first line",
                bytes(rng.randrange(1, 256) for _ in range(5_000_000)) + b"\n" + body.encode()))
    out.append((f"{name}: NUL bytes inside", body[:40].encode() + b"\0\0\0" + body[40:].encode()))
    out.append((f"{name}: random bytes appended", body.encode() + bytes(rng.randrange(256) for _ in range(512))))
    out.append((f"{name}: Windows line end", body.replace("\n", "\r\n").encode()))
    out.append((f"{name}: no final newline", body[:-1].encode()))
    out.append((f"{name}: empty file", b""))
    return out


# ---- mutations of key = value material files and time,T profiles -------------------------------------
def material_mutations(text, name, values):
    lines = text.rstrip("\n").split("\n")
    keyed = [(k, ln.split("=")[0].strip()) for k, ln in enumerate(lines) if "=" in ln and not ln.startswith("#")]
    out = []
    for k, key in keyed:
        for v in values:
            m = list(lines)
            m[k] = f"{key} = {v}"
            out.append((f"{name}: {key} = '{v}'", ("\n".join(m) + "\n").encode()))
        m = list(lines)
        del m[k]
        out.append((f"{name}: {key} removed", ("\n".join(m) + "\n").encode()))
    extra = ["no_such_key = 1", "Omega", "= 1", "Omega = 1e-29 2e-29", "Omega == 1e-29", "nu = -0.3", "nu = 0.5",
             "E = -1", "gamma_gb = 10", "T_transus = 1200", "T_transus = 1e5", "D_vol0_low = 1e-5",
             "D_gb0 = 1e-2", "delta = 1e-9", "D_gb0 = 1e-2\ndelta_gb = 0", "name = " + "x" * 5000,
             "Omega = 1.18e-29 # " + "y" * 5000, "D_vol0 = 0\ndeltaD_gb0 = 0\ndeltaD_s0 = 0",
             "T_transus = 1200\nD_vol0_low = 1e-5\nQ_vol_low = 1e5"]
    for e in extra:
        out.append((f"{name}: line '{e[:40]}' appended", (text.rstrip("\n") + "\n" + e + "\n").encode()))
    rng = random.Random(27)
    out += [(f"{name}: empty file", b""), (f"{name}: only comments", b"# nothing\n"),
            (f"{name}: 4 kB of random bytes", bytes(rng.randrange(256) for _ in range(4096))),
            (f"{name}: a 4 kB binary first line", bytes(rng.randrange(1, 256) for _ in range(4096)) + b"\n" + text.encode()),
            (f"{name}: NUL bytes", text[:30].encode() + b"\0\0" + text[30:].encode()),
            (f"{name}: Windows line ends", text.replace("\n", "\r\n").encode()),
            (f"{name}: truncated at 50%", text[: len(text) // 2].encode())]
    return out


def profile_mutations(t_end, temp, values):
    rows = [(0.0, temp), (t_end / 2, temp + 7), (t_end, temp + 7)]

    def prof(rs, head="time,T"):
        return (head + "\n" + "\n".join(f"{a},{b}" for a, b in rs) + "\n").encode()

    out = []
    for i in range(len(rows)):
        for col in range(2):
            for v in values:
                rs = [list(map(str, r)) for r in rows]
                rs[i][col] = v
                out.append((f"profile: row {i + 1} {'time' if col == 0 else 'T'} = '{v}'", prof(rs)))
    for T in ("2e4", "1e5", "1e300", "9999", "1e4", "1e-300"):
        out.append((f"profile: a row at T = {T} K (issue 27)", prof([rows[0], (t_end / 2, T), rows[2]])))
    out += [("profile: times decreasing", prof([rows[2], rows[1], rows[0]])),
            ("profile: a jump (two equal times)", prof([rows[0], (t_end / 2, temp), (t_end / 2, temp + 50), rows[2]])),
            ("profile: three equal times", prof([rows[0]] + [(t_end / 2, temp + k) for k in range(3)] + [rows[2]])),
            ("profile: starts at a negative time", prof([(-t_end, temp)] + rows[1:])),
            ("profile: starts after t = 0", prof(rows[1:])),
            ("profile: ends before --time", prof(rows[:2])),
            ("profile: one row", prof(rows[:1])),
            ("profile: header only", b"time,T\n"),
            ("profile: no header", prof(rows, head="").lstrip(b"\n")),
            ("profile: header T,time", prof(rows, head="T,time")),
            ("profile: header with a third column", prof(rows, head="time,T,p")),
            ("profile: semicolons", prof(rows).replace(b",", b";")),
            ("profile: a row with three fields", prof(rows) + b"1,2,3\n"),
            ("profile: a row with one field", prof(rows) + b"7\n"),
            ("profile: 1e5 rows", prof([(t_end * k / 1e5, temp + (k % 2)) for k in range(100000)])),
            ("profile: 1e5 rows at one time", prof([(0.0, temp)] * 100000)),
            ("profile: Windows line ends", prof(rows).replace(b"\n", b"\r\n")),
            ("profile: empty file", b""),
            ("profile: 4 kB of random bytes", bytes(random.Random(5).randrange(256) for _ in range(4096))),
            ("profile: a 4 kB binary first line", bytes(random.Random(6).randrange(1, 256) for _ in range(4096)) +
             b"\n" + prof(rows)),
            ("profile: NUL bytes", prof(rows)[:12] + b"\0\0" + prof(rows)[12:])]
    return out


def packing3_reproducers(text):
    lines = text.rstrip("\n").split("\n")
    hdr = [ln for ln in lines if not (ln and ln[0].isdigit())]
    data = [ln.split(",") for ln in lines if ln and ln[0].isdigit()]

    def build(h, rows):
        return ("\n".join(h) + "\n" + "\n".join(",".join(r) for r in rows) + "\n").encode()

    out = []
    for v in ("1e-300", "4.9e-324", "0", "1e300", "0.02"):
        out.append((f"packing3: every radius = {v}", build(hdr, [r[:4] + [v] for r in data])))
    rows = [list(r) for r in data]
    rows[1][1:4] = rows[0][1:4]
    out.append(("packing3: two spheres at one centre", build(hdr, rows)))
    out.append(("packing3: one sphere far outside the box", build(hdr, data[:-1] + [[data[-1][0], "1", "1", "1", data[-1][4]]])))
    out.append(("packing3: r_max/r_min = 1e6", build(hdr, [data[0][:4] + [repr(float(data[0][4]) * 1e-6)]] + data[1:])))
    out.append(("packing3: box of zero size", build(["# box 0 0 0 0 0 0", "# dim 3", "id,x,y,z,r"], data)))
    out.append(("packing3: a 2D packing (id,x,y,r)", build(["# box 0 0 1 1", "id,x,y,r"], [r[:3] + [r[4]] for r in data])))
    out.append(("packing3: # dim 2 with 3D rows", build([h if not h.startswith("# dim") else "# dim 2" for h in hdr], data)))
    rng = random.Random(3)
    near = [[str(k), repr(1e-4 + rng.uniform(0, 1e-14)), repr(1e-4 + rng.uniform(0, 1e-14)),
             repr(1e-4 + rng.uniform(0, 1e-14)), "2.5e-05"] for k in range(20000)]
    out.append(("packing3: 2e4 spheres within 1e-14 m of each other",
                build(["# box 0 0 0 0.0002 0.0002 0.0002", "# dim 3", "id,x,y,z,r"], near)))
    return out


# ---- the run folders ----------------------------------------------------------------------------------
def dead_pid():
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def marker(pid, process_line=True, start_ticks=1):
    boot = ""
    try:
        with open("/proc/sys/kernel/random/boot_id") as fh:
            boot = fh.read().strip()
    except OSError:
        pass
    s = f"unfinished netdem run (running, failed or killed): pid {pid}, started 2026-12-04T00:00:00Z\nnetsolve pack\n"
    if process_line:
        s += f"process {start_ticks} boot {boot} host {socket.gethostname()}\n"
    return s + "before: 0 entries\n"


def snapshot(path):
    if not os.path.lexists(path):
        return None
    if not os.path.isdir(path):
        st = os.stat(path)
        return ("file", st.st_size, st.st_mtime_ns)
    out = []
    for root, _d, files in os.walk(path):
        for f in files:
            p = os.path.join(root, f)
            try:
                st = os.stat(p)
                out.append((os.path.relpath(p, path), st.st_size, st.st_mtime_ns))
            except OSError:
                pass
    return tuple(sorted(out))


def before_run(task):
    """Sets up a run-folder case (prep ops, a live holder); returns the context for after_run."""
    ctx = {}
    out = task["out"]
    for op in task.get("prep", []):
        path = op[1].replace("{out}", out)
        if op[0] == "dir":
            os.makedirs(path, exist_ok=True)
        elif op[0] == "file":
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "wb") as fh:
                fh.write(op[2] if isinstance(op[2], bytes) else op[2].encode())
        elif op[0] == "run":  # a finished run of the tool into the folder
            subprocess.run([a.replace("{out}", out) for a in op[2]], cwd=task["cwd"], stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL, timeout=120)
        elif op[0] == "marker":
            pid = {"dead": dead_pid(), "self": os.getpid()}.get(op[2], op[2])
            with open(path, "w") as fh:
                fh.write(marker(pid, op[3] if len(op) > 3 else True))
    if task.get("hold"):
        hold = subprocess.Popen([a.replace("{out}", out) for a in task["hold"]], cwd=task["cwd"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        ctx["hold"] = hold
        t0 = time.monotonic()
        while time.monotonic() - t0 < 30 and not os.path.exists(os.path.join(out, ".incomplete")):
            time.sleep(0.02)
        time.sleep(0.2)
        ctx["hold_marker"] = read(os.path.join(out, ".incomplete"))
    ctx["before"] = snapshot(task.get("out_check", out).replace("{out}", out))
    ctx["kept"] = {p: read(p.replace("{out}", out)) for p in task.get("expect", {}).get("kept", [])}
    return ctx


def read(p):
    try:
        with open(p, "rb") as fh:
            return fh.read()
    except OSError:
        return None


def after_run(task, res, ctx, stderr):
    """Reasons the run contradicts its expectation ([] if none); stops a holder. Sets res['untouched']."""
    out = task["out"]
    chk = task.get("out_check", out).replace("{out}", out)
    res["untouched"] = ctx.get("before") is not None and snapshot(chk) == ctx["before"]
    exp = task.get("expect", {})
    why = []
    if "rc" in exp and res["rc"] not in exp["rc"]:
        why.append(f"exit {res['rc']}, expected {'/'.join(map(str, exp['rc']))}")
    if "status" in exp and res["rc"] is not None and res["status"] not in exp["status"]:
        why.append(f"status {res['status']}, expected {'/'.join(exp['status'])}")
    for p, data in ctx.get("kept", {}).items():
        if read(p.replace("{out}", out)) != data:
            why.append(f"{os.path.basename(p)} was changed or removed")
    if exp.get("stderr") and not re.search(exp["stderr"], stderr):
        why.append(f"stderr does not match /{exp['stderr']}/")
    if exp.get("stderr_not") and re.search(exp["stderr_not"], stderr):
        why.append(f"stderr matches /{exp['stderr_not']}/")
    for key, want in exp.get("summary", {}).items():
        try:
            with open(os.path.join(out, "summary.json")) as fh:
                v = json.load(fh)
            for k in key.split("."):
                v = v[k]
        except (OSError, ValueError, KeyError, TypeError):
            v = "(missing)"
        if v != want:
            why.append(f"summary.json {key} = {v!r}, expected {want!r}")
    hold = ctx.get("hold")
    if hold is not None:
        if hold.poll() is not None:
            why.append(f"the holding run ended early (exit {hold.returncode})")
        elif read(os.path.join(out, ".incomplete")) != ctx.get("hold_marker"):
            why.append("the holding run's .incomplete was changed or removed")
        try:
            os.killpg(hold.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        hold.wait()
    return why


def folder_cases(a, work, bases, add):
    """The run-folder cases: [(tool, args)] bases that exit 0, each with every folder case."""
    cases = []
    if a.netsolve:
        cases += [("netsolve", ["pack", "--width", "20"]),
                  ("netsolve", ["pack", "--dim", "3", "--width", "5"]),
                  ("netsolve", ["compact", "--width", "20", "--increments", "20", "--to-density", "0.84", "--quiet"]),
                  ("netsolve", ["sinter", "--packing", bases["lattice"], "--time", "100", "--quiet"]),
                  ("netsolve", ["sinter-pair", "--time", "100", "--quiet"])]
    if a.demsolve:
        cases += [("demsolve", ["prepare", "--n", "20", "--time", "0.002", "--quiet"]),
                  ("demsolve", ["prepare", "--dim", "3", "--n", "20", "--time", "0.002", "--quiet"]),
                  ("demsolve", ["compact", "--dim", "3", "--width", "4", "--affine", "--increments", "5",
                                "--to-density", "0.6", "--inertial-number", "1e-3", "--quiet"])]
    if "dem3_state" in bases:
        cases.append(("demsolve", ["compress", "--state", bases["dem3_state"], "--max-strain", "0.002", "--quiet"]))
    holders = []
    if a.netsolve:
        holders.append([a.netsolve, "sinter", "--packing", bases["lattice"], "--time", "1e6", "--dt-max", "1",
                        "--quiet", "--out", "{out}"])
    if a.demsolve:
        holders.append([a.demsolve, "prepare", "--n", "500", "--time", "30", "--quiet", "--out", "{out}"])
    notes = "{out}/notes.txt"
    for tool, args in cases:
        exe = getattr(a, tool)
        sub = args[0]
        first = [exe] + args + ["--out", "{out}"]

        def case(label, extra, expect, prep=(), hold=None, out_arg=None):
            t = add(tool, "run folders", f"run folder ({sub})", args + extra + ([] if out_arg is None else ["--out", out_arg]),
                    add_out=out_arg is None)
            t["label"] = f"run folder: {sub}: {label}"
            t["prep"] = list(prep)
            t["expect"] = expect
            if out_arg is not None:
                t["out_check"] = out_arg
            if hold:
                t["hold"] = hold
            return t

        case("--out is a file", [], dict(rc=[2], kept=["{out}"]), prep=[("file", "{out}", "user's file\n")])
        case("--out is a file, --overwrite", ["--overwrite"], dict(rc=[2], kept=["{out}"]),
             prep=[("file", "{out}", "user's file\n")])
        case("--out under a file", [], dict(rc=[2]), out_arg="{out}/x/y", prep=[("file", "{out}/x", "a file\n")])
        case("--out under /proc", [], dict(rc=[2]), out_arg="/proc/self/netdem_no/x")
        case("--out ''", [], dict(rc=[2]), out_arg="")
        case("--out a name of 300 bytes", [], dict(rc=[2]), out_arg="{out}/" + "n" * 300)
        case("--out with a newline in its name", [], {}, out_arg="{out}/a\nb")
        case("--out a folder with a user's file", [], dict(rc=[0], kept=[notes]), prep=[("file", notes, "mine\n")])
        case("--out a folder with a user's file and subfolder, --overwrite", ["--overwrite"], dict(rc=[0], kept=[notes]),
             prep=[("file", notes, "mine\n"), ("file", "{out}/sub/keep.csv", "1,2\n")])
        fin = [("run", "{out}", first), ("file", notes, "mine\n"), ("file", "{out}/mydata.csv", "a,b\n1,2\n")]
        case("a finished run and a user's file", [], dict(rc=[2], kept=[notes, "{out}/summary.json"]), prep=fin)
        case("a finished run and a user's file, --overwrite", ["--overwrite"],
             dict(rc=[0], kept=[notes, "{out}/mydata.csv"]), prep=fin)
        fin_sub = fin + [("file", "{out}/sub/x.txt", "x\n")]
        case("a finished run with a user's subfolder, --overwrite", ["--overwrite"],
             dict(rc=[2], kept=[notes, "{out}/sub/x.txt", "{out}/summary.json"]), prep=fin_sub)
        for who, lab in (("dead", "a dead pid"), ("self", "a reused pid (another start time)")):
            st = [("file", notes, "mine\n"), ("file", "{out}/history.csv", "old\n"), ("marker", "{out}/.incomplete", who)]
            case(f"a stale .incomplete of {lab}", [], dict(rc=[2], kept=[notes]), prep=st)
            case(f"a stale .incomplete of {lab}, --overwrite", ["--overwrite"], dict(rc=[0], kept=[notes]), prep=st)
        st = [("file", notes, "mine\n"), ("marker", "{out}/.incomplete", 1, False)]
        case("an old-format .incomplete of a live pid, --overwrite", ["--overwrite"], dict(rc=[2], kept=[notes],
             stderr="pid 1"), prep=st)
        case("a garbage .incomplete, --overwrite", ["--overwrite"], dict(kept=[notes]),
             prep=[("file", notes, "mine\n"), ("file", "{out}/.incomplete", b"\x00\xff" * 100)])
        for hold in holders:
            hname = "netsolve sinter" if "sinter" in hold else "demsolve prepare"
            for ow in ([], ["--overwrite"]):
                case(f"held by a live {hname} run{', --overwrite' if ow else ''}", ow,
                     dict(rc=[2], stderr=r"pid \d+", kept=[notes]), prep=[("file", notes, "mine\n")], hold=hold)
    # --overwrite on the folder that holds the run's own input (a packing written there by pack): refused
    own = []
    if a.netsolve:
        own += [("netsolve", "compact", [a.netsolve, "pack", "--width", "20", "--out", "{out}"],
                 ["compact", "--increments", "20", "--to-density", "0.84", "--quiet"]),
                ("netsolve", "sinter", [a.netsolve, "pack", "--dim", "3", "--route", "green-body", "--n", "30",
                                        "--target-density", "0.4", "--quiet", "--out", "{out}"],
                 ["sinter", "--time", "100", "--quiet"])]
        if a.demsolve:
            own.append(("demsolve", "prepare", [a.netsolve, "pack", "--width", "20", "--out", "{out}"],
                        ["prepare", "--time", "0.002", "--quiet"]))
    for tool, sub, maker, args in own:
        t = add(tool, "run folders", f"run folder ({sub})", args + ["--packing", "{out}/packing.csv", "--overwrite"])
        t["label"] = f"run folder: {sub}: --overwrite on the folder of its own --packing"
        t["prep"] = [("run", "{out}", maker), ("file", "{out}/notes.txt", "mine\n")]
        t["expect"] = dict(rc=[2], kept=["{out}/packing.csv", "{out}/notes.txt"])


def add_tasks(a, work, bases, add, write, rng, values):
    """Every task of the issue-27 surfaces."""
    help_cache = {}

    def numeric(tool, sub):
        if (tool, sub) not in help_cache:
            h = subprocess.run([getattr(a, tool), sub, "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               timeout=30).stdout.decode(errors="replace")
            help_cache[(tool, sub)] = [m.group(1) for m in re.finditer(r"^\s+(--[\w-]+)\s+(?:\S*(?:FLOAT|INT|UINT))", h, re.M)]
        return help_cache[(tool, sub)]

    skip = {"--jobs", "--probe-worker"}
    # 1. numeric options x the 13 values
    for tool, label, sub, base, which in BASES:
        if not getattr(a, tool) or not all(k in bases for k in re.findall(r"\{(\w+)\}", " ".join(base))):
            continue
        base = [x.format(**bases) for x in base]
        opts = which if which is not None else [o for o in numeric(tool, sub) if o not in skip]
        opts += [o for o in EXTRA.get((tool, label), []) if o not in opts and which is None]
        slow = "--generate" in base
        add(tool, label, "base run", base, timeout=(a.timeout + 60) if slow else None)
        for o in opts:
            for v in values:
                add(tool, label, f"option {o}", with_option(base, o, v), timeout=(a.timeout + 60) if slow else None)
    if a.demsolve:
        base = ["prepare", "--dim", "3", "--n", "20", "--time", "0.002", "--quiet"]
        for pn in PARAMS:
            for v in ["0", "-1", "1e300", "inf", "nan", "abc"]:
                add("demsolve", "prepare --dim 3", "option --param", base + ["--param", f"{pn}={v}"])
    if a.netsolve:
        # sinter-pair --radii pairs and malformed lists
        R = ["1e-9", "1e-6", "5e-5", "1e-3", "1e-2", "0", "-1", "nan", "inf", "1e300", "4.9e-324", "abc", ""]
        for ra in R:
            for rb in R:
                add("netsolve", "sinter-pair", "option --radii", ["sinter-pair", "--time", "100", "--quiet", "--radii",
                                                                  f"{ra},{rb}"])
        for integ in ("rk4", "cvode", "arkode"):
            for ra in R[:5]:
                for rb in R[:5]:
                    add("netsolve", "sinter-pair", "option --radii", ["sinter-pair", "--time", "100", "--quiet",
                                                                      "--integrator", integ, "--radii", f"{ra},{rb}"])
        for bad in ("1e-5", "1e-5,", ",1e-5", "1e-5,1e-5,1e-5", "1e-5;1e-5", "1e-5 1e-5", ",", "1e-5,,1e-5"):
            add("netsolve", "sinter-pair", "option --radii", ["sinter-pair", "--time", "100", "--quiet", "--radii", bad])
        for integ in ("dp45", "rk4", "cvode", "arkode", "", "DP45", "euler", "dp45,rk4"):
            add("netsolve", "sinter-pair", "option --integrator", ["sinter-pair", "--time", "100", "--quiet",
                                                                   "--integrator", integ])
        # 2. the readers: material files and --set, profiles, the 3D packing, the staggered state
        sn = ["sinter", "--packing", bases["lattice"], "--time", "100", "--quiet"]
        sp = ["sinter-pair", "--time", "100", "--quiet"]
        for m in ("cu", "ti"):
            if f"mat_{m}" not in bases:
                continue
            with open(bases[f"mat_{m}"]) as fh:
                mtext = fh.read()
            for lab, data in material_mutations(mtext, f"material {m}", values):
                p = write(lab, data)
                for b, sub in ((sn, "sinter"), (sp, "sinter-pair")):
                    add("netsolve", sub, "material file", b + ["--material", p])["label"] = lab
            keys = [ln.split("=")[0].strip() for ln in mtext.split("\n") if "=" in ln and not ln.startswith("#")]
            for key in keys + ["nu", "E", "T_transus", "no_such_key", ""]:
                for v in values:
                    for b, sub in ((sn, "sinter"), (sp, "sinter-pair")):
                        add("netsolve", sub, "option --set", b + ["--material", m, "--set", f"{key}={v}"])
        for spec in ("", "/dev/null", bases["lattice"], os.path.join(work, "inputs"), "no_such_material.txt"):
            for b, sub in ((sn, "sinter"), (sp, "sinter-pair")):
                add("netsolve", sub, "material file", b + ["--material", spec])["label"] = f"material: '{spec[-30:]}'"
        pbase = [("sinter", sn), ("sinter-pair", sp)] + [
            ("sinter-pair", sp + ["--integrator", i]) for i in ("rk4", "cvode", "arkode")]
        for k, (lab, data) in enumerate(profile_mutations(100.0, 1293.0, values)):
            p = write(lab, data)
            for j, (sub, b) in enumerate(pbase):
                if j < 2 or k % 4 == 0:
                    t = add("netsolve", sub, "profile file", b + ["--profile", p])
                    t["label"] = lab
                    if lab == "profile: 1e5 rows":  # 99,999 breakpoints within the run: the work limit
                        t["expect"] = dict(rc=[2], stderr="--allow-long")
        for sub, b in pbase[:2]:
            for lab, p in (("a directory", os.path.join(work, "inputs")), ("a missing file", "no_such.csv"),
                           ("/dev/null", "/dev/null"), ("''", "")):
                add("netsolve", sub, "profile file", b + ["--profile", p])["label"] = "profile: " + lab
        with open(bases["lattice"]) as fh:
            ltext = fh.read()
        lines = ltext.rstrip("\n").split("\n")
        muts = mutate_text(ltext, "packing3", [], 0, values, rng)
        for li in (0, 1, 2, 4, len(lines) - 1):  # # box, # dim, # seed, the first and last data lines
            muts += field_mutations("packing3", lines, li, None, values)
        muts += packing3_reproducers(ltext)
        for lab, data in muts:
            p = write(lab, data)
            add("netsolve", "sinter", "packing file", sn[:1] + ["--packing", p] + sn[3:])["label"] = lab
        if a.demsolve:  # demsolve compact reads lengths in units of R: the mutations of pack --dim 3's packing
            # (the metre lattice above is a valid input there, ~3e8 steps within --max-steps: a long run, not a hang)
            with open(bases["packing3"]) as fh:
                ptext = fh.read()
            plines = ptext.rstrip("\n").split("\n")
            muts3 = mutate_text(ptext, "packing3R", [], 0, values, rng)
            for li in (0, 1, 2, 4, len(plines) - 1):
                muts3 += field_mutations("packing3R", plines, li, None, values)
            for n, (lab, data) in enumerate(muts3 + packing3_reproducers(ptext)):
                if n % 3 == 0:
                    add("demsolve", "compact --dim 3", "packing file",
                        ["compact", "--dim", "3", "--affine", "--increments", "5", "--to-density", "0.6",
                         "--inertial-number", "1e-3", "--quiet", "--packing", write(lab, data)])["label"] = lab
        with open(bases["sn_state"]) as fh:
            stext = fh.read()
        rbase = ["sinter", "--restart", None, "--time", "150", "--quiet"]
        for lab, data in json_mutations(stext, "sinter state", rng) + staggered_reproducers(stext):
            rbase[2] = write(lab, data)
            t = add("netsolve", "sinter", "state file", list(rbase))
            t["label"] = lab
            if "issue 27" in lab:
                t["expect"] = dict(rc=[2])
        for lab, p in (("a directory", os.path.join(work, "inputs")), ("a missing file", "no_such_state.txt"),
                       ("/dev/null", "/dev/null"), ("''", ""), ("the 3D packing", bases["lattice"])):
            rbase[2] = p
            add("netsolve", "sinter", "state file", list(rbase))["label"] = "sinter state: " + lab
        if "dem3_state" in bases:  # each tool's state given to the other
            rbase[2] = bases["dem3_state"]
            add("netsolve", "sinter", "state file", list(rbase))["label"] = "sinter state: a demsolve state"
            add("demsolve", "sinter --dim 3", "state file", ["sinter", "--state", bases["sn_state"]] + SINTER_T)[
                "label"] = "dem state: a netsolve sinter state"
        # the record of origin comes from the state (issue 27 item 4): a 27-sphere state beside a foreign summary
        d = os.path.join(work, "inputs", "origin")
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, "state.txt"), "w") as fh:
            fh.write(stext)
        with open(os.path.join(d, "summary.json"), "w") as fh:
            fh.write(json.dumps({"seed": 99, "packing": {"source": "other.csv", "particles": 100}}) + "\n")
        t = add("netsolve", "sinter", "state file", ["sinter", "--restart", os.path.join(d, "state.txt"), "--time",
                                                     "150", "--quiet"])
        t["label"] = "sinter state: beside a 100-sphere run's summary.json (issue 27)"
        t["expect"] = dict(rc=[0], summary={"packing.particles": 27})
    if a.demsolve and "dem3_state" in bases:
        with open(bases["dem3_state"]) as fh:
            dtext = fh.read()
        subs = [("sinter --dim 3", ["sinter", "--state", None] + SINTER_T),
                ("compress --dim 3", ["compress", "--state", None, "--max-strain", "0.002", "--quiet"])]
        for n, (lab, data) in enumerate(json_mutations(dtext, "dem3 state", rng)):
            sub, b = subs[n % 2]
            b = list(b)
            b[2] = write(lab, data)
            add("demsolve", sub, "state file", b)["label"] = lab
        add("demsolve", "vibrate", "state file", ["vibrate", "--state", bases["dem3_state"], "--time", "0.001",
                                                  "--quiet"])["label"] = "dem3 state: vibrate is 2D only"
    # 3. the reproducers of issue 27 with the documented answer
    repro = []
    if a.netsolve:
        L = bases["lattice"]
        for integ in ("dp45", "rk4", "cvode", "arkode"):
            repro.append(("netsolve", "sinter-pair", ["sinter-pair", "--radii", "1e-9,1e-3", "--integrator", integ,
                                                      "--quiet"], dict(rc=[0], status=["incomplete"])))
        repro += [("netsolve", "sinter", ["sinter", "--packing", L, "--time", "1e12", "--quiet"], dict(rc=[2])),
                  ("netsolve", "sinter", ["sinter", "--packing", L, "--temperature", "1e5", "--quiet"], dict(rc=[2])),
                  ("netsolve", "sinter", ["sinter", "--packing", L, "--time", "100", "--nu", "-0.3", "--quiet"],
                   dict(rc=[2], stderr_not="no Poisson")),
                  ("netsolve", "sinter-pair", ["sinter-pair", "--paths", "", "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--n", "10000000",
                                                "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--steps-per-contact",
                                                "1e6", "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--wall-speed", "1e-9",
                                                "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--n", "30",
                                                "--target-density", "0.4", "--gravity", "1e300", "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--n", "30",
                                                "--target-density", "0.4", "--lamina", "1e-12", "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--n", "30",
                                                "--target-density", "0.4", "--dispersion", "0.999", "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--n", "1",
                                                "--quiet"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--route", "green-body", "--lateral", "periodic",
                                                "--n", "30", "--target-density", "0.4", "--quiet"], {}),
                  ("netsolve", "pack --dim 3", ["pack", "--route", "green-body", "--n", "30", "--quiet"], {}),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--width", "1e7"], dict(rc=[2])),
                  ("netsolve", "pack --dim 3", ["pack", "--dim", "3", "--lateral", "periodic", "--width", "1"], {})]
    if a.demsolve:
        repro += [("demsolve", "prepare --dim 3", ["prepare", "--dim", "3", "--n", "1000000", "--quiet"], dict(rc=[2])),
                  ("demsolve", "prepare --dim 3", ["prepare", "--dim", "3", "--n", "20", "--time", "0.002",
                                                   "--packing", bases.get("packing3", ""), "--quiet"], {}),
                  ("demsolve", "prepare --dim 3", ["prepare", "--dim", "3", "--n", "20", "--time", "0.002",
                                                   "--packing", bases.get("packing", ""), "--quiet"], {}),
                  ("demsolve", "compact --dim 3", ["compact", "--dim", "3", "--width", "4", "--quiet"], {}),
                  ("demsolve", "compact --dim 3", ["yield", "--dim", "3", "--width", "4", "--quiet"], dict(rc=[2])),
                  ("demsolve", "compact --dim 3", ["compact", "--dim", "3", "--width", "4", "--affine", "--increments",
                                                   "5", "--to-density", "0.6", "--inertial-number", "1e-3", "--path",
                                                   "1,1,1,1,1,1,1", "--quiet"], {}),
                  ("demsolve", "compact --dim 3", ["compact", "--dim", "3", "--width", "4", "--boundary", "walls",
                                                   "--increments", "5", "--to-density", "0.6", "--inertial-number",
                                                   "1e-3", "--path", "0,0,-1,0,0,1", "--quiet"], {}),
                  ("demsolve", "compact --dim 3", ["compact", "--dim", "3", "--width", "4", "--affine", "--lateral",
                                                   "periodic", "--quiet"], dict(rc=[2]))]
    for tool, sub, args, exp in repro:
        t = add(tool, sub, "reproducer", args)
        if t is not None:
            t["label"] = "issue 27: " + " ".join(args)[:80]
            t["expect"] = exp
    folder_cases(a, work, bases, add)


def staggered_reproducers(text):
    """The restart reproducers of issue 27 item 3 (refused, exit 2)."""
    good = json.loads(text)
    out = []
    for col, v, what in (("r0", -abs(good["particles"]["r0"][0]), "a negative initial radius"),
                         ("r0", 0.0, "a zero initial radius"), ("r", -abs(good["particles"]["r"][0]), "a negative radius"),
                         ("r", 0.0, "a zero radius"), ("x", "nan", "a NaN centre"), ("x0", "nan", "a NaN initial centre")):
        j = copy.deepcopy(good)
        j["particles"][col][len(j["particles"][col]) // 2] = v
        out.append((f"sinter state: {what} (issue 27)", dump(j).encode()))
    j = copy.deepcopy(good)
    j["clock"]["t"] = "nan"
    out.append(("sinter state: a NaN clock (issue 27)", dump(j).encode()))
    out.append(("sinter state: an old text state (issue 27)", b"netdem-staggered-state 1\nt 0\n"))
    return out


# set by run_campaign.py (shared helpers)
PARAMS = []
with_option = field_mutations = mutate_text = None
