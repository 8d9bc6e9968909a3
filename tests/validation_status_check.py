#!/usr/bin/python3
"""ctest readme_validation_status (issue 32 item 4): the README's validation block says what the reports say.

    /usr/bin/python3 tests/validation_status_check.py [ROOT]

Fails (exit 1) when the counts or report commits of README.md's generated block differ from what
validation/status.py reads in the reports of ROOT's work tree (fix: `/usr/bin/python3
validation/status.py --write-readme`). The current/stale column is not compared: it is a flag that a
later commit may change without any report changing, and a regeneration takes hours. Also checks the
shared report helpers (apps/scripts/report_paths.py) on a made-up report: verdict counting with MISSING,
the machine-readable provenance line and the unaffected-by lines; and two prose claims of the README
against their sources: the robustness campaign's count of hostile runs without a crash, hang or NaN
(docs/robustness_campaign.md) and the walls ensemble's numbers (validation/quasistatic_vs_dynamic_walls/
ensemble.md). Runs nothing, reads git only.
"""
import importlib.util
import os
import re
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


def number(text):
    return float(text.replace("−", "-").replace(",", "").replace("+", ""))


def table_rows(text):
    """The cells of every Markdown table row of a text."""
    return [[c.strip() for c in line.strip().strip("|").split("|")] for line in text.splitlines()
            if line.startswith("|") and not line.startswith("|---")]


def check_robustness_claim(root, readme, failures):
    """README: '0 crashes, hangs or NaN results in N hostile runs' must be a campaign's 'all' row of
    docs/robustness_campaign.md with N inputs and 0 in its crash, hang and NaN/inf-with-exit-0 columns."""
    m = re.search(r"0 crashes, hangs\s+or NaN results in ([\d,]+) hostile runs", readme)
    if not m:
        failures.append("README.md: the robustness claim ('0 crashes, hangs or NaN results in N hostile runs') is gone")
        return
    n = int(number(m.group(1)))
    text = open(os.path.join(root, "docs", "robustness_campaign.md"), encoding="utf-8").read()
    rows = [r for r in table_rows(text) if len(r) >= 9 and r[0] == "**all**" and r[2].strip("*") == str(n)]
    if not rows or any(int(c.strip("*")) != 0 for c in rows[0][6:9]):
        failures.append(f"README.md claims 0 crashes, hangs and NaN results in {n} hostile runs; "
                        f"docs/robustness_campaign.md has no such 'all' row ({rows[0] if rows else 'none'})")


def check_ensemble_claim(root, readme, failures):
    """README's sentence on the walls ensemble: seeds, the largest |mean d| with sticking and mu = 0.1,
    the frictionless range and its largest se, against validation/quasistatic_vs_dynamic_walls/ensemble.md
    (Sigma rows), to the README's rounding."""
    flat = " ".join(readme.split())
    m = re.search(r"over (\d+) seeds to within ([\d.]+) % \(sticking\) and ([\d.]+) % \(μ = 0\.1", flat)
    f = re.search(r"the mean \(([−-][\d.]+) … \+([\d.]+) %, se up to ([\d.]+) %", flat)
    if not m or not f:
        failures.append("README.md: the walls ensemble sentence (seeds, sticking, μ = 0.1, frictionless range) is gone")
        return
    rows = [r for r in table_rows(open(os.path.join(root, "validation", "quasistatic_vs_dynamic_walls", "ensemble.md"),
                                       encoding="utf-8").read()) if len(r) > 7 and r[3] in ("S11", "S22")]
    by = lambda suffix: [r for r in rows if r[0].endswith(suffix)]  # noqa: E731
    mean = lambda r: number(r[5].rstrip(" %"))  # noqa: E731
    checks = [("seeds", int(m.group(1)), {int(r[4]) for r in rows}, None),
              ("sticking", number(m.group(2)), max(abs(mean(r)) for r in by("_inf")), 0.005),
              ("μ = 0.1", number(m.group(3)), max(abs(mean(r)) for r in by("_mu0.1")), 0.005),
              ("frictionless lowest", number(f.group(1)), min(mean(r) for r in by("_mu0")), 0.05),
              ("frictionless highest", number(f.group(2)), max(mean(r) for r in by("_mu0")), 0.05),
              ("frictionless se", number(f.group(3)), max(number(r[7].rstrip(" %")) for r in by("_mu0")), 0.05)]
    for what, claim, actual, tol in checks:
        ok = actual == {claim} if tol is None else abs(claim - actual) <= tol + 1e-12
        if not ok:
            failures.append(f"README.md's walls ensemble sentence, {what}: {claim} against ensemble.md's {actual}")


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
    check_robustness_claim(root, readme, failures)
    check_ensemble_claim(root, readme, failures)
    for f in failures:
        print("FAIL:", f)
    if not failures:
        print("README.md's validation counts and prose claims match the reports; report helpers ok")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
