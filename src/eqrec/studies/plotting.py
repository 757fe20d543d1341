"""Figures in the style of the papers: error trajectories with guarantee bars.

Shared by the figure modules of every study (``p1_figures``, ``p2_figures``, ``p3_figures``,
``p4_figures``); figures are written by :func:`eqrec.studies.pipeline.outputs.save_figure`
(atomic, PDF without a creation date).  Matplotlib is imported on first use
(non-interactive ``Agg`` backend), so importing a study stays cheap.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


STATE_LABELS_ACC = (r"$\xi_1$: ego speed error [m/s]", r"$\xi_2$: headway error [m]",
                    r"$\xi_3$: lead speed error [m/s]")


def pyplot():
    """``matplotlib.pyplot`` with the non-interactive ``Agg`` backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: Width (px) at which a reader sees a figure (the report, a notebook) and the smallest text height (em, px)
#: allowed there, mathtext scripts aside; ``tests/test_figure_text.py`` measures every stored PDF against it.
REPORT_WIDTH_PX, MIN_EM_PX = 800, 11.0
#: The smallest height (px, at :data:`REPORT_WIDTH_PX`) of a digit's glyph, and of a script's digit (the exponent
#: of a logarithmic axis's tick label); measured on the outlines by ``tests/test_figure_text.py``.
MIN_DIGIT_PX, MIN_SCRIPT_DIGIT_PX = 9.0, 7.0


#: Size of a mathtext sub- or superscript relative to its text (matplotlib's default is 0.7, TeX's at small
#: sizes 0.75 to 0.8): at 0.8 the subscript of a 9-pt ``$\xi_1$`` stays above :data:`MIN_SCRIPT_DIGIT_PX` in a
#: figure up to 7.5 in wide shown :data:`REPORT_WIDTH_PX` wide.
SCRIPT_SCALE = 0.8


def larger_scripts(scale: float = SCRIPT_SCALE) -> float:
    """Set the size of mathtext's sub- and superscripts relative to their text; returns the previous size.

    Matplotlib has no setting for it: the module constant ``matplotlib._mathtext.SHRINK_FACTOR`` is read
    each time a formula is laid out, so setting it here changes every formula drawn afterwards in this
    process (``tests/test_figure_text.py`` measures the result on every stored figure).

    Parameters
    ----------
    scale : float, optional
        The script size as a fraction of the text size.

    Returns
    -------
    float
        The size it replaces (to restore it).
    """
    from matplotlib import _mathtext

    previous, _mathtext.SHRINK_FACTOR = _mathtext.SHRINK_FACTOR, scale
    return previous


def paper_style() -> None:
    """Matplotlib settings close to the papers' (serif, small, grid) and the maths in the text's serif font.

    With 8 pt for the smallest text, a figure up to 7.2 in wide (as saved, ``bbox="tight"``) shows every
    text at least :data:`MIN_EM_PX` tall and every digit at least :data:`MIN_DIGIT_PX` tall when drawn
    :data:`REPORT_WIDTH_PX` wide; the mathtext scripts are :data:`SCRIPT_SCALE` of their text
    (:func:`larger_scripts`), so their digits reach :data:`MIN_SCRIPT_DIGIT_PX`.
    """
    larger_scripts()
    pyplot().rcParams.update({
        "font.family": "serif", "font.size": 9, "axes.titlesize": 9, "axes.labelsize": 9,
        "legend.fontsize": 8, "xtick.labelsize": 8, "ytick.labelsize": 8, "axes.grid": True,
        "grid.alpha": 0.3, "figure.dpi": 150, "savefig.bbox": "tight", "lines.linewidth": 0.8,
        "mathtext.fontset": "dejavuserif", "figure.titlesize": 10,
    })


def same_scale_per_row(axes) -> None:
    """One y scale per row of a grid of axes (the same quantity across the columns), ``±`` the largest limit.

    Parameters
    ----------
    axes : numpy.ndarray
        ``(rows, cols)`` axes; each row gets ``(-lim, lim)`` with ``lim`` its largest absolute limit.
    """
    for row in np.atleast_2d(axes):
        lim = max(abs(v) for ax in row for v in ax.get_ylim())
        for ax in row:
            ax.set_ylim(-lim, lim)


