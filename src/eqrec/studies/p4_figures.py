"""P4 figures: Figs. 1-8 of the LMV paper and the zero- vs hold-input regions (plotting only).

Called by the steps of :mod:`eqrec.studies.p4`; every figure is written as
PDF and PNG by :func:`eqrec.studies.outputs.save_figure`.
"""

from __future__ import annotations

import numpy as np

from eqrec.studies.chunks import merge_npz
from eqrec.studies.outputs import save_figure
from eqrec.studies.plotting import paper_style, pyplot


def _plt():
    paper_style()
    return pyplot()

def fig_tracking(x: np.ndarray, est: np.ndarray, title: str, sym: str, eta: float, num: int, pdf: str,
                 png: str) -> None:
    """Figs. 1-3: true state components and their estimate against time."""
    plt = _plt()
    n = x.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(5.0, 1.8 * n), sharex=True)
    t = np.arange(x.shape[0])
    for i, ax in enumerate(np.atleast_1d(axes)):
        ax.plot(t, x[:, i], "k-", label=rf"true $x_{i + 1}(t)$")
        ax.plot(t, est[:, i], "r--", label="estimate " + sym.format(i=i + 1))
        ax.set_ylabel(rf"$x_{i + 1}$ (state units)")
        ax.legend(loc="upper right", ncol=2)
    np.atleast_1d(axes)[-1].set_xlabel("time step $t$")
    np.atleast_1d(axes)[0].set_title(rf"Fig. {num}: tracking performance of the {title}, $\bar\eta = {eta:g}$")
    save_figure(fig, pdf, png)


def fig_variances(d, N: int, eta: float, pdf: str, png: str) -> None:
    """Fig. 4: theoretical (lines) and Monte Carlo (markers) error variances, zero-input."""
    plt = _plt()
    n = d["zero/theory_pred"].shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(5.0, 2.0 * n), sharex=True)
    t = d["t"]
    styles = [("pred", "predictor $P(t|t-1)$", "C3"), ("filt", "filter $P(t|t)$", "C0"),
              (f"smooth{N}", f"smoother $P(t|t+{N})$", "C2")]
    for i, ax in enumerate(np.atleast_1d(axes)):
        for key, label, col in styles:
            ax.plot(t, d[f"zero/theory_{key}"][:, i], color=col, label=label + " (theory)")
            ax.plot(t[::4], d[f"zero/mc_{key}"][::4, i], "o", ms=2.2, color=col, mfc="none",
                    label="Monte Carlo" if key == "filt" else None)
        ax.set_ylabel(rf"error variance of $x_{i + 1}$")
        if i == 0:
            ax.legend(loc="lower right", fontsize=7)
            ax.set_title(rf"Fig. 4: estimation error variances, $\bar\eta = {eta:g}$")
    np.atleast_1d(axes)[-1].set_xlabel("time step $t$")
    save_figure(fig, pdf, png)


def fig_eta(d: dict, ex: str, N: int, example: dict, pdf: str, png: str) -> None:
    """Fig. 5: steady-state variances against eta_bar (zero-input)."""
    plt = _plt()
    etas = d["eta"]
    n = d[f"{ex}/zero/filt"].shape[1]
    fig, axes = plt.subplots(1, n, figsize=(3.0 * n, 2.6))
    p = example
    for i, ax in enumerate(np.atleast_1d(axes)):
        for key, label, col in (("pred", "predictor", "C3"), ("filt", "filter", "C0"),
                                ("smooth", f"smoother (N = {N})", "C2")):
            ax.plot(etas, d[f"{ex}/zero/{key}"][:, i], color=col, label=label)
        ax.set_xlabel(r"arrival probability $\bar\eta$")
        ax.set_ylabel(rf"steady error variance of $x_{i + 1}$")
        ax.set_yscale("log")
    np.atleast_1d(axes)[0].legend()
    fig.suptitle(rf"Fig. 5: error variances, $Q_\xi = {p['Qxi']:g}$, $Q_\lambda = {p['Qlam']:g}$, "
                 rf"${etas[0]:g} \leq \bar\eta \leq {etas[-1]:g}$", fontsize=9)
    save_figure(fig, pdf, png)


