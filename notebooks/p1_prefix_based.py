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
# results under `results/p1/` (run `snakemake --cores 2` first); it recomputes nothing.
#
# The ACC model (Section VI) is discretised from the Table I constants; the
# missing-data language is $L_1 = \{101111, 110111, 111011, 111101\}$ (one
# dropout in six steps), $M_1 = 1$, $T = 6$.

# %%
import json
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path.cwd() if (Path.cwd() / "results").exists() else Path.cwd().parent
RES = ROOT / "results" / "p1"

model = json.loads((RES / "model.json").read_text())
designs = json.loads((RES / "designs.json").read_text())
ext = json.loads((RES / "extensions.json").read_text())
claims = pd.read_csv(ROOT / "results" / "claims.csv")

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
from IPython.display import Image, display

display(Image(filename=str(RES / "fig1_trajectories.png")))

# %% [markdown]
# ## P1-EXT: $M_2^*(M_1)$, smallest $M_1$, finite-length language, minimum $T$

# %%
display(Image(filename=str(RES / "fig_ext_M2_vs_M1.png")))
display(pd.DataFrame({"smallest feasible M1": ext["min_M1"]})
        .rename(index={"prefix": "prefix-based", "time": "time-based"}).round(6))
display(pd.DataFrame([{"finite-length language": ", ".join(ext["finite_language"]["words"]),
                       "optimal M2": ext["finite_language"]["mu2"]}]).round(6))
min_T = pd.DataFrame(ext["min_T"])
min_T["T"] = [f"{int(t)}" if pd.notna(t) else "none up to T_max" for t in min_T["T"]]
min_T.rename(columns={"M1": "recovery level M1", "T": "minimum recovery time T"})

# %% [markdown]
# ## Claims: published numbers next to ours
#
# The solve-time rows (P1-TIME, `[s]`) name `results/timings/claims.csv`, where the times of the run are.

# %%
pd.set_option("display.max_colwidth", 200)
claims[claims["id"].str.startswith("P1")]
