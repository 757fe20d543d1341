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
# # P2 — State-augmented bounded-error estimator with missing data
#
# Hassaan, Shen, Yong (ACC 2019). This notebook only **reads** the pipeline's results
# under `results/p2/` (run `snakemake --cores 2 p2` first); it recomputes nothing, and every number in its
# text is read from those files.
#
# Key fact used throughout: for fixed $L$ and $s_0$ the augmented gains $(M, \nu)$ and the
# time-based gains $(F, u_0)$ are in bijection (`eqrec.design.augmented.runtime`), so the augmented estimator
# can never beat the time-based optimum on the same word, and its optimum does not depend on $L$ or $s_0$.

# %%
import json
from pathlib import Path

import numpy as np
import pandas as pd
from IPython.display import Image, Markdown, display

from eqrec.studies.notebooks.text import claims_markdown

ROOT = Path.cwd() if (Path.cwd() / "results").exists() else Path.cwd().parent
RES = ROOT / "results" / "p2"

values = json.loads((RES / "values.json").read_text())
designs = json.loads((RES / "designs.json").read_text())
checks = json.loads((RES / "checks.json").read_text())
heat = pd.read_csv(RES / "heatmap.csv")
real = pd.read_csv(RES / "realaxis.csv")
claims = pd.read_csv(ROOT / "results" / "claims.csv")
paper = claims.set_index("id")["paper_value"]

#: the readings of the paper's text compared here (eqrec.studies.p2.readings), in words
READINGS = {"theorem2": "Theorem 2 as stated", "one_based": "word read with 1-based times",
            "leak": "constant L kept at missing steps", "masked_gain": "Appendix, gain masked when missing"}
pd.set_option("display.precision", 4)
pd.set_option("display.max_colwidth", None)

# %% [markdown]
# ## P2-F1 and P2-F2: optimal $\mu_2$ (certified from the converted time-based gains)
#
# Solve times are not shown here (they vary from run to run): see `results/timings/`.

# %%
f1, f2 = designs["f1"], designs["f2"]
display(Markdown(f"""
Without missing data (Fig. 1) the time-based design reaches {f1["time"]["certified_mu2"]:.4g} and the augmented
design (IPOPT, $L$ and $s_0$ free) {f1["augmented_free"]["certified_mu2"]:.4g}; the paper reports
{paper["P2-F1:mu2-augmented"]}. On the language of Fig. 2 (worst-case word {f2["worst_case_word"]}) the augmented
design reaches {f2["augmented_free"]["certified_mu2"]:.4g}, the time-based optimum being
{f2["time"]["certified_mu2"]:.4g}; the paper reports {paper["P2-F2:mu2-augmented"]}.
"""))
rows = []
for fig in ("f1", "f2"):
    d = designs[fig]
    rows.append({"figure": f"Fig. {fig[1]}", "worst-case word": d["worst_case_word"],
                 "paper": float(paper[f"P2-{fig.upper()}:mu2-augmented"]),
                 "time-based": d["time"]["certified_mu2"],
                 "augmented LP (pole placement)": d["augmented_lp"]["certified_mu2"],
                 "augmented IPOPT (L, s₀ free)": d["augmented_free"]["certified_mu2"],
                 "IPOPT iterations": d["augmented_free"]["iterations"]})
pd.DataFrame(rows).set_index("figure").round(4)

# %% [markdown]
# Fig. 1: both estimators on the same noise draws; the bars are the certified guarantees, dashed the paper's
# $\mu_2$ (rows `P2-F1` of the claims table compare them).

# %%
display(Image(filename=str(RES / "f1_trajectories.png"), width=800))

# %%
ob = designs["f2"]["one_based"]
display(Markdown(f"""
Fig. 2: on the word {f2["worst_case_word"]} no estimator guarantees less than the time-based optimum
{f2["time"]["certified_mu2"]:.4g}, {"above" if f2["time"]["certified_mu2"] > float(paper["P2-F2:mu2-augmented"])
else "not above"} the paper's {paper["P2-F2:mu2-augmented"]} (dashed). The third column is the design for the word read with 1-based times (word {ob["word"]}, its optimum
{ob["time_mu2"]:.4g}) run on the true data.
"""))
display(Image(filename=str(RES / "f2_trajectories.png"), width=800))

