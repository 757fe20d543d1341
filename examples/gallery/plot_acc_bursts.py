"""
Adaptive cruise control with bursts of losses
=============================================

The papers' adaptive cruise control plant (:func:`eqrec.acc_system`) on a channel that loses packets in bursts
(a Gilbert–Elliott channel: 10 % loss, bursts of 2 on average).  The design covers "at most ``m`` lost in a block",
``m`` the smallest budget whose block probability reaches 95 % (:func:`eqrec.loss_coverage`).  A burst longer
than the budget leaves the language: with ``strict=False`` the estimator keeps running with its exact bound and
comes back to the designed levels when the data allow.
"""

import matplotlib.pyplot as plt
import numpy as np

import eqrec
from eqrec.arrivals.draws import gilbert_elliott_trace
from eqrec.simulate.loop import closed_loop

plant = eqrec.acc_system()
T, loss, burst = 8, 0.1, 2.0

# %%
# The loss budget per block, and the design for it (delays up to 1).
m = eqrec.loss_coverage(max_delay=1, horizon=T, loss=loss, burst=burst, coverage=0.95)
free = eqrec.design_delay_global(plant, eqrec.delay_classes(max_delay=1, horizon=T, max_lost=m))
print(f"budget m = {m} lost per block of {T}; mu1 = {free.mu1:.4f}, largest level = {free.design.mu2:.4f}")

# %%
# 240 steps of the bursty channel (p_bg = 1 / burst, p_gb so that the loss rate is 10 %).
rng = np.random.default_rng(7)
steps = 240
p_bg = 1 / burst
p_gb = loss * p_bg / (1 - loss)
trace = gilbert_elliott_trace(rng, steps, p_gb, p_bg)
w = rng.uniform(-1, 1, (steps, plant.nw)) * plant.eta_w
v = rng.uniform(-1, 1, (steps, plant.nv)) * plant.eta_v
est = free.design.estimator(strict=False)
inside = []
run = closed_loop(plant, est, trace, np.zeros(plant.n), rng.uniform(-free.mu1, free.mu1, plant.n), w, v,
                  after_step=lambda k: inside.append(est.in_design))
errors = np.abs(run.error).max(axis=1)[1:]
print(f"steps outside the design: {inside.count(False)} of {steps}; "
      f"largest error / bound: {np.max(errors / run.bound):.3f}")
assert np.all(errors <= run.bound)

# %%
# Error and bound; the shaded steps ran outside the designed language.
fig, ax = plt.subplots(figsize=(7, 3.5))
k = np.arange(1, steps + 1)
ax.plot(k, errors, label=r"$\|x - \hat x\|_\infty$")
ax.step(k, run.bound, where="post", label="exact bound (strict=False)")
ax.axhline(free.design.mu2, color="grey", ls=":", label="designed level")
ax.fill_between(k, 0, 1, where=~np.array(inside), transform=ax.get_xaxis_transform(), alpha=0.15,
                color="red", label="outside the language")
ax.set_xlabel("step")
ax.legend(fontsize=8)
fig.tight_layout()
