"""Figures in the style of the papers: error trajectories with guarantee bars.

Shared helpers (:func:`paper_style`, :func:`save_figure`) are used by every
figure of the package; the per-paper figure functions live here as well.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STATE_LABELS_ACC = (r"$\xi_1$: ego speed error [m/s]", r"$\xi_2$: headway error [m]",
                    r"$\xi_3$: lead speed error [m/s]")


def paper_style() -> None:
    """Matplotlib settings close to the papers' (serif, small, grid)."""
    plt.rcParams.update({
        "font.family": "serif", "font.size": 9, "axes.titlesize": 9, "axes.labelsize": 9,
        "legend.fontsize": 8, "xtick.labelsize": 8, "ytick.labelsize": 8, "axes.grid": True,
        "grid.alpha": 0.3, "figure.dpi": 150, "savefig.bbox": "tight", "lines.linewidth": 0.8,
    })


def save_figure(fig: plt.Figure, *paths: str | Path) -> None:
    """Save a figure to each path (PDF, PNG, ... by suffix) and close it."""
    for p in paths:
        Path(p).parent.mkdir(parents=True, exist_ok=True)
        # no creation date in PDFs: re-running the pipeline leaves unchanged figures byte-identical
        meta = {"CreationDate": None} if str(p).endswith(".pdf") else None
        fig.savefig(p, metadata=meta)
    plt.close(fig)


def guarantee_bars(ax: plt.Axes, levels: Sequence[float], label: str | None = "guarantee") -> None:
    """Draw the guarantee ``|ξ_i(t)| <= level(t)`` as clear bars, one per time step.

    ``levels[t]`` is M1 at t = 0 and t = T, M2 in between (Definition 2 of the
    prefix-based paper).
    """
    levels = np.asarray(levels, float)
    for t, lev in enumerate(levels):
        ax.add_patch(plt.Rectangle((t - 0.3, -lev), 0.6, 2 * lev, fill=False, edgecolor="0.35",
                                   linewidth=0.9, label=label if t == 0 else None))


def error_trajectories(ax: plt.Axes, errors: np.ndarray, color: str = "C0", alpha: float = 0.35,
                       label: str | None = None) -> None:
    """Plot many error trajectories ``errors[run, t]`` of one state component."""
    T1 = errors.shape[1]
    t = np.arange(T1)
    for i, e in enumerate(errors):
        ax.plot(t, e, color=color, alpha=alpha, label=label if i == 0 else None)


def trajectory_panel(axes_column: Sequence[plt.Axes], errors: np.ndarray, levels: Sequence[float],
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
        if i == 0:
            ax.set_title(title)
    axes_column[-1].set_xlabel("time step $t$")
