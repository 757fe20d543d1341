"""P2 figures: Figs. 1, 2, 3a and 3b of the augmented paper (steps ``figure_trajectories``,
``figure_heatmap``, ``figure_realaxis``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from eqrec.studies.outputs import save_figure
from eqrec.studies.plotting import paper_style, pyplot, trajectory_panel


def _levels(T: int, mu1: float, mu2: float) -> np.ndarray:
    lev = np.full(T + 1, mu2)
    lev[0] = lev[-1] = mu1
    return lev


def step_figure_trajectories(cfg, inputs, outputs, wildcards) -> None:
    """P2-F1 / P2-F2: augmented (left) vs time-based (right), same draws, certified guarantee bars.

    For F2 a third column shows the 1-based-reading design run on the true data.
    """
    fig = wildcards["fig"]
    paper_style()
    plt = pyplot()
    d = json.loads(Path(inputs.designs).read_text())[fig]
    sim = np.load(inputs.simulation)
    mu1 = float(cfg["mu1"])
    cols = [("augmented_free", f"augmented (IPOPT), $\\mu_2$ = {d['augmented_free']['certified_mu2']:.4g}",
             d["augmented_free"]["certified_mu2"], "C0"),
            ("time", f"time-based, $\\mu_2$ = {d['time']['certified_mu2']:.4g}", d["time"]["certified_mu2"], "C1")]
    if fig == "f2" and "f2/one_based" in sim.files:
        c = d["one_based"]["certified_on_true_words"][d["worst_case_word"]]
        cols.append(("one_based", f"1-based reading ({d['one_based']['word']}) on true data,\ncertified {c:.4g}",
                     c, "C3"))
    errs0 = sim[f"{fig}/time"]
    T = errs0.shape[1] - 1
    f, axes = plt.subplots(3, len(cols), figsize=(3.3 * len(cols), 6.0), sharex=True, squeeze=False,
                           layout="constrained")
    for j, (name, title, mu2, color) in enumerate(cols):
        trajectory_panel(axes[:, j], sim[f"{fig}/{name}"], _levels(T, mu1, mu2), title, color=color,
                         ylabels=(j == 0))
    for i in range(axes.shape[0]):  # one scale per state across the estimators (the same quantity)
        lim = max(abs(v) for ax in axes[i] for v in ax.get_ylim())
        for ax in axes[i]:
            ax.set_ylim(-lim, lim)
    # one legend entry per estimator, in its own colour, and the bars
    handles = [plt.Line2D([], [], color=color, lw=1.2) for _, _, _, color in cols]
    labels = [f"error: {title.split(',')[0].split(' (')[0]}" for _, title, _, _ in cols]
    bars = axes[0, 0].get_legend_handles_labels()[0][-1]
    f.legend(handles + [bars], labels + ["certified guarantee"], loc="outside lower center", ncol=len(cols) + 1)
    f.suptitle(f"{'no missing data' if fig == 'f1' else 'language ' + str(d['language'])}: "
               f"{errs0.shape[0]} runs, same draws for every estimator")
    save_figure(f, outputs.pdf, outputs.png)


#: Colours of the non-optimal classes of a sweep point (the optimal ones carry the colour scale).
CLASS_STYLE = {"infeasible": ("0.82", "LP infeasible"), "solver_failed": ("tab:orange", "solver failure (both solvers)"),
               "placement_failed": ("black", "placement failure")}


def _edges(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[lo], mid, [hi]])


def _polar_grid(g: pd.DataFrame, r_grid: np.ndarray, th_grid: np.ndarray, column: str) -> np.ndarray:
    """``(n_theta, n_r)`` array of one column of a variant's rows, placed by nearest grid point."""
    i = np.abs(g["r"].to_numpy(float)[:, None] - r_grid[None, :]).argmin(axis=1)
    j = np.abs(g["theta"].to_numpy(float)[:, None] - th_grid[None, :]).argmin(axis=1)
    out = np.full((len(th_grid), len(r_grid)), np.nan if column != "status" else "", dtype=object)
    out[j, i] = g[column].to_numpy()
    return out


