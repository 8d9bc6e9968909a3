#!/usr/bin/env python3
"""Validation of demsolve against Luding, Manetsberger & Muellers (2005), long-time sintering, section 4.

usage: /usr/bin/python3 validation/luding_sintering/run.py
           [--quick] [--force] [--jobs 2] [--demsolve PATH] [--out DIR] [--runs DIR] [--report-only]
           [--netsolve PATH (ignored)]

Runs the study of study.py (the section 4.1 protocol for N in {100, 300}, p in {10, 100},
t_s in {1e-4, 0.01, 0.02, 0.05, 0.1, 1}, the three-particle and da_T = 0 controls, the mu_w = 0.5
investigation, and `demsolve compress` / `demsolve vibrate` on the final states; --quick: N = 100 and
t_s in {1e-4, 0.1, 1}), skipping runs that are up to date, then writes figures in the style of
Figs 8-19, 21-22 and report.md (a table of the paper's findings beside the measured values, each with
its acceptance band) into --out (default: this folder, or ./quick with --quick).

Needs numpy and matplotlib (Debian: /usr/bin/python3 with python3-numpy, python3-matplotlib).
"""
import argparse
import csv
import datetime
import json
import math
import os
import shlex
import subprocess
import sys
import warnings

import numpy as np
import matplotlib

matplotlib.use("Agg")
warnings.filterwarnings("ignore", message=".*tight_layout.*")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import study  # noqa: E402

REPO = study.REPO


sys.path.insert(0, os.path.join(str(REPO), "apps", "scripts"))
from report_paths import (MISSING, missing_text, provenance, provenance_lines, shown_path, tally,  # noqa: E402
                          totals_text, verdict)


def shown(p):
    """A path for the report (apps/scripts/report_paths.py)."""
    return shown_path(p, REPO)
PAPER_K1 = {1e-4: ("0.95", 0.95, 0.005), 0.01: ("0.17", 0.17, 0.005), 0.02: ("0.10", 0.10, 0.005),
            0.1: ("0.036", 0.036, 0.0005), 1.0: ("0.0198", 0.0198, 0.00005)}


# ----------------------------------------------------------------------------------------- reading
def read_table(path):
    """CSV with a header line -> {column: np.array} (non-numeric columns stay lists of strings)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(line for line in f if not line.startswith("#")))
    head, data = rows[0], rows[1:]
    out = {}
    for k, h in enumerate(head):
        col = [r[k] for r in data]
        try:
            out[h] = np.array([float(v) for v in col])
        except ValueError:
            out[h] = col
    return out


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


class Sim:
    """A sinter run; a branched run is completed with its base run's time series and phases."""

    def __init__(self, run, sims):
        self.run, self.name, self.dir, self.info = run, run.name, run.dir, run.info
        self.summary = read_json(os.path.join(self.dir, "summary.json"))
        self.meta = read_json(os.path.join(self.dir, "meta.json")) or {}
        self.ok = self.summary is not None and os.path.isfile(os.path.join(self.dir, "timeseries.csv"))
        if not self.ok:
            return
        self.ts = read_table(os.path.join(self.dir, "timeseries.csv"))
        self.phases = {ph["phase"]: ph for ph in self.summary.get("phases", [])}
        self.phases["final"] = self.summary["final"]
        self.parent = sims.get(run.deps[0]) if run.deps else None
        if self.parent is not None and self.parent.ok:
            t0 = self.ts["t"][0]
            keep = self.parent.ts["t"] < t0 - 1e-12
            for k, v in self.parent.ts.items():
                if isinstance(v, list):
                    self.ts[k] = [x for x, m in zip(v, keep) if m] + self.ts[k]
                else:
                    self.ts[k] = np.concatenate([v[keep], self.ts[k]])
            for name in ("prepare", "heat"):
                if name not in self.phases and name in self.parent.phases:
                    self.phases[name] = self.parent.phases[name]
        elif run.deps:
            self.ok = False

    def at(self, col, t):
        return float(np.interp(t, self.ts["t"], self.ts[col]))

    def nu_ref_radii(self, phase=None):
        """nu computed with the radii at T_radius_ref (Eq 9 undone): nu / (1 - da_T (T_ref - T))^2."""
        cp = (read_json(os.path.join(self.dir, "parameters.json")) or {}).get("contact_params", {})
        da, tref = cp.get("da_T", 0.0), cp.get("T_radius_ref", cp.get("T_melt", 120.0))
        if phase is None:
            return self.ts["nu"] / (1.0 - da * (tref - self.ts["T"])) ** 2
        ph = self.phases[phase]
        return ph["nu"] / (1.0 - da * (tref - ph["T"])) ** 2

    def nu(self, phase):
        return self.phases[phase]["nu"] if phase in self.phases else float("nan")

    @property
    def densification(self):
        return self.nu("final") / self.nu("prepare") - 1.0

    def contacts(self, phase):
        p = os.path.join(self.dir, f"contacts_{phase}.csv")
        return read_table(p) if os.path.isfile(p) else None

    @property
    def t_sinter_end(self):
        return 0.3 + self.info["ts"]

    @property
    def cpu_s(self):
        return self.meta.get("cpu_s", float("nan"))


class Test:
    def __init__(self, run):
        self.run, self.name, self.dir, self.info = run, run.name, run.dir, run.info
        self.summary = read_json(os.path.join(self.dir, "summary.json"))
        self.meta = read_json(os.path.join(self.dir, "meta.json")) or {}
        self.ok = self.summary is not None
        self.table = None
        fname = "compress.csv" if run.kind == "compress" else "clusters.csv"
        if self.ok and os.path.isfile(os.path.join(self.dir, fname)):
            try:
                self.table = read_table(os.path.join(self.dir, fname))
            except (OSError, IndexError, ValueError):
                self.table = None


# ----------------------------------------------------------------------------------------- helpers
def three_particle_pair_only(s):
    """Densification of a walled sample if the particle-wall overlaps had kept their values at t_heat:
    each wall moved back by the mean growth of the overlaps of the particles touching it (left and
    bottom walls at 0, right and top at box_width / box_height)."""
    out = {}
    geo = {}
    for ph, t in (("prepare", 0.2), ("final", s.ts["t"][-1])):
        v = read_vtp(os.path.join(s.dir, f"particles_{ph}.vtp"))
        x, y, r = v["points"][:, 0], v["points"][:, 1], v["radius"]
        W, H = s.at("box_width", t), s.at("box_height", t)
        ov = {"L": r - x, "R": r - (W - x), "B": r - y, "T": r - (H - y)}
        geo[ph] = (W, H, ov, float(np.mean(r)))
        c = s.contacts(ph)
        out["pair0" if ph == "prepare" else "pair1"] = float(np.mean(c["overlap_rel"]) * 2) if c is not None else np.nan
    W0, H0, ov0, a0 = geo["prepare"]
    W1, H1, ov1, a1 = geo["final"]
    grow, w0, w1 = {}, [], []
    for k in ov1:
        m = ov1[k] > 0
        grow[k] = float(np.mean(ov1[k][m] - np.maximum(ov0[k][m], 0.0))) if m.any() else 0.0
        if m.any():
            w0.append(float(np.mean(np.maximum(ov0[k][m], 0.0))))
            w1.append(float(np.mean(ov1[k][m])))
    Wp, Hp = W1 + grow["L"] + grow["R"], H1 + grow["B"] + grow["T"]
    out["d_pairs"] = (W0 * H0) / (Wp * Hp) - 1.0
    out["wall0"], out["wall1"] = float(np.mean(w0)) / a0, float(np.mean(w1)) / a1
    return out



def fmt(v, p=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{p}f}"