# %% [markdown]
# Other readings of the text for Fig. 2 and Fig. 1: each design's optimal $\mu_2$, certified.

# %%
leak = {k: v.get("certified_mu2", v.get("status", "")) for k, v in designs["f2"]["leak"].items()}
pd.DataFrame([
    {"figure": "Fig. 2", "reading": "word read with 1-based times (110011), augmented",
     "optimal μ₂": ob["augmented_free"]["certified_mu2"], "note": "its design word"},
    {"figure": "Fig. 2", "reading": "word read with 1-based times (110011), time-based",
     "optimal μ₂": ob["time_mu2"], "note": "its design word"},
    *({"figure": "Fig. 2", "reading": f"the 1-based design's gains run on the true word {w}",
       "optimal μ₂": v, "note": "certified on the true word"} for w, v in ob["certified_on_true_words"].items()),
    *({"figure": "Fig. 2", "reading": f"constant L kept at missing steps ({k.replace('leak_', '')})",
       "optimal μ₂": v if isinstance(v, float) else np.nan, "note": v if isinstance(v, str) else ""}
      for k, v in leak.items()),
    {"figure": "Fig. 1", "reading": "strictly causal measurement injection", "optimal μ₂":
     designs["f1"]["strictly_causal_mu2"], "note": ""},
    {"figure": "Fig. 1", "reading": "process noise W = I", "optimal μ₂": designs["f1"]["process_noise_identity_mu2"],
     "note": ""},
]).round(4)

# %% [markdown]
# ## P2-F3a / F3b: dependence on the eigenvalues of $A - LC$
#
# Fig. 3a sweeps $L$ by pole placement (eigenvalues 0 and $r e^{\pm j\theta}$), one map per reading of the
# text; the fifth panel shows what the Appendix reading's gains guarantee when they run as the estimator
# (logarithmic scale).

# %%
var = values["f3a_mu2_region"]["evidence"]["variants"]
display(Markdown("Smallest and largest optimal $\\mu_2$ of each map, and its points without an optimum:\n\n"
                 + "\n".join(f"* {READINGS[k]}: {v['min']:.4g} to {v['max']:.4g}; {v['points'] - v['optimal']} of "
                              f"{v['points']} points without an optimum" for k, v in var.items())
                 + f"\n\nThe paper's region is at {paper['P2-F3a:mu2-region']}."))
display(Image(filename=str(RES / "f3a_heatmap.png"), width=800))

# %%
summary = (heat.assign(reading=heat["variant"].map(READINGS))
           .groupby(["reading", "status"])
           .agg(points=("mu2", "size"), **{"smallest μ₂": ("mu2", "min"), "largest μ₂": ("mu2", "max")}))
summary.round(4)

# %%
iv = values["f3b_interval"]["evidence"]["variants"]
no_solution = real[real["status"] != "optimal"].assign(reading=lambda d: d["variant"].map(READINGS))
display(Markdown(f"""
Fig. 3b: a real double eigenvalue $\\lambda$ (third at 0). The Appendix reading is at its minimum
{iv["masked_gain"]["min_mu2"]:.4g} on the interval {np.round(values["f3b_interval_masked_gain"]["value"], 4).tolist()}
of the grid (the paper: {paper["P2-F3b:interval-masked-gain"]}). """ + "".join(
    f"Reading \"{r}\": no solution for $\\lambda$ from {g['lam'].min():.2f} to {g['lam'].max():.2f} "
    "(strip below the plot). " for r, g in no_solution.groupby("reading"))))
display(Image(filename=str(RES / "f3b_realaxis.png"), width=800))

# %%
(real.assign(reading=real["variant"].map(READINGS))
 .groupby(["reading", "status"])
 .agg(points=("mu2", "size"), **{"λ from": ("lam", "min"), "λ to": ("lam", "max"),
                                  "smallest μ₂": ("mu2", "min"), "largest μ₂": ("mu2", "max")})
 .round(4))

