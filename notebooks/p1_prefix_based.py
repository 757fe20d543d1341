# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # P1 — Prefix-based bounded-error estimation with intermittent observations
#
# Rutledge, Yong, Ozay (ACC 2019). This notebook only **reads** the pipeline's
# results under `results/p1/` (run `snakemake --cores 2` first); it recomputes nothing,
# and every number in its text is read from those files.
#
# The ACC model (Section VI) is discretised from the Table I constants.

# %%
import json
from pathlib import Path

import numpy as np
import pandas as pd
from IPython.display import Image, Markdown, display

from eqrec.studies.notebooks.text import claims_markdown

ROOT = Path.cwd() if (Path.cwd() / "results").exists() else Path.cwd().parent
RES = ROOT / "results" / "p1"

model = json.loads((RES / "model.json").read_text())
designs = json.loads((RES / "designs.json").read_text())
ext = json.loads((RES / "extensions.json").read_text())
claims = pd.read_csv(ROOT / "results" / "claims.csv")
our = claims.set_index("id")["our_value"]
display(Markdown(f"""The missing-data language is $L_1 = \\{{{", ".join(designs["language"])}\\}}$, $M_1 = {designs["M1"]:g}$,
$T = {len(designs["language"][0])}$."""))

# %% [markdown]
# ## P1-T1: the model from Table I

# %%
for key in ("A", "B", "f", "E"):
    print(key, "=\n", np.array(model[key]))

# %% [markdown]
# ## P1-M2: optimal intermediate levels
#
# Each optimum is certified from the recovered gains alone (exact worst case
# over the noise box, per word) and compared across solvers. Solve times are
# not shown: they vary from run to run and are kept in `results/timings/`.

# %%
rows = []
for method, d in designs["designs"].items():
    for solver, s in d["solvers"].items():
        rows.append({"estimator": f"{method}-based", "solver": solver, "optimal M2": s["mu2"],
                     "certified M2": s["certified_mu2"], "certified end level": s["certified_terminal"],
                     "iterations": s["iterations"]})
pd.DataFrame(rows).set_index(["estimator", "solver"]).round(6)

# %% [markdown]
# Readings of the paper other than ours (to explain differences):

# %%
pd.DataFrame(designs["variants"]).T

# %% [markdown]
# ## P1-F1: error trajectories with guarantee bars

# %%
prefix, time = designs["designs"]["prefix"], designs["designs"]["time"]
display(Markdown(f"""
The prefix-based estimator (left) and the time-based estimator designed for the worst-case word
{designs["worst_case_word"]} (right), both for $M_1 = {designs["M1"]:g}$, run on the same random words of the
language and the same noise. The bars are the certified guarantees: $M_1$ at both ends, $M_2^*$ in between,
{prefix["certified_mu2"]:.4g} for the prefix-based estimator against {time["certified_mu2"]:.4g} for the
time-based one, on one scale per state, so the bars compare. The errors of the prefix-based runs are
{our["P1-F1:prefix-inside"]} the bars, those of the time-based runs {our["P1-F1:time-inside"]} (rows
`P1-F1` of the claims table).
"""))
display(Image(filename=str(RES / "fig1_trajectories.png"), width=800))

# %% [markdown]
# ## P1-EXT: $M_2^*(M_1)$, smallest $M_1$, finite-length language, minimum $T$

# %%
display(Markdown(f"""
Left: $M_2^*$ as a function of $M_1$ for both estimators; below its smallest feasible $M_1$
({ext["min_M1"]["prefix"]:.4f} prefix-based, {ext["min_M1"]["time"]:.4f} time-based) an estimator has no design.
Right: the minimum recovery time $T$ per level, for the words extended by available measurements.
"""))
display(Image(filename=str(RES / "fig_ext_M2_vs_M1.png"), width=800))
display(pd.DataFrame({"smallest feasible M1": ext["min_M1"]})
        .rename(index={"prefix": "prefix-based", "time": "time-based"}).round(6))
display(pd.DataFrame([{"finite-length language": ", ".join(ext["finite_language"]["words"]),
                       "optimal M2": ext["finite_language"]["mu2"]}]).round(6))
min_T = pd.DataFrame(ext["min_T"])
min_T["T"] = [f"{int(t)}" if pd.notna(t) else "none up to the largest T tried" for t in min_T["T"]]
min_T.rename(columns={"M1": "recovery level M1", "T": "minimum recovery time T"})

# %% [markdown]
# ## Claims: published numbers next to ours
#
# The solve-time rows (P1-TIME, `[s]`) name `results/timings/claims.csv`, where the times of the run are.

# %%
display(Markdown(claims_markdown(claims, "P1")))