def equalized_levels(T: int, mu1: float, mu2: float) -> np.ndarray:
    """The guarantee of an equalized-recovery design along ``t = 0..T``: ``mu1`` at ``t = 0`` and ``t = T``,
    ``mu2`` in between (Definition 2 of the prefix-based paper).

    Parameters
    ----------
    T : int
        The horizon.
    mu1, mu2 : float
        The recovery and intermediate levels.

    Returns
    -------
    numpy.ndarray
        Shape ``(T+1,)``.
    """
    return np.r_[mu1, np.full(T - 1, mu2), mu1]


def guarantee_bars(ax, levels: Sequence[float], label: str | None = "guarantee") -> None:
    """Draw the guarantee ``|ξ_i(t)| <= level(t)`` as clear bars, one per time step.

    ``levels[t]`` is M1 at t = 0 and t = T, M2 in between (Definition 2 of the
    prefix-based paper).
    """
    plt = pyplot()
    levels = np.asarray(levels, float)
    for t, lev in enumerate(levels):
        ax.add_patch(plt.Rectangle((t - 0.3, -lev), 0.6, 2 * lev, fill=False, edgecolor="0.35",
                                   linewidth=0.9, label=label if t == 0 else None))


def error_trajectories(ax, errors: np.ndarray, color: str = "C0", alpha: float = 0.35,
                       label: str | None = None) -> None:
    """Plot many error trajectories ``errors[run, t]`` of one state component (one line collection: hundreds of
    runs draw in one artist)."""
    from matplotlib import rcParams
    from matplotlib.collections import LineCollection

    t = np.arange(errors.shape[1], dtype=float)
    segments = np.stack([np.broadcast_to(t, errors.shape), errors], axis=-1)
    ax.add_collection(LineCollection(segments, colors=color, alpha=alpha, linewidths=rcParams["lines.linewidth"],
                                    label=label))
    ax.autoscale_view()


def trajectory_panel(axes_column, errors: np.ndarray, levels: Sequence[float],
                     title: str, state_labels: Sequence[str] = STATE_LABELS_ACC, color: str = "C0",
                     ylabels: bool = True) -> None:
    """One column of a Fig.-1-like panel: a subplot per state with runs and bars.

    Parameters
    ----------
    axes_column
        One axis per state component.
    errors
        Array ``(runs, T+1, n)``.
    levels
        Guarantee level per time step (length ``T+1``).
    """
    for i, ax in enumerate(axes_column):
        error_trajectories(ax, errors[:, :, i], color=color, label="estimation error")
        guarantee_bars(ax, levels)
        lim = 1.15 * max(np.max(levels), np.max(np.abs(errors[:, :, i])))
        ax.set_ylim(-lim, lim)
        ax.set_xlim(-0.6, errors.shape[1] - 0.4)
        if ylabels:
            ax.set_ylabel(state_labels[i] if i < len(state_labels) else rf"$\xi_{i + 1}$")
    axes_column[0].set_title(title)
    axes_column[-1].set_xlabel("time step $t$")


def worst_case_lines(axes_column, worst: np.ndarray, label: str = "exact worst case") -> None:
    """Dashed ``±worst[t, i]`` on the subplot of each state ``i``: the exact worst case per time and component.

    Parameters
    ----------
    axes_column
        One axis per state component.
    worst
        Array ``(T+1, n)`` (e.g. the certified bounds of :mod:`eqrec.bounds.certify`).
    label
        Legend entry (on the first axis only).
    """
    t = np.arange(worst.shape[0])
    for i, ax in enumerate(axes_column):
        ax.plot(t, worst[:, i], "k--", lw=0.7, label=label if i == 0 else None)
        ax.plot(t, -worst[:, i], "k--", lw=0.7)