# %% [markdown]
# ## One reading for Figs. 2, 3a and 3b: the Appendix, gain masked at missing steps
# The Appendix's stacked matrices with $\Phi_k = A - LC$ at every step and the measurement gain zeroed at missing
# steps. Its design LP at the printed $L$ (Fig. 2), its region (Fig. 3a) and interval (Fig. 3b), and what its gains
# guarantee as the estimator that runs (certified from the gains alone, per LP solver: the optima are not unique;
# the best any optimum gives is an LP over the optima, `best_guarantee_among_optima`).

# %%
mg = values["f2_masked_gain_certified"]["evidence"]
region = values["f3a_mu2_region_masked_gain"]["evidence"]
rows = [{"quantity": "design LP optimum at the printed L (Fig. 2)", "ours": values["f2_mu2_masked_gain"]["value"],
         "paper": paper["P2-F2:mu2-masked-gain"]},
        {"quantity": "time-based optimum on the same word", "ours": mg["time_mu2"], "paper": ""},
        *({"quantity": f"its gains as run (constant L kept), the optimum {s} returns", "ours": b["hold"],
           "paper": ""} for s, b in mg["by_solver"].items()),
        *({"quantity": f"best any optimum guarantees as run ({rt}, {s})", "ours": v, "paper": ""}
          for rt, r in mg["among_optima"]["runtimes"].items() for s, v in r["by_solver"].items()),
        {"quantity": "Fig. 3a: grid points at the minimum", "ours": region["at_min"], "paper": ""},
        {"quantity": "Fig. 3a: largest r of the region at the minimum", "ours": region["at_min_r_max"], "paper": ""},
        {"quantity": "Fig. 3a: largest μ₂ of the map", "ours": region["max"], "paper": ""},
        {"quantity": "Fig. 3b interval, grid k/14", "ours": str(np.round(values["f3b_interval_masked_gain"]["value"], 4)),
         "paper": paper["P2-F3b:interval-masked-gain"]},
        {"quantity": "Fig. 3b interval, fine grid", "ours": str(np.round(values["f3b_interval_masked_gain_fine"]["value"],
                                                                        4)), "paper": ""}]
pd.DataFrame(rows).set_index("quantity").round(4)

# %% [markdown]
# Grid points of the heat map per reading and class (optimal + infeasible + solver failure + placement failure
# = points).

# %%
cls = ("optimal", "infeasible", "solver_failed", "placement_failed", "points", "second_solver_decided", "deadbeat")
(pd.DataFrame({READINGS.get(k, k): {c: v[c] for c in cls} for k, v in values["f3a_mu2_region"]["evidence"]["variants"].items()})
 .T.rename(columns={"solver_failed": "solver failure", "placement_failed": "placement failure",
                    "second_solver_decided": "decided by the second solver", "deadbeat": "r = 0 (nilpotent L)"}))

# %% [markdown]
# ## P2-S0 and P2-SOLVER
# The optimum does not depend on $s_0$ (rows: sampled $s_0$), and every solver reaches the same $\mu_2$ with
# different gains (the optimum is not unique).

# %%
s0 = pd.DataFrame(checks["s0"]["rows"])
s0["s₀"] = s0.pop("s0").map(lambda v: "[" + ", ".join(f"{x:g}" for x in v) + "]")
s0.set_index("s₀").rename(columns=lambda c: c.replace("_", " ").replace("mu2", "μ₂")).round(6)

# %%
solver = pd.DataFrame(checks["solver"]).T.apply(pd.to_numeric, errors="coerce")
solver["iterations"] = solver["iterations"].astype("Int64")
solver.rename(columns=lambda c: c.replace("_", " ").replace("mu2", "μ₂")).round(4)

# %% [markdown]
# ## Values compared with the paper (see `results/claims.csv` for the statuses)
# The wording of each row (and whether its explanation still holds) comes from `config/claims.yaml`:

# %%
display(Markdown(claims_markdown(claims, "P2", ("id", "quantity", "paper_value", "our_value", "status", "reason"))))
