"""P1 figures: Fig. 1 of the prefix-based paper and the P1-EXT figure (steps ``figure1``, ``figure_ext``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from eqrec.studies.pipeline.outputs import save_figure
from eqrec.studies.plotting import equalized_levels, paper_style, pyplot, same_scale_per_row, trajectory_panel


def step_figure1(cfg, inputs, outputs, wildcards) -> None:
    """P1-F1: prefix-based (left) vs time-based (right) error trajectories with guarantee bars.

    One y scale per row: the same state error in both columns, so the bars' heights compare
    (``M2*`` of the two designs).
    """
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    mu1 = float(data["M1"])
    fig, axes = plt.subplots(3, 2, figsize=(7.0, 6.4), sharex=True, sharey="row", layout="constrained")
    for col, method, name in ((0, "prefix", "Prefix-based"), (1, "time", "Time-based")):
        errs = data[f"{method}_errors"]
        mu2 = float(data[f"{method}_mu2"])
        trajectory_panel(axes[:, col], errs, equalized_levels(errs.shape[1] - 1, mu1, mu2),
                         f"{name} estimator\n$M_1$ = {mu1:g}, $M_2^*$ = {mu2:.4f}", ylabels=(col == 0))
    same_scale_per_row(axes)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, ["estimation error (one line per run)", "guarantee: $M_1$ at $t$ = 0 and $T$, $M_2^*$ between"],
               loc="outside lower center", ncol=2)
    fig.suptitle(f"ACC, language $L_1$, {errs.shape[0]} runs: estimation errors and guarantees (same scale per row)")
    save_figure(fig, outputs.pdf, outputs.png)


def _feasibility_bands(ax, lo: dict, T: int, labels: bool) -> None:
    """The levels with no design at horizon ``T`` (grey) and those only the time-based estimator lacks (red)."""
    ax.axvspan(0.0, lo["prefix"], color="0.80", lw=0,
               label=f"no design at $T$ = {T}: $M_1$ < {lo['prefix']:.4f}\n(a longer $T$ allows less, right)"
               if labels else None)
    ax.axvspan(lo["prefix"], lo["time"], color="C3", alpha=0.35, lw=0,
               label=f"time-based infeasible: $M_1$ < {lo['time']:.4f}" if labels else None)


def _feasibility_panel(ax, res: dict, T: int) -> None:
    """Left panel of P1-EXT: ``M2*(M1)`` per estimator at horizon ``T``; levels below the smallest feasible
    ``M1`` shaded, with an inset magnifying the narrow band where only the prefix-based estimator exists."""
    c = res["curve"]
    lo = res["min_M1"]
    _feasibility_bands(ax, lo, T, labels=True)
    for m, style, marker, name in (("prefix", "C0-", "o", "prefix-based"), ("time", "C3--", "s", "time-based")):
        mu1, M2 = zip(*[(a, b) for a, b in zip(c["M1"], c[m]) if b is not None])  # the computed levels
        ax.plot(mu1, M2, style, marker=marker, ms=3.5, mfc="white", mew=0.8,
                label=f"{name}, computed from $M_1$ = {min(mu1):g}")
    ax.set_xlim(0.0, 1.03 * max(c["M1"]))
    ax.set_ylim(0.0, None)
    ax.set_xlabel("recovery level $M_1$")
    ax.set_ylabel("optimal intermediate level $M_2^*$")
    ax.set_title(f"$M_2^*$ against $M_1$ on $L_1$, $T$ = {T}")
    # the band [lo_prefix, lo_time) is a few pixels wide at this scale: magnified in an inset
    width = lo["time"] - lo["prefix"]
    inset = ax.inset_axes([0.17, 0.72, 0.33, 0.16])
    _feasibility_bands(inset, lo, T, labels=False)
    inset.set_xlim(lo["prefix"] - 0.3 * width, lo["time"] + 0.3 * width)
    inset.set_xticks([lo["prefix"], lo["time"]], [f"{lo['prefix']:.4f}", f"{lo['time']:.4f}"])
    inset.set_yticks([])
    inset.grid(False)
    inset.set_title("$M_1$ magnified", fontsize=8, pad=2)
    ax.annotate("", xy=(lo["time"], 0.8), xycoords=("data", "axes fraction"), xytext=(0.17, 0.8),
                textcoords="axes fraction", arrowprops={"arrowstyle": "->", "color": "0.3", "lw": 0.8})


def _min_time_panel(ax, res: dict, T: int, t_max: int) -> None:
    """Right panel of P1-EXT: minimum recovery time (integer) against ``M1``, near the smallest feasible level."""
    near = [r for r in res["min_T"] if r["M1"] <= 1.05 * res["min_M1"]["prefix"]]  # where T grows
    far = [r for r in res["min_T"] if r not in near]
    ok = sorted((r["M1"], r["T"]) for r in near if r["T"] is not None)
    none = [r["M1"] for r in near if r["T"] is None]
    if ok:  # T is an integer, non-increasing in M1: steps between the computed levels, markers where computed
        ax.plot([a for a, _ in ok], [b for _, b in ok], "C0-", drawstyle="steps-post", lw=1.0)
        ax.plot([a for a, _ in ok], [b for _, b in ok], "C0o", ms=5, label="minimum $T$ (computed at the markers)")
    row = t_max + 1.5  # a row above the axis of T for the levels with no T up to T_max
    if none:
        ax.plot(none, [row] * len(none), "C3^", ms=7, label=f"no $T \\leq$ {t_max} (the largest tried)")
    ax.axhline(t_max + 0.75, color="0.3", lw=0.6)
    ax.axvline(res["min_M1"]["prefix"], color="0.4", ls=":", lw=1.0,
               label=f"smallest $M_1$ at $T$ = {T}: {res['min_M1']['prefix']:.4f}")
    ticks = list(range(T, t_max + 1, 2))
    ax.set_yticks(ticks + [row], [str(t) for t in ticks] + ["none"])
    xs = [r["M1"] for r in near] + [res["min_M1"]["prefix"]]
    pad = 0.06 * (max(xs) - min(xs))
    ax.set_xlim(min(xs) - pad, max(xs) + pad)
    ax.set_ylim(min([b for _, b in ok] + [T]) - 0.8, row + 0.8)
    ax.set_xlabel("recovery level $M_1$")
    ax.set_ylabel("minimum recovery time $T$ [steps]")
    extra = "; ".join(f"$M_1$ = {r['M1']:g}: $T$ = {r['T']}" for r in far)
    ax.set_title("Minimum $T$ on $L_1$, words extended by 1s" + (f"\n({extra})" if extra else ""))


def step_figure_ext(cfg, inputs, outputs, wildcards) -> None:
    """P1-EXT: optimal M2 against M1 for both estimators; minimum T against M1 (legends below the panels)."""
    paper_style()
    plt = pyplot()
    res = json.loads(Path(inputs.json).read_text())
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(7.0, 3.8), layout="constrained")
    fig.get_layout_engine().set(w_pad=0.12)  # room between the panels for the right one's y label
    T = len(cfg["language"][0])  # the horizon of L1 (its words' length)
    _feasibility_panel(ax1, res, T)
    _min_time_panel(ax2, res, T, int(cfg["extensions"]["T_max"]))
    for ax in (ax1, ax2):
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=1, frameon=False)
    save_figure(fig, outputs.pdf, outputs.png)