def spearman(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    m = np.isfinite(x) & np.isfinite(y)
    x, y = x[m], y[m]
    if len(x) < 3:
        return float("nan")
    rx, ry = np.argsort(np.argsort(x)), np.argsort(np.argsort(y))
    return float(np.corrcoef(rx, ry)[0, 1])


def ts_label(ts):
    return f"t_s = {ts:g}"


def ts_colors(tss):
    cmap = plt.get_cmap("viridis")
    return {ts: cmap(k / max(1, len(tss) - 1) * 0.9) for k, ts in enumerate(sorted(tss))}


def pdf(values, bins):
    h, e = np.histogram(values, bins=bins, density=True)
    c = 0.5 * (e[1:] + e[:-1])
    return c, h


# ----------------------------------------------------------------------------------------- figures
def grid_sims(sims, n, p):
    out = {s.info["ts"]: s for s in sims.values()
           if s.ok and s.info.get("role") == "grid" and s.info["n"] == n and s.info["p"] == p}
    return dict(sorted(out.items()))


def save(fig, out, name):
    """Lays out, writes out/name (110 dpi) and closes fig; returns name."""
    fig.tight_layout()
    fig.savefig(os.path.join(out, name), dpi=110)
    plt.close(fig)
    return name


def fig8(sims, nb, out):
    g = grid_sims(sims, nb, 100)
    if not g:
        return None
    col = ts_colors(g)
    fig, ax = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    for ts, s in g.items():
        ax[0].plot(s.ts["t"], s.ts["T"], color=col[ts], label=ts_label(ts))
        ax[1].semilogy(s.ts["t"], s.ts["k1"], color=col[ts], label=ts_label(ts))
        ax[1].plot([s.t_sinter_end], [s.phases["sinter"]["k1_over_k1"]], "o", color=col[ts], ms=4)
    for ts, (txt, v, _) in PAPER_K1.items():
        ax[1].plot([0.3 + ts], [v], "kx", ms=7)
    ax[1].plot([], [], "kx", label="paper (Fig 8 numbers)")
    ax[0].set_ylabel("T [deg C]")
    ax[1].set_ylabel("k1(T,t) / k1")
    ax[1].set_xlabel("t [s]")
    ax[0].legend(fontsize=8)
    ax[1].legend(fontsize=8)
    ax[0].set_title(f"Fig 8 style: temperature and stiffness, N = {nb}, p = 100")
    return save(fig, out, "fig08_T_k1.png")


def fig9(sims, nb, out):
    fig, ax = plt.subplots(2, 1, figsize=(7, 8))
    any_ = False
    for k, p in enumerate((100, 10)):
        g = grid_sims(sims, nb, p)
        col = ts_colors(g)
        for ts, s in g.items():
            ax[k].plot(s.ts["t"], s.ts["nu"], color=col[ts], label=ts_label(ts))
            any_ = True
        if 1.0 in g:
            ax[k].plot(g[1.0].ts["t"], g[1.0].nu_ref_radii(), color="gray", ls="--", lw=0.8,
                       label="t_s = 1, nu with radii at T_melt (hypothesis)")
        ax[k].set_ylabel("nu")
        ax[k].set_title(f"Fig 9 style: N = {nb}, p = {p}")
        ax[k].set_xlabel("t [s]")
        ax[k].legend(fontsize=8)
        lo = min((np.min(s.ts["nu"][s.ts["t"] > 0.1]) for s in g.values()), default=0.78)
        ax[k].set_ylim(lo - 0.005, None)
    if not any_:
        plt.close(fig)
        return None
    return save(fig, out, "fig09_density.png")


def fig10(sims, ns, out):
    fig, ax = plt.subplots(1, len(ns), figsize=(6 * len(ns), 4.5), squeeze=False)
    for k, n in enumerate(ns):
        for p, c in ((10, "tab:blue"), (100, "tab:red")):
            s = grid_sims(sims, n, p).get(1.0)
            if s is None:
                continue
            ax[0, k].plot(s.ts["t"], s.ts["C"], color=c, label=f"p = {p}: C = (2 N_pp + N_pw)/N")
            ax[0, k].plot(s.ts["t"], s.ts["C_without_walls"], color=c, ls="--", lw=0.8,
                          label=f"p = {p}: 2 N_pp / N")
        ax[0, k].axvline(0.3, color="gray", lw=0.5)
        ax[0, k].axvline(1.3, color="gray", lw=0.5)
        ax[0, k].set_ylim(2.5, 5.5)
        ax[0, k].set_xlabel("t [s]")
        ax[0, k].set_ylabel("C")
        ax[0, k].set_title(f"Fig 10 style: N = {n}, t_s = 1")
        ax[0, k].legend(fontsize=8)
    return save(fig, out, "fig10_coordination.png")


def fig11(sims, nb, out):
    fig, ax = plt.subplots(2, 1, figsize=(7, 8))
    for k, p in enumerate((100, 10)):
        s = grid_sims(sims, nb, p).get(1.0)
        if s is None:
            continue
        m = (s.ts["t"] >= 0.28) & (s.ts["t"] <= 1.32)
        t = s.ts["t"][m]
        ax[k].plot(t, s.ts["nu"][m], "s", ms=2, color="tab:blue", label="nu")
        ax[k].plot(t, s.ts["C"][m] / 5, "o", ms=2, color="tab:green", label="C / 5")
        ax[k].plot(t, s.ts["szz_over_p"][m], "-", lw=0.6, color="tab:red", label="sigma_zz / p (top wall)")
        ax[k].set_ylim(0.6, 1.2)
        ax[k].set_xlabel("t [s]")
        ax[k].set_title(f"Fig 11 style: sintering t_s = 1, N = {nb}, p = {p}")
        ax[k].legend(fontsize=8, loc="lower right")
    return save(fig, out, "fig11_nu_C_szz.png")


def fig_overlap(sims, nb, phase, fig_no, out):
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    for k, p in enumerate((10, 100)):
        g = grid_sims(sims, nb, p)
        col = ts_colors(g)
        allv = [s.contacts(phase) for s in g.values()]
        vmax = max((np.max(c["overlap_rel"]) for c in allv if c is not None and len(c["overlap_rel"])), default=0.05)
        bins = np.linspace(0, vmax * 1.01, 30 if nb >= 300 else 20)
        for (ts, s), c in zip(g.items(), allv):
            if c is None or not len(c["overlap_rel"]):
                continue
            x, h = pdf(c["overlap_rel"], bins)
            ax[k].semilogy(x, np.where(h > 0, h, np.nan), "-o", ms=2, color=col[ts], label=ts_label(ts))
        ax[k].set_xlabel("delta / (a_1 + a_2)")
        ax[k].set_ylabel("pdf")
        ax[k].set_title(f"Fig {fig_no} style: N = {nb}, p = {p}, after {phase}")
        ax[k].legend(fontsize=8)
    return save(fig, out, f"fig{fig_no}_overlap_{phase}.png")


def fig_force(sims, nb, p, fig_no, out):
    g = grid_sims(sims, nb, p)
    col = ts_colors(g)
    fig, ax = plt.subplots(2, 1, figsize=(7, 8))
    for k, phase in enumerate(("sinter", "relax")):
        cs = {ts: s.contacts(phase) for ts, s in g.items()}
        vals = [c["f_n"] for c in cs.values() if c is not None and len(c["f_n"])]
        if not vals:
            continue
        lo, hi = min(np.min(v) for v in vals), max(np.max(v) for v in vals)
        bins = np.linspace(lo, hi, 30 if nb >= 300 else 20)
        for ts, c in cs.items():
            if c is None or not len(c["f_n"]):
                continue
            x, h = pdf(c["f_n"], bins)
            ax[k].semilogy(x, np.where(h > 0, h, np.nan), "-o", ms=2, color=col[ts], label=ts_label(ts))
        ax[k].axvline(0, color="gray", lw=0.5)
        ax[k].set_xlabel("f_n [N]")
        ax[k].set_ylabel("pdf")
        ax[k].set_title(f"Fig {fig_no} style: N = {nb}, p = {p}, after {'sintering' if phase == 'sinter' else 'cool-down and relaxation'}")
        ax[k].legend(fontsize=8)
    return save(fig, out, f"fig{fig_no}_force_p{p}.png")


def test_group(tests, kind, n, p):
    out = {t.info["ts"]: t for t in tests.values()
           if t.ok and t.info.get("role") == kind and t.info["n"] == n and t.info["p"] == p}
    return dict(sorted(out.items()))


def fig_compress(tests, n, col_name, ylabel, fig_no, out, role="compress"):
    fig, ax = plt.subplots(2, 1, figsize=(7, 8))
    any_ = False
    for k, p in enumerate((10, 100)):
        g = test_group(tests, role, n, p)
        col = ts_colors(g)
        for ts, t in g.items():
            if t.table is None or col_name not in t.table:
                continue
            ax[k].plot(t.table["eps_zz"], t.table[col_name], color=col[ts], label=ts_label(ts))
            any_ = True
        if col_name == "szz" and g.get(1.0) is not None and "stiffness" in g[1.0].summary:
            e = np.linspace(0, 0.01, 3)
            t1 = g[1.0]
            s0 = float(np.interp(0.0, t1.table["eps_zz"], t1.table["szz"])) if t1.table is not None else 0.0
            ax[k].plot(e, s0 + t1.summary["stiffness"] * e, "k--", lw=1, label="stiffness (t_s = 1)")
        ax[k].set_xlabel("eps_zz")
        ax[k].set_ylabel(ylabel)
        rate = (study.COMPRESS_SLOW if role == "compress_slow" else study.COMPRESS)["strain_rate"]
        ax[k].set_title(f"Fig {fig_no} style: N = {n}, p = {p}, strain rate {rate:g}/s"
                        + (" (investigation)" if role == "compress_slow" else ""))
        ax[k].legend(fontsize=8)
    if not any_:
        plt.close(fig)
        return None
    return save(fig, out, f"fig{fig_no}_{role}_N{n}_{col_name}.png")


def fig_vibrate(tests, ns, out):
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    any_ = False
    for n in ns:
        for p, c in ((10, "tab:blue"), (100, "tab:red")):
            g = test_group(tests, "vibrate", n, p)
            if not g:
                continue
            ls = "-" if n == max(ns) else "--"
            x = list(g)
            ax[0].semilogx(x, [t.summary.get("largest_cluster_fraction", np.nan) for t in g.values()], "o" + ls,
                           color=c, label=f"N = {n}, p = {p}")
            ax[1].semilogx(x, [t.summary.get("single_grain_fraction", np.nan) for t in g.values()], "o" + ls,
                           color=c, label=f"N = {n}, p = {p}")
            any_ = True
    if not any_:
        plt.close(fig)
        return None
    ax[0].set_ylabel("largest cluster / N")
    ax[1].set_ylabel("single grains / N")
    for a in ax:
        a.set_xlabel("t_s [s]")
        a.set_ylim(-0.02, 1.02)
        a.legend(fontsize=8)
    ax[0].set_title("Figs 21-22 style: vibration f = 100 Hz, a = 0.2 mm, t = 0.1")
    return save(fig, out, "fig21_22_vibration_clusters.png")


def fig_cluster_sizes(tests, nb, out):
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    any_ = False
    for k, p in enumerate((10, 100)):
        g = test_group(tests, "vibrate", nb, p)
        col = ts_colors(g)
        for ts, t in g.items():
            if t.table is None or "size" not in t.table:
                continue
            sizes = np.sort(np.asarray(t.table["size"]))[::-1]
            ax[k].loglog(np.arange(1, len(sizes) + 1), sizes, "o-", ms=3, color=col[ts], label=ts_label(ts))
            any_ = True
        ax[k].set_xlabel("cluster rank")
        ax[k].set_ylabel("cluster size")
        ax[k].set_title(f"cluster sizes after vibration, N = {nb}, p = {p}")
        ax[k].legend(fontsize=8)
    if not any_:
        plt.close(fig)
        return None
    return save(fig, out, "fig21_22_cluster_sizes.png")


def read_vtp(path):
    """Points and named point-data arrays of an ascii .vtp written by demsolve."""
    import re
    txt = open(path).read()
    arrays = {}
    for m in re.finditer(r'<DataArray([^>]*)>(.*?)</DataArray>', txt, re.S):
        attrs, body = m.group(1), m.group(2)
        nm = re.search(r'Name="([^"]+)"', attrs)
        nc = re.search(r'NumberOfComponents="(\d+)"', attrs)
        v = np.array(body.split(), dtype=float)
        if nc and int(nc.group(1)) > 1:
            v = v.reshape(-1, int(nc.group(1)))
        arrays[nm.group(1) if nm else "points"] = v
    return arrays


def fig_vibration_snapshots(tests, nb, out):
    from matplotlib.patches import Circle
    from matplotlib.collections import PatchCollection
    names = []
    for p, fig_no, wanted in ((10, 21, (1e-4, 0.02, 1.0)), (100, 22, (1e-4, 0.01, 1.0))):
        g = test_group(tests, "vibrate", nb, p)
        tss = [ts for ts in wanted if ts in g] or list(g)[:3]
        if not tss:
            continue
        fig, ax = plt.subplots(len(tss), 1, figsize=(9, 2.6 * len(tss)), squeeze=False)
        for k, ts in enumerate(tss):
            path = os.path.join(g[ts].dir, "particles_final.vtp")
            a = ax[k, 0]
            if not os.path.isfile(path):
                continue
            v = read_vtp(path)
            xy, r, cl = v["points"][:, :2], v["radius"], v.get("cluster", np.zeros(len(v["radius"])))
            sizes = np.bincount(cl.astype(int))
            cmap = plt.get_cmap("tab10")
            colors = [("lightgray" if sizes[int(c)] == 1 else cmap(int(c) % 10)) for c in cl]
            a.add_collection(PatchCollection([Circle(q, rr) for q, rr in zip(xy, r)], facecolor=colors,
                                             edgecolor="k", linewidths=0.3))
            a.axhline(0, color="tab:blue", lw=2)
            a.set_xlim(xy[:, 0].min() - 0.003, xy[:, 0].max() + 0.003)
            a.set_ylim(-0.001, max(xy[:, 1].max() + 0.002, 0.01))
            a.set_aspect("equal")
            sm = g[ts].summary
            a.set_title(f"t_s = {ts:g}: largest cluster {sm.get('largest_cluster_fraction', float('nan')):.2f} N, "
                        f"single grains {sm.get('single_grain_fraction', float('nan')):.2f} N (grey)", fontsize=9)
        fig.suptitle(f"Fig {fig_no} style: after vibration (t = 0.1, f = 100 Hz, a = 0.2 mm), N = {nb}, p = {p}; "
                     "colour = cluster of touching disks", fontsize=9)
        names.append(save(fig, out, f"fig{fig_no}_vibration_snapshots_p{p}.png"))
    return names


def fig_controls(sims, nb, out):
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    ref = grid_sims(sims, nb, 100).get(1.0)
    for s in sims.values():
        if not s.ok:
            continue
        r = s.info.get("role")
        if r == "three":
            ax[0].plot(s.ts["t"], s.ts["nu"] / s.nu("prepare") - 1, label=f"3 particles, {s.info['arrangement']}, p = {s.info['p']:g}")
        if r in ("daT0", "investigation") and s.info["n"] == nb:
            ax[1].plot(s.ts["t"], s.ts["nu"], label=s.name)
    if ref is not None:
        ax[1].plot(ref.ts["t"], ref.ts["nu"], "k", label=ref.name + " (reference)")
        for p in (10, 100):
            r2 = grid_sims(sims, nb, p).get(1.0)
            if r2 is not None:
                ax[0].plot(r2.ts["t"], r2.ts["nu"] / r2.nu("prepare") - 1, "k", ls="-" if p == 100 else "--",
                           label=f"N = {nb}, p = {p}")
    ax[0].set_ylabel("nu(t) / nu(t_heat) - 1")
    ax[1].set_ylabel("nu")
    for a in ax:
        a.set_xlabel("t [s]")
        a.legend(fontsize=7)
    ax[0].set_xlim(0.1, None)
    ax[0].set_ylim(-0.02, None)
    ax[1].set_xlim(0.1, None)
    ax[1].set_ylim(0.8, None)
    ax[0].set_title("three-particle controls (t_s = 1)")
    ax[1].set_title("da_T = 0 control and mu_w = 0.5 investigation")
    return save(fig, out, "fig_controls.png")


# ---------------------------------------------------------------------------------------- findings
class Findings:
    def __init__(self):
        self.rows = []

    def add(self, no, finding, source, measured, band, ok, note=""):
        status = verdict(ok)
        if ok is not None and "[investigation" in finding:
            status += " (investigation)"
        self.rows.append((no, finding, source, measured, band, status, note))

    def missing(self, no, finding, source, band, reason):
        """A line that cannot be evaluated: MISSING, with the reason, counted in the totals."""
        self.rows.append((no, finding, source, missing_text(reason), band, MISSING, ""))


def inband(v, lo, hi):
    return None if not (isinstance(v, (int, float)) and math.isfinite(v)) else (lo <= v <= hi)


def force_stats(c):
    """Normal-force statistics of a contacts_*.csv table (particle pairs): attractive fraction,
    quantiles q05 and q95 of f_n, width q95 - q05, mean."""
    if c is None or not len(c["f_n"]):
        return None
    f = np.asarray(c["f_n"], dtype=float)
    q05, q95 = np.quantile(f, [0.05, 0.95])
    return dict(n=len(f), att=float(np.mean(f < 0)), q05=float(q05), q95=float(q95), width=float(q95 - q05),
                mean=float(np.mean(f)), ratio=float(abs(q05) / q95) if q95 > 0 else float("nan"))


DIP_WINDOW, DIP_DC, DIP_SMOOTH, DIP_MAX_SAMPLING = 0.010, -0.02, 5, 0.001


def coordination_dips(s, col="C", t0=0.3, t1=None):
    """Issue 15 definition: C(t) sampled every <= 1 ms, 5-sample running mean; a dip is a stretch of
    windows of 10 ms over which the smoothed C falls by <= -0.02 while nu rises. Returns (dips,
    sampling interval, largest fall of the smoothed C over 10 ms with nu rising)."""
    t1 = t1 if t1 is not None else s.t_sinter_end
    m = (s.ts["t"] >= t0 - 1e-12) & (s.ts["t"] <= t1 + 1e-12)
    t, C, nu = s.ts["t"][m], s.ts[col][m], s.ts["nu"][m]
    if len(t) < 3 * DIP_SMOOTH:
        return 0, float("nan"), float("nan")
    dt = float(np.median(np.diff(t)))
    Cs = np.convolve(C, np.ones(DIP_SMOOTH) / DIP_SMOOTH, mode="valid")
    ts_ = t[DIP_SMOOTH // 2: DIP_SMOOTH // 2 + len(Cs)]
    nus = nu[DIP_SMOOTH // 2: DIP_SMOOTH // 2 + len(Cs)]
    k = max(1, int(round(DIP_WINDOW / dt)))
    if len(Cs) <= k:
        return 0, dt, float("nan")
    dC, dnu = Cs[k:] - Cs[:-k], nus[k:] - nus[:-k]
    hit = (dC <= DIP_DC + 1e-9) & (dnu > 0)  # (1e-9: a fall of exactly 0.02 in floating point)
    rising = dnu > 0
    worst = float(np.min(dC[rising])) if rising.any() else float("nan")
    # count stretches of consecutive qualifying windows, and windows that overlap count once
    dips, last = 0, -10 ** 9
    for i in np.nonzero(hit)[0]:
        if i > last + k:
            dips += 1
        last = i
    return dips, dt, worst


def issue15_rows(F, sims, nb, quick):
    """The lines issue 15 asks for (force pdf, density, coordination dips, narrowing, controls)."""
    qn = " (quick: N = 100 stands in for N = 300)" if quick and nb != 300 else ""
    # force pdf before and after cool-down, t_s = 1
    for p in (10, 100):
        g = grid_sims(sims, nb, p).get(1.0)
        b, a = (force_stats(g.contacts("sinter")), force_stats(g.contacts("relax"))) if g is not None else (None, None)
        pre = f"N = {nb}, p = {p}, t_s = 1: "
        if b is None or a is None:
            why = "the run is missing or failed" if g is None else "no contact file at the end of sintering or relaxation"
            for fin in ("attractive fraction of the contacts after cool-down (f_n < 0)", "|q05| / q95 of f_n after "
                        "cool-down (two-sided pdf)", "width q95 - q05 of f_n grows on cool-down"):
                F.missing("15a", pre + fin, "4.3.2, Figs 14-15", "", why)
            continue
        F.add("15a", pre + "attractive fraction of the contacts after cool-down (f_n < 0)",
              "abstract; 4.3.2, Figs 14-15; concl. iii ('almost equally strong attractive and repulsive')",
              f"{a['att']:.3f} (end of sintering {b['att']:.3f}; {a['n']} contacts)", ">= 0.2",
              a["att"] >= 0.2, qn.strip())
        F.add("15a", pre + "|q05| / q95 of f_n after cool-down (two-sided pdf)", "4.3.2, Figs 14-15",
              f"{a['ratio']:.3f} (q05 = {a['q05']:+.4g} N, q95 = {a['q95']:+.4g} N; end of sintering "
              f"q05 = {b['q05']:+.4g} N, q95 = {b['q95']:+.4g} N)", "0.5..2", inband(a["ratio"], 0.5, 2.0),
              "q05 > 0 means the pdf is one-sided (repulsive)" if a["q05"] > 0 else "")
        F.add("15a", pre + "width q95 - q05 of f_n grows on cool-down ('broadening towards both positive and "
              "negative forces')", "4.3.2, Figs 14-15",
              f"{b['width']:.4g} N -> {a['width']:.4g} N (x {a['width'] / b['width']:.3f}); mean f_n "
              f"{b['mean']:.4g} -> {a['mean']:.4g} N", "after / before > 1", a["width"] > b["width"])
    # density through cool-down at the paper's t_s values
    for p in (100, 10):
        g = grid_sims(sims, nb, p)
        if not g or g.get(1.0) is None and p == 100:
            for fin in ([f"(information) nu at the end of sintering -> nu(t_f) for every t_s, N = {nb}, p = {p}"] if not g
                        else []) + ([f"nu(t_f) after the longest sintering, N = {nb}, p = 100, t_s = 1 (primary target)",
                                     f"rise of nu on cool-down, N = {nb}, p = 100, t_s = 1"] if p == 100 else []):
                F.missing("15b", fin, "4.1.2-4.1.4, Fig 9", "", "the run is missing or failed")
        if not g:
            continue
        parts = []
        for ts, s2 in g.items():
            parts.append(f"t_s = {ts:g}: {s2.at('nu', s2.t_sinter_end):.4f} -> {s2.nu('final'):.4f} "
                         f"({s2.nu('final') - s2.at('nu', s2.t_sinter_end):+.4f})")
        F.add("15b", f"(information) nu at the end of sintering -> nu(t_f) for every t_s, N = {nb}, p = {p}",
              "4.1.2, Fig 9", "; ".join(parts), "none (Fig 9 values are given in the text for t_s = 1, "
              "p = 100 only)", None, qn.strip())
        s1 = g.get(1.0)
        if s1 is not None and p == 100:
            v13, vf = s1.at("nu", s1.t_sinter_end), s1.nu("final")
            F.add("15b", f"nu(t_f) after the longest sintering, N = {nb}, p = 100, t_s = 1 (primary target)",
                  "4.1.4, Fig 9 ('almost 0.94')", f"{vf:.4f}", "0.92..0.96 (band of line 2c)",
                  inband(vf, 0.92, 0.96), qn.strip())
            F.add("15b", f"rise of nu on cool-down, N = {nb}, p = 100, t_s = 1", "4.1.4, Fig 9 ('almost 0.92' -> "
                  "'almost 0.94', 'due to negative thermal expansion')", f"{vf - v13:+.4f} (radii at T_melt: "
                  f"{s1.nu_ref_radii('final') - s1.nu_ref_radii('sinter'):+.4f})", "+0.01..+0.03 (our band for "
                  "'about +0.02')", inband(vf - v13, 0.01, 0.03), "")
    # coordination dips
    for n in sorted({s2.info["n"] for s2 in sims.values() if s2.ok and s2.info.get("role") == "grid"}):
        for p in (10, 100):
            g = grid_sims(sims, n, p).get(1.0)
            if g is None:
                F.missing("15c", f"coordination dips during sintering (t_s = 1, N = {n}, p = {p})",
                          "abstract; 4.2, Figs 10-11; concl. i", ">= 1 dip", "the run is missing or failed")
                continue
            dips, dt, worst = coordination_dips(g)
            dw, _, worstw = coordination_dips(g, "C_without_walls")
            ok = dips >= 1 if dt <= DIP_MAX_SAMPLING * (1 + 1e-6) else None
            F.add("15c", f"coordination dips during sintering (t_s = 1, N = {n}, p = {p}): C sampled every "
                  f"{1e3 * dt:.2f} ms, 5-sample mean, dip = dC <= -0.02 over 10 ms with dnu > 0",
                  "abstract; 4.2, Figs 10-11; concl. i", f"{dips} dips (largest fall over 10 ms with nu rising: "
                  f"{worst:+.4f}; without wall contacts {dw} dips, {worstw:+.4f})", ">= 1 dip", ok,
                  f"one contact changes C by 2/N = {2.0 / n:.4f}"
                  + (" (a single lost contact is a dip)" if 2.0 / n >= -DIP_DC - 1e-9 else "")
                  + ("" if ok is not None else "; sampling coarser than 1 ms"))
    # narrowing of the force distribution with t_s
    for p in (10, 100):
        g = grid_sims(sims, nb, p)
        tss, wr = [], []
        for ts, s2 in g.items():
            st = force_stats(s2.contacts("sinter"))
            if st is not None:
                tss.append(ts)
                wr.append(st["width"] / st["mean"])
        if len(wr) < 3:
            F.missing("15d", f"width (q95 - q05)/mean of f_n at the end of sintering narrows with t_s, N = {nb}, p = {p}",
                      "4.3.2, Fig 15 top; concl. ii", "Spearman <= -0.8", f"force statistics for {len(wr)} t_s values "
                      "(3 needed)")
            continue
        r = spearman(tss, wr)
        F.add("15d", f"width (q95 - q05)/mean of f_n at the end of sintering narrows with t_s, N = {nb}, p = {p}",
              "4.3.2, Fig 15 top; concl. ii", ", ".join(f"{v:.3f}" for v in wr) + f" (t_s = "
              + ", ".join(f"{t:g}" for t in tss) + f"); Spearman {r:+.2f}",
              "width(t_s=1) < width(t_s=1e-4) and Spearman <= -0.8", (wr[-1] < wr[0]) and r <= -0.8, qn.strip())
    # three-particle control without creeping wall contacts (experiment)
    for p, lo, hi in ((100, 0.05, 0.11), (10, -1.0, 0.01)):
        for arr in ("triangle", "line"):
            t3 = sims.get(f"N3_{arr}_p{p:g}_ts1_wallcold")
            ref = sims.get(f"N3_{arr}_p{p:g}_ts1")
            if t3 is None or not t3.ok:
                F.missing("15e", f"three-particle control ({arr}), p = {p}, wall contacts not creeping [investigation]",
                          "4.1.3", "", "the run is missing or failed")
                continue
            F.add("15e", f"three-particle control ({arr}), p = {p}, wall contacts not creeping "
                  "[investigation: --param wall_sintering=0]", "4.1.3 (paper: about 8 % / 0.2 %, data not shown)",
                  f"{100 * t3.densification:.2f} % (default, creeping walls: "
                  f"{100 * ref.densification:.2f} %)" if ref is not None and ref.ok else f"{100 * t3.densification:.2f} %",
                  f"{100 * lo:g}..{100 * hi:g} %" if p == 100 else "< 1 %", inband(t3.densification, lo, hi))


def experiment_table(sims, nb):
    """Issue 15 experiments (t_s = 1): one row per run, the reference (seed 1, defaults) first."""
    rows = []
    for p in (10, 100):
        ref = grid_sims(sims, nb, p).get(1.0)
        group = [("reference (seed 1, defaults)", ref)] if ref is not None else []
        for s2 in sims.values():
            if s2.info.get("p") == p and s2.info.get("role") in ("experiment", "daT0", "investigation") \
                    and s2.info.get("ts") == 1.0:
                group.append((s2.info.get("what", s2.info.get("role")), s2))
        for what, s2 in group:
            if s2 is None or not s2.ok:
                rows.append(f"| {p} | {what} | {s2.name if s2 else ''} | failed or missing |||||||||")
                continue
            b, a = force_stats(s2.contacts("sinter")), force_stats(s2.contacts("relax"))
            if b is None and s2.parent is not None and s2.parent.ok:  # branched at the end of sintering
                b = force_stats(s2.parent.contacts("sinter"))
            dips, dt, worst = coordination_dips(s2)
            v13 = s2.at("nu", s2.t_sinter_end)
            cp = (read_json(os.path.join(s2.dir, "parameters.json")) or {}).get("contact_params", {})
            da, tm = cp.get("da_T", 1e-4), cp.get("T_melt", 120.0)
            er = 1.0 - (1.0 - da * (tm - 80.0)) / (1.0 - da * (tm - 140.0))  # radius strain 140 -> 80 C
            t1 = float(s2.ts["t"][-1])
            eb = 1.0 - math.sqrt(s2.at("box_width", t1) * s2.at("box_height", t1)
                                 / (s2.at("box_width", s2.t_sinter_end) * s2.at("box_height", s2.t_sinter_end)))
            aff = f"{1e2 * eb:.3f} / {1e2 * er:.3f} %" if er > 0 else f"{1e2 * eb:.3f} / 0 %"
            rows.append(f"| {p} | {what} | {s2.name} | {s2.info['n']} | {s2.nu('prepare'):.4f} | {v13:.4f} | "
                        f"{s2.nu('final'):.4f} | {100 * s2.densification:.2f} % | "
                        + (f"{a['att']:.3f} | {a['ratio']:.3f} | {a['width'] / b['width']:.3f} | " if a and b else "|||")
                        + f"{dips} ({worst:+.3f}) | {aff} |")
    L = ["## Experiments of issue 15 (t_s = 1)\n",
         "The reference is the grid run (seed 1, defaults). Columns: nu after preparation, at the end of sintering "
         "and at t_f; densification nu(t_f)/nu(t_heat) - 1; after cool-down: attractive fraction, |q05|/q95 and the "
         "width q95 - q05 after / before cool-down; coordination dips during sintering (definition of line 15c; in "
         "brackets the largest fall of the smoothed C over 10 ms with nu rising); linear contraction of the box "
         "from the end of sintering to t_f against the radius contraction of Eq 9 (140 -> 80 C): equal numbers "
         "mean an affine cool-down, which leaves every contact's elastic overlap delta - delta_0 unchanged.\n",
         "| p | experiment | run | N | nu(t_heat) | nu(end sinter) | nu(t_f) | densification | attractive | "
         "/q05//q95 | width after/before | dips | box / radius contraction |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|"] + rows
    # seed spread
    for p in (10, 100):
        seeds = [s2 for s2 in [grid_sims(sims, nb, p).get(1.0)] + [sims.get(study.sinter_name(nb, p, 1.0, f"_seed{k}"))
                                                                     for k in (2, 3)] if s2 is not None and s2.ok]
        if len(seeds) >= 2:
            def ms(vals):
                return f"{np.mean(vals):.4f} +- {np.std(vals, ddof=1):.4f}"
            att = [force_stats(s2.contacts("relax"))["att"] for s2 in seeds]
            L.append(f"\nSeeds 1-{len(seeds)}, N = {nb}, p = {p} (mean +- sample std): nu(t_heat) "
                     f"{ms([s2.nu('prepare') for s2 in seeds])}, nu(t_f) {ms([s2.nu('final') for s2 in seeds])}, "
                     f"densification {ms([s2.densification for s2 in seeds])}, attractive fraction after cool-down "
                     f"{ms(att)}.")
    L.append("")
    return "\n".join(L)


def evaluate(sims, tests, nb, ns, quick):
    F = Findings()
    qn = " (quick: N = 100 stands in for N = 300)" if quick and nb != 300 else ""
    # 1 preparation density
    for n in ns:
        for p in (10, 100):
            g = grid_sims(sims, n, p)
            if not g:
                F.missing("1a", f"nu after preparation about 0.8 (N = {n}, p = {p})", "4.1.2, Fig 9", "0.78..0.82",
                          "no grid run")
                continue
            s = next(iter(g.values()))
            v = s.nu("prepare")
            F.add("1a", f"nu after preparation about 0.8 (N = {n}, p = {p})", "4.1.2, Fig 9", fmt(v, 4), "0.78..0.82",
                  inband(v, 0.78, 0.82), "see known differences" if not inband(v, 0.78, 0.82) else "")
    s = grid_sims(sims, nb, 100).get(1.0)
    if s is not None:
        jump = s.nu("heat") - s.nu("prepare")
        F.add("1b", f"small jump of nu at t_heat (wall friction switched off), N = {nb}, p = 100",
              "4.1.2, Fig 9", f"nu(0.3) - nu(0.2) = {jump:+.5f}", "0.001..0.01 (our band for 'visible, small')",
              inband(jump, 0.001, 0.01),
              "mu_w = 0 during preparation (Table 1), so nothing is switched off at t_heat; see the mu_w = 0.5 investigation" + qn)
    else:
        F.missing("1b", f"small jump of nu at t_heat, N = {nb}, p = 100", "4.1.2, Fig 9", "0.001..0.01",
                  "the run is missing or failed")
    # 2 monotonic in t_s
    for n in ns:
        for p in (10, 100):
            g = grid_sims(sims, n, p)
            if len(g) < 2:
                F.missing("2a", f"nu(t_f) rises monotonically with t_s (N = {n}, p = {p})", "4.1.2, Fig 9",
                          "strictly increasing over t_s", f"{len(g)} t_s value(s) run (2 needed)")
                continue
            nus = [s.nu("final") for s in g.values()]
            mono = all(b > a for a, b in zip(nus, nus[1:]))
            F.add("2a", f"nu(t_f) rises monotonically with t_s (N = {n}, p = {p})", "4.1.2, Fig 9",
                  ", ".join(fmt(v, 4) for v in nus), "strictly increasing over t_s", mono)
    if s is not None:
        v13, vf = s.nu("sinter"), s.nu("final")
        F.add("2b", f"nu at t = 1.3 (end of sintering), N = {nb}, p = 100, t_s = 1", "4.1.4, Fig 9", fmt(v13, 4),
              "0.90..0.94", inband(v13, 0.90, 0.94), qn.strip())
        F.add("2c", f"nu at t_f = 1.5, N = {nb}, p = 100, t_s = 1", "4.1.4, Fig 9", fmt(vf, 4), "0.92..0.96",
              inband(vf, 0.92, 0.96), qn.strip())
        F.add("2d", "(information) cool-down: 'almost 0.92' at t = 1.3 -> 'almost 0.94' at t_f; nu with the radii "
                    "at T_radius_ref = T_melt (hypothesis: the paper's nu used fixed radii)", "4.1.4, Fig 9",
              f"actual radii: {v13:.4f} -> {vf:.4f}; radii at T_melt: {s.nu_ref_radii('sinter'):.4f} -> "
              f"{s.nu_ref_radii('final'):.4f}", "none", None,
              "with fixed radii the cool-down adds +0.012 (the paper: about +0.02); with the current radii +0.0005")
    else:
        for no, fin in (("2b", "nu at t = 1.3 (end of sintering)"), ("2c", "nu at t_f = 1.5"), ("2d", "(information) cool-down")):
            F.missing(no, f"{fin}, N = {nb}, p = 100, t_s = 1", "4.1.4, Fig 9", "", "the run is missing or failed")
    # 3 densification
    for p, lo, hi in ((100, 0.12, 0.20), (10, 0.03, 0.07)):
        for n in ns:
            g = grid_sims(sims, n, p).get(1.0)
            if g is None:
                F.missing("3a" if p == 100 else "3b", f"densification nu(t_f)/nu(t_heat) - 1, p = {p}, t_s = 1, N = {n}",
                          "4.1.3", f"{100 * lo:g}..{100 * hi:g} %", "the run is missing or failed")
                continue
            d = g.densification
            main_ = n == nb
            F.add("3a" if p == 100 else "3b", f"densification nu(t_f)/nu(t_heat) - 1, p = {p}, t_s = 1, N = {n}",
                  "4.1.3", f"{100 * d:.2f} %", f"{100 * lo:g}..{100 * hi:g} %",
                  inband(d, lo, hi) if main_ else None, "" if main_ else "information (the paper's numbers are for its main samples)")
    for p, dpaper in ((100, 0.16), (10, 0.05)):
        g = grid_sims(sims, nb, p).get(1.0)
        if g is not None:
            F.add("3e", f"(information) nu(t_f) implied by the paper, 0.8 x (1 + {dpaper:g}), vs measured, N = {nb}, p = {p}",
                  "4.1.2-4.1.3", f"{g.nu('final'):.4f} (paper ~{0.8 * (1 + dpaper):.3f}); with our nu(t_heat) = "
                  f"{g.nu('prepare'):.4f} the paper's densification would need nu(t_f) = {g.nu('prepare') * (1 + dpaper):.4f}",
                  "none", None, "the final densities agree; the densification differs through the preparation density")
        else:
            F.missing("3e", f"(information) nu(t_f) implied by the paper, N = {nb}, p = {p}", "4.1.2-4.1.3", "none",
                      "the run is missing or failed")
    for p, lo, hi in ((100, 0.05, 0.11), (10, -1.0, 0.01)):
        for arr in ("triangle", "line"):
            t3 = sims.get(f"N3_{arr}_p{p:g}_ts1")
            if t3 is None or not t3.ok:
                F.missing("3c" if p == 100 else "3d", f"three-particle control ({arr}), p = {p}: densification",
                          "4.1.3 (data not shown)", "", "the run is missing or failed")
                continue
            d = t3.densification
            F.add("3c" if p == 100 else "3d", f"three-particle control ({arr}), p = {p}: densification",
                  "4.1.3 (data not shown)", f"{100 * d:.2f} %", f"{100 * lo:g}..{100 * hi:g} %" if p == 100 else "< 1 %",
                  inband(d, lo, hi))
    for arr in ("triangle", "line"):
        for p in (100, 10):
            t3 = sims.get(f"N3_{arr}_p{p:g}_ts1")
            try:
                if t3 is None or not t3.ok:
                    raise ValueError("the run is missing or failed")
                est = three_particle_pair_only(t3)
            except (OSError, KeyError, ValueError, IndexError) as e:
                F.missing("3g", f"(information) three-particle control ({arr}), p = {p}: densification with the wall "
                          "overlaps frozen", "4.1.3", "none", str(e) or type(e).__name__)
                continue
            F.add("3g", f"(information) three-particle control ({arr}), p = {p}: densification with the wall overlaps "
                        "frozen at their t_heat values (pair contacts only)", "4.1.3", f"{100 * est['d_pairs']:.2f} % "
                  f"(total {100 * t3.densification:.2f} %)", "none", None,
                  f"mean wall overlap {est['wall0']:.4f} a -> {est['wall1']:.4f} a, pair overlap "
                  f"{est['pair0']:.4f} a -> {est['pair1']:.4f} a (a = mean radius)")
    # 4 coordination
    bands = {(10, 100): (3.7, 4.3), (10, 300): (3.7, 4.3), (100, 100): (4.2, 4.8), (100, 300): (4.5, 5.1)}
    for n in ns:
        for p in (10, 100):
            g = grid_sims(sims, n, p).get(1.0)
            if g is None:
                F.missing("4a", f"C at t = 1.3 (t_s = 1), N = {n}, p = {p}", "4.2, Fig 10", "", "the run is missing or failed")
                continue
            lo, hi = bands[(p, n)]
            c, cw = g.phases["sinter"]["C"], g.phases["sinter"]["C_without_walls"]
            F.add("4a", f"C at t = 1.3 (t_s = 1), N = {n}, p = {p}", "4.2, Fig 10",
                  f"{c:.3f} (without walls {cw:.3f})", f"{lo:g}..{hi:g}", inband(c, lo, hi))
    for n in ns:
        for p in (10, 100):
            g = grid_sims(sims, n, p).get(1.0)
            if g is None:
                F.missing("4b", f"C falls at times while nu rises (sintering, t_s = 1, N = {n}, p = {p})",
                          "4.2, Figs 10-11", ">= 1 window", "the run is missing or failed")
                continue
            m = (g.ts["t"] >= 0.3) & (g.ts["t"] <= 1.3)
            t, C, nu = g.ts["t"][m], g.ts["C"][m], g.ts["nu"][m]
            edges = np.arange(0.3, 1.3 + 1e-9, 0.05)
            Ce, nue = np.interp(edges, t, C), np.interp(edges, t, nu)
            dC, dnu = np.diff(Ce), np.diff(nue)
            cnt = int(np.sum((dC < -1e-9) & (dnu > 0)))
            F.add("4b", f"C falls at times while nu rises (sintering, t_s = 1, N = {n}, p = {p})", "4.2, Figs 10-11",
                  f"{cnt} of {len(dC)} windows of 0.05 s with dC < 0 and dnu > 0", ">= 1 window", cnt >= 1)
    # 5 contact statistics
    for p in (10, 100):
        g = grid_sims(sims, nb, p)
        if len(g) < 3:
            for no in ("5a", "5b", "5c", "5e", "5d"):
                F.missing(no, f"contact statistics over t_s, N = {nb}, p = {p}", "4.3", "",
                          f"{len(g)} t_s value(s) run (3 needed)")
            continue
        tss = list(g)
        std_o, cv, frac, ratio, neg = [], [], [], [], []
        for s2 in g.values():
            cs, cr = s2.contacts("sinter"), s2.contacts("relax")
            std_o.append(float(np.std(cs["overlap_rel"])) if cs is not None and len(cs["f_n"]) else np.nan)
            cv.append(float(np.std(cs["f_n"]) / np.mean(cs["f_n"])) if cs is not None and len(cs["f_n"]) else np.nan)
            if cr is not None and len(cr["f_n"]):
                frac.append(float(np.mean(cr["mu_t"] >= 0.99 * cr["mu"])))
                ratio.append(float(np.min(cr["f_n"]) / np.max(cr["f_n"])))
                neg.append(float(np.mean(cr["f_n"] < 0)))
            else:
                frac.append(np.nan)
                ratio.append(np.nan)
                neg.append(np.nan)
        r = spearman(tss, std_o)
        F.add("5a", f"overlap pdf broadens with t_s (end of sintering), N = {nb}, p = {p}", "4.3.1, Fig 12",
              "std(delta/(a1+a2)): " + ", ".join(f"{v:.2e}" for v in std_o) + f"; Spearman {r:+.2f}",
              "std(t_s=1) > std(t_s=1e-4) and Spearman >= 0.8", (std_o[-1] > std_o[0]) and r >= 0.8)
        r = spearman(tss, cv)
        F.add("5b", f"std(f_n)/mean(f_n) at the end of sintering falls with t_s, N = {nb}, p = {p}", "4.3.2, Figs 14-15",
              ", ".join(f"{v:.3f}" for v in cv) + f"; Spearman {r:+.2f}",
              "CV(t_s=1) < CV(t_s=1e-4) and Spearman <= -0.8", (cv[-1] < cv[0]) and r <= -0.8)
        F.add("5c", f"after cool-down strong attraction: min f_n <= -0.5 max f_n (t_s = 1, N = {nb}, p = {p})",
              "4.3.2, Figs 14-15", f"min/max = {ratio[-1]:+.3f} (t_s = 1e-4: {ratio[0]:+.3f})", "<= -0.5",
              inband(ratio[-1], -1e9, -0.5), f"fraction of contacts with f_n < 0 after relaxation: {neg[-1]:.3f}")
        fs_ = []
        for s2 in g.values():
            cs = s2.contacts("sinter")
            fs_.append(float(np.mean(cs["mu_t"] >= 0.99 * cs["mu"])) if cs is not None and len(cs["f_n"]) else np.nan)
        F.add("5e", f"(information) fully activated friction at the end of sintering, N = {nb}, p = {p}", "4.3.3",
              ", ".join(f"{v:.3f}" for v in fs_) + f"; Spearman {spearman(tss, fs_):+.2f}", "none", None,
              "mu(T,t) = mu k1(T,t)/k1 is small while hot, so many contacts slide")
        r = spearman(tss, frac)
        F.add("5d", f"fully activated friction (mu_t >= 0.99 mu) rarer with t_s (after relaxation), N = {nb}, p = {p}",
              "4.3.3", ", ".join(f"{v:.3f}" for v in frac) + f"; Spearman {r:+.2f}",
              "frac(t_s=1) < frac(t_s=1e-4) and Spearman <= -0.8", (frac[-1] < frac[0]) and r <= -0.8)
    # 6 compression (the default test; the slow test is an investigation)
    for role, tag in (("compress", ""), ("compress_slow", " [investigation: 0.1/s]")):
        for n in ns:
            a, b = test_group(tests, role, n, 100).get(1.0), test_group(tests, role, n, 10).get(1.0)
            if a is None or b is None:
                F.missing("6a", f"stiffness ratio p = 100 / p = 10 at t_s = 1, N = {n}{tag}", "4.4.1-4.4.2, Figs 17, 19",
                          "1.5..3", "demsolve compress missing or failed")
                continue
            ka, kb = a.summary.get("stiffness", np.nan), b.summary.get("stiffness", np.nan)
            rr = ka / kb if kb else float("nan")

            def secant(t):
                sm = t.summary
                s0 = float(t.table["szz"][0]) if t.table is not None and "szz" in t.table else float("nan")
                return (sm.get("peak_szz", np.nan) - s0) / sm.get("peak_strain", np.nan) if sm.get("peak_strain") else np.nan
            sa, sb = secant(a), secant(b)

            def slope(t, e1):
                if t.table is None or "eps_zz" not in t.table:
                    return float("nan")
                e, z = np.asarray(t.table["eps_zz"]), np.asarray(t.table["szz"])
                m = e <= e1
                return float(np.polyfit(e[m], z[m], 1)[0]) if m.sum() > 3 else float("nan")
            la, lb = slope(a, 0.002), slope(b, 0.002)
            F.add("6a", f"stiffness ratio p = 100 / p = 10 at t_s = 1, N = {n}{tag}", "4.4.1-4.4.2, Figs 17, 19",
                  f"{ka:.4g} / {kb:.4g} = {rr:.2f}", "1.5..3", inband(rr, 1.5, 3.0),
                  "slope of szz vs eps_zz over eps in [0, 0.005] (summary.json `stiffness`); secant to the peak: "
                  f"{sa:.4g} / {sb:.4g} = {sa / sb:.2f}; slope over [0, 0.002]: {la:.4g} / {lb:.4g} = {la / lb:.2f}; peak strains {a.summary.get('peak_strain', np.nan):.4f} / "
                  f"{b.summary.get('peak_strain', np.nan):.4f}")
        for n in ns:
            for p in (10, 100):
                g = test_group(tests, role, n, p)
                if len(g) < 3:
                    for no, what in (("6b", "stress"), ("6c", "strain")):
                        F.missing(no, f"failure {what} rises with t_s (N = {n}, p = {p}){tag}", "4.4.1-4.4.2, Figs 17, 19",
                                  "Spearman >= 0.8", f"{len(g)} test(s) run (3 needed)")
                    continue
                ps = [t.summary.get("peak_szz", np.nan) for t in g.values()]
                pe = [t.summary.get("peak_strain", np.nan) for t in g.values()]
                r1, r2 = spearman(list(g), ps), spearman(list(g), pe)
                e90 = []
                for t in g.values():
                    if t.table is None or "szz" not in t.table:
                        e90.append(np.nan)
                        continue
                    z = np.convolve(np.asarray(t.table["szz"]), np.ones(9) / 9, mode="same")
                    k = int(np.argmax(z >= 0.9 * np.max(z)))
                    e90.append(float(t.table["eps_zz"][k]))
                F.add("6b", f"failure stress rises with t_s (N = {n}, p = {p}){tag}", "4.4.1-4.4.2, Figs 17, 19",
                      ", ".join(f"{v:.3g}" for v in ps) + f"; Spearman {r1:+.2f}", "Spearman >= 0.8",
                      r1 >= 0.8)
                F.add("6c", f"failure strain rises with t_s (N = {n}, p = {p}){tag}", "4.4.1-4.4.2, Figs 17, 19",
                      ", ".join(f"{v:.3g}" for v in pe) + f"; Spearman {r2:+.2f}", "Spearman >= 0.8",
                      r2 >= 0.8, "peak_strain of summary.json (strain at the maximum of szz); strain where the "
                      "smoothed szz first reaches 90 % of its maximum: " + ", ".join(f"{v:.3g}" for v in e90)
                      + f" (Spearman {spearman(list(g), e90):+.2f})")
    # 7 vibration
    for n in ns:
        for p in (10, 100):
            g = test_group(tests, "vibrate", n, p)
            for ts, no, what in ((1.0, "7a", "largest cluster holds >= 90 % of N"), (1e-4, "7b", ">= 90 % single grains")):
                if ts not in g:
                    F.missing(no, f"vibration, t_s = {ts:g}: {what} (N = {n}, p = {p})", "4.4.3, Figs 21-22", ">= 0.9",
                              "demsolve vibrate missing or failed")
            if 1.0 in g:
                v = g[1.0].summary.get("largest_cluster_fraction", np.nan)
                note = ""
                tsp = os.path.join(g[1.0].dir, "timeseries.csv")
                if os.path.isfile(tsp):
                    vt = read_table(tsp)
                    if "largest_cluster" in vt and len(vt["largest_cluster"]):
                        note = (f"before vibrating (t = 0): largest cluster {vt['largest_cluster'][0] / n:.3f} N, "
                                f"single (rattlers) {vt['single_grains'][0] / n:.3f} N")
                F.add("7a", f"vibration, t_s = 1: largest cluster holds >= 90 % of N (N = {n}, p = {p})",
                      "4.4.3, Figs 21-22", fmt(v, 3), ">= 0.9", inband(v, 0.9, 1.0), note)
            if 1e-4 in g:
                t4 = g[1e-4]
                v = t4.summary.get("single_grain_fraction", np.nan)
                note = f"largest cluster {t4.summary.get('largest_cluster_fraction', float('nan')):.3f} N"
                tsp = os.path.join(t4.dir, "timeseries.csv")
                if os.path.isfile(tsp):
                    vt = read_table(tsp)
                    if "single_grains" in vt and len(vt["single_grains"]):
                        sg = np.asarray(vt["single_grains"]) / n
                        note += f"; single-grain fraction over the test: max {np.max(sg):.2f}, mean {np.mean(sg[1:]):.2f}"
                F.add("7b", f"vibration, t_s = 1e-4: >= 90 % single grains (N = {n}, p = {p})",
                      "4.4.3, Figs 21-22", fmt(v, 3), ">= 0.9", inband(v, 0.9, 1.0), note)
    # 8 da_T = 0
    ctl = sims.get(study.sinter_name(nb if not quick else 100, 100, 1.0, "_daT0"))
    ref = grid_sims(sims, nb, 100).get(1.0)
    if ctl is not None and ctl.ok and ref is not None:
        dnu = ctl.nu("final") - ref.nu("final")
        ok = abs(dnu) <= 0.02 and ctl.densification > 0.05
        F.add("8", f"da_T = 0 changes densities slightly, not the outcome (N = {nb}, p = 100, t_s = 1)", "4.1.3",
              f"nu(t_f) {ctl.nu('final'):.4f} vs {ref.nu('final'):.4f} (diff {dnu:+.4f}); densification "
              f"{100 * ctl.densification:.2f} % vs {100 * ref.densification:.2f} %",
              "|diff nu(t_f)| <= 0.02 and densification > 5 % (our band)", ok)
    else:
        F.missing("8", f"da_T = 0 changes densities slightly, not the outcome (N = {nb}, p = 100, t_s = 1)", "4.1.3",
                  "|diff nu(t_f)| <= 0.02 and densification > 5 % (our band)", "the run or its reference is missing or failed")
    # investigation: wall friction during the preparation
    inv = sims.get(study.sinter_name(nb if not quick else 100, 100, 1.0, f"_muw{study.INVESTIGATION_MU_WALL:g}"))
    if inv is not None and inv.ok and ref is not None:
        jump = inv.nu("heat") - inv.nu("prepare")
        F.add("1c", f"nu about 0.8 after preparation with wall friction mu_w = {study.INVESTIGATION_MU_WALL:g} "
                    f"[investigation], N = {nb}, p = 100", "4.1.2, Fig 9", fmt(inv.nu("prepare"), 4), "0.78..0.82",
              inband(inv.nu("prepare"), 0.78, 0.82), f"default mu_w = 0: {ref.nu('prepare'):.4f}")
        F.add("1d", f"jump of nu at t_heat with mu_w = {study.INVESTIGATION_MU_WALL:g} [investigation]", "4.1.2, Fig 9",
              f"{jump:+.5f}", "0.001..0.01", inband(jump, 0.001, 0.01))
        F.add("3f", f"densification with mu_w = {study.INVESTIGATION_MU_WALL:g} [investigation], p = 100, t_s = 1",
              "4.1.3", f"{100 * inv.densification:.2f} % (nu(t_f) = {inv.nu('final'):.4f})", "12..20 %",
              inband(inv.densification, 0.12, 0.20))
    else:
        for no in ("1c", "1d", "3f"):
            F.missing(no, f"wall friction mu_w = {study.INVESTIGATION_MU_WALL:g} during the preparation [investigation], "
                      f"N = {nb}, p = 100", "4.1.2-4.1.3", "", "the run or its reference is missing or failed")
    issue15_rows(F, sims, nb, quick)
    # 9 Fig 8 numbers
    g = grid_sims(sims, nb, 100)
    for ts, (txt, v, tol) in PAPER_K1.items():
        s2 = g.get(ts)
        if s2 is None:
            F.missing("9", f"k1(T,t)/k1 at the end of sintering, t_s = {ts:g}", "4.1.1, Fig 8", f"{txt} +- {tol:g}",
                      "the run is missing or failed")
            continue
        k = s2.phases["sinter"]["k1_over_k1"]
        F.add("9", f"k1(T,t)/k1 at the end of sintering, t_s = {ts:g}", "4.1.1, Fig 8", f"{k:.5g}",
              f"{txt} +- {tol:g}", inband(k, v - tol, v + tol),
              "passes by construction: Eq 10-12 with Table 1's t0 fix k1(T, t); no packing enters")
    return F


# ------------------------------------------------------------------------------------------ report
def branching_check(sims):
    a = sims.get(study.sinter_name(100, 100, 0.1, "_unbranched"))
    b = sims.get(study.sinter_name(100, 100, 0.1))
    if a is None or b is None or not (a.ok and b.ok):
        return "not available"
    fa, fb = os.path.join(a.dir, "state.txt"), os.path.join(b.dir, "state.txt")
    try:
        same = open(fa, "rb").read() == open(fb, "rb").read()
    except OSError:
        return "not available"
    return ("identical (bit for bit)" if same else "DIFFERENT") + \
        f": `{os.path.relpath(fa, REPO)}` vs `{os.path.relpath(fb, REPO)}`"


def write_report(out, a, runs, sims, tests, figs, F, notes, binary, t_total, nb, ns):
    L = []
    mode = "quick" if a.quick else "full"
    prov = provenance(REPO, "luding_sintering", [binary])
    L.append("# Validation: long-time sintering (Luding, Manetsberger & Muellers 2005), section 4\n")
    L.append(f"Generated {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')} by "
             f"`/usr/bin/python3 validation/luding_sintering/run.py{' --quick' if a.quick else ''}` ({mode} grid).\n")
    L.append(f"* binary given to this invocation (used for the runs made now): `{shown(binary)}`, git revision "
             f"{a.revision or (prov['commit'] or 'unknown')[:10] + (' (work tree modified)' if prov['modified'] else '')}")
    shas = {}
    for r in list(sims.values()) + list(tests.values()):
        if r.meta.get("binary_sha256"):
            k = (r.meta["binary_sha256"][:12], shown(r.meta.get("binary", "?")))
            shas[k] = shas.get(k, 0) + 1
    L.append("* binaries of the runs (sha256 first 12 hex, path, runs): "
             + ("; ".join(f"{h} `{b}` ({c})" for (h, b), c in sorted(shas.items())) or "n/a"))
    for note in a.note or []:
        L.append(f"* {note}")
    L.append("* paper: S. Luding, K. Manetsberger, J. Muellers, J. Mech. Phys. Solids 53 (2005) 455-491")
    cpu = sum(x.meta.get("cpu_s", 0.0) or 0.0 for x in list(sims.values()) + list(tests.values()))
    wall = sum(x.meta.get("wall_s", 0.0) or 0.0 for x in list(sims.values()) + list(tests.values()))
    L.append(f"* run time: {cpu:.0f} CPU-s summed over {len(sims) + len(tests)} runs ({wall:.0f} s wall summed; "
             f"this invocation {t_total:.0f} s wall, shared 2-core machine, `nice -n 10`)")
    L.append(f"* branching check (`--state state_heat.txt` vs the unbranched run, N = 100, p = 100, t_s = 0.1): "
             f"{branching_check(sims)}\n")
    if notes:
        L.append("Notes from the runner:\n")
        for n in notes:
            L.append(f"* {n}")
        L.append("")
    L.append("## Findings\n")
    counts = tally(r[5] for r in F.rows)
    L.append(f"{totals_text(counts)} (other: investigation or information; MISSING: could not be evaluated, the reason "
             "in the measured column). Bands are fixed in `run.py` (`evaluate()`) and are never widened to make a finding pass.\n")
    L.append("| # | paper's finding | source | measured | band | result | note |")
    L.append("|---|---|---|---|---|---|---|")
    for r in F.rows:
        L.append("| " + " | ".join(str(x).replace("|", "/") for x in r) + " |")
    L.append("")
    L.append("## Summary of the sinter runs\n")
    L.append("| run | nu(t_heat) | nu(0.3) | nu(end sinter) | nu(t_f) | densification | C(end sinter) | C w/o walls | "
             "k1/k1 end sinter | CPU s |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    for s in sims.values():
        if not s.ok:
            L.append(f"| {s.name} | failed or missing |||||||||")
            continue
        sp = s.phases.get("sinter", {})
        L.append(f"| {s.name} | {fmt(s.nu('prepare'), 4)} | {fmt(s.nu('heat'), 4)} | {fmt(s.nu('sinter'), 4)} | "
                 f"{fmt(s.nu('final'), 4)} | {100 * s.densification:.2f} % | {fmt(sp.get('C'), 2)} | "
                 f"{fmt(sp.get('C_without_walls'), 2)} | {sp.get('k1_over_k1', float('nan')):.4g} | {fmt(s.cpu_s, 1)} |")
    L.append("")
    if tests:
        L.append("## Material tests\n")
        L.append("| run | stiffness [N/m] | peak szz | peak strain | largest cluster / N | single grains / N | clusters | CPU s |")
        L.append("|---|---|---|---|---|---|---|---|")
        for t in tests.values():
            sm = t.summary or {}
            def g4(k, sm=sm):
                v = sm.get(k)
                return f"{v:.4g}" if isinstance(v, (int, float)) else ""
            L.append(f"| {t.name} | {g4('stiffness')} | {g4('peak_szz')} | {g4('peak_strain')} | "
                     f"{g4('largest_cluster_fraction')} | {g4('single_grain_fraction')} | "
                     f"{g4('clusters')} | {fmt(t.meta.get('cpu_s'), 1)} |")
        L.append("")
    L.append("## Figures\n")
    for f_ in figs:
        if f_:
            L.append(f"![{f_}]({f_})\n")
    L.append(experiment_table(sims, nb))
    L.append(KNOWN_DIFFERENCES)
    L.append("## Commands\n")
    L.append("Every run (dependency order; `study.py --print-commands"
             f"{' --quick' if a.quick else ''}` prints the same list), each run under `nice -n 10`:\n")
    L.append("```")
    for r in runs:
        L.append(shlex.join([shown(binary)] + [shown(x) for x in r.args]))
    L.append("```\n")
    L += provenance_lines(prov, counts)
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write("\n".join(L) + "\n")


KNOWN_DIFFERENCES = """## Known differences, explanations and open points

Numbers below are from the full grid (N = 300 unless stated); the findings table above is the
reference for the current runs.

### Issue 15: the headline findings, what the audit changed, what does not reproduce and why

* **The law audit** (docs/luding.md, audit table) found one departure from the text: on cooling,
  section 3.3.2 ends "also the stiffness is increased accordingly", while our k2' line was kept.
  Fixed: delta_max^- now solves delta_max (1 - k1(T)/k2(delta_max)) = delta_0 with Eq 7 at the new
  delta_max, and k2', k_c (Eq 13), f_min (Eq 15) and k_t (Eq 23) grow with it (test
  `Luding.CoolingReevaluatesEq7`). A contact at delta_max = 0.1 a0 cools to k2' = 1.63e5 N/m instead
  of 1.25e5. Before/after (experiment "k2' kept on cooling" against the reference, N = 300, t_s = 1):
  attractive fraction after cool-down 0.000 -> 0.004 (p = 10) and 0.025 -> 0.037 (p = 100), width
  q95 - q05 after/before cool-down 0.84 -> 0.93 (p = 10) and 0.99 -> 1.14 (p = 100); nu(t_f) moves by
  < 0.0005. The freeze rule of section 3.4, the quenched time axis (t0 = 0.1 s during sintering only),
  Eq 9-12, footnote 5 and Eq 1 are implemented as written.
* **Attractive contacts after cool-down (15a): not reproduced.** Band >= 0.2; measured 0.004
  (p = 10) and 0.037 (p = 100), and 0.000-0.054 in every experiment of the table above that cools
  in 0.1 s or slower: three seeds
  (p = 100: 0.037, 0.000, 0.006 - the fraction is seed noise at this level), N = 1000 (0.015, 0.004),
  no thermal expansion (0.045, 0.054), the text's larger expansion da_T = 2.5e-4 (0.000, 0.000),
  footnote 5 off (0.010, 0.007: cohesion while sliding does not create attraction), wall contacts
  that do not creep (0.005, 0.006), the old k2' rule. |q05|/q95 stays at 0.001-0.27 (band 0.5-2):
  the pdf stays one-sided. **Why:** at the end of sintering 97-99.7 % of the pair contacts sit on
  their loading line (delta >= delta_0; delta < delta_0 for 2.9 % at p = 10 and 0.3 % at p = 100,
  from `state_sinter.txt`), and
  the cool-down is affine: the box contracts by 0.601-0.628 % (linear) while Eq 9 shrinks the radii
  by 0.599 % (column "box / radius contraction"; 1.51-1.55 % vs 1.49 % with da_T = 2.5e-4). An
  affine contraction changes every overlap by the fraction 0.6 % of itself, a change of 0.6 % of
  delta_0 ~ 6e-4 a0 that is nearly proportional to the contact force (delta_0 ~ f/k1(T,t) after
  creep), so it rescales the force state instead of making it two-sided; the rising k1 moves
  delta_max, not the force (section 3.3.2), and the re-evaluated k2' scales the forces on the line by
  the same sign. Attraction needs contacts pulled below delta_0, i.e. a non-affine cool-down. The
  result turns on the **cooling rate relative to the packing's response**: cooling in 1 ms instead
  of 0.1 s (experiment "quench", branched at t = 1.3) leaves the box behind the radii (0.35-0.38 %
  against 0.60 %) and freezes in a self-stressed block: at p = 10 the attractive fraction becomes
  0.205 (>= 0.2; 20.5 % of the contacts below delta_0 in `state.txt`; 425 pair contacts against 563 after the 0.1 s cool-down) and
  the width grows x 2.7, at p = 100 0.073 and x 1.6; cooling in 1 s changes
  nothing (0.037, x 1.13). The walls are not the bottleneck: 100 x the wall damping (20 kg/s) during
  the cool-down creates no attraction either (0.000 at p = 10, 0.035 at p = 100). The section 4.1 protocol states the cool-down time (0.1) but
  calls "the time unit ... arbitrary" and the process quasi-static; with Table 1's parameters our
  0.1 s cool-down is quasi-static, so the paper's "almost equally strong attractive and repulsive
  contact forces" are reproduced only by a cool-down about 100 times faster than the text's, and
  even then |q05|/q95 stays below 0.5 (0.23 at p = 10). None of the Table 1 parameters we varied
  (da_T, footnote 5, the wall law and damping, the k2' rule) turns the result on.
* **Broadening on cool-down (15a, width):** passes at p = 100 (x 1.14), fails at p = 10 (x 0.93);
  with the seeds 2 and 3 at p = 100 it is x 0.91 and x 0.90, so the p = 100 pass is not robust.
* **Density through the cool-down (15b):** nu(t_f) = 0.9245 at p = 100, t_s = 1 passes (band
  0.92-0.96; seeds: 0.9250 +- 0.0032); the rise on cool-down is +0.0003 against the paper's about
  +0.02 (fails). With the radii held at T_melt (nu computed from fixed radii) the same run rises by
  +0.011: the paper's rise "due to negative thermal expansion" is what a fixed-radius nu gives for
  an affine contraction of 0.6 % (1.2 % in area); with da_T = 2.5e-4 it would be 3 %. The paper
  does not say which radii its nu uses; its only definition (section 3.1.3) is N pi h a0^2 / V.
* **Coordination dips (15c):** 0 dips in the N = 300 grid runs (t_s = 1, both p) with the issue's
  definition; seeds 2 give 1 dip each (p = 10 and p = 100), seeds 3 and N = 1000 none. At N = 100
  one lost contact is already a dip (2/N = 0.02): p = 100 has 1, p = 10 none. The largest fall
  of the smoothed C over 10 ms while nu rises is one contact (-0.0067 at N = 300), so in our runs C
  rises almost monotonically during sintering: the creep is smooth, without the "large scale
  re-organizations" of Fig 11. Not reproduced (rare at best); not a sampling issue (0.4 ms).
* **Narrowing (15d):** (q95 - q05)/mean of f_n at the end of sintering falls with t_s at p = 100
  (2.34 -> 1.81, Spearman -0.89, passes) but not at p = 10 (Spearman +0.09).
* **Three-particle control (3c, 3d, 15e).** The law is homogeneous of degree one in force and
  overlap while delta << delta_max^fluid = 0.4 a0 (Eq 7) and delta_0 < delta_fluid, so the
  densification of a fixed arrangement scales with p: our p = 100 / p = 10 ratio is 10.4-10.6
  (creeping walls) and 10.2-10.6 (non-creeping walls), while the paper's estimates (8 % and 0.2 %)
  have the ratio 40; no Table 1 parameter makes the three-particle densification non-linear in p
  at these overlaps. With creeping wall contacts (default) the triangle densifies 24 % at p = 100,
  more than the paper's bulk samples (16 %), which would contradict the paper's conclusion drawn
  from this control ("the strong increase in density observed for larger samples is caused by
  re-arrangements"); with `--param wall_sintering=0` the values are 5.8 % / 3.4 % (p = 100,
  triangle / line) and 0.57 % / 0.32 % (p = 10), i.e. 0.4-0.7 x and 1.6-2.9 x the paper's. We keep
  creeping walls as the default because the bulk density then agrees with Fig 9 (N = 300, p = 100:
  nu(t_f) = 0.9245 with, 0.9108 without creeping walls).
* **Preparation density:** seeds 1-3 give 0.8262 +- 0.0021 (p = 10) and 0.8296 +- 0.0023
  (p = 100) at N = 300, N = 1000 gives 0.836 / 0.838 and N = 100 0.811: nu grows with N (fewer wall
  particles); the paper's 0.8 at N = 300 is 12-13 sample standard deviations below our seeds.

* **Preparation density (finding 1a).** The paper reports nu ~ 0.8 after the frictionless
  preparation; demsolve gives 0.825 (p = 10) and 0.828 (p = 100) for N = 300 (0.812 and 0.811 for
  N = 100, within the band). These numbers move by ~0.003 with round-off: a binary differing only
  in the last bits of the force loop (before the issue #4 speed commit) gave 0.827 and 0.831. The paper says that the wall friction was switched off at t_heat, which
  implies wall friction during the preparation, while Table 1 gives mu_w = 0; our default follows
  Table 1. The **investigation** run `N300_p100_ts1_muw0.5` (`--mu-wall 0.5` during the preparation,
  not a default) does *not* explain the difference: it prepares slightly denser (0.831), and no jump
  appears at t_heat (findings 1c, 1d). The source of the paper's lower preparation density stays
  open (a shorter effective compression, a different density definition or wall treatment; 0.83 is
  close to random close packing of these polydisperse frictionless disks).
* **Jump at t_heat (finding 1b).** With mu_w = 0 there is nothing to switch off at t_heat and the
  frictionless packing is already static, so the small jump of Fig 9 is absent by construction
  (nu(0.3) - nu(0.2) < 1e-5); also absent with mu_w = 0.5.
* **Densification (findings 3a, 3b).** The *final* densities agree with those the paper implies
  (p = 100: 0.925 vs 0.8 x 1.16 = 0.928; p = 10: 0.838 vs 0.8 x 1.05 = 0.84, finding 3e), and the
  densities at t = 1.3 and t_f pass (2b, 2c). The densification nu(t_f)/nu(t_heat) - 1 falls short
  (11.7 % vs 16 +- 4 %, 1.5 % vs 5 +- 2 %) because our sample starts denser (previous point): from
  nu = 0.80 the same final density would be a 15.6 % densification at p = 100.
* **Three-particle controls (3c, 3d, 3g, 15e).** demsolve applies the full sintering law to
  particle-wall contacts as well (default `wall_sintering=1`), and a three-particle sample has more
  wall contacts than particle contacts (triangle: 3 pairs + 5 wall contacts; line: 2 pairs + 8 wall
  contacts), so its box shrinks by the creep of the wall contacts too: 17-24 % at p = 100 and
  1.7-2.3 % at p = 10 against the paper's estimates 8 % and 0.2 % ("data not shown"). With wall
  contacts that keep the cold k1 (`--param wall_sintering=0`, line 15e) it is 3.4-5.8 % and
  0.32-0.57 %; the estimate from the snapshots with the wall overlaps frozen (3g) agrees. See the
  issue 15 section above for the p-scaling (10 in our law, 40 in the paper's estimates).
* **Cooling (findings 2c, 2d, 5c).** See the issue 15 section above (15a, 15b): the cool-down is
  affine, adds +0.0003 to nu computed from the current radii and +0.011 computed from the radii at
  T_melt (2d); min f_n / max f_n after cool-down is in line 5c, the attractive fraction in 15a.
  Fixed radii would not explain the preparation density (0.828 / 0.992 = 0.835 with radii at T_melt).
* **Force homogenisation (5b, 15d).** std(f_n)/mean(f_n) at the end of sintering falls from
  t_s = 1e-4 to 1 for p = 100 (0.73 -> 0.55, but not monotonically: Spearman -0.49) and not for
  p = 10; the width (q95 - q05)/mean (15d) falls with Spearman -0.89 at p = 100 (pass) and not at
  p = 10.
* **Fully activated friction after cool-down (5d).** No contact has mu_t >= 0.99 mu after the
  relaxation, for any t_s: the tangential springs were limited by the hot mu(T, t) = mu k1(T,t)/k1
  (~0.01 at the end of long sintering) and the nearly affine, quasi-static cool-down does not
  re-mobilise them once mu is back to 0.5. The trend "rarer with t_s" can therefore not be seen;
  at the end of sintering (5e, information) the fraction of fully activated contacts is 0-34 %.
* **Compression test (6a-6c).** The top wall starts smoothly (`--ramp-time`, default 5 ms, speed
  rising as (1 - cos)/2): the first version of this grid started it at full speed, and the
  stress-controlled right wall (m_w = 0.01 kg, ~260 particle masses, gamma_w = 0.2 kg/s, damping
  time 0.05 s) then rang with a period of ~7 ms, comparable with the 5 ms needed to reach
  eps = 0.005, which made the fitted stiffness of weak samples negative and the ratio 3.1 (N = 100)
  and 4.0 (N = 300). With the ramp the ratio over the issue's window [0, 0.005] was 2.95 and 2.85
  before issue 15; the section 3.3.2 fix (k2' re-evaluated on cooling) makes the cooled contacts
  stiffer, more so the strongly sintered ones of p = 100 (stiffness 9.0e4 -> 1.13e5 N/m at N = 100,
  9.9e4 -> 1.25e5 at N = 300, against 3.0e4 -> 3.5e4 and 3.5e4 -> 3.8e4 at p = 10), so the ratio is
  now 3.27 and 3.32, just above the band (6a FAIL; the band is not widened). The initial slope over
  [0, 0.002] gives 2.06 and 2.06 and the secant to the peak 2.20 and 2.19, in line with the paper's
  "about two" (notes of 6a). The stiffness of the weak p = 10 samples depends on the strain rate:
  the 10 times slower **investigation** (`*_compress_slow`, 0.1/s) gives 1.2e4 instead of 3.5e4 N/m
  for N = 100 while the p = 100 value stays, so the ratio there is 9.2 and 14: at 1/s part of the
  p = 10 response is the
  damping and inertia of the contacts, and the paper does not state its rate. For weak samples the
  peak of sigma_zz comes early (eps ~ 0.003-0.004, inside the window) and the failure strain of
  unsintered samples is ill-defined (a noisy plateau after an early yield, stick-slip of the right
  wall), which breaks the monotonic trend of the failure strain at short t_s (6c); the failure
  stress rises with t_s everywhere (6b).
* **Vibration (7a, 7b).** `demsolve vibrate` defines a cluster by touching pairs at the end of the
  test; in a vibrated bed (peak floor acceleration 8 g) non-cohesive grains that happen to collide or
  rest on each other count as clusters, so the single-grain fraction of unsintered samples stays near
  0.6-0.9 even though the largest cluster holds only 1-3 % of N; conversely, rattlers (disks without
  contacts inside the sintered block, already present before the vibration, see the note of 7a)
  count as broken-off single grains and lower the largest-cluster fraction of sintered samples.
  A cluster definition by cohesive (attractive or sintered) bonds, or by distance with a small
  gap tolerance, would match the paper's visual judgement better. After the issue 15 fix the
  N = 300, p = 10, t_s = 1 sample keeps 0.897 N in its largest cluster (0.923 before; 0.960 N
  before vibrating, 4 % rattlers), just below the band (7a FAIL); 7b for N = 300, p = 10 now passes
  (0.947, was 0.853). These lines move by a few per cent between binaries: one or two fragments.
* **Zero-length phases (demsolve), fixed.** The first version of this study found that
  `demsolve sinter --sinter-time 0 --cool-time 0 --relax-time 0` did not end in the heated state:
  the last time step (t = K dt slightly past 0.3) fell past the zero-length phases into `relax` at
  T_cold. Fixed (the schedule time is clamped to the protocol's end; CLI test
  `zero_length_phases_end_hot`) before the current grid ran. The study still branches from
  `state_heat.txt` of the t_s = 1e-4 run, whose first 0.3 s are identical.
* The three-particle, da_T = 0 and mu_w investigation runs are made from scratch (no branching).
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="N = 100, t_s in {1e-4, 0.1, 1}")
    ap.add_argument("--demsolve", default=study.DEFAULT_BIN)
    ap.add_argument("--netsolve", default=None, help="ignored (accepted for validation/run_all.sh)")
    ap.add_argument("--jobs", type=int, default=2, help="simulations in parallel (default 2)")
    ap.add_argument("--out", default=None, help="folder for report.md and PNGs (default: this folder or ./quick)")
    ap.add_argument("--runs", default=None, help="folder of the run folders (default: ./runs)")
    ap.add_argument("--force", action="store_true", help="rerun every run")
    ap.add_argument("--report-only", action="store_true", help="run nothing, only rebuild the report")
    ap.add_argument("--timeout", type=float, default=7200, help="per-run time limit in seconds")
    ap.add_argument("--note", action="append", help="a line to add to the report header (repeatable)")
    ap.add_argument("--revision", default=None,
                    help="git revision to record for the binary (default: this repository's HEAD and its state)")
    a = ap.parse_args()
    import time
    t0 = time.time()
    out = os.path.abspath(a.out or (os.path.join(HERE, "quick") if a.quick else HERE))
    runs_dir = os.path.abspath(a.runs or os.path.join(HERE, "runs"))
    os.makedirs(out, exist_ok=True)
    runs = study.build_runs(runs_dir, a.quick)
    notes = []
    binary = os.path.abspath(a.demsolve)
    if os.access(binary, os.X_OK):
        runs_x, notes = study.adapt_to_binary(runs, binary)
        if not a.report_only:
            print(f"luding_sintering: {len(runs_x)} runs, --jobs {a.jobs}")
            res = study.execute(runs_x, binary, a.jobs, a.force, a.timeout)
            for name, (ok, msg) in res.items():
                if not ok:
                    notes.append(f"{name}: {msg}")
    else:
        notes.append(f"no executable demsolve at {binary}: report from existing runs only")
    sims, tests = {}, {}
    for r in runs:
        if r.kind == "sinter":
            sims[r.name] = Sim(r, sims)
        elif os.path.isfile(os.path.join(r.dir, "summary.json")):
            tests[r.name] = Test(r)
    ns = study.QUICK_N if a.quick else study.GRID_N
    nb = max(ns)
    figs = [fig8(sims, nb, out), fig9(sims, nb, out), fig10(sims, ns, out), fig11(sims, nb, out),
            fig_overlap(sims, nb, "sinter", 12, out), fig_overlap(sims, nb, "relax", 13, out),
            fig_force(sims, nb, 10, 14, out), fig_force(sims, nb, 100, 15, out)]
    for role in ("compress", "compress_slow"):
        for n, f1, f2 in ((100, 16, 17), (300, 18, 19)):
            if n in ns:
                figs += [fig_compress(tests, n, "nu", "nu", f1, out, role),
                         fig_compress(tests, n, "szz", "sigma_zz [N/m]", f2, out, role)]
    figs += [fig_vibrate(tests, ns, out), fig_cluster_sizes(tests, nb, out)] + fig_vibration_snapshots(tests, nb, out)
    figs += [fig_controls(sims, nb, out)]
    F = evaluate(sims, tests, nb, ns, a.quick)
    write_report(out, a, runs, sims, tests, figs, F, notes, binary, time.time() - t0, nb, ns)
    for r in F.rows:
        print(f"  [{r[5]}] {r[0]} {r[1]}: {r[3]} (band {r[4]})")
    print(f"luding_sintering: report -> {os.path.join(out, 'report.md')}")
    bad = [n for n in notes if "failed" in n or "rc=" in n]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