def _heat_panel(ax, plt, g, r_grid, th_grid, column, norm, cmap, outline_tol=None, interval=None):
    """One filled polar map in the complex plane: optimal points coloured by ``column``, every other class
    filled with its own colour; returns the mappable, the legend handles and the counts per class (text)."""
    from matplotlib import patheffects
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    R, TH = np.meshgrid(_edges(r_grid, 0.0, r_grid[-1]), _edges(th_grid, 0.0, np.pi))
    X, Y = R * np.cos(TH), R * np.sin(TH)
    status = _polar_grid(g, r_grid, th_grid, "status")
    val = _polar_grid(g, r_grid, th_grid, column).astype(float)
    ok = status == "optimal"
    pm = ax.pcolormesh(X, Y, np.ma.masked_where(~ok, val), cmap=cmap, norm=norm, shading="flat")
    handles = []  # the optimal points' colours are on the colour bar
    counts = [f"optimal {int(ok.sum())}"]
    for cls, (color, label) in CLASS_STYLE.items():
        m = status == cls
        if m.any():
            ax.pcolormesh(X, Y, np.ma.masked_where(~m, np.ones(m.shape)), cmap=ListedColormap([color]),
                          shading="flat")
            counts.append(f"{label} {int(m.sum())}")
        handles.append(Patch(facecolor=color, edgecolor="0.5", label=label))
    if "observer" in g and (g["observer"] == "deadbeat").any():
        handles.append(plt.Line2D([], [], marker="*", ls="", color="magenta",
                                  label=f"r = 0: nilpotent L ({int((g['observer'] == 'deadbeat').sum())} points)"))
        ax.plot([0], [0], "*", color="magenta", ms=8, zorder=5)
    if outline_tol is not None and ok.any():
        at_min = np.ma.masked_where(~ok, np.where(ok, val <= np.nanmin(np.where(ok, val, np.nan)) + outline_tol,
                                                  False).astype(float))
        if 0 < at_min.sum() < ok.sum():
            Rc, THc = np.meshgrid(r_grid, th_grid)
            halo = [patheffects.withStroke(linewidth=2.4, foreground="black")]
            cs = ax.contour(Rc * np.cos(THc), Rc * np.sin(THc), at_min, levels=[0.5], colors="white", linewidths=1.2)
            cs.set(path_effects=halo)
            handles.append(plt.Line2D([], [], color="white", lw=1.2, label="edge of the region at the minimum",
                                      path_effects=halo))
    if interval is not None:
        ax.plot(interval, [0, 0], color="red", lw=3, solid_capstyle="butt", zorder=6)
        handles.append(plt.Line2D([], [], color="red", lw=3, label="published Fig. 3b interval"))
    ax.set_aspect("equal")
    ax.set_xlim(-r_grid[-1] * 1.02, r_grid[-1] * 1.02)
    ax.set_ylim(0, r_grid[-1] * 1.02)
    ax.set_xlabel(r"Re $\lambda$")
    ax.set_ylabel(r"Im $\lambda$")
    ax.set_facecolor("white")
    return pm, handles, ", ".join(counts)