def fig_q(d: dict, ex: str, eta: float, pdf: str, png: str) -> None:
    """Fig. 6: steady filter variance surfaces over (Q_xi, Q_lambda), zero-input."""
    plt = _plt()
    F = d[f"{ex}/zero/filt"]
    n = F.shape[-1]
    XI, LA = np.meshgrid(d["qxi"], d["qlam"], indexing="ij")
    fig = plt.figure(figsize=(3.4 * n, 3.0))
    for i in range(n):
        ax = fig.add_subplot(1, n, i + 1, projection="3d")
        ax.plot_surface(XI, LA, F[..., i], cmap="viridis", linewidth=0.2, edgecolor="k", alpha=0.9)
        ax.set_xlabel(r"$Q_\xi$")
        ax.set_ylabel(r"$Q_\lambda$")
        ax.set_zlabel(rf"filter variance of $x_{i + 1}$")
    fig.suptitle(rf"Fig. 6: filtering error variances, $0 \leq Q_\xi, Q_\lambda \leq {d['qxi'][-1]:g}$, "
                 rf"$\bar\eta = {eta:g}$", fontsize=9)
    save_figure(fig, pdf, png)


def fig_regions(d: dict, names: dict, eta_bar: float, pdf: str, png: str) -> None:
    """Extra: where hold-input beats zero-input (trace of the steady filter variance), per example.

    One colour scale for every panel (the same quantity) and one colour bar.
    """
    from matplotlib.colors import TwoSlopeNorm

    plt = _plt()
    exs = list(names)
    ratios = {ex: d[f"{ex}/hold/filt"].sum(-1) / d[f"{ex}/zero/filt"].sum(-1) for ex in exs}
    lo = min(0.8, *(float(np.nanmin(r)) for r in ratios.values()))
    hi = max(1.2, *(float(np.nanmax(r)) for r in ratios.values()))
    # white = equal variances (ratio 1), blue = hold-input better, red = zero-input better
    norm = TwoSlopeNorm(vcenter=1.0, vmin=lo, vmax=hi)
    fig, axes = plt.subplots(1, len(exs), figsize=(3.6 * len(exs) + 0.8, 3.2), layout="constrained", squeeze=False)
    for ax, ex in zip(axes[0], exs):
        im = ax.pcolormesh(d["qlam"], d["qxi"], ratios[ex], cmap="RdBu_r", norm=norm, shading="auto")
        ax.contour(d["qlam"], d["qxi"], ratios[ex], levels=[1.0], colors="k", linewidths=1.0)
        ax.set_xlabel(r"$Q_\lambda$")
        ax.set_ylabel(r"$Q_\xi$")
        ax.set_title(names[ex])
    fig.colorbar(im, ax=list(axes[0]), label="tr $P_{hold}$ / tr $P_{zero}$ (filter)")
    fig.suptitle(rf"hold-input vs zero-input filter, $\bar\eta = {eta_bar:g}$ "
                 "(< 1: hold-input better; black: equal)", fontsize=9)
    save_figure(fig, pdf, png)


def fig_compare(d, name: str, eta: float, number: int, pdf: str, png: str) -> None:
    """Figs. 7-8: filter error variances of zero- and hold-input, theory (lines) and Monte Carlo (markers)."""
    plt = _plt()
    n = d["zero/theory_filt"].shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(5.0, 1.9 * n), sharex=True)
    t = d["t"]
    for i, ax in enumerate(np.atleast_1d(axes)):
        for k, label, col in (("zero", "zero-input", "C0"), ("hold", "hold-input", "C3")):
            ax.plot(t, d[f"{k}/theory_filt"][:, i], color=col, label=f"{label} (theory)")
            ax.plot(t[::4], d[f"{k}/mc_filt"][::4, i], "o", ms=2.2, mfc="none", color=col,
                    label=f"{label} (Monte Carlo)")
        ax.set_ylabel(rf"filter variance of $x_{i + 1}$")
        if i == 0:
            ax.legend(loc="lower right", fontsize=7, ncol=2)
            ax.set_title(rf"Fig. {number}: filtering error variances of the two mechanisms, {name}, "
                         rf"$\bar\eta = {eta:g}$")
    np.atleast_1d(axes)[-1].set_xlabel("time step $t$")
    save_figure(fig, pdf, png)


# --------------------------------------------------------------------------- steps

def step_fig4(cfg, inputs, outputs, wildcards) -> None:
    """Fig. 4 from the Monte Carlo file of the tracking example."""
    fig_variances(np.load(inputs.mc), int(cfg["smoother_lag"]), float(cfg["eta_bar"]),
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
    names = {ex: cfg["examples"][ex].get("name", ex) for ex in cfg["examples"]}
    fig_regions(d, names, float(cfg["eta_bar"]), outputs.rpdf, outputs.rpng)


def step_compare(cfg, inputs, outputs, wildcards) -> None:
    """Figs. 7-8: zero-input vs hold-input filter of one example."""
    ex = wildcards["example"]
    fig_compare(np.load(inputs.mc), cfg["examples"][ex].get("name", ex), float(cfg["eta_bar"]),
                           int(wildcards["number"]), outputs.pdf, outputs.png)


STEPS = {
    "fig4": step_fig4,
    "fig5": step_fig5,
    "fig6": step_fig6,
    "compare": step_compare,
}
