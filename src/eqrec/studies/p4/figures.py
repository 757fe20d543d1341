"""P4 figures: Figs. 1-8 of the LMV paper and the zero- vs hold-input regions (plotting only).

Called by the steps of :mod:`eqrec.studies.p4.steps`; every figure is written as
PDF and PNG by :func:`eqrec.studies.pipeline.outputs.save_figure`.
"""

from __future__ import annotations

import numpy as np

from eqrec.studies.pipeline.chunks import merge_npz
from eqrec.studies.pipeline.outputs import save_figure
from eqrec.studies.plotting import paper_style, pyplot


def _plt():
    paper_style()
    return pyplot()


#: The examples' states have no physical unit (the paper gives none): their axes say so.
UNIT = "[–]"
#: Half-width of the Monte Carlo bands in standard errors (a 95 % normal interval).
Z_BAND = 1.96
#: Colour (Okabe-Ito, told apart with every common colour-vision deficiency), line style and marker of each
#: estimator or mechanism: a curve is recognised by its style and marker as well as its colour (Figs. 4, 5, 7, 8).
STYLE = {"pred": ("#D55E00", "--", "s"), "filt": ("#0072B2", "-", "o"), "smooth": ("#009E73", "-.", "^"),
         "zero": ("#0072B2", "-", "o"), "hold": ("#D55E00", "--", "s")}


def _time_panels(n: int, width: float, per_panel: float, extra: float):
    """A column of ``n`` panels (one per state component) against time: shared x axis, labelled below."""
    fig, axes = _plt().subplots(n, 1, figsize=(width, per_panel * n + extra), sharex=True, layout="constrained",
                                squeeze=False)
    axes[-1, 0].set_xlabel("time step $t$")
    return fig, axes[:, 0]


def fig_tracking(x: np.ndarray, est: np.ndarray, title: str, sym: str, eta: float, pdf: str, png: str,
                 arrived: np.ndarray | None = None) -> None:
    """Figs. 1-3: true state components and their estimate against time (legend below the panels); the steps
    whose packet was lost (``arrived[t] == 0``) shaded grey, so that a flat stretch of the estimate reads as the
    dropouts it follows."""
    fig, axes = _time_panels(x.shape[1], 5.4, 1.8, 0.9)
    t = np.arange(x.shape[0])
    lost = [] if arrived is None else [int(k) for k in np.flatnonzero(np.asarray(arrived) == 0)]
    for i, ax in enumerate(axes):
        for j, k in enumerate(lost):
            ax.axvspan(k - 0.5, k + 0.5, color="0.85", lw=0, zorder=0, label=None if j else "packet lost")
        ax.plot(t, x[:, i], "k-", label=r"true state $x_i(t)$")
        ax.plot(t, est[:, i], "r--", label="estimate " + sym.format(i="i"))
        ax.set_ylabel(rf"state $x_{i + 1}$ {UNIT}")
    axes[0].set_title(rf"Tracking by the LMV {title}, arrival probability $\bar\eta$ = {eta:g}")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=3)
    save_figure(fig, pdf, png)


def _mc_band(ax, t: np.ndarray, mc: np.ndarray, se: np.ndarray, style: tuple, every: int = 4) -> None:
    """Monte Carlo estimates (markers, every ``every``-th step) with their ``± Z_BAND`` standard-error band,
    in the ``(colour, line style, marker)`` ``style`` of their curve."""
    color, _, marker = style
    ax.fill_between(t, mc - Z_BAND * se, mc + Z_BAND * se, color=color, alpha=0.18, lw=0)
    ax.plot(t[::every], mc[::every], marker, ls="", ms=2.8, color=color, mfc="none", mew=0.8)


def _mc_legend(fig, rows: list[tuple[str, tuple]], runs: int) -> None:
    """One entry per curve (its style: line, markers and band together), then what line, markers and band are."""
    from matplotlib.legend_handler import HandlerTuple
    from matplotlib.patches import Patch

    Line2D = pyplot().Line2D

    def keys(style):  # band, line, markers of one curve
        col, ls, marker = style
        return (Patch(color=col, alpha=0.18, lw=0), Line2D([], [], color=col, ls=ls),
                Line2D([], [], ls="", marker=marker, ms=2.8, color=col, mfc="none"))

    band, line, markers = keys(("0.3", "-", "o"))
    labels = [label for label, _ in rows] + [
        "line: theory", f"markers: Monte Carlo, {runs} runs (every 4th step);\n"
                        f"band: its 95 % interval (± {Z_BAND:g} standard errors)"]
    fig.legend([keys(style) for _, style in rows] + [line, (band, markers)], labels, loc="outside lower center",
               ncol=2, handler_map={tuple: HandlerTuple(ndivide=1)})


