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
# Reads `results/p4/` only (run `snakemake --cores 2` first); every number in its text is read from
# those files. One LMV innovation
# recursion for systems with multiplicative noises (`eqrec.lmv`) serves both
# compensation mechanisms; the hold-input filter is the augmented-state
# estimator of the paper's ref. [15], derived in `eqrec.lmv.model.hold_input_system`.
# Initial conditions (symbolic in the paper): $x(0) \sim N(0, I)$, $y_h(-1) = 0$.

# %%
import json
from pathlib import Path

import pandas as pd
from IPython.display import Image, Markdown, display

from eqrec.studies.notebooks.text import ascii_to_tex, claims_markdown

ROOT = Path.cwd() if (Path.cwd() / "results").exists() else Path.cwd().parent
RES = ROOT / "results" / "p4"
values = json.loads((RES / "values.json").read_text())
claims = pd.read_csv(ROOT / "results" / "claims.csv")
reason = claims.set_index("id")["reason"]
tr, order, b1, b2 = (values[k]["evidence"] for k in ("tracking", "ordering", "better_ex1", "better_ex2"))
N = order["N"]
EXAMPLE = {"ex1": "Example 1", "ex2": "Example 2"}

# %%
display(Markdown(f"""## P4-F1..F3: tracking ({EXAMPLE[tr["example"]]}, $\\bar\\eta = {tr["eta_bar"]:g}$, zero-input)

One realisation of {EXAMPLE[tr["example"]]} with arrival probability $\\bar\\eta = {tr["eta_bar"]:g}$: the true
states and their LMV estimates, first the filter $\\hat x(t|t)$ (Fig. 1), then the one-step predictor
$\\hat x(t|t-1)$ (Fig. 2) and the {N}-step smoother $\\hat x(t|t+{N})$ (Fig. 3), on the same realisation.
"""))
display(Image(filename=str(RES / "fig1_filter.png"), width=800))

# %%
display(Image(filename=str(RES / "fig2_predictor.png"), width=800))

# %%
display(Image(filename=str(RES / "fig3_smoother.png"), width=800))

# %%
display(Markdown(f"""## P4-F4: error variances, theory against Monte Carlo

The error variances $P(t|t-1)$, $P(t|t)$ and $P(t|t+{N})$ of the three estimators: the recursion's values
(lines) and those of {b1["runs"]:,} Monte Carlo runs (markers, with their 95 % band). Each estimator has its own
colour, line style and marker. The paper's ordering, smoother below filter below predictor, is checked at every
step: found "{values["ordering"]["value"]}".
"""))
display(Image(filename=str(RES / "fig4_variances.png"), width=800))
display(Markdown(ascii_to_tex(f'{values["ordering"]["value"]}: {reason["P4-F4:ordering"]}')))

# %%
eta, q = values["eta_trend"]["evidence"], values["q_trend"]["evidence"]
display(Markdown(f"""## P4-F5: steady-state variances against the arrival probability $\\bar\\eta$

Sweeping $\\bar\\eta$ from {eta["eta_lo"]:g} to {eta["eta_hi"]:g} ({eta["points"]} points, zero-input): the
steady-state variances are found "{values["eta_trend"]["value"]}" as more packets arrive.
"""))
display(Image(filename=str(RES / "fig5_eta.png"), width=800))

# %%
display(Markdown(f"""## P4-F6: steady filter variance over the multiplicative-noise variances $(Q_\\xi, Q_\\lambda)$

The steady filtering error variance of each state component over
${q["q_lo"]:g} \\le Q_\\xi, Q_\\lambda \\le {q["q_hi"]:g}$ (zero-input, $\\bar\\eta = {q["eta_bar"]:g}$), found
"{values["q_trend"]["value"]}" in both; the colour bar beside each surface reads its height.
"""))
display(Image(filename=str(RES / "fig6_q.png"), width=800))

# %%
th = b1["qlam_threshold"]
display(Markdown(f"""### Beyond the paper: where each compensation wins

On the same grid, the ratio $\\mathrm{{tr}}\\, P_{{\\mathrm{{hold}}}} / \\mathrm{{tr}}\\, P_{{\\mathrm{{zero}}}}$ of
the two mechanisms' steady filter variances, one logarithmic colour scale per example (blue: hold-input better,
red: zero-input better, black line: equal). In Example 1 hold-input is better in {100 * b1["frac_hold"]:.0f} % of
the grid points; at $Q_\\xi = {th["Qxi"]:g}$ the two are equal at $Q_\\lambda = {th["root"]:.4f}$, {th["below"]}
better below, {th["above"]} above. In Example 2 hold-input is better in {100 * b2["frac_hold"]:.0f} % of the grid
points, zero-input in {100 * b2["frac_zero"]:.0f} %. The star is the working point of Figs. 7 and 8.
"""))
display(Image(filename=str(RES / "regions.png"), width=800))

# %% [markdown]
# ## P4-F7, P4-F8: zero-input vs hold-input at the working point
#
# The filter error variances of the two compensation mechanisms, theory and Monte Carlo, for Example 1
# (Fig. 7) and Example 2 (Fig. 8); each title gives the theoretical verdict and the paper's.

# %%
display(Image(filename=str(RES / "fig7_compare_ex1.png"), width=800))

# %%
display(Image(filename=str(RES / "fig8_compare_ex2.png"), width=800))
for key, cid in (("better_ex1", "P4-F7:better-ex1"), ("better_ex2", "P4-F8:better-ex2")):
    display(Markdown(ascii_to_tex(f"**{cid}**: {values[key]['value']}. {reason[cid]}")))

# %% [markdown]
# ## P4-THEORY: theory against Monte Carlo, and the printed eq. (9)

# %%
mc = {ex: json.loads((RES / f"mc_{ex}.json").read_text()) for ex in ("ex1", "ex2")}
rows = [{"example": ex, "check": k, **{c: v[c] for c in ("passed", "max_abs_z", "z_crit", "max_rel_err_var")}}
        for ex, r in mc.items() for k, v in r["checks"].items()]
pd.DataFrame(rows).rename(columns={"max_abs_z": "largest |z|", "z_crit": "critical |z|",
                                   "max_rel_err_var": "largest relative error of the variance"})

# %%
display(Markdown(claims_markdown(claims, "P4")))
