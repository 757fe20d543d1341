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


def compare_figure(result: CompareResult, *paths: str, title: str | None = None, memo: "dict | None" = None) -> None:
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
    memo : dict or None, optional
        A dict kept between calls (the figures of one process, such as the settings of one compare job): the
        figure and its panels are made on the first call and drawn again by the next ones, which saves about a
        fifth of a figure's cost; the files are the same bytes as without it.  ``None``: a figure of its own.
    """
    import matplotlib
    import matplotlib.style
    from matplotlib import _mathtext

    matplotlib.use("Agg")

    # from matplotlib's defaults, whatever the caller set (paper_style() of the studies changes rcParams globally):
    # the same figure, byte for byte, from any process
    # tick labels 9 pt on a figure about 7 in wide: digits at least 9 px tall when shown 800 px wide; the
    # logarithmic axis labelled 0.01, 0.1, 1, 10 (no exponents, which would be drawn at 70 % of that)
    style = {"font.family": "serif", "font.size": 9, "axes.titlesize": 9, "legend.fontsize": 8, "axes.grid": True,
             "grid.alpha": 0.3, "figure.dpi": 150, "xtick.labelsize": 9,
             "ytick.labelsize": 9, "mathtext.fontset": "dejavuserif",
             "axes.titley": 1.0}  # the titles at a fixed height: not placed again at each draw
    # mathtext scripts (mu_1) at 0.8 of their text instead of 0.7: set, then restored (a module constant)
    shrink, _mathtext.SHRINK_FACTOR = _mathtext.SHRINK_FACTOR, 0.8
    try:
        with matplotlib.style.context("default"), matplotlib.rc_context(style):
            _draw(result, title, paths, memo)
    finally:
        _mathtext.SHRINK_FACTOR = shrink


def _draw(result: CompareResult, title: str | None, paths: tuple[str, ...], memo: "dict | None") -> None:
    """The figure of :func:`compare_figure`, drawn inside its style.

    Laid out once, from the measured sizes of its texts (:func:`_layout`), and saved as laid out: no
    ``tight_layout`` and no tight bounding box, each of which draws the figure again (they were about half of its
    cost).  The panels share their limits without ``sharex``/``sharey`` (whose label placement consults every
    sibling at each draw) and the titles sit at a fixed height above the axes.
    """
    import matplotlib.lines
    from matplotlib.ticker import FuncFormatter, MultipleLocator, NullLocator

    from eqrec.io import save_figure

    s = result.setup
    t = np.arange(1, s.steps + 1)
    fig, axes = _panels(memo)
    arrays = [*result.errors.values(), *result.bounds.values(), result.limit]
    positive = [a[a > 0] for a in arrays]
    low = min(float(np.quantile(a, 0.01)) for a in positive if a.size)
    high = max(float(np.nanmax(a)) for a in arrays if a.size)
    # whole decades: the range moves less between the settings of one system
    low, high = 10.0 ** np.floor(np.log10(low / 2)), 10.0 ** np.ceil(np.log10(high * 2))
    margin = 0.05 * (t[-1] - t[0]) if t.size > 1 else 0.5  # matplotlib's default x margin, the same in every panel
    mu1 = min(result.mu1.values()) if result.mu1 else None
    table = result.table.set_index("estimator")
    limit_median = np.median(result.limit, axis=0)
    # period ends: short ticks on the top edge, one line of segments per panel
    ends = np.arange(s.horizon, s.steps + 1, s.horizon) + 0.5
    end_x = np.repeat(ends, 3)
    end_x[2::3] = np.nan
    end_y = np.tile([0.94, 1.0, np.nan], ends.size)
    for i, (ax, family) in enumerate(zip(axes.flat, FAMILIES)):
        ax.plot(t, limit_median, color="k", linewidth=0.9, label="information limit, median")
        if mu1 is not None:
            # a wide pale band under the lines: not confused with the dashed bound it may run along
            ax.axhline(mu1, color="C2", linewidth=3.0, alpha=0.45, zorder=1.5, solid_capstyle="butt",
                       label=r"$\mu_1$ (smallest design)")
        ax.plot(end_x, end_y, color="C7", linewidth=1.2, transform=ax.get_xaxis_transform(), scalex=False,
                scaley=False)
        ax.set_yscale("log")
        ax.set_xlim(t[0] - margin, t[-1] + margin)
        ax.set_ylim(low, high)
        ax.yaxis.set_minor_locator(NullLocator())  # the decades are the grid (and the layout is faster)
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        # x ticks at period ends, at most five labels
        ax.xaxis.set_major_locator(MultipleLocator(s.horizon * max(1, int(np.ceil(s.steps / s.horizon / 4)))))
        # tick labels on the outer panels only (the panel above the legend has none, as with shared axes)
        ax.tick_params(labelleft=i % 3 == 0, labelbottom=i >= 6)
        if family not in result.errors:
            ax.set_title(f"{family}\nno design (see the table)", fontsize=8)
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
    for ax in axes[-1]:
        ax.set_xlabel("time step t + 1")
    for ax in axes[:, 0]:
        ax.set_ylabel(r"$\|x - \hat x\|_\infty$ (largest state error)" if result.state_weights is None
                      else r"$\max_i w_i |x_i - \hat x_i|$ (weighted)", fontsize=8)
    for axis in (axis for ax in axes.flat for axis in (ax.xaxis, ax.yaxis) if not axis.get_label_text()):
        # an axis without a label: nothing to place (Matplotlib would measure its tick labels once more at each
        # draw to move the empty label clear of them; an empty text draws nothing wherever it is)
        axis.set_label_coords(*axis.label.get_position())
    handles, labels = axes[0, 2].get_legend_handles_labels()
    handles.append(matplotlib.lines.Line2D([], [], color="C7", linewidth=1.2))
    labels.append("period end (tick on the top edge)")
    spare = axes.flat[len(FAMILIES)]  # the ninth panel holds the legend
    spare.axis("off")
    if result.state_weights is None:  # the states' errors compared as they are, each in its own unit
        handles.append(matplotlib.lines.Line2D([], [], linestyle=""))
        labels.append("error: largest over the states,\neach in its own unit")
    legend = spare.legend(handles, labels, loc="center left", bbox_to_anchor=(0.0, 0.5), frameon=False,
                          fontsize=8, borderaxespad=0.0)
    burst = "independent losses" if s.burst is None else f"bursts of {s.burst:g} steps on average"
    suptitle = fig.suptitle(title or f"loss {s.loss:g} ({burst}), delays up to {s.max_delay}, T = {s.horizon}, "
                            f"{s.runs} runs", fontsize=9)
    _layout(fig, axes, legend, suptitle)
    save_figure(fig, *paths)


def _panels(memo: "dict | None"):
    """The figure and its 3 × 3 panels: made here, or those of ``memo``, emptied, in the state they were made in.

    A figure kept in ``memo`` (``memo["panels"]``, made by the first call) is taken back with its panels, their
    ticks and their labels: what a figure of its own would make again (about a fifth of a figure's cost, in
    Matplotlib's axes and ticks).  What a result draws is removed (lines, bands, titles, the legend), and what
    the last drawing moved is put back where it was made (the spacing of the panels, the axis labels), so the
    texts are measured at the same places and the files are those of a figure of its own, byte for byte
    (``tests/test_compare.py``).  Drawn without pyplot: ``matplotlib.figure.Figure`` on an Agg canvas, so the
    figure is not one of pyplot's open figures.

    Parameters
    ----------
    memo : dict or None
        Kept between calls (see :func:`compare_figure`); ``None``: a figure of its own.

    Returns
    -------
    tuple
        ``(figure, axes)``, ``axes`` the ``(3, 3)`` array of panels.
    """
    if memo is not None and "panels" in memo:
        fig, axes, spacing, labels = memo["panels"]
        for ax in axes.flat:
            for artist in (*ax.lines, *ax.collections, *ax.patches, *ax.texts):
                artist.remove()
            ax.set_title("")
            if ax.get_legend() is not None:
                ax.get_legend().remove()
        fig.subplots_adjust(**spacing)
        for label, position in labels:
            label.set_position(position)
        return fig, axes
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 7.2))
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 3)
    if memo is not None:
        spacing = {key: getattr(fig.subplotpars, key) for key in ("left", "right", "bottom", "top", "wspace",
                                                                   "hspace")}
        labels = [(axis.label, axis.label.get_position()) for ax in axes.flat for axis in (ax.xaxis, ax.yaxis)]
        memo["panels"] = fig, axes, spacing, labels
    return fig, axes


def _layout(fig, axes, legend, suptitle) -> None:
    """Place the 3 × 3 panels from the measured sizes of the texts around them, in one pass (no draw).

    Left: the y label and the widest y tick label; bottom: the x tick labels and the x label; between the rows
    and at the top: the tallest panel title (and the figure title above it); between the columns: the widest
    panel title; right: what the legend (left-aligned in the ninth panel) needs beyond that panel.  Every gap
    has a margin of a few points, so nothing is clipped and nothing overlaps.
    """
    from matplotlib import rcParams as rc_params

    def rc(key: str) -> float:
        return float(rc_params[key])

    renderer = fig.canvas.get_renderer()
    dpi = fig.dpi
    W, H = fig.get_size_inches()

    def size(text) -> tuple[float, float]:  # width and height in inches of a Text, as it will be drawn
        box = text.get_window_extent(renderer)
        return box.width / dpi, box.height / dpi

    pt = 1.0 / 72.0
    flat = list(axes.flat)
    titles = [size(ax.title) for ax in flat if ax.get_title()]
    title_h = max((h for _, h in titles), default=0.0)
    title_w = max((w for w, _ in titles), default=0.0)
    major = rc("xtick.major.size") + rc("xtick.major.pad")
    ax0 = axes[0, 0]
    ax0.yaxis.set_view_interval(*ax0.get_ylim())
    ylabels = [ax0.yaxis.get_major_formatter()(v, i) for i, v in enumerate(ax0.yaxis.get_majorticklocs())
               if ax0.get_ylim()[0] <= v <= ax0.get_ylim()[1]]
    probe = fig.text(0, 0, "", fontsize=rc("ytick.labelsize"))
    tick_w = 0.0
    for text in ylabels:
        probe.set_text(text)
        tick_w = max(tick_w, size(probe)[0])
    probe.set_text("0123456789")
    tick_h = size(probe)[1]
    probe.remove()
    ylabel_w = size(ax0.yaxis.label)[0] if ax0.get_ylabel() else 0.0  # rotated: the width of its box
    xlabel_h = size(axes[-1, 0].xaxis.label)[1] if axes[-1, 0].get_xlabel() else 0.0
    labelpad = rc("axes.labelpad") * pt
    edge = 4 * pt
    left = edge + ylabel_w + labelpad + tick_w + major * pt
    bottom = edge + xlabel_h + labelpad + tick_h + major * pt
    title_gap = rc("axes.titlepad") * pt + title_h
    top = edge + size(suptitle)[1] + 2 * pt + title_gap
    legend_w = legend.get_window_extent(renderer).width / dpi
    # columns: the tick marks and a margin, or more where the widest title (centred on its panel) overhangs; right:
    # what the legend needs beyond its panel, r >= edge + legend_w - panel_w with panel_w = (W - left - r - 2 g) / 3
    gap_w = right = 0.0
    for _ in range(2):
        panel_w = (W - left - right - 2 * gap_w) / 3
        gap_w = max(major * pt + 6 * pt, title_w - panel_w + 4 * pt)
        right = max(edge, 1.5 * (edge + legend_w - (W - left - 2 * gap_w) / 3))
    panel_w = (W - left - right - 2 * gap_w) / 3
    gap_h = title_gap + major * pt + 4 * pt
    panel_h = (H - top - bottom - 2 * gap_h) / 3
    fig.subplots_adjust(left=left / W, right=1 - right / W, bottom=bottom / H, top=1 - top / H,
                        wspace=gap_w / panel_w, hspace=gap_h / panel_h)
    suptitle.set_y(1 - (edge + 0.0) / H)
    suptitle.set_verticalalignment("top")
