"""The figures of the Luding et al. (2005) study (run.py): the paper's Figs 8-20 from the runs."""
import os

import numpy as np

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import study  # noqa: E402
from analysis import PAPER_K1, cool_sweep, grid_sims, read_vtp, test_group  # noqa: E402

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


def fig_cooldown(sims, nb, out):
    """Issue 32: the attractive fraction after cool-down against cool-down time / tau_w (Eq 1)."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for p, mw, style in ((10, None, "o-"), (100, None, "s-"), (100, study.COOL_LIGHT_WALL, "s--")):
        pts = cool_sweep(sims, nb, p, mw)
        if not pts:
            continue
        lab = f"p = {p:g}, tau_w = {1e3 * pts[0][1]:.0f} ms" + (f" (m_wall = {mw:g})" if mw is not None else "")
        ax.plot([c / tw for c, tw, _ in pts], [a for _, _, a in pts], style, label=lab)
    ax.set_xscale("log")
    ax.set_xlabel("cool-down time / tau_w (tau_w = m_wall / gamma_wall, Eq 1)")
    ax.set_ylabel("attractive fraction after relaxation")
    ax.set_title(f"Attraction after cool-down, N = {nb}, t_s = 1")
    ax.legend(fontsize=8)
    return save(fig, out, "fig_cooldown_attraction.png")
