#!/usr/bin/python3
"""Scene files (issue 33 item 2, README.md "Scene files"): for every subcommand of netsolve and
demsolve, a small run, then `--config RUN/scene.toml --out OTHER`, must write the same files, bit
for bit after the normalisation of tests/regress/default_outputs.py (wall-clock keys and columns
dropped) and without the command line (command.txt, the "command" keys of the JSON files and state
files, the report lines that quote it); the rerun's scene.toml equals the run's. A command-line
option overrides the file (the run equals the one given both options on the command line); the
sections of other subcommands are skipped; a bad file (missing, not a regular file, unknown key,
bad value, key outside a section, unknown section) is one line on stderr, exit 2 and no run folder.

usage: test_scene_files.py PATH/TO/netsolve PATH/TO/demsolve
"""
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "regress"))
import default_outputs  # noqa: E402

NS, DS = (os.path.abspath(p) for p in sys.argv[1:3])
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL " + what)


def run(argv, cwd):
    return subprocess.run(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=120)


def without_command(v):
    if isinstance(v, dict):
        return {k: without_command(x) for k, x in v.items() if k != "command"}
    return [without_command(x) for x in v] if isinstance(v, list) else v


def content(path):
    """A file's bytes as compared: default_outputs' normalisation (wall-clock keys and columns), and
    without the command line: JSON files (summary.json, parameters.json, the JSON state files)
    without "command" keys, reports without the lines that quote it."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:1] == b"{":
        try:
            return json.dumps(without_command(default_outputs.strip_json(json.loads(data))), sort_keys=True).encode()
        except ValueError:
            pass
    data = default_outputs.normalised(path)
    if path.endswith(".md"):
        data = b"\n".join(l for l in data.split(b"\n") if b"<bin>/" not in l)
    return data


def files(folder):
    out = set()
    for base, _, names in os.walk(folder):
        out |= {os.path.relpath(os.path.join(base, n), folder) for n in names}
    return out - {"command.txt"}


def same_run(a, b, name):
    fa, fb = files(a), files(b)
    check(fa == fb, f"{name}: files differ: {sorted(fa ^ fb)}")
    check("scene.toml" in fa, f"{name}: no scene.toml")
    for rel in sorted(fa & fb):
        check(content(os.path.join(a, rel)) == content(os.path.join(b, rel)), f"{name}: {rel} differs")


def round_trip(tool, name, args, cwd):
    a, b = os.path.join(cwd, name), os.path.join(cwd, name + "_again")
    r = run([tool] + args + ["--out", a], cwd)
    check(r.returncode in (0, 3), f"{name}: exit {r.returncode}: {r.stderr.strip()}")
    sub = args[0]
    r2 = run([tool, sub, "--config", os.path.join(name, "scene.toml"), "--out", b], cwd)
    check(r2.returncode == r.returncode, f"{name}: the rerun exits {r2.returncode}, the run {r.returncode}: {r2.stderr.strip()}")
    same_run(a, b, name)


def refused(tool, name, args, word, cwd):
    out = os.path.join(cwd, name)
    r = run([tool] + args + ["--out", out], cwd)
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    check(r.returncode == 2 and len(lines) == 1 and word in r.stderr and not os.path.exists(out),
          f"{name}: exit {r.returncode}, {len(lines)} lines, out exists {os.path.exists(out)}: {r.stderr.strip()}")


def write(cwd, name, text):
    with open(os.path.join(cwd, name), "w") as f:
        f.write(text)
    return name


def main():
    with tempfile.TemporaryDirectory() as t:
        compact = ["compact", "--width", "16", "--friction", "0.2", "--increments", "5", "--snapshots", "0.8",
                   "--no-rotation"]
        for name, args in [
            ("pack", ["pack", "--width", "20", "--seed", "3"]),
            ("pack3d", ["pack", "--dim", "3", "--width", "5", "--lateral", "periodic", "--r-max", "1"]),
            ("pack_periodic", ["pack", "--periodic", "--n", "60"]),
            ("green", ["pack", "--dim", "3", "--route", "green-body", "--n", "20", "--quiet"]),
            ("compact", compact),
            ("yield", ["yield", "--width", "16", "--directions", "4", "--probes", "0,2", "--jobs", "1", "--increments", "5"]),
            ("merge", ["yield-merge", "yield"]),
            ("sinter_pair", ["sinter-pair", "--time", "10", "--radii", "1e-5,2e-5", "--set", "D_vol0=1.9e-7",
                             "--set", "gamma_s=1.6", "--paths", "I,II"]),
            ("sinter", ["sinter", "--packing", "green/packing.csv", "--time", "10", "--checkpoints", "5", "--quiet"]),
        ]:
            round_trip(NS, name, args, t)
        for name, args in [
            ("prepare", ["prepare", "--n", "30", "--time", "0.02", "--quiet"]),
            ("dsinter", ["sinter", "--n", "30", "--t-heat", "0.01", "--heat-time", "0.01", "--sinter-time", "0.02",
                         "--cool-time", "0.01", "--relax-time", "0.01", "--param", "k2=2e5", "--quiet"]),
            ("compress", ["compress", "--state", "dsinter/state.txt", "--max-strain", "0.01", "--quiet"]),
            ("vibrate", ["vibrate", "--state", "dsinter/state.txt", "--time", "0.01", "--quiet"]),
            ("dcompact", ["compact", "--width", "8", "--increments", "3", "--to-density", "0.8", "--snapshots", "", "--quiet"]),
            ("dyield", ["yield", "--width", "8", "--directions", "2", "--probes", "1", "--increments", "3", "--jobs", "1",
                        "--to-density", "0.8", "--max-strain", "0.002", "--settle-time", "5", "--quiet"]),
        ]:
            round_trip(DS, name, args, t)

        # the command line overrides the file: the same as both options on the command line
        r = run([NS, "compact", "--config", "compact/scene.toml", "--friction", "0.5", "--out", "over"], t)
        r2 = run([NS] + compact[:4] + ["0.5"] + compact[5:] + ["--out", "direct"], t)
        check(r.returncode == r2.returncode, f"override: exit {r.returncode} and {r2.returncode}")
        same_run(os.path.join(t, "over"), os.path.join(t, "direct"), "override")
        check('friction = "0.5"\n' in open(os.path.join(t, "over", "scene.toml")).read(), "override: scene.toml")
        # a file for several subcommands: each reads its own section
        write(t, "two.toml", '[pack]\nseed = 5\nwidth = 30\n[compact]\nwidth = "16"\nincrements = 3\n')
        r = run([NS, "compact", "--config", "two.toml", "--out", "two"], t)
        scene = open(os.path.join(t, "two", "scene.toml")).read()
        check(r.returncode in (0, 3) and 'width = "16"\n' in scene and '# seed = "1"\n' in scene,
              f"two sections: exit {r.returncode}: {scene}")
        help_text = subprocess.run([DS, "vibrate", "--help"], capture_output=True, text=True).stdout
        check("--config" in help_text and "scene.toml" in help_text, "demsolve vibrate --help: no --config")

        bad = {"unknown_key": ("[compact]\nwidht = 20\n", "widht"),
               "bad_value": ("[compact]\nincrements = \"many\"\n", "many"),
               "outside": ("width = 20\n", "outside a section"),
               "unknown_section": ("[compakt]\nwidth = 20\n", "compakt")}
        for name, (text, word) in bad.items():
            f = write(t, name + ".toml", text)
            refused(NS, "bad_" + name, ["compact", "--config", f], word, t)
            refused(DS, "bad_dem_" + name, ["compact", "--config", f], word, t)
        f = write(t, "pair.toml", "[sinter-pair]\nradius = \"-\"\nnonsense = 1\n")
        refused(NS, "bad_pair", ["sinter-pair", "--config", f], "nonsense", t)
        refused(NS, "bad_missing", ["compact", "--config", "missing.toml"], "missing.toml", t)
        refused(NS, "bad_missing_pair", ["sinter-pair", "--config", "missing.toml"], "missing.toml", t)
        refused(DS, "bad_dem_missing", ["prepare", "--config", "missing.toml"], "missing.toml", t)
        os.mkfifo(os.path.join(t, "fifo.toml"))  # opening it for reading would wait for a writer for ever
        refused(NS, "bad_fifo", ["compact", "--config", "fifo.toml"], "not a regular file", t)
        refused(NS, "bad_folder", ["sinter-pair", "--config", "yield"], "not a regular file", t)
    print(f"scene files: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
