"""The figures of the Redanz & Fleck (2001) compaction study (run.py): Figs 5-8 from the runs'
history.csv files, with the paper's line styles."""
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.axes_grid1.inset_locator import inset_axes  # noqa: E402

STYLE = {  # Fig 5-8 line styles: friction level by colour, affine black (solid in the paper)
    "mu0": dict(color="tab:blue", ls="-"),
    "mu0.1": dict(color="tab:orange", ls="-"),
    "inf": dict(color="tab:green", ls="-"),
    "inf_norot": dict(color="tab:red", ls="--"),
    "affine": dict(color="black", ls="-"),
    "affine_mu0": dict(color="black", ls="-"),
    "affine_inf": dict(color="dimgray", ls="-."),
}


def sty(name):
    key = name.split("_", 1)[1] if "_" in name else name
    return STYLE.get(key, dict(color="gray", ls=":"))


def finish(ax, ylabel, title, ncol=2):
    ax.set_xlabel("relative density D")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=ncol, frameon=False)


def make_figures(R, out, mode_label, cases):
    figs = {}

    def save(fig, fname):
        fig.savefig(os.path.join(out, fname), dpi=110, bbox_inches="tight")
        plt.close(fig)
        figs[fname] = True

    # Fig 4: mono vs poly, hydrostatic, sticking and frictionless
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    for name, col in (("hydro_inf", "tab:green"), ("hydro_mu0", "tab:blue"),
                      ("mono_hydro_inf", "tab:olive"), ("mono_hydro_mu0", "tab:purple")):
        r = R.get(name)
        if not r or not r.ok:
            continue
        mu = "sticking" if name.endswith("inf") else "mu = 0"
        pk = "r = R" if name.startswith("mono") else "r = R[0.9,1.1]"
        ax.plot(r.h["D"], r.mag("S22"), color=col, ls="-", label=f"-S22/sy, {pk}, {mu}")
        ax.plot(r.h["D"], r.mag("S11"), color=col, ls="--", label=f"-S11/sy, {pk}, {mu}")
    finish(ax, "-Sigma_ij / sigma_y  (compression)", f"Fig 4 style: hydrostatic compaction, mono vs poly ({mode_label})")
    save(fig, "fig4_hydrostatic_mono_poly.png")

    # Fig 5a: hydrostatic -S22
    hydro = ["hydro_mu0", "hydro_mu0.1", "hydro_inf", "hydro_inf_norot", "hydro_affine"]
    die = ["die_mu0", "die_mu0.1", "die_inf", "die_inf_norot", "die_affine_mu0", "die_affine_inf"]
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    for name in hydro:
        r = R.get(name)
        if r and r.ok:
            ax.plot(r.h["D"], r.mag("S22"), label=r.label, **sty(name))
    finish(ax, "-Sigma_22 / sigma_y  (compression)", f"Fig 5a style: hydrostatic, polydisperse ({mode_label})")
    save(fig, "fig5a_hydrostatic_S22.png")

    # Fig 5b: closed die -S22 (thick) and -S11 (thin)
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    for name in die:
        r = R.get(name)
        if r and r.ok:
            s = sty(name)
            ax.plot(r.h["D"], r.mag("S22"), lw=2.0, label=f"-S22, {r.label}", **s)
            ax.plot(r.h["D"], r.mag("S11"), lw=0.9, label=f"-S11, {r.label}", color=s["color"], ls=":")
    finish(ax, "-Sigma_ij / sigma_y  (compression)",
           f"Fig 5b style: closed die, S22 (thick) and S11 (thin dotted) ({mode_label})")
    save(fig, "fig5b_closed_die_S22_S11.png")

    # Fig 6a/b: Z
    for tag, names, title in (("6a", hydro, "hydrostatic"), ("6b", die, "closed die")):
        fig, ax = plt.subplots(figsize=(7.0, 5.0))
        for name in names:
            r = R.get(name)
            if r and r.ok:
                ax.plot(r.h["D"][1:], r.h["Z"][1:], label=r.label, **sty(name))
        finish(ax, "co-ordination number Z (load-bearing contacts)", f"Fig {tag} style: {title} ({mode_label})")
        save(fig, f"fig{tag}_{'hydrostatic' if tag == '6a' else 'closed_die'}_Z.png")

    # Fig 7a/b: normal affine deviation. Left: linear, paper-like axes (mean-of-ratios curves may leave
    # the axes, see the note); right: the same on a log axis, everything visible.
    for tag, names, title in (("7a", hydro[:4], "hydrostatic"), ("7b", die[:4], "closed die")):
        fig, (ax, axl) = plt.subplots(1, 2, figsize=(11.0, 5.0))
        for name in names:
            r = R.get(name)
            if r and r.ok:
                s = sty(name)
                for a in (ax, axl):
                    a.plot(r.h["D"][1:], r.h["dev_un_mean_ratio"][1:], label=f"<|uN-uNA|/uNA>, {r.label}", **s)
                    a.plot(r.h["D"][1:], r.h["dev_un_ratio_of_means"][1:], lw=0.8, color=s["color"], ls=":",
                           label=f"<|uN-uNA|>/<uNA>, {r.label}")
        for a in (ax, axl):
            a.axhline(2.0, color="k", lw=0.5, ls="--")
            a.axhline(0.5, color="k", lw=0.5, ls="--")
        top = max([2.5] + [1.2 * float(np.max(R[n].h["dev_un_ratio_of_means"][1:])) for n in names
                           if R.get(n) and R[n].ok])
        top = min(top, 20.0)
        over = [f"{n} (max {float(np.max(R[n].h['dev_un_mean_ratio'][1:])):.3g})" for n in names
                if R.get(n) and R[n].ok and float(np.max(R[n].h["dev_un_mean_ratio"][1:])) > top]
        ax.set_ylim(0, top)
        if over:
            ax.text(0.01, 0.98, "off scale: <|uN-uNA|/uNA> of\n" + "\n".join(over), transform=ax.transAxes,
                    fontsize=6, va="top")
        axl.set_yscale("log")
        axl.set_xlabel("relative density D")
        axl.set_title("same, log scale", fontsize=10)
        axl.grid(alpha=0.3)
        finish(ax, "normal affine deviation", f"Fig {tag} style: {title} (dashed lines: 200 %, 50 %) ({mode_label})")
        save(fig, f"fig{tag}_{'hydrostatic' if tag == '7a' else 'closed_die'}_normal_deviation.png")

    # Fig 8a/b: tangential affine deviation, frictionless in an inset (as in the paper)
    for tag, names, title in (("8a", hydro[:4], "hydrostatic"), ("8b", die[:4] + ["die_affine_mu0", "die_affine_inf"],
                                                                  "closed die")):
        fig, ax = plt.subplots(figsize=(7.0, 5.0))
        ins = inset_axes(ax, width="38%", height="38%", loc="upper right", borderpad=1.2)
        for name in names:
            r = R.get(name)
            if not (r and r.ok):
                continue
            s = sty(name)
            if "affine" in name:
                ax.plot(r.h["D"][1:], r.h["affine_ut"][1:], label=f"<|uTA|>/<uNA>, {r.label}", **s)
                continue
            target = ins if name.endswith("mu0") else ax
            target.plot(r.h["D"][1:], r.h["dev_ut_rotations"][1:], label=f"uT with rotations, {r.label}", **s)
            target.plot(r.h["D"][1:], r.h["dev_ut_centres"][1:], lw=0.8, color=s["color"], ls=":",
                        label=f"centres only, {r.label}")
        ins.set_title("mu = 0", fontsize=7)
        ins.tick_params(labelsize=6)
        ins.grid(alpha=0.3)
        ax.set_xlabel("relative density D")
        ax.set_ylabel("<|uT - uTA|> / <uNA>")
        ax.set_title(f"Fig {tag} style: {title}; inset: frictionless ({mode_label})", fontsize=10)
        ymax = max([0.1] + [float(np.max(l.get_ydata())) for l in ax.get_lines()])
        ax.set_ylim(0, 1.75 * ymax)  # room for the inset above the curves
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
        save(fig, f"fig{tag}_{'hydrostatic' if tag == '8a' else 'closed_die'}_tangential_deviation.png")

    # solver health: residual per increment
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    cmap = plt.get_cmap("tab20")
    for k, name in enumerate(cases):  # the cases in run.py's order
        r = R.get(name)
        if r and r.ok:
            ax.semilogy(r.h["D"][1:], np.maximum(r.h["residual"][1:], 1e-16), lw=0.7, color=cmap(k % 20),
                        label=name)
    ax.axhline(1e-6, color="k", ls="--", lw=0.8)
    finish(ax, "residual (max / mean contact force) at commit", f"Solver residual per increment ({mode_label}); "
           "dashed: --tol", ncol=4)
    save(fig, "fig_solver_residual.png")
    return list(figs)


# ---------------------------------------------------------------------------------------- findings
