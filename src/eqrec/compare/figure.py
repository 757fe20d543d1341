"""The figure of ``eqrec compare``: per family, the error over time across the runs, and the guaranteed bounds."""

from __future__ import annotations

import numpy as np

from eqrec.compare.families import FAMILIES, CompareResult


def compare_figure(result: CompareResult, *paths: str, title: str | None = None) -> None:
    """``compare.png``: per family, the error over time across the runs and, for the guaranteed ones, the bound.

    One panel per family on one logarithmic scale: the band between the 10 %
    and 90 % quantiles of ``‖x(t+1) − x̂(t+1)‖∞`` over the runs, its median,
    and for a guaranteed family the median and the largest bound of the runs.

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
    from matplotlib.ticker import NullLocator

    from eqrec.io import save_figure

    s = result.setup
    t = np.arange(1, s.steps + 1)
    # from matplotlib's defaults, whatever the caller set (paper_style() of the studies changes rcParams globally):
    # the same figure, byte for byte, from any process
    style = {"font.family": "serif", "font.size": 9, "axes.titlesize": 9, "legend.fontsize": 8, "axes.grid": True,
             "grid.alpha": 0.3, "savefig.bbox": "tight", "figure.dpi": 150}
    with plt.style.context("default"), plt.rc_context(style):
        fig, axes = plt.subplots(2, 3, figsize=(7.5, 4.8), sharex=True, sharey=True)
        positive = [a[a > 0] for a in (*result.errors.values(), *result.bounds.values())]
        low = min(float(np.quantile(a, 0.01)) for a in positive if a.size)
        high = max(float(np.nanmax(a)) for a in (*result.errors.values(), *result.bounds.values()))
        for ax, family in zip(axes.flat, FAMILIES):
            err = result.errors[family]
            ax.fill_between(t, np.quantile(err, 0.1, axis=0), np.quantile(err, 0.9, axis=0), color="C0", alpha=0.3,
                            linewidth=0, label="error, 10-90 % of runs")
            ax.plot(t, np.median(err, axis=0), color="C0", linewidth=1.0, label="error, median")
            if family in result.bounds:
                bnd = result.bounds[family]
                ax.plot(t, np.median(bnd, axis=0), color="C3", linewidth=1.0, linestyle="--", label="bound, median")
                ax.plot(t, bnd.max(axis=0), color="C3", linewidth=0.8, linestyle=":", label="bound, largest")
                row = result.table.set_index("estimator").loc[family]
                ax.set_title(f"{family}\n{int(row['violations'])} violations, "
                             f"{100 * row['outside_design']:.0f} % outside design", fontsize=8)
            else:
                ax.set_title(f"{family}\n(no guarantee)", fontsize=8)
            for k in range(s.horizon, s.steps + 1, s.horizon):
                ax.axvline(k + 0.5, color="0.85", linewidth=0.5, zorder=0)
            ax.set_yscale("log")
            ax.set_ylim(low / 2, high * 2)
            ax.yaxis.set_minor_locator(NullLocator())  # the decades are the grid (and the layout is faster)
        for ax in axes[1]:
            ax.set_xlabel("time step t + 1")
        for ax in axes[:, 0]:
            ax.set_ylabel(r"$\|x - \hat x\|_\infty$ (state units)")
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=4, bbox_to_anchor=(0.5, -0.04), frameon=False)
        burst = "independent losses" if s.burst is None else f"bursts of {s.burst:g} steps on average"
        fig.suptitle(title or f"loss {s.loss:g} ({burst}), delays up to {s.max_delay}, T = {s.horizon}, "
                     f"{s.runs} runs", fontsize=9)
        fig.tight_layout(rect=(0, 0.03, 1, 1))
        save_figure(fig, *paths)
