#!/usr/bin/env python3
"""The campaign's classifier (run_campaign.py scan_outputs): a JSON null that a document names on
purpose is not a failure, per subcommand and key (DOCUMENTED_NULLS), while any other null still is.
The campaign of issue 27 counted sinter-pair's infinite viscosity_bouvard_mcmeeking (null,
docs/sintering_pair.md) as "NaN with exit 0" because the valid base run has none.
usage: test_documented_nulls.py (python3, standard library only; runs no binary)"""
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run_campaign as rc  # noqa: E402

fails = []


def check(name, ok):
    if not ok:
        fails.append(name)
        print(f"FAIL {name}")


with tempfile.TemporaryDirectory() as d:
    summary = {"status": "ok",
               "at": {"60": {"viscosity": None, "viscosity_bouvard_mcmeeking": None, "x_over_R": 0.1},
                      "57600": {"viscosity": 1e12, "viscosity_bouvard_mcmeeking": None}},
               "final": {"viscosity_bouvard_mcmeeking": None, "shrinkage": None},
               "density": {"bulk": None}}
    with open(os.path.join(d, "summary.json"), "w") as fh:
        json.dump(summary, fh)
    base = {("netsolve", "sinter-pair"): set(), ("netsolve", "pack --dim 3"): {"state"}}
    bad = rc.scan_outputs(d, rc.null_ok_for(base, "netsolve", "sinter-pair"))
    # the documented viscosities pass; final.shrinkage and density.bulk (not sinter-pair's) do not
    check("sinter-pair documented nulls", sorted(bad) == ["summary.json: density.bulk = null",
                                                          "summary.json: final.shrinkage = null"])
    bad = rc.scan_outputs(d, rc.null_ok_for(base, "netsolve", "pack --dim 3"))
    check("pack --dim 3: its own nulls only", "summary.json: density.bulk = null" not in bad and
          "summary.json: at.60.viscosity_bouvard_mcmeeking = null" in bad)
    bad = rc.scan_outputs(d, rc.null_ok_for(base, "netsolve", "sinter"))
    check("sinter: none documented", len(bad) == 6)
    bad = rc.scan_outputs(d, rc.null_ok_for(base, "netsolve", "run folders"))
    check("run folders: all documented", bad == ["summary.json: final.shrinkage = null"])
    check("a pattern needs its '*'", not rc.null_allowed("at.60.viscosity", {"at.60"}))

print(f"documented nulls: {5 - len(fails)} passed, {len(fails)} failed")
sys.exit(1 if fails else 0)
