"""The figure of ``eqrec compare``: per family, the error over time across the runs, and the guaranteed bounds."""

from __future__ import annotations

import numpy as np

from eqrec.compare.families import FAMILIES, CompareResult


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
    from matplotlib.ticker import NullLocator

    from eqrec.io import save_figure

    s = result.setup
    t = np.arange(1, s.steps + 1)
    # from matplotlib's defaults, whatever the caller set (paper_style() of the studies changes rcParams globally):
    # the same figure, byte for byte, from any process
    style = {"font.family": "serif", "font.size": 9, "axes.titlesize": 9, "legend.fontsize": 8, "axes.grid": True,
             "grid.alpha": 0.3, "savefig.bbox": "tight", "figure.dpi": 150}
    with plt.style.context("default"), plt.rc_context(style):
        fig, axes = plt.subplots(2, 4, figsize=(7.5, 5.0), sharex=True, sharey=True)
        arrays = [*result.errors.values(), *result.bounds.values(), result.limit]
        positive = [a[a > 0] for a in arrays]
        low = min(float(np.quantile(a, 0.01)) for a in positive if a.size)
        high = max(float(np.nanmax(a)) for a in arrays if a.size)
        mu1 = min(result.mu1.values()) if result.mu1 else None
        table = result.table.set_index("estimator")
        for ax, family in zip(axes.flat, FAMILIES):
            ax.plot(t, np.median(result.limit, axis=0), color="k", linewidth=0.9, label="information limit, median")
            if mu1 is not None:
                ax.axhline(mu1, color="C2", linewidth=0.9, linestyle="-.", label=r"$\mu_1$ (smallest design)")
            for k in range(s.horizon, s.steps + 1, s.horizon):  # period ends: short ticks on the top edge
                ax.axvline(k + 0.5, ymin=0.94, ymax=1.0, color="C7", linewidth=1.2)
            if family not in result.errors:
                ax.set_title(f"{family}\nno design (see the table)", fontsize=8)
                ax.set_yscale("log")
                continue
            err = result.errors[family]
            ax.fill_between(t, np.quantile(err, 0.1, axis=0), np.quantile(err, 0.9, axis=0), color="C0", alpha=0.3,
                            linewidth=0, label="error, 10-90 % of runs")
            ax.plot(t, np.median(err, axis=0), color="C0", linewidth=1.0, label="error, median")
            if family in result.bounds:
                bnd = result.bounds[family]
                ax.plot(t, np.median(bnd, axis=0), color="C3", linewidth=1.0, linestyle="--", label="bound, median")
                ax.plot(t, bnd.max(axis=0), color="C3", linewidth=0.8, linestyle=":", label="bound, largest")
                row = table.loc[family]
                outside = "" if np.isnan(row["outside_design"]) else f", {100 * row['outside_design']:.0f} % out"
                ax.set_title(f"{family}\n{int(row['violations'])} viol.{outside}\n"
                             f"bound/limit {row['bound_over_limit_median']:.2f} (median)", fontsize=8)
            else:
                ax.set_title(f"{family}\n(no bound)", fontsize=8)
            ax.set_yscale("log")
            ax.set_ylim(low / 2, high * 2)
            ax.yaxis.set_minor_locator(NullLocator())  # the decades are the grid (and the layout is faster)
        for ax in axes[1]:
            ax.set_xlabel("time step t + 1")
        for ax in axes[:, 0]:
            ax.set_ylabel(r"$\|x - \hat x\|_\infty$ (largest state error)" if result.state_weights is None
                          else r"$\max_i w_i |x_i - \hat x_i|$ (weighted)")
        handles, labels = axes[0, 2].get_legend_handles_labels()
        handles.append(matplotlib.lines.Line2D([], [], color="C7", linewidth=1.2))
        labels.append("period end (tick on the top edge)")
        spare = axes.flat[len(FAMILIES)]  # the eighth panel holds the legend
        spare.axis("off")
        spare.legend(handles, labels, loc="center", frameon=False, fontsize=8)
        burst = "independent losses" if s.burst is None else f"bursts of {s.burst:g} steps on average"
        fig.suptitle(title or f"loss {s.loss:g} ({burst}), delays up to {s.max_delay}, T = {s.horizon}, "
                     f"{s.runs} runs", fontsize=9)
        fig.tight_layout(rect=(0, 0.03, 1, 1))
        save_figure(fig, *paths)