def _theory_mc_figure(d, se, rows: tuple, what: str, width: float, per_panel: float, extra: float):
    """Theory (lines) and Monte Carlo (markers, 95 % band) against time, one panel per component, one curve per
    row ``(mechanism, estimator, label, style)`` of ``rows`` (``style``: colour, line style, marker); returns the
    figure and its panels."""
    fig, axes = _time_panels(d["zero/theory_filt"].shape[1], width, per_panel, extra)
    t = d["t"]
    for i, ax in enumerate(axes):
        for mech, est, _, style in rows:
            ax.plot(t, d[f"{mech}/theory_{est}"][:, i], color=style[0], ls=style[1])
            _mc_band(ax, t, d[f"{mech}/mc_{est}"][:, i], se[f"{mech}/se_{est}"][:, i], style)
        ax.set_ylabel(rf"{what} of $x_{i + 1}$ {UNIT}")
    _mc_legend(fig, [(label, style) for *_, label, style in rows], int(se["runs"]))
    return fig, axes


def fig_variances(d, se, N: int, eta: float, pdf: str, png: str) -> None:
    """Fig. 4: theoretical (lines) and Monte Carlo (markers, 95 % band) error variances, zero-input."""
    rows = (("zero", "pred", "one-step predictor $P(t|t-1)$", STYLE["pred"]),
            ("zero", "filt", "filter $P(t|t)$", STYLE["filt"]),
            ("zero", f"smooth{N}", f"{N}-step smoother $P(t|t+{N})$", STYLE["smooth"]))
    fig, axes = _theory_mc_figure(d, se, rows, "error variance", 5.4, 2.0, 1.2)
    axes[0].set_title(rf"Estimation error variances, zero-input, $\bar\eta$ = {eta:g}")
    save_figure(fig, pdf, png)


def fig_eta(d: dict, ex: str, N: int, example: dict, pdf: str, png: str) -> None:
    """Fig. 5: steady-state variances against eta_bar (zero-input); linear axes (the range is under a decade)."""
    plt = _plt()
    etas = d["eta"]
    n = d[f"{ex}/zero/filt"].shape[1]
    fig, axes = plt.subplots(1, n, figsize=(3.2 * n, 3.3), layout="constrained", squeeze=False)
    for i, ax in enumerate(axes[0]):
        for key, label in (("pred", "one-step predictor"), ("filt", "filter"), ("smooth", f"{N}-step smoother")):
            col, ls, marker = STYLE[key]
            ax.plot(etas, d[f"{ex}/zero/{key}"][:, i], color=col, ls=ls, marker=marker, ms=3.2, mfc="none",
                    mew=0.8, markevery=max(1, len(etas) // 8), label=label)
        ax.set_xlabel(r"arrival probability $\bar\eta$")
        ax.set_ylabel(rf"steady error variance of $x_{i + 1}$ {UNIT}")
        ax.set_ylim(0, None)
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=3)
    fig.suptitle(rf"Steady-state error variances (zero-input), $Q_\xi$ = {example['Qxi']:g}, "
                 rf"$Q_\lambda$ = {example['Qlam']:g}")
    save_figure(fig, pdf, png)


def fig_q(d: dict, ex: str, eta: float, pdf: str, png: str) -> None:
    """Fig. 6: steady filter variance surfaces over (Q_xi, Q_lambda), zero-input; the variance is the height and
    the colour of a surface, read on the colour bar beside it and on the labelled z axis."""
    plt = _plt()
    F = d[f"{ex}/zero/filt"]
    n = F.shape[-1]
    XI, LA = np.meshgrid(d["qxi"], d["qlam"], indexing="ij")
    fig, axes = plt.subplots(1, n, figsize=(3.6 * n, 3.3), layout="constrained", squeeze=False,
                             subplot_kw={"projection": "3d"})
    for i, ax in enumerate(axes[0]):
        surf = ax.plot_surface(XI, LA, F[..., i], cmap="viridis", linewidth=0.2, edgecolor="k", alpha=0.9)
        ax.set_xlabel(r"$Q_\xi$", labelpad=2)
        ax.set_ylabel(r"$Q_\lambda$", labelpad=6)
        ax.set_zlabel("variance", labelpad=4)
        ax.tick_params(axis="both", pad=0)
        ax.set_title(rf"component $x_{i + 1}$", y=0.98)
        fig.colorbar(surf, ax=ax, shrink=0.65, pad=0.1, label=rf"filter variance of $x_{i + 1}$ {UNIT}")
    fig.suptitle(rf"Steady filtering error variances (zero-input), $0 \leq Q_\xi, Q_\lambda \leq {d['qxi'][-1]:g}$, "
                 rf"$\bar\eta$ = {eta:g}", fontsize=9)
    save_figure(fig, pdf, png)


def _ratio_ticks(m: float) -> list[float]:
    """Colour-bar ticks of a ratio scale from ``1/m`` to ``m``: round values, at most about nine."""
    grid = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.98, 1.0, 1.02, 1.05, 1.1, 1.25, 1.5, 1.75, 2.0)
    ticks = [t for t in grid if 1.0 / m <= t <= m]
    return ticks if len(ticks) <= 9 else [t for t in ticks if t not in (0.95, 0.98, 1.02, 1.05)]


