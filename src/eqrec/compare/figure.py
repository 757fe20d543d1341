"""The figure of ``eqrec compare``: per family, the error over time across the runs, and the guaranteed bounds."""

from __future__ import annotations

import numpy as np

from eqrec.compare.families import FAMILIES, CompareResult


#: What every panel draws besides its family's error, in the words of the legend and of the report's caption
#: (``tests/test_prose.py`` checks that the caption names each).
#: The quantiles of the error band over the runs.
BAND = (0.1, 0.9)
#: The band in words: ``10–90 %``.
BAND_WORDS = f"{100 * BAND[0]:g}–{100 * BAND[1]:g} %"
LINES = ("information limit", "μ₁", "bound", "median", BAND_WORDS, "period")


def compare_figure(result: CompareResult, *paths: str, title: str | None = None) -> None:
    """``compare.png``: per family, the error over time across the runs, its bound, the information limit and ``μ1``.

    One panel per family on one logarithmic scale: the band between the 10 %
    and 90 % quantiles of ``‖x(t+1) − x̂(t+1)‖∞`` over the runs, its median,
    for a family with a bound the median and the largest bound of the runs,
    and in every panel the median information limit (the smallest bound any
    estimator can guarantee) and the smallest design's ``μ1``; period ends are
    ticks on the top edge.

    Parameters
    ----------
    result : CompareResult
        The comparison.
    *paths : str
        Files to write (PDF and/or PNG; PDF without a creation date).
    title : str or None, optional
        Figure title (default: the settings).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import _mathtext

    # from matplotlib's defaults, whatever the caller set (paper_style() of the studies changes rcParams globally):
    # the same figure, byte for byte, from any process
    # tick labels 9 pt on a figure about 7 in wide: digits at least 9 px tall when shown 800 px wide; the
    # logarithmic axis labelled 0.01, 0.1, 1, 10 (no exponents, which would be drawn at 70 % of that)
    style = {"font.family": "serif", "font.size": 9, "axes.titlesize": 9, "legend.fontsize": 8, "axes.grid": True,
             "grid.alpha": 0.3, "savefig.bbox": "tight", "figure.dpi": 150, "xtick.labelsize": 9,
             "ytick.labelsize": 9, "mathtext.fontset": "dejavuserif"}
    # mathtext scripts (mu_1) at 0.8 of their text instead of 0.7: set, then restored (a module constant)
    shrink, _mathtext.SHRINK_FACTOR = _mathtext.SHRINK_FACTOR, 0.8
    try:
        with plt.style.context("default"), plt.rc_context(style):
            _draw(result, title, paths)
    finally:
        _mathtext.SHRINK_FACTOR = shrink


def _draw(result: CompareResult, title: str | None, paths: tuple[str, ...]) -> None:
    """The figure of :func:`compare_figure`, drawn inside its style."""
    import matplotlib
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, MultipleLocator, NullLocator

    from eqrec.io import save_figure

    s = result.setup
    t = np.arange(1, s.steps + 1)
    fig, axes = plt.subplots(3, 3, figsize=(7.0, 7.2), sharex=True, sharey=True)
    arrays = [*result.errors.values(), *result.bounds.values(), result.limit]
    positive = [a[a > 0] for a in arrays]
    low = min(float(np.quantile(a, 0.01)) for a in positive if a.size)
    high = max(float(np.nanmax(a)) for a in arrays if a.size)
    # whole decades: the range moves less between the settings of one system
    low, high = 10.0 ** np.floor(np.log10(low / 2)), 10.0 ** np.ceil(np.log10(high * 2))
    mu1 = min(result.mu1.values()) if result.mu1 else None
    table = result.table.set_index("estimator")
    for ax, family in zip(axes.flat, FAMILIES):
        ax.plot(t, np.median(result.limit, axis=0), color="k", linewidth=0.9, label="information limit, median")
        if mu1 is not None:
            # a wide pale band under the lines: not confused with the dashed bound it may run along
            ax.axhline(mu1, color="C2", linewidth=3.0, alpha=0.45, zorder=1.5, solid_capstyle="butt",
                       label=r"$\mu_1$ (smallest design)")
        for k in range(s.horizon, s.steps + 1, s.horizon):  # period ends: short ticks on the top edge
            ax.axvline(k + 0.5, ymin=0.94, ymax=1.0, color="C7", linewidth=1.2)
        if family not in result.errors:
            ax.set_title(f"{family}\nno design (see the table)", fontsize=8)
            ax.set_yscale("log")
            continue
        err = result.errors[family]
        ax.fill_between(t, np.quantile(err, BAND[0], axis=0), np.quantile(err, BAND[1], axis=0), color="C0",
                        alpha=0.3, linewidth=0, label=f"error, {BAND_WORDS} of runs")
        ax.plot(t, np.median(err, axis=0), color="C0", linewidth=1.0, label="error, median")
        if family in result.bounds:
            bnd = result.bounds[family]
            ax.plot(t, np.median(bnd, axis=0), color="C3", linewidth=1.0, linestyle="--", label="bound, median")
            ax.plot(t, bnd.max(axis=0), color="C3", linewidth=0.8, linestyle=":", label="bound, largest")
            row = table.loc[family]
            outside = "" if np.isnan(row["outside_design"]) else f", {100 * row['outside_design']:.0f} % out"
            name = family if len(err) == s.runs else f"{family}, first {len(err)} runs"
            ax.set_title(f"{name}\n{int(row['violations'])} viol.{outside}\n"
                         f"bound/limit {row['bound_over_limit_median']:.2f} (median)", fontsize=8)
        else:
            ax.set_title(f"{family}\n(no bound)", fontsize=8)
        ax.set_yscale("log")
        ax.set_ylim(low, high)
        ax.yaxis.set_minor_locator(NullLocator())  # the decades are the grid (and the layout is faster)
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        # x ticks at period ends, at most five labels
        ax.xaxis.set_major_locator(MultipleLocator(s.horizon * max(1, int(np.ceil(s.steps / s.horizon / 4)))))
    for ax in axes[-1]:
        ax.set_xlabel("time step t + 1")
    for ax in axes[:, 0]:
        ax.set_ylabel(r"$\|x - \hat x\|_\infty$ (largest state error)" if result.state_weights is None
                      else r"$\max_i w_i |x_i - \hat x_i|$ (weighted)", fontsize=8)
    handles, labels = axes[0, 2].get_legend_handles_labels()
    handles.append(matplotlib.lines.Line2D([], [], color="C7", linewidth=1.2))
    labels.append("period end (tick on the top edge)")
    spare = axes.flat[len(FAMILIES)]  # the ninth panel holds the legend
    spare.axis("off")
    if result.state_weights is None:  # the states' errors compared as they are, each in its own unit
        handles.append(matplotlib.lines.Line2D([], [], linestyle=""))
        labels.append("error: largest over the states,\neach in its own unit")
    spare.legend(handles, labels, loc="center", frameon=False, fontsize=8)
    burst = "independent losses" if s.burst is None else f"bursts of {s.burst:g} steps on average"
    fig.suptitle(title or f"loss {s.loss:g} ({burst}), delays up to {s.max_delay}, T = {s.horizon}, "
                 f"{s.runs} runs", fontsize=9)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    save_figure(fig, *paths)
