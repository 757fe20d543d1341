"""P3 figures: Fig. 1 (batch reactor, proposed vs Kalman-type filters) and Fig. 2 (ACC, proposed vs P1 prefix-based).

Steps ``figure1`` and ``figure2``; errors per state with the per-time
guarantee levels ``μ2,k`` along the true pattern's path (clear bars), as in
the paper's figures.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from eqrec.studies.outputs import save_figure
from eqrec.studies.plotting import STATE_LABELS_ACC, paper_style, pyplot, trajectory_panel, worst_case_lines

# the linearised batch reactor's states are dimensionless deviations (Sec. IV-A of the delayed-data paper)
STATE_LABELS_REACTOR = tuple(rf"$\tilde x_{i}$ [–]" for i in range(1, 5))
FILTER_TITLES = {"timestamped": "Time-stamped Kalman (re-filtering)", "unaware": "Delay-unaware Kalman",
                 "random_delay_lmv": "Random-delay LMV (ref. [9])"}


def step_figure1(cfg, inputs, outputs, wildcards) -> None:
    """P3-F1: errors of the proposed estimator and of each Kalman-type filter (prediction ``x̂(t|I_{t-1})``)
    on the true pattern, with the proposed estimator's guarantee levels along that pattern."""
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    res = json.loads(Path(inputs.json).read_text())
    levels = data["levels"]
    names = list(res["filters"])
    cols = [("proposed", "Proposed estimator", data["proposed_errors"], "C0")]
    cols += [(n, FILTER_TITLES.get(n, n), data[f"{n}_prediction_errors"], "C3") for n in names]
    fig, axes = plt.subplots(4, len(cols), figsize=(2.6 * len(cols), 7.0), sharex=True, squeeze=False)
    for c, (name, title, errs, color) in enumerate(cols):
        verdict = "" if name == "proposed" else f"\nexact worst case {res['filters'][name]['prediction']['verdict']}"
        trajectory_panel(axes[:, c], errs, levels, title + verdict, state_labels=STATE_LABELS_REACTOR,
                         color=color, ylabels=(c == 0))
        worst = data["proposed_bounds"] if name == "proposed" else data[f"{name}_prediction_worst"]
        worst_case_lines(axes[:, c], worst, "exact worst case")
    # one scale per state across the estimators: the same quantity, compared
    for i in range(axes.shape[0]):
        lim = 1.15 * max(max(np.max(levels), np.max((data["proposed_bounds"] if n == "proposed" else
                                                     data[f"{n}_prediction_worst"])[:, i]),
                             np.max(np.abs(e[:, :, i]))) for n, _, e, _ in cols)
        for ax in axes[i]:
            ax.set_ylim(-lim, lim)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    labels = ["proposed estimator: error" if lab == "estimation error" else lab for lab in labels]
    if len(cols) > 1:  # the Kalman-type filters' traces, drawn in their own colour
        handles.insert(1, plt.Line2D([], [], color=cols[1][3], alpha=0.6, lw=1.0))
        labels.insert(1, "Kalman-type filter: error")
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(f"Batch reactor, true delay pattern {res['true_pattern']}, {res['runs']} runs "
                 f"(truncated normal, bound = {res['sigmas']:g} sigma): errors and the guarantees "
                 rf"$\mu_{{2,k}}$ ($\mu_1$ = {res['mu1']:.4f})")
    save_figure(fig, outputs.pdf, outputs.png)


def step_figure2(cfg, inputs, outputs, wildcards) -> None:
    """P3-F2: proposed estimator (time-varying levels) vs P1's prefix-based estimator (one level), same draws."""
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    pattern = cfg["acc"]["true_pattern"]
    fig, axes = plt.subplots(3, 2, figsize=(7.0, 6.0), sharex=True)
    for col, name, title in ((0, "proposed", "Proposed estimator (levels per event prefix)"),
                             (1, "prefix", "Prefix-based estimator of P1 (one level $M_2$)")):
        errs = data[f"{name}_errors"]
        trajectory_panel(axes[:, col], errs, data[f"{name}_levels"],
                         f"{title}\nmax level {float(data[f'{name}_mu2']):.4f}", state_labels=STATE_LABELS_ACC,
                         ylabels=(col == 0))
        worst = data[f"{name}_bounds"]
        worst_case_lines(axes[:, col], worst, "certified worst case")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(f"ACC, true pattern {pattern} (missing data at k = 1), {data['proposed_errors'].shape[0]} runs, "
                 rf"$\mu_1$ = {float(data['mu1']):g}")
    save_figure(fig, outputs.pdf, outputs.png)


STEPS = {"figure1": step_figure1, "figure2": step_figure2}