def fig_regions(d: dict, examples: dict, eta_bar: float, pdf: str, png: str) -> None:
    """Extra: where hold-input beats zero-input (trace of the steady filter variance), per example.

    Each panel has its own colour bar (the examples' ratios differ by a decade in spread: on one scale Example 2's
    variation would not show), logarithmic and symmetric about 1, so a ratio ``r`` and ``1/r`` are equally strong;
    the working point of Figs. 7/8 (``Qxi``, ``Qlam`` of ``examples[ex]``, the configured examples, titled by their
    ``name``) marked, the axes reaching a little past the grid so that it sits inside the frame (grey: no data).
    """
    from matplotlib.colors import LogNorm

    plt = _plt()
    exs = list(examples)
    fig, axes = plt.subplots(1, len(exs), figsize=(3.4 * len(exs), 3.6), layout="constrained", squeeze=False)
    # Q_xi on x and Q_lambda on y, as in Fig. 6
    pad = 0.07 * (d["qxi"][-1] - d["qxi"][0]), 0.07 * (d["qlam"][-1] - d["qlam"][0])
    for ax, ex in zip(axes[0], exs):
        ratio = d[f"{ex}/hold/filt"].sum(-1) / d[f"{ex}/zero/filt"].sum(-1)
        m = max(1.02, float(np.nanmax(ratio)), 1.0 / float(np.nanmin(ratio)))
        # white = equal variances (ratio 1), blue = hold-input better, red = zero-input better
        im = ax.pcolormesh(d["qxi"], d["qlam"], ratio.T, cmap="RdBu_r", norm=LogNorm(vmin=1.0 / m, vmax=m),
                           shading="auto")
        ax.contour(d["qxi"], d["qlam"], ratio.T, levels=[1.0], colors="k", linewidths=1.0)
        ax.plot([float(examples[ex]["Qxi"])], [float(examples[ex]["Qlam"])], "*", color="gold", mec="k", mew=0.6,
                ms=11, zorder=5, label="working point of Figs. 7 and 8")
        ax.set_xlim(d["qxi"][0] - pad[0], d["qxi"][-1] + pad[0])
        ax.set_ylim(d["qlam"][0] - pad[1], d["qlam"][-1] + pad[1])
        ax.set_facecolor("0.75")
        ax.grid(False)
        ax.set_xlabel(r"$Q_\xi$ (variance of $\xi$)")
        ax.set_ylabel(r"$Q_\lambda$ (variance of $\lambda$)")
        ax.set_title(examples[ex].get("name", ex))
        cb = fig.colorbar(im, ax=ax, label=r"tr $P_{\mathrm{hold}}$ / tr $P_{\mathrm{zero}}$, log scale")
        ticks = _ratio_ticks(m)
        cb.set_ticks(ticks, labels=[f"{t:g}" for t in ticks])
        cb.minorticks_off()
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend([*handles, plt.Line2D([], [], color="k", lw=1.0)], [*labels, "equal variances (ratio 1)"],
               loc="outside lower center", ncol=2)
    fig.suptitle(rf"Hold-input vs zero-input filter, $\bar\eta$ = {eta_bar:g}: blue, ratio < 1: hold-input better; "
                 "red: zero-input better", fontsize=9)
    save_figure(fig, pdf, png)


