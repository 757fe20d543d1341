"""P2 figures: Figs. 1, 2, 3a and 3b of the augmented paper (steps ``figure_trajectories``,
``figure_heatmap``, ``figure_realaxis``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from eqrec.studies.pipeline.outputs import save_figure
from eqrec.studies.plotting import equalized_levels, paper_style, pyplot, same_scale_per_row, trajectory_panel

if TYPE_CHECKING:
    import pandas as pd


#: The readings of the paper's text (:mod:`eqrec.studies.p2.readings`) in words, for titles and legends.
READING_NAMES = {"theorem2": "Theorem 2 as stated", "one_based": "word read with 1-based times",
                 "leak": "constant $L$ kept at missing steps", "masked_gain": "Appendix, gain masked when missing"}

#: The paper's value, dashed (plot and legend).
PAPER_LINE = {"color": "k", "ls": (0, (4, 2)), "lw": 1.0}
#: The star of an exact nilpotent ``L`` (eigenvalue 0).
STAR = {"mec": "k", "mew": 0.4, "ms": 9}


def step_figure_trajectories(cfg, inputs, outputs, wildcards) -> None:
    """P2-F1 / P2-F2: augmented (left) vs time-based (right), same draws, certified guarantee bars.

    For F2 a third column shows the design for the word read with 1-based times, run on the true data.  One
    y scale per row; the paper's ``μ2`` (``cfg["published"][fig]``, from ``config/claims.yaml``) dashed.
    """
    fig = wildcards["fig"]
    paper_style()
    plt = pyplot()
    d = json.loads(Path(inputs.designs).read_text())[fig]
    sim = np.load(inputs.simulation)
    mu1 = float(cfg["mu1"])
    paper = float(cfg["published"][fig])
    cols = [("augmented_free", "augmented estimator (IPOPT)", d["augmented_free"]["certified_mu2"], "C0"),
            ("time", "time-based estimator", d["time"]["certified_mu2"], "C1")]
    if fig == "f2" and "f2/one_based" in sim.files:
        ob = d["one_based"]["word"]
        c = d["one_based"]["certified_on_true_words"][d["worst_case_word"]]
        missing = ", ".join(str(k) for k, ch in enumerate(ob) if ch == "0")
        cols.append(("one_based", f"designed for missing $k$ = {missing} ({ob}),\nrun on the true words", c, "C3"))
    errs0 = sim[f"{fig}/time"]
    T = errs0.shape[1] - 1
    f, axes = plt.subplots(3, len(cols), figsize=(2.05 * len(cols) + 0.4, 6.6), sharex=True, sharey="row",
                           squeeze=False, layout="constrained")
    for j, (name, title, mu2, color) in enumerate(cols):
        trajectory_panel(axes[:, j], sim[f"{fig}/{name}"], equalized_levels(T, mu1, mu2),
                         f"{title}\ncertified $\\mu_2$ = {mu2:.4g}", color=color, ylabels=(j == 0))
        for ax in axes[:, j]:
            for sign in (1, -1):
                ax.plot([0.5, T - 0.5], [sign * paper] * 2, **PAPER_LINE)
    same_scale_per_row(axes)
    # one legend entry per estimator, in its own colour, the bars and the paper's value
    entries = [(plt.Line2D([], [], color=color, lw=1.2), f"error: {title.split(chr(10))[0].split(' (')[0]}")
               for _, title, _, color in cols]
    entries += [(axes[0, 0].get_legend_handles_labels()[0][-1], "certified guarantee"),
                (plt.Line2D([], [], **PAPER_LINE), f"$\\pm\\mu_2$ reported by the paper: {paper:g}")]
    f.legend(*zip(*entries), loc="outside lower center", ncol=min(len(entries), 3))
    what = ("no missing data" if fig == "f1" else
            f"language {{{', '.join(d['language'])}}} (worst case {d['worst_case_word']})")
    f.suptitle(f"{what[0].upper()}{what[1:]}, {errs0.shape[0]} runs, the same draws for every estimator")
    save_figure(f, outputs.pdf, outputs.png)


#: Hatches of the non-optimal classes of a sweep point (the optimal ones carry the colour scale; a hatch on white
#: is no colour of any map): class -> (hatch, label).
CLASS_STYLE = {"infeasible": ("////", "LP infeasible"), "solver_failed": ("xxxx", "solver failure (both solvers)"),
               "placement_failed": ("....", "pole placement failure")}


def _sweep_inputs(inputs):
    """Pyplot in the paper style, a sweep's CSV (text columns as strings, ``""`` where empty) and ``printed.json``."""
    import pandas as pd  # imported here: the two trajectory figures read no sweep (saves ~0.3-0.5 s CPU per job)

    paper_style()
    plt = pyplot()
    df = pd.read_csv(inputs.csv, keep_default_na=False, na_values=["nan", "NaN", ""])
    for col in ("status", "observer", "status_second"):
        if col in df:
            df[col] = df[col].astype(object).fillna("").astype(str)
    return plt, df, json.loads(Path(inputs.printed).read_text())


