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
# Initial conditions (symbolic in the paper): x(0) ~ N(0, I), y_h(−1) = 0.

# %%
import json
from pathlib import Path

import pandas as pd
from IPython.display import Image, display

ROOT = Path.cwd() if (Path.cwd() / "results").exists() else Path.cwd().parent
RES = ROOT / "results" / "p4"
values = json.loads((RES / "values.json").read_text())
claims = pd.read_csv(ROOT / "results" / "claims.csv")
pd.set_option("display.max_colwidth", 300)

# %% [markdown]
# ## P4-F1..F4: tracking and error variances (Example 1, η̄ = 0.8)

# %%
for name in ("fig1_filter", "fig2_predictor", "fig3_smoother", "fig4_variances"):
    display(Image(filename=str(RES / f"{name}.png")))
reason = claims.set_index("id")["reason"]
print(values["ordering"]["value"], "—", reason["P4-F4:ordering"])

# %% [markdown]
# ## P4-F5, P4-F6: sweeps over η̄ and (Q_ξ, Q_λ)

# %%
for name in ("fig5_eta", "fig6_q", "regions"):
    display(Image(filename=str(RES / f"{name}.png")))

# %% [markdown]
# ## P4-F7, P4-F8: zero-input vs hold-input

# %%
for name in ("fig7_compare_ex1", "fig8_compare_ex2"):
    display(Image(filename=str(RES / f"{name}.png")))
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
