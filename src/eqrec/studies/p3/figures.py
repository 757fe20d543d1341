"""P3 figures: Fig. 1 (batch reactor, proposed vs Kalman-type filters), Fig. 2 (ACC, proposed vs P1
prefix-based) and the implementation-strategy figure (P3-IMPL, long runs of :mod:`eqrec.studies.p3.strategy`).

Steps ``figure1`` and ``figure2``: errors per state with the per-time
guarantee levels ``μ2,k`` along the true pattern's path (clear bars), as in
the paper's figures; ``strategy_figure``: a window of each long run with its
per-time guarantees.  Drawing only: no design is computed here.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from eqrec.studies.pipeline.outputs import save_figure
from eqrec.studies.plotting import STATE_LABELS_ACC, paper_style, pyplot, trajectory_panel, worst_case_lines

# the linearised batch reactor's states are dimensionless deviations (Sec. IV-A of the delayed-data paper)
STATE_LABELS_REACTOR = tuple(rf"$\tilde x_{i}$ [–]" for i in range(1, 5))
FILTER_TITLES = {"timestamped": "Time-stamped KF", "unaware": "Delay-unaware KF", "random_delay_lmv": "Random-delay LMV"}


def step_figure1(cfg, inputs, outputs, wildcards) -> None:
    """P3-F1: errors of the proposed estimator and of each Kalman-type filter (prediction ``x̂(t|I_{t-1})``)
    on the true pattern, with the proposed estimator's guarantee levels along that pattern (one y scale per row,
    tick labels on the first column only)."""
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    res = json.loads(Path(inputs.json).read_text())
    levels = data["levels"]
    def verdict(n: str) -> str:  # whether the runs of filter n stay inside the levels; its exact worst case's verdict
        inside = np.all(np.abs(data[f"{n}_prediction_errors"]) <= levels[None, :, None] + 1e-12)
        worst = res["filters"][n]["prediction"]["verdict"]
        return f"runs {'in' if inside else 'OUT'}, worst {'in' if worst == 'inside' else 'out'}"

    # (title, errors, exact worst case, colour) per column
    cols = [("Proposed estimator\nruns in, worst in", data["proposed_errors"], data["proposed_bounds"], "C0")]
    cols += [(f"{FILTER_TITLES.get(n, n)}\n{verdict(n)}", data[f"{n}_prediction_errors"], data[f"{n}_prediction_worst"],
              "C3") for n in res["filters"]]
    fig, axes = plt.subplots(4, len(cols), figsize=(min(7.0, 1.6 * len(cols) + 0.6), 7.4), sharex=True,
                             sharey="row", squeeze=False, layout="constrained")
    for c, (title, errs, worst, color) in enumerate(cols):
        trajectory_panel(axes[:, c], errs, levels, title, state_labels=STATE_LABELS_REACTOR, color=color,
                         ylabels=(c == 0))
        worst_case_lines(axes[:, c], worst, "exact worst case")
        for ax in axes[:, c]:
            ax.tick_params(labelsize=9)
    axes[-1, 0].xaxis.set_major_locator(pyplot().MaxNLocator(integer=True))
    # one scale per state across the estimators: the same quantity, compared
    for i in range(axes.shape[0]):
        lim = 1.1 * max(max(np.max(levels), np.max(worst[:, i]), np.max(np.abs(errs[:, :, i])))
                        for _, errs, worst, _ in cols)
        for ax in axes[i]:
            ax.set_ylim(-lim, lim)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    labels = ["proposed estimator: error" if lab == "estimation error" else lab for lab in labels]
    labels = ["guarantee $\\mu_{2,k}$ of the proposed estimator" if lab == "guarantee" else lab for lab in labels]
    if len(cols) > 1:  # the Kalman-type filters' traces, drawn in their own colour
        handles.insert(1, plt.Line2D([], [], color=cols[1][3], alpha=0.6, lw=1.0))
        labels.insert(1, "Kalman-type filter: error")
    fig.legend(handles, labels, loc="outside lower center", ncol=2)
    fig.suptitle(f"Batch reactor, true delay pattern {res['true_pattern']}, {res['runs']} runs (truncated normal, "
                 f"bound = {res['sigmas']:g} sigma):\nerrors and the guarantees $\\mu_{{2,k}}$ "
                 f"($\\mu_1$ = {res['mu1']:.4f}); the same scale in each row;\ntitles: runs and exact worst case in or "
                 "out of the guarantee; KF: Kalman filter, LMV: ref. [9]")
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
        trajectory_panel(axes[:, col], data[f"{name}_errors"], data[f"{name}_levels"],
                         f"{title}\nmax level {float(data[f'{name}_mu2']):.4f}", state_labels=STATE_LABELS_ACC,
                         ylabels=(col == 0))
        worst_case_lines(axes[:, col], data[f"{name}_bounds"], "certified worst case")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(f"ACC, true pattern {pattern} (missing data at k = 1), {data['proposed_errors'].shape[0]} runs, "
                 rf"$\mu_1$ = {float(data['mu1']):g}")
    save_figure(fig, outputs.pdf, outputs.png)


def step_strategy_figure(cfg, inputs, outputs, wildcards) -> None:
    """P3-IMPL figure: errors per state with the per-time guarantees over a window of each long run.

    Columns: periodic reuse on the batch reactor, on the ACC, and the
    switching scheme on the batch reactor (switching instants marked), each
    with its own ``μ1`` in its title.  The run with the first noise kind is
    shown; the reactor's states are named as in Fig. 1; no vertical grid, so
    that the vertical lines are the period boundaries and switching instants.
    """
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    kind = str(data["noise"][0])
    window = int(cfg["strategy"]["figure"]["window"])
    cols = (("reactor_periodic", "Batch reactor,\ngains reused every $T$ = {T}", list(STATE_LABELS_REACTOR),
             float(data["reactor_mu1"])),
            ("acc_periodic", "ACC,\ngains reused every $T$ = {T}", [lab.replace(" error", "\nerror") for lab in
                                                                  STATE_LABELS_ACC], float(data["acc_mu1"])),
            ("reactor_switching", "Batch reactor,\nswitching scheme", list(STATE_LABELS_REACTOR),
             float(data["switching_mu1"])))
    fig, axes = plt.subplots(4, 3, figsize=(7.0, 8.0), sharex="col", layout="constrained")
    # the error and the level of each run over the window
    shown = {label: (data[f"{label}_{kind}_error"][: window + 1], data[f"{label}_{kind}_level"][: window + 1])
             for label, *_ in cols}

    def limit(label: str, i: int) -> float:  # the y range of state i over the window of one run
        err, lev = shown[label]
        return 1.15 * max(float(lev.max()), float(np.abs(err[:, i]).max()))

    for c, (label, title, ylabels, mu1) in enumerate(cols):
        err, lev = shown[label]
        N, n, t = len(err) - 1, err.shape[1], np.arange(len(err))
        T, Ts = int(data[f"{label}_T"]), float(data[f"{label}_Ts"])
        # the vertical lines: (instants, style, legend entry)
        if label == "reactor_switching":
            # black dashed against orange dotted: told apart by colour-blind readers and in grey print
            marks = [(data[f"{label}_{kind}_switch"], {"color": "k", "ls": "--", "lw": 0.9}, "switch to recovery"),
                     (data[f"{label}_{kind}_revert"], {"color": "C1", "ls": ":", "lw": 1.5}, "back to performance")]
        else:
            marks = [(range(T, N + 1, T), {"color": "C4", "ls": "-", "lw": 0.7, "alpha": 0.8},
                      "period boundary (every $T$ steps)")]
        for i, ax in enumerate(axes[:, c]):
            if i >= n:
                ax.axis("off")
                continue
            ax.grid(False, axis="x")
            ax.fill_between(t, -lev, lev, step="mid", color="0.85", label="guarantee")
            ax.plot(t, err[:, i], "C0.-", ms=2.5, label="estimation error")
            for instants, style, name in marks:
                for j, s in enumerate(x for x in instants if x <= N):
                    ax.axvline(s, **style, label=None if j else name)
            ax.set_ylabel(ylabels[i])
            # one scale per reactor state across the two reactor columns (the same quantity)
            lim = (max(limit("reactor_periodic", i), limit("reactor_switching", i)) if label.startswith("reactor")
                   else limit(label, i))
            ax.set_ylim(-lim, lim)
            if i == 0:
                ax.set_title(f"{title.format(T=T)}\n$\\mu_1$ = {mu1:g}")
        last = axes[min(n, 4) - 1, c]
        last.set_xlabel(f"time step $t$\n($T_s$ = {Ts:g} s)")  # t, as in Figs. 1 and 2
        last.tick_params(labelbottom=True)
    # one legend under the figure (inside an axis it covers the bands)
    seen: dict[str, object] = {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    fig.legend(list(seen.values()), list(seen), loc="outside lower center", ncol=3)
    fig.suptitle(f"P3 implementation strategy: estimation errors and per-time guarantees\n({kind} noise, first "
                 f"{window} steps of each run)")
    save_figure(fig, outputs.pdf, outputs.png)


def step_scale_free_figure(cfg, inputs, outputs, wildcards) -> None:
    """P3 scale, ``μ1`` free: design time against the number of classes (log-log), one line per configuration
    of :func:`eqrec.studies.p3.free_table.step_scale_free`, from its values (``inputs.csv``) and measured times
    (``inputs.timings``).

    Each point of the two-worker line is labelled ``(τ̄, T)``, the language ``{0..τ̄}^T`` (largest delay, then
    horizon), below the line; the one block LP is run only up to
    :data:`eqrec.studies.p3.free_table.FREE_MONOLITHIC_MAX_CLASSES` classes (it takes minutes beyond): its legend
    entry names the largest size it ran (read from the values, so that this module imports no design code).
    """
    import pandas as pd
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    paper_style()
    plt = pyplot()
    keys = ["tau", "T", "config"]
    frame = pd.read_csv(inputs.csv).merge(pd.read_csv(inputs.timings), on=keys, validate="one_to_one")
    fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    ran = frame[(frame["config"] == "monolithic") & (frame["status"] == "optimal")]["classes"]
    styles = {"monolithic": (f"one block LP (1 core; run up to {int(ran.max()) if len(ran) else 0:,} classes only)",
                             "s--"),
              "blocks-1": ("per class, 1 worker", "o-"), "blocks-2": ("per class, 2 workers", "^-")}
    for config, (label, style) in styles.items():
        part = frame[(frame["config"] == config) & (frame["status"] == "optimal")].sort_values("classes")
        if len(part):
            ax.plot(part["classes"], part["wall_time"], style, label=label, ms=4)
    # labels under the lowest line; two sizes with close class counts: one label to the left, one to the right
    low = frame[frame["config"] == "blocks-2"].sort_values("classes").reset_index(drop=True)
    for k, r in low.iterrows():
        close_next = k + 1 < len(low) and low["classes"][k + 1] < 1.25 * r["classes"]
        close_prev = k > 0 and r["classes"] < 1.25 * low["classes"][k - 1]
        ha, dx = ("right", -1) if close_next else ("left", 1) if close_prev else ("center", 0)
        ax.annotate(f"({r['tau']}, {r['T']})", (r["classes"], r["wall_time"]), textcoords="offset points",
                    xytext=(dx, -11), ha=ha, va="center", fontsize=8)
    lo, hi = frame["classes"].min(), frame["classes"].max()
    ax.set(xscale="log", yscale="log", xlim=(lo / 1.2, hi * 1.4),
           ylim=(frame["wall_time"].min() / 2.5, frame["wall_time"].max() * 1.6),
           xticks=[300, 500, 1000, 2000, 4000], xlabel="number of classes (time, available data)",
           ylabel=r"design time, $\mu_1$ free [s]",
           title=r"Batch reactor, language $\{0..\bar\tau\}^T$, $\mu_1$ free: the class engine")
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    handles, labels = ax.get_legend_handles_labels()
    handles.append(plt.Line2D([], [], ls=""))
    labels.append(r"point labels: $(\bar\tau, T)$, largest delay and horizon")
    fig.legend(handles, labels, loc="outside lower center", ncol=2)
    save_figure(fig, outputs.pdf, outputs.png)
