"""P2 figures: Figs. 1, 2, 3a and 3b of the augmented paper (steps ``figure_trajectories``,
``figure_heatmap``, ``figure_realaxis``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from eqrec.studies.harness import save_figure
from eqrec.studies.plotting import paper_style, pyplot, trajectory_panel


def _levels(T: int, M1: float, mu2: float) -> np.ndarray:
    lev = np.full(T + 1, mu2)
    lev[0] = lev[-1] = M1
    return lev


def step_figure_trajectories(cfg, inputs, outputs, wildcards) -> None:
    """P2-F1 / P2-F2: augmented (left) vs time-based (right), same draws, certified guarantee bars.

    For F2 a third column shows the 1-based-reading design run on the true data.
    """
    fig = wildcards["fig"]
    paper_style()
    plt = pyplot()
    d = json.loads(Path(inputs.designs).read_text())[fig]
    sim = np.load(inputs.simulation)
    M1 = float(cfg["mu1"])
    cols = [("augmented_free", f"augmented (IPOPT), $\\mu_2$ = {d['augmented_free']['certified_mu2']:.4g}",
             d["augmented_free"]["certified_mu2"], "C0"),
            ("time", f"time-based, $\\mu_2$ = {d['time']['certified_mu2']:.4g}", d["time"]["certified_mu2"], "C1")]
    if fig == "f2" and "f2/one_based" in sim.files:
        c = d["one_based"]["certified_on_true_words"][d["worst_case_word"]]
        cols.append(("one_based", f"1-based reading ({d['one_based']['word']}) on true data,\ncertified {c:.4g}",
                     c, "C3"))
    errs0 = sim[f"{fig}/time"]
    T = errs0.shape[1] - 1
    f, axes = plt.subplots(3, len(cols), figsize=(3.3 * len(cols), 6.0), sharex=True, squeeze=False,
                           layout="constrained")
    for j, (name, title, mu2, color) in enumerate(cols):
        trajectory_panel(axes[:, j], sim[f"{fig}/{name}"], _levels(T, M1, mu2), title, color=color,
                         ylabels=(j == 0))
    handles, labels = axes[0, 0].get_legend_handles_labels()
    f.legend(handles, ["estimation error", "certified guarantee"], loc="outside lower center", ncol=2)
    f.suptitle(f"{'no missing data' if fig == 'f1' else 'language ' + str(d['language'])}: "
               f"{errs0.shape[0]} runs, same draws for every estimator")
    save_figure(f, outputs.pdf, outputs.png)


def step_figure_heatmap(cfg, inputs, outputs, wildcards) -> None:
    """P2-F3a: optimal μ2 over the eigenvalue pair ``r e^{±jθ}`` per variant; failures marked."""
    paper_style()
    plt = pyplot()
    df = pd.read_csv(inputs.csv)
    variants = list(dict.fromkeys(df["variant"]))
    f, axes = plt.subplots(1, len(variants), figsize=(3.9 * len(variants), 3.2), squeeze=False,
                           layout="constrained")
    for ax, var in zip(axes[0], variants):
        g = df[df["variant"] == var]
        x = g["r"] * np.cos(g["theta"])
        y = g["r"] * np.sin(g["theta"])
        ok = g["status"] == "optimal"
        mu = g["mu2"].where(ok)
        vmin, vmax = np.nanmin(mu), np.nanmax(mu)
        if vmax - vmin < 1e-6:
            vmin, vmax = vmin - 0.05, vmax + 0.05
        sc = ax.scatter(x[ok], y[ok], c=mu[ok], s=9, marker="s", cmap="viridis", vmin=vmin, vmax=vmax)
        inf = g["status"] == "infeasible"
        ax.scatter(x[inf], y[inf], s=9, marker="s", color="0.8", label="LP infeasible")
        fl = g["status"] == "placement_failed"
        ax.scatter(x[fl], y[fl], s=25, marker="x", color="red", label="placement failed")
        ax.set_aspect("equal")
        ax.set_xlabel(r"Re $\lambda$")
        if ax is axes[0][0]:
            ax.set_ylabel(r"Im $\lambda$")
        ax.set_title(f"{var} (word {g['word'].iloc[0]})")
        f.colorbar(sc, ax=ax, label=r"optimal $\mu_2$", shrink=0.7, location="bottom")
    handles, labels = [], []
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    f.legend(handles, labels, loc="outside upper center", ncol=len(labels))
    save_figure(f, outputs.pdf, outputs.png)


def step_figure_realaxis(cfg, inputs, outputs, wildcards) -> None:
    """P2-F3b: optimal μ2 against a real double eigenvalue λ (third eigenvalue at 0)."""
    paper_style()
    plt = pyplot()
    df = pd.read_csv(inputs.csv)
    f, ax = plt.subplots(figsize=(5, 2.8))
    for i, (var, g) in enumerate(df.groupby("variant", sort=False)):
        g = g.sort_values("lam")
        mu = np.where(g["status"] == "optimal", g["mu2"], np.nan)
        ax.plot(g["lam"], mu, marker=".", ms=2, color=f"C{i}", label=f"{var} ({g['word'].iloc[0]})")
        inf = g["status"] == "infeasible"
        if inf.any():
            ax.plot(g["lam"][inf], np.full(inf.sum(), np.nanmax(df["mu2"].replace(np.inf, np.nan)) * 1.05), "|",
                    color=f"C{i}", label=f"{var}: LP infeasible")
        fl = g["status"] == "placement_failed"
        ax.plot(g["lam"][fl], np.full(fl.sum(), 1.0), "x", color="red",
                label="placement failed" if i == 0 else None)
    ax.set_xlabel(r"real eigenvalue $\lambda$ (double), third at 0")
    ax.set_ylabel(r"optimal $\mu_2$")
    ax.legend(fontsize=6)
    save_figure(f, outputs.pdf, outputs.png)
