"""P1 figures: Fig. 1 of the prefix-based paper and the P1-EXT figure (steps ``figure1``, ``figure_ext``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from eqrec.studies.outputs import save_figure
from eqrec.studies.plotting import paper_style, pyplot, trajectory_panel


def step_figure1(cfg, inputs, outputs, wildcards) -> None:
    """P1-F1: prefix-based (left) vs time-based (right) error trajectories with guarantee bars."""
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    mu1 = float(data["M1"])
    fig, axes = plt.subplots(3, 2, figsize=(7.0, 6.0), sharex=True)
    for col, method, name in ((0, "prefix", "Prefix-based"), (1, "time", "Time-based")):
        errs = data[f"{method}_errors"]
        mu2 = float(data[f"{method}_mu2"])
        T = errs.shape[1] - 1
        levels = [mu1] + [mu2] * (T - 1) + [mu1]
        trajectory_panel(axes[:, col], errs, levels,
                         f"{name} estimator ($M_1$ = {mu1:g}, $M_2^*$ = {mu2:.4f})", ylabels=(col == 0))
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(f"ACC, $L_1$, {errs.shape[0]} runs: estimation errors and guarantees")
    save_figure(fig, outputs.pdf, outputs.png)


def step_figure_ext(cfg, inputs, outputs, wildcards) -> None:
    """P1-EXT: optimal M2 against M1 for both estimators; minimum T against M1."""
    paper_style()
    plt = pyplot()
    res = json.loads(Path(inputs.json).read_text())
    c = res["curve"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(7.0, 2.8))
    for m, style in (("prefix", "C0-"), ("time", "C3--")):
        mu1 = [a for a, b in zip(c["M1"], c[m]) if b is not None]
        M2 = [b for b in c[m] if b is not None]
        ax1.plot(mu1, M2, style, marker=".", label=f"{m}-based")
        ax1.axvline(res["min_M1"][m], color=style[:2], lw=0.8, ls=":",
                    label=f"smallest $M_1$: {res['min_M1'][m]:.4f}")
    ax1.set_xlim(0.0, 1.03 * max(c["M1"]))  # the smallest levels stand clear of the y axis
    ax1.set_ylim(0.0, None)
    ax1.set_xlabel("recovery level $M_1$")
    ax1.set_ylabel("optimal intermediate level $M_2^*$")
    ax1.set_title("$M_2^*(M_1)$ on $L_1$ (dotted: smallest feasible $M_1$)")
    ax1.legend(fontsize=7, loc="upper left")
    near = [r for r in res["min_T"] if r["M1"] <= 1.05 * res["min_M1"]["prefix"]]  # where T grows
    far = [r for r in res["min_T"] if r not in near]
    ok = [(r["M1"], r["T"]) for r in near if r["T"] is not None]
    if ok:
        ax2.plot([a for a, _ in ok], [b for _, b in ok], "C0o-", label="minimum $T$")
    t_max = max([b for _, b in ok] + [6])
    for r in near:
        if r["T"] is None:
            ax2.plot(r["M1"], t_max + 1, "C3x", label="none up to $T_{max}$")
    ax2.axvline(res["min_M1"]["prefix"], color="0.5", ls=":", lw=0.8, label="smallest $M_1$ at $T = 6$")
    if far:  # levels far from the smallest one: a note where no marker is (top right)
        ax2.text(0.98, 0.96, "; ".join(f"$M_1$ = {r['M1']:g}: $T$ = {r['T']}" for r in far),
                 transform=ax2.transAxes, ha="right", va="top", fontsize=7)
    xs = [r["M1"] for r in near] + [res["min_M1"]["prefix"]]
    pad = 0.06 * (max(xs) - min(xs))
    ax2.set_xlim(min(xs) - pad, max(xs) + pad)  # no marker on the frame
    ax2.set_ylim(min([b for _, b in ok] + [6]) - 0.8, t_max + 1.8)
    ax2.legend(fontsize=7, loc="lower left")
    ax2.set_xlabel("recovery level $M_1$")
    ax2.set_ylabel("minimum recovery time $T$")
    ax2.set_title("Minimum $T$ for $L_1$ (words extended by 1s)")
    save_figure(fig, outputs.pdf, outputs.png)


STEPS = {"figure1": step_figure1, "figure_ext": step_figure_ext}
