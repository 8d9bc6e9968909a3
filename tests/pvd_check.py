#!/usr/bin/python3
"""A run folder's snapshots.pvd against the .vtp files in it (issue 33 item 3: every tool that
writes a snapshot series writes its ParaView collection, snapshots.pvd).

    /usr/bin/python3 tests/pvd_check.py DIR KIND,KIND,... [--tags TAG,TAG,...] [--history FILE:COLUMN]
    /usr/bin/python3 tests/pvd_check.py DIR --none

Checks (each failure one line on stderr, exit 1; `snapshot_series_errors` returns them):
  * DIR/snapshots.pvd is well-formed XML: a VTKFile of type Collection holding one Collection of
    DataSet elements, each with a timestep, group="", a part and a file, and no name or the name of
    its kind;
  * each timestep holds one data set per kind, part k of the k-th kind, the files KIND_TAG.vtp of
    one TAG, each a PolyData file that parses and has points; the timesteps strictly increase;
  * the .pvd names exactly the KIND_*.vtp files present, but for a snapshot left out as the same
    state as one listed (its files byte for byte those of a listed tag): `final` as the last one
    (after the last phase, at the last density reached), a D<density> as the first one at or past
    its density;
  * a tag D<density> (compaction: the time is the density D) lies at or past its density (less
    half a unit of its last digit: the tag rounds the density asked for); a tag t<time> (demsolve
    compress) within 1 % of its time; initial and eps0 come first, final last;
  * --tags: the tags listed, in this order; --history FILE:COLUMN: every timestep is a value of
    that column of DIR/FILE (to its 9 digits), a D<density> the first row at or past it (row 0,
    the start, aside);
  * --none: the folder holds no .pvd (a run that wrote no snapshot series).
"""
import glob
import os
import re
import sys
import xml.etree.ElementTree as ET


def _density_tag(tag):
    """The lowest and highest density a tag D<density> stands for (it rounds the density asked
    for), or None."""
    m = re.fullmatch(r"D(\d+\.(\d+))", tag)
    if not m:
        return None
    half = 0.5 * 10.0 ** -len(m.group(2))
    return float(m.group(1)) - half - 1e-12, float(m.group(1)) + half + 1e-12


def _tag_errors(tag, t):
    d = _density_tag(tag)
    if d is not None and not t >= d[0]:
        return [f"{tag}: at density {t!r}"]
    m = re.fullmatch(r"t(\d+(\.\d+)?(e-?\d+)?)", tag)
    if m and not abs(t - float(m.group(1))) <= 0.01 * float(m.group(1)):
        return [f"{tag}: at time {t!r}"]
    return []


def _column(path, name):
    with open(path) as f:
        rows = [l for l in f.read().splitlines() if l and not l.startswith("#")]
    k = rows[0].split(",").index(name)
    return [float(r.split(",")[k]) for r in rows[1:]]


