#!/usr/bin/python3
"""ctest readme_validation_status (issue 32 item 4): the README's validation block says what the reports say.

    /usr/bin/python3 tests/validation_status_check.py [ROOT]

Fails (exit 1) when the counts or report commits of README.md's generated block differ from what
validation/status.py reads in the reports of ROOT's work tree (fix: `/usr/bin/python3
validation/status.py --write-readme`). The current/stale column is not compared: it is a flag that a
later commit may change without any report changing, and a regeneration takes hours. Also checks the
shared report helpers (apps/scripts/report_paths.py) on a made-up report: verdict counting with MISSING,
the machine-readable provenance line and the unaffected-by lines. Runs nothing, reads git only.
"""
import importlib.util
import os
import sys


def load(path, name):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def check_helpers(rp, failures):
    prov = {"case": "x", "commit": "0" * 40, "modified": False, "modified_files": [], "sources": {"src": "1" * 40},
            "binaries": {"build/apps/netsolve": "2" * 64}, "generated": "2026-01-01 00:00 UTC"}
    rows = [("a", "1.0", "0..2", rp.verdict(True)), ("b", "3.0", "0..2", rp.verdict(False)),
            ("c", rp.missing_text("run x failed"), "0..2", rp.MISSING), ("d", "4", "-", rp.verdict(None))]
    counts = rp.tally(r[3] for r in rows)
    text = "\n".join(["# made up", "", "| finding | measured | band | result |", "|---|---|---|---|"]
                     + ["| " + " | ".join(r) + " |" for r in rows]
                     + ["", "| case | verdict |", "|---|---|", "| e | **FAIL** |", "| f | MISSING (not run: y) |"]
                     + ["", "| other table | value |", "|---|---|", "| PASS | 1 |"]
                     + rp.provenance_lines(prov, counts)
                     + ["<!-- unaffected-by: abcdef1234 only comments changed -->"])
    want = {"PASS": 1, "FAIL": 2, rp.MISSING: 2, "other": 1}
    got = rp.count_verdicts(text)
    if got != want:
        failures.append(f"count_verdicts: {got}, expected {want}")
    if counts != {"PASS": 1, "FAIL": 1, rp.MISSING: 1, "other": 1}:
        failures.append(f"tally: {counts}")
    meta = rp.read_meta(text)
    if not meta or meta.get("commit") != "0" * 40 or meta.get("counts") != counts:
        failures.append(f"read_meta: {meta}")
    if rp.read_meta("# an old report\n\nno provenance line\n") is not None:
        failures.append("read_meta found a provenance line in a report without one")
    if rp.unaffected_by(text) != [("abcdef1234", "only comments changed")]:
        failures.append(f"unaffected_by: {rp.unaffected_by(text)}")


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    rp = load(os.path.join(root, "apps", "scripts", "report_paths.py"), "report_paths")
    status = load(os.path.join(root, "validation", "status.py"), "validation_status")
    failures = []
    check_helpers(rp, failures)
    readme = open(os.path.join(root, "README.md"), encoding="utf-8").read()
    block = status.readme_block(readme)
    if block is None:
        failures.append("README.md has no validation-status block")
    else:
        want = status.claims(status.markdown([status.case_status(c) for c in status.CASES]))
        have = status.claims(block)
        if have != want:
            failures.append("README.md's validation block differs from the reports (run /usr/bin/python3 "
                            "validation/status.py --write-readme):\n  README:  " + "\n  README:  ".join(have)
                            + "\n  reports: " + "\n  reports: ".join(want))
    for f in failures:
        print("FAIL:", f)
    if not failures:
        print("README.md's validation counts match the reports; report helpers ok")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