def step_figure_heatmap(cfg, inputs, outputs, wildcards) -> None:
    """P2-F3a: filled polar maps of the optimal μ2 over the eigenvalue pair ``r e^{±jθ}`` (third at 0), one per
    variant on one shared colour scale, every grid point's class in the legend with its count; last panel: the
    masked_gain gains certified as the estimator that runs (own scale)."""
    from matplotlib.colors import Normalize

    from eqrec.studies.p2_grids import heatmap_grid

    paper_style()
    plt = pyplot()
    df = pd.read_csv(inputs.csv, keep_default_na=False, na_values=["nan", "NaN", ""])
    for col in ("status", "observer", "status_second"):
        if col in df:
            df[col] = df[col].fillna("").astype(str)
    printed = json.loads(Path(inputs.printed).read_text())
    r_grid, th_grid = heatmap_grid(cfg)
    tol = float(cfg["mu2_tol"])
    variants = [v for v in cfg["heatmap"]["variants"] if v in set(df["variant"])]
    ok = df["status"] == "optimal"
    vmin, vmax = float(df.loc[ok, "mu2"].min()), float(df.loc[ok, "mu2"].max())
    if vmax - vmin < 1e-6:
        vmin, vmax = vmin - 0.05, vmax + 0.05
    norm = Normalize(vmin, vmax)
    cmap = plt.get_cmap("viridis")
    extra = "masked_gain" in variants and "certified_mu2" in df
    npanel = len(variants) + int(extra)
    ncols = 2
    nrows = (npanel + 1 + ncols - 1) // ncols  # one more cell for the legend
    f, axes = plt.subplots(nrows, ncols, figsize=(7.4, 2.0 * nrows + 0.3), squeeze=False, layout="constrained")
    axes = axes.ravel()
    pm = None
    legend: dict[str, object] = {}
    lp_axes = []
    for ax, var in zip(axes, variants):
        g = df[df["variant"] == var]
        mg = var == "masked_gain"  # the reading with a region: its edge and the published interval drawn
        pm, handles, counts = _heat_panel(ax, plt, g, r_grid, th_grid, "mu2", norm, cmap,
                                          outline_tol=tol if mg else None,
                                          interval=printed.get("published_interval") if mg else None)
        ax.set_title(f"{var}, word {g['word'].iloc[0]}\n{counts}", fontsize=8)
        legend.update({h.get_label(): h for h in handles})
        lp_axes.append(ax)
    f.colorbar(pm, ax=lp_axes, label=r"design LP optimum $\mu_2$ (one scale)", shrink=0.8)
    if extra:
        ax = axes[len(variants)]
        g = df[df["variant"] == "masked_gain"]
        c = g.loc[g["status"] == "optimal", "certified_mu2"].astype(float)
        norm2 = Normalize(float(c.min()), float(np.percentile(c, 95)))
        pm2, handles, counts = _heat_panel(ax, plt, g, r_grid, th_grid, "certified_mu2", norm2,
                                           plt.get_cmap("magma"))
        ax.set_title(f"masked_gain gains as run (L kept)\n{counts}", fontsize=8)
        legend.update({h.get_label(): h for h in handles})
        f.colorbar(pm2, ax=ax, label="certified worst case\n(clipped at 95th pct.)", extend="max", shrink=0.9)
    for ax in axes[npanel:]:
        ax.axis("off")
    axes[npanel].legend(handles=list(legend.values()), loc="center", fontsize=8, frameon=False,
                        title="grid points (counts in each title)", title_fontsize=8)
    save_figure(f, outputs.pdf, outputs.png)


def step_figure_realaxis(cfg, inputs, outputs, wildcards) -> None:
    """P2-F3b: optimal μ2 against a real double eigenvalue λ (third at 0), every variant; λ = 0 uses a
    nilpotent L (starred); infeasible and unsolved points marked; the published interval shaded."""
    paper_style()
    plt = pyplot()
    df = pd.read_csv(inputs.csv, keep_default_na=False, na_values=["nan", "NaN", ""])
    df["status"] = df["status"].astype(str)
    printed = json.loads(Path(inputs.printed).read_text())
    f, ax = plt.subplots(figsize=(5.5, 3.8), layout="constrained")
    lo, hi = printed["published_interval"]
    ax.axvspan(lo, hi, color="red", alpha=0.08, label="published interval (Fig. 3b)")
    finite = df.loc[df["status"] == "optimal", "mu2"].astype(float)
    top = float(finite.max()) * 1.05
    for i, (var, g) in enumerate(df.groupby("variant", sort=False)):
        g = g.sort_values("lam")
        mu = np.where(g["status"] == "optimal", g["mu2"].astype(float), np.nan)
        ax.plot(g["lam"], mu, marker=".", ms=2, color=f"C{i}", label=f"{var} ({g['word'].iloc[0]})")
        inf = (g["status"] == "infeasible").to_numpy()
        if inf.any():
            ax.plot(g["lam"][inf], np.full(inf.sum(), top), "|", color=f"C{i}",
                    label=f"{var}: LP infeasible ({int(inf.sum())})")
        bad = g["status"].isin(["solver_failed", "placement_failed"]).to_numpy()
        if bad.any():
            ax.plot(g["lam"][bad], np.full(bad.sum(), top * 1.02), "x", color=f"C{i}",
                    label=f"{var}: not solved ({int(bad.sum())})")
        if "observer" in g:
            z = (g["observer"] == "deadbeat").to_numpy() & (g["status"] == "optimal").to_numpy()
            ax.plot(g["lam"][z], mu[z], "*", color=f"C{i}", ms=7)
    ax.plot([], [], "*", color="0.3", label=r"$\lambda = 0$: nilpotent $L$ (one of many)")
    ax.set_xlabel(r"real eigenvalue $\lambda$ (double), third at 0")
    ax.set_ylabel(r"optimal $\mu_2$")
    ax.legend(fontsize=5.5, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, frameon=False)
    save_figure(f, outputs.pdf, outputs.png)


STEPS = {"figure_trajectories": step_figure_trajectories, "figure_heatmap": step_figure_heatmap,
         "figure_realaxis": step_figure_realaxis}