def _verdict(d, T: int) -> tuple[str, float]:
    """Which mechanism has the lower theoretical filter variance at ``t = T`` in every component, and the
    trace gap in percent of the lower one."""
    z, h = d["zero/theory_filt"][T], d["hold/theory_filt"][T]
    who = "zero-input" if np.all(z < h) else "hold-input" if np.all(h < z) else "neither (mixed)"
    return who, 100.0 * abs(float(h.sum() - z.sum())) / min(float(h.sum()), float(z.sum()))


def fig_compare(d, se, name: str, eta: float, paper: str | None, pdf: str, png: str) -> None:
    """Figs. 7-8: filter error variances of zero- and hold-input, theory (lines) and Monte Carlo (markers, 95 %
    band); the title gives the theoretical verdict and the paper's (``paper``, from ``config/claims.yaml``)."""
    rows = (("zero", "filt", "zero-input", STYLE["zero"]), ("hold", "filt", "hold-input", STYLE["hold"]))
    fig, axes = _theory_mc_figure(d, se, rows, "filter variance", 5.6, 1.9, 1.5)
    T = int(np.flatnonzero(np.isfinite(d["zero/theory_filt"][:, 0]))[-1])
    who, gap = _verdict(d, T)
    rel_se = 100.0 * Z_BAND * float(np.nanmax(se["zero/se_filt"][T] / d["zero/mc_filt"][T]))
    opposite = " (the opposite)" if paper != who and "mixed" not in who else ""
    flag = "" if paper is None else f"; the paper: {paper} lower{opposite}"
    axes[0].set_title(
        rf"{name}: filter error variances of the two mechanisms, $\bar\eta$ = {eta:g}" + "\n"
        f"theory at t = {T}: {who} lower (trace {gap:.1f} % apart){flag}" + "\n"
        f"Monte Carlo 95 % interval: up to ± {rel_se:.1f} % of the variance", fontsize=8)
    save_figure(fig, pdf, png)


# --------------------------------------------------------------------------- steps

def step_fig4(cfg, inputs, outputs, wildcards) -> None:
    """Fig. 4 from the Monte Carlo file of the tracking example."""
    fig_variances(np.load(inputs.mc), np.load(inputs.se), int(cfg["smoother_lag"]), float(cfg["eta_bar"]),
                  outputs.pdf, outputs.png)


def step_fig5(cfg, inputs, outputs, wildcards) -> None:
    """Merge the eta-sweep chunks (whole grid, once) and draw Fig. 5."""
    d = merge_npz(list(inputs.chunks), int(cfg["sweep_eta"]["num"]), outputs.merged)
    ex = cfg["tracking"]["example"]
    fig_eta(d, ex, int(cfg["smoother_lag"]), cfg["examples"][ex], outputs.pdf, outputs.png)


def step_fig6(cfg, inputs, outputs, wildcards) -> None:
    """Merge the Q-sweep chunks (whole grid, once); Fig. 6 and the regions figure."""
    d = merge_npz(list(inputs.chunks), int(cfg["sweep_q"]["num"]), outputs.merged, shared=("qlam",))
    fig_q(d, cfg["tracking"]["example"], float(cfg["eta_bar"]), outputs.pdf, outputs.png)
    fig_regions(d, cfg["examples"], float(cfg["eta_bar"]), outputs.rpdf, outputs.rpng)


def step_compare(cfg, inputs, outputs, wildcards) -> None:
    """Figs. 7-8: zero-input vs hold-input filter of one example."""
    ex = wildcards["example"]
    fig_compare(np.load(inputs.mc), np.load(inputs.se), cfg["examples"][ex].get("name", ex), float(cfg["eta_bar"]),
                cfg["published"].get(ex), outputs.pdf, outputs.png)