def snapshot_series_errors(folder, kinds, tags=None, history=None):
    """The failures of the checks above (an empty list: the series is right)."""
    pvd = os.path.join(folder, "snapshots.pvd")
    if not os.path.isfile(pvd):
        return [f"{pvd}: missing"]
    try:
        root = ET.parse(pvd).getroot()
    except ET.ParseError as e:
        return [f"{pvd}: not well-formed XML: {e}"]
    collections = root.findall("Collection")
    if root.tag != "VTKFile" or root.get("type") != "Collection" or len(collections) != 1:
        return [f"{pvd}: not a VTKFile of type Collection with one Collection"]
    sets = list(collections[0])
    if not sets or any(d.tag != "DataSet" for d in sets):
        return [f"{pvd}: no DataSet, or another element in the Collection"]
    errors, steps = [], []  # steps: (timestep, tag)
    if len(sets) % len(kinds):
        return [f"{pvd}: {len(sets)} data sets, not a multiple of the {len(kinds)} kinds"]
    for i in range(0, len(sets), len(kinds)):
        group = sets[i:i + len(kinds)]
        try:
            t = [float(d.get("timestep")) for d in group]
            parts = [int(d.get("part")) for d in group]
        except (TypeError, ValueError):
            errors.append(f"{pvd}: data set {i}: a timestep or part that is not a number")
            continue
        files = [d.get("file") or "" for d in group]
        m = re.fullmatch(re.escape(kinds[0]) + r"_(.+)\.vtp", files[0])
        tag = m.group(1) if m else None
        if len(set(t)) != 1 or parts != list(range(len(kinds))) or tag is None or \
                files != [f"{k}_{tag}.vtp" for k in kinds] or any(d.get("group") != "" for d in group) or \
                any(d.get("name") not in (None, k) for d, k in zip(group, kinds)):
            errors.append(f"{pvd}: data sets {i}..{i + len(kinds) - 1} are not one snapshot of {kinds}: {files} "
                          f"at {t}, parts {parts}")
            continue
        steps.append((t[0], tag))
        for f in files:
            path = os.path.join(folder, f)
            try:
                piece = ET.parse(path).getroot().find("PolyData/Piece")
                if piece is None or int(piece.get("NumberOfPoints")) == 0:
                    errors.append(f"{path}: no PolyData piece with points")
            except (OSError, ET.ParseError, TypeError, ValueError) as e:
                errors.append(f"{path}: {e}")
    times = [t for t, _ in steps]
    if any(b <= a for a, b in zip(times, times[1:])):
        errors.append(f"{pvd}: timesteps not strictly increasing: {times}")
    listed = [tag for _, tag in steps]
    for t, tag in steps:
        errors += [f"{pvd}: {e}" for e in _tag_errors(tag, t)]
    for first in ("initial", "eps0"):
        if first in listed and listed[0] != first:
            errors.append(f"{pvd}: {first} is not the first snapshot: {listed}")
    if "final" in listed and listed[-1] != "final":
        errors.append(f"{pvd}: final is not the last snapshot: {listed}")
    if tags is not None and listed != list(tags):
        errors.append(f"{pvd}: snapshots {listed}, expected {list(tags)}")
    present = set()
    for k in kinds:
        present |= {re.fullmatch(re.escape(k) + r"_(.+)\.vtp", os.path.basename(p)).group(1)
                    for p in glob.glob(os.path.join(glob.escape(folder), f"{k}_*.vtp"))}
    for tag in sorted(present - set(listed)):
        def same(other):
            try:
                return all(open(os.path.join(folder, f"{k}_{tag}.vtp"), "rb").read() ==
                           open(os.path.join(folder, f"{k}_{other}.vtp"), "rb").read() for k in kinds)
            except OSError:
                return False
        # the state it must share: final the last one listed; D<density> one at or past its density
        # (crossed in the same increment as another, or lying below the start); another any
        d = _density_tag(tag)
        if tag == "final":
            candidates = listed[-1:]
        elif d is not None:
            candidates = [tg for t, tg in steps if t >= d[0]]
        else:
            candidates = listed
        if not any(same(other) for other in candidates):
            errors.append(f"{pvd}: the snapshot {tag} is present but not listed (and not the same state as "
                          f"{candidates or 'one listed'})")
    if history:
        file, name = history.split(":")
        values = _column(os.path.join(folder, file), name)
        for t, tag in steps:
            rows = [k for k, v in enumerate(values) if abs(t - v) <= 1e-8 * max(abs(v), 1e-300)]
            d = _density_tag(tag)
            if not rows:
                errors.append(f"{pvd}: {tag} at {t!r}, not a value of {file}'s {name}")
            elif d is not None and any(v >= d[1] for v in values[1:rows[0]]):
                # the first row past it (row 0, the start, aside: demsolve compact's first is row 1)
                errors.append(f"{pvd}: {tag} at {t!r}, not the first row of {file} at or past its density")
    return errors


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    folder = argv[1]
    if argv[2] == "--none":
        extra = sorted(os.path.basename(p) for p in glob.glob(os.path.join(glob.escape(folder), "*.pvd")))
        for e in extra:
            print(f"{folder}: {e} present, expected none", file=sys.stderr)
        return 1 if extra else 0
    kinds, tags, history = argv[2].split(","), None, None
    rest = argv[3:]
    while rest:
        if rest[0] == "--tags" and len(rest) > 1:
            tags = [t for t in rest[1].split(",") if t]
        elif rest[0] == "--history" and len(rest) > 1:
            history = rest[1]
        else:
            print(f"pvd_check: unknown argument {rest[0]!r}", file=sys.stderr)
            return 2
        rest = rest[2:]
    errors = snapshot_series_errors(folder, kinds, tags, history)
    for e in errors:
        print(e, file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
