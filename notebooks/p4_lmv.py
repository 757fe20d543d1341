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
# # P4 — LMV estimation with zero-input vs hold-input compensation of packet dropouts
#
# Reads `results/p4/` only (run `snakemake --cores 2` first). One LMV innovation
# recursion for systems with multiplicative noises (`eqrec.lmv`) serves both
# compensation mechanisms; the hold-input filter is the augmented-state
# estimator of the paper's ref. [15], derived in `eqrec.lmv.model.hold_input_system`.
# Initial conditions (symbolic in the paper): $x(0) \sim N(0, I)$, $y_h(-1) = 0$.

# %%
import json
from pathlib import Path

import pandas as pd
from IPython.display import Image, display

ROOT = Path.cwd() if (Path.cwd() / "results").exists() else Path.cwd().parent
RES = ROOT / "results" / "p4"
values = json.loads((RES / "values.json").read_text())
claims = pd.read_csv(ROOT / "results" / "claims.csv")
reason = claims.set_index("id")["reason"]
pd.set_option("display.max_colwidth", 300)

# %% [markdown]
# ## P4-F1..F3: tracking (Example 1, $\bar\eta = 0.8$, zero-input)
#
# One realisation of Example 1 with arrival probability $\bar\eta = 0.8$: the true states and their LMV
# estimates, first the filter $\hat x(t|t)$ (Fig. 1), then the one-step predictor $\hat x(t|t-1)$ (Fig. 2) and
# the 2-step smoother $\hat x(t|t+2)$ (Fig. 3), on the same realisation.

# %%
display(Image(filename=str(RES / "fig1_filter.png")))

# %%
display(Image(filename=str(RES / "fig2_predictor.png")))

# %%
display(Image(filename=str(RES / "fig3_smoother.png")))

# %% [markdown]
# ## P4-F4: error variances, theory against Monte Carlo
#
# The error variances $P(t|t-1)$, $P(t|t)$ and $P(t|t+2)$ of the three estimators: the recursion's values
# (lines) and those of $10^4$ Monte Carlo runs (markers, with their 95 % band). Each estimator has its own
# colour, line style and marker. The paper's ordering, smoother below filter below predictor, holds at every
# step:

# %%
display(Image(filename=str(RES / "fig4_variances.png")))
print(values["ordering"]["value"], "—", reason["P4-F4:ordering"])

# %% [markdown]
# ## P4-F5: steady-state variances against the arrival probability $\bar\eta$
#
# Sweeping $\bar\eta$ from 0.1 to 1 (zero-input, $Q_\xi = Q_\lambda = 2$): every steady-state variance falls
# as more packets arrive, and the ordering of Fig. 4 holds over the whole range.

# %%
display(Image(filename=str(RES / "fig5_eta.png")))

# %% [markdown]
# ## P4-F6: steady filter variance over the multiplicative-noise variances $(Q_\xi, Q_\lambda)$
#
# The steady filtering error variance of each state component over $0 \le Q_\xi, Q_\lambda \le 2$
# (zero-input, $\bar\eta = 0.8$); the colour bar beside each surface reads its height.

# %%
display(Image(filename=str(RES / "fig6_q.png")))

# %% [markdown]
# ### Beyond the paper: where each compensation wins
#
# On the same grid, the ratio $\mathrm{tr}\, P_{\mathrm{hold}} / \mathrm{tr}\, P_{\mathrm{zero}}$ of the two
# mechanisms' steady filter variances, one logarithmic colour scale per example (blue: hold-input better, red:
# zero-input better, black line: equal). In Example 1 hold-input wins for $Q_\lambda$ below about 0.8; in
# Example 2 zero-input wins everywhere but at the smallest $Q_\xi$, by at most about 11 %. The star is the working point of Figs. 7 and 8.

# %%
display(Image(filename=str(RES / "regions.png")))

# %% [markdown]
# ## P4-F7, P4-F8: zero-input vs hold-input at the working point
#
# The filter error variances of the two compensation mechanisms, theory and Monte Carlo, for Example 1
# (Fig. 7) and Example 2 (Fig. 8); each title gives the theoretical verdict and the paper's.

# %%
display(Image(filename=str(RES / "fig7_compare_ex1.png")))

# %%
display(Image(filename=str(RES / "fig8_compare_ex2.png")))
for key, cid in (("better_ex1", "P4-F7:better-ex1"), ("better_ex2", "P4-F8:better-ex2")):
    print(key, "=", values[key]["value"], "\n  ", reason[cid], "\n")

# %% [markdown]
# ## P4-THEORY: theory against Monte Carlo, and the printed eq. (9)

# %%
mc = {ex: json.loads((RES / f"mc_{ex}.json").read_text()) for ex in ("ex1", "ex2")}
rows = [{"example": ex, "check": k, **{c: v[c] for c in ("passed", "max_abs_z", "z_crit", "max_rel_err_var")}}
        for ex, r in mc.items() for k, v in r["checks"].items()]
pd.DataFrame(rows)

# %%
claims[claims["id"].str.startswith("P4")]