def _edges(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return np.concatenate([[lo], 0.5 * (x[1:] + x[:-1]), [hi]])


def _polar_grid(g: pd.DataFrame, r_grid: np.ndarray, th_grid: np.ndarray, column: str) -> np.ndarray:
    """``(n_theta, n_r)`` array of one column of a variant's rows, placed by nearest grid point."""
    i = np.abs(g["r"].to_numpy(float)[:, None] - r_grid[None, :]).argmin(axis=1)
    j = np.abs(g["theta"].to_numpy(float)[:, None] - th_grid[None, :]).argmin(axis=1)
    out = np.full((len(th_grid), len(r_grid)), np.nan if column != "status" else "", dtype=object)
    out[j, i] = g[column].to_numpy()
    return out


def _class_cells(ax, X, Y, mask, hatch: str) -> None:
    """The grid cells of one non-optimal class, white with a grey hatch."""
    from matplotlib.collections import PolyCollection

    jj, ii = np.nonzero(mask)
    quads = [[(X[j, i], Y[j, i]), (X[j, i + 1], Y[j, i + 1]), (X[j + 1, i + 1], Y[j + 1, i + 1]),
              (X[j + 1, i], Y[j + 1, i])] for j, i in zip(jj, ii)]
    ax.add_collection(PolyCollection(quads, facecolor="white", edgecolor="0.35", linewidth=0.0, hatch=hatch))


def _heat_panel(ax, plt, g, r_grid, th_grid, column, norm, cmap, legend: dict, outline_tol=None, interval=None):
    """One filled polar map in the complex plane: optimal points coloured by ``column``, every other class
    hatched, their legend handles added to ``legend`` (by label); returns the mappable and the count of each class."""
    from matplotlib import patheffects
    from matplotlib.patches import Patch

    def key(label: str, **style) -> None:
        legend[label] = plt.Line2D([], [], label=label, **style)

    R, TH = np.meshgrid(_edges(r_grid, 0.0, r_grid[-1]), _edges(th_grid, 0.0, np.pi))
    X, Y = R * np.cos(TH), R * np.sin(TH)
    status = _polar_grid(g, r_grid, th_grid, "status")
    val = _polar_grid(g, r_grid, th_grid, column).astype(float)
    ok = status == "optimal"
    pm = ax.pcolormesh(X, Y, np.ma.masked_where(~ok, val), cmap=cmap, norm=norm, shading="flat")
    counts = {"optimal": int(ok.sum())}
    for cls, (hatch, label) in CLASS_STYLE.items():
        m = status == cls
        counts[cls] = int(m.sum())
        if m.any():
            _class_cells(ax, X, Y, m, hatch)
            legend[label] = Patch(facecolor="white", edgecolor="0.35", hatch=hatch, label=label)
    if "observer" in g and (g["observer"] == "deadbeat").any():
        key("$r$ = 0: an exact nilpotent $L$", marker="*", ls="", color="magenta", **STAR)
        ax.plot([0], [0], "*", color="magenta", **STAR, zorder=7, clip_on=False)
    if outline_tol is not None and ok.any():
        at_min = np.ma.masked_where(~ok, np.where(ok, val <= np.nanmin(np.where(ok, val, np.nan)) + outline_tol,
                                                  False).astype(float))
        if 0 < at_min.sum() < ok.sum():
            Rc, THc = np.meshgrid(r_grid, th_grid)
            halo = [patheffects.withStroke(linewidth=2.4, foreground="black")]
            cs = ax.contour(Rc * np.cos(THc), Rc * np.sin(THc), at_min, levels=[0.5], colors="white", linewidths=1.2)
            cs.set(path_effects=halo)
            key("edge of the region at the minimum", color="white", lw=1.2, path_effects=halo)
    if interval is not None:
        ax.plot(interval, [0, 0], color="red", lw=3, solid_capstyle="butt", zorder=6, clip_on=False)
        key("published Fig. 3b interval", color="red", lw=3)
    ax.set_aspect("equal")
    ax.set_xlim(-r_grid[-1] * 1.04, r_grid[-1] * 1.04)
    ax.set_ylim(-r_grid[-1] * 0.08, r_grid[-1] * 1.04)  # the star and the interval on y = 0 fully inside
    ax.set(xlabel=r"Re $\lambda$", ylabel=r"Im $\lambda$", facecolor="white")
    return pm, counts


def _optimal_values(g: pd.DataFrame, column: str = "mu2") -> tuple[pd.Series, bool]:
    """``column`` at the optimal points, and whether it is one value there (a flat map, relative ``1e-6``)."""
    vals = g.loc[g["status"] == "optimal", column].astype(float)
    return vals, bool(len(vals)) and float(vals.max() - vals.min()) <= 1e-6 * max(1.0, abs(float(vals.max())))


def _panel_title(name: str, word: str, vals: pd.Series, flat: bool, counts: dict) -> str:
    """Reading and word, then what the panel shows in words: a flat map, else the range; the other classes."""
    lines = [name, f"word {word}: " + (f"one value at all {counts['optimal']} points" if flat else
                                       f"from {float(vals.min()):.4g} to {float(vals.max()):.4g}")]
    other = [f"{CLASS_STYLE[c][1]} at {k}" for c, k in counts.items() if c != "optimal" and k]
    if other:
        lines.append(", ".join(other) + f" of {int(sum(counts.values()))} points")
    return "\n".join(lines)


def step_figure_heatmap(cfg, inputs, outputs, wildcards) -> None:
    """P2-F3a: filled polar maps of the optimal μ2 over the eigenvalue pair ``r e^{±jθ}`` (third at 0), one per
    reading on one shared colour scale (the paper's μ2, ``cfg["published"]["mu2"]``, a labelled tick), the
    classes of the other grid points hatched; last panel: the masked-gain gains certified as the estimator that
    runs (own logarithmic scale, nothing clipped)."""
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.ticker import MaxNLocator

    from eqrec.studies.p2.grids import heatmap_grid

    plt, df, printed = _sweep_inputs(inputs)
    r_grid, th_grid = heatmap_grid(cfg)
    paper = float(cfg["published"]["mu2"])
    variants = [v for v in cfg["heatmap"]["variants"] if v in set(df["variant"])]
    ok = df["status"] == "optimal"
    vmin, vmax = float(df.loc[ok, "mu2"].min()), float(df.loc[ok, "mu2"].max())
    if vmax - vmin < 1e-6:
        vmin, vmax = vmin - 0.05, vmax + 0.05
    norm = Normalize(min(vmin, paper), max(vmax, paper))
    extra = "masked_gain" in variants and "certified_mu2" in df
    npanel = len(variants) + int(extra)
    nrows = (npanel + 2) // 2  # two columns, and one more cell for the legend
    # "compressed": the maps (equal aspect) packed together, the colour bar next to them, not a column away
    f, axes = plt.subplots(nrows, 2, figsize=(7.2, 2.3 * nrows + 0.2), squeeze=False, layout="compressed")
    axes = axes.ravel()
    for ax in axes:
        ax.tick_params(labelsize=9)
    legend: dict[str, object] = {}
    for ax, var in zip(axes, variants):
        g = df[df["variant"] == var]
        mg = var == "masked_gain"  # the reading with a region: its edge and the published interval drawn
        pm, counts = _heat_panel(ax, plt, g, r_grid, th_grid, "mu2", norm, plt.get_cmap("viridis"), legend,
                                 outline_tol=float(cfg["mu2_tol"]) if mg else None,
                                 interval=printed.get("published_interval") if mg else None)
        vals, flat = _optimal_values(g)
        ax.set_title(_panel_title(READING_NAMES.get(var, var), g["word"].iloc[0], vals, flat, counts), fontsize=9)
        if flat and (g["status"] == "optimal").all():  # the value printed inside (one colour says little)
            ax.text(0.0, 0.55 * r_grid[-1], f"$\\mu_2$ = {float(vals.iloc[0]):.4g}\neverywhere", ha="center",
                    va="center", fontsize=9, bbox={"facecolor": "white", "edgecolor": "0.5",
                                                   "boxstyle": "round,pad=0.3"})
    # one colour bar for the maps, its ticks including the paper's value (labelled as such; the norm includes it)
    # (pad: the right maps' titles are wider than the maps and must clear the bar)
    cb = f.colorbar(pm, ax=list(axes[:len(variants)]), label=r"design LP optimum $\mu_2$ (all four maps)", shrink=0.7,
                    pad=0.06)
    cb.ax.tick_params(labelsize=9)
    lo, hi = pm.norm.vmin, pm.norm.vmax
    ticks = sorted([t for t in MaxNLocator(6).tick_values(lo, hi)
                    if lo <= t <= hi and abs(t - paper) > 0.06 * (hi - lo)] + [paper])
    cb.set_ticks(ticks, labels=[f"{t:g} (paper)" if t == paper else f"{t:g}" for t in ticks])
    if extra:
        ax = axes[len(variants)]
        g = df[df["variant"] == "masked_gain"]
        c, _ = _optimal_values(g, "certified_mu2")
        lo, hi = float(c.min()), float(c.max())
        pm2, _ = _heat_panel(ax, plt, g, r_grid, th_grid, "certified_mu2", LogNorm(lo, hi), plt.get_cmap("magma"),
                             legend)
        ax.set_title(f"the Appendix gains as run (constant $L$ kept)\ncertified worst case from {lo:.3g} to "
                     f"{hi:.3g}", fontsize=8)
        cax = ax.inset_axes((1.06, 0.0, 0.06, 1.0))  # as tall as the map (the axes keep their aspect)
        cb = f.colorbar(pm2, cax=cax, label="certified worst case\n(log scale)")
        cb.ax.tick_params(labelsize=9)
        ticks = [lo] + [t for t in (5, 10, 20, 50, 100) if 1.3 * lo < t < hi / 1.8] + [hi]
        cb.set_ticks(ticks, labels=[f"{t:.3g}" for t in ticks])
        cb.minorticks_off()
    for ax in axes[npanel:]:
        ax.axis("off")
    axes[npanel].legend(handles=list(legend.values()), loc="center", frameon=False,
                        title="eigenvalues of $A - LC$: 0 and $r e^{\\pm j\\theta}$", title_fontsize=8)
    save_figure(f, outputs.pdf, outputs.png)


#: Line styles of the readings on Fig. 3b: wide, light lines under narrow ones, so coinciding series stay visible.
REALAXIS_STYLE = {"theorem2": {"color": "C0", "lw": 5.0, "alpha": 0.45, "zorder": 2},
                  "leak": {"color": "C2", "lw": 1.4, "ls": (0, (5, 2)), "zorder": 3},
                  "one_based": {"color": "C1", "lw": 5.0, "alpha": 0.45, "zorder": 2},
                  "masked_gain": {"color": "C3", "lw": 1.4, "zorder": 4}}


def step_figure_realaxis(cfg, inputs, outputs, wildcards) -> None:
    """P2-F3b: optimal μ2 against a real double eigenvalue λ (third at 0), every reading; λ = 0 uses a
    nilpotent L (starred); where a reading's LP has no solution is shown in a strip below (no value); the
    published interval shaded."""
    plt, df, printed = _sweep_inputs(inputs)
    groups = [(var, g.sort_values("lam")) for var, g in df.groupby("variant", sort=False)]
    unsolved = [(v, g) for v, g in groups if (g["status"] != "optimal").any()]
    f, axs = plt.subplots(2 if unsolved else 1, 1, figsize=(6.4, 4.9 if unsolved else 4.2), sharex=True,
                          squeeze=False, layout="constrained",
                          gridspec_kw={"height_ratios": [4, 0.2 + 0.55 * len(unsolved)] if unsolved else [1]})
    ax = axs[0, 0]
    lo, hi = printed["published_interval"]
    for a in axs[:, 0]:
        a.axvspan(lo, hi, color="red", alpha=0.08, lw=0)
    entries = [(plt.Rectangle((0, 0), 1, 1, color="red", alpha=0.15, lw=0),
                f"published interval (Fig. 3b): [{lo:g}, {hi:g}]")]
    for i, (var, g) in enumerate(groups):
        style = REALAXIS_STYLE.get(var, {"color": f"C{i}", "lw": 1.2})
        mu = np.where(g["status"] == "optimal", g["mu2"].astype(float), np.nan)
        (line,) = ax.plot(g["lam"], mu, solid_capstyle="butt", **style)
        entries.append((line, f"{READING_NAMES.get(var, var)} ({g['word'].iloc[0]})"))
        if "observer" in g:
            z = (g["observer"] == "deadbeat").to_numpy() & (g["status"] == "optimal").to_numpy()
            ax.plot(g["lam"][z], mu[z], "*", color=style["color"], **STAR, zorder=6)
    entries.append((plt.Line2D([], [], marker="*", ls="", color="0.6", **STAR),
                    r"$\lambda = 0$: an exact nilpotent $L$ (one of many)"))
    ax.set(ylabel=r"optimal $\mu_2$ of the design LP",
           title=r"Optimal $\mu_2$ against a real double eigenvalue $\lambda$ of $A - LC$ (third at 0)")
    if unsolved:
        st = axs[1, 0]
        for row, (var, g) in enumerate(unsolved):
            bad = (g["status"] != "optimal").to_numpy()
            x = g["lam"].to_numpy(float)
            step = float(np.median(np.diff(x))) if len(x) > 1 else 0.01
            color = REALAXIS_STYLE.get(var, {}).get("color", "0.4")
            st.broken_barh([(xi - step / 2, step) for xi in x[bad]], (row - 0.45, 0.4), facecolor="white",
                           edgecolor=color, hatch="////", linewidth=0.0)
            what = "LP infeasible" if (g["status"][bad] == "infeasible").all() else "no solution"
            st.text(float(np.mean(x[bad][[0, -1]])), row + 0.22, f"{READING_NAMES.get(var, var)}: {what} "
                    f"for $\\lambda$ from {float(x[bad].min()):g} to {float(x[bad].max()):g}",
                    ha="center", va="center", fontsize=8)
        st.set(yticks=[], ylim=(-0.55, len(unsolved) - 0.45))
        st.set_title(r"where the LP has no solution (no $\mu_2$)", fontsize=8)
        st.grid(False, axis="y")
    axs[-1, 0].set_xlabel(r"real eigenvalue $\lambda$ (double) of $A - LC$, third eigenvalue at 0")
    f.legend(*zip(*entries), loc="outside lower center", ncol=2, frameon=False)
    save_figure(f, outputs.pdf, outputs.png)
