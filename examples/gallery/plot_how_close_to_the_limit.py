"""
How close is my bound to the limit?
===================================

:func:`eqrec.information_limit` gives, per step and state, the smallest worst-case error *any* estimator can
guarantee on the arrivals of a run (one linear program per state and step).  Dividing an estimator's bound by it
says how much room is left: a ratio of 1 is the best possible.  Here the set-membership estimator and a guaranteed
design on the batch reactor, on one trace with 20 % loss and delays up to 2.
"""

import matplotlib.pyplot as plt
import numpy as np

import eqrec
from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.simulate.loop import closed_loop

plant = eqrec.batch_reactor()
steps, loss, D = 60, 0.2, 2

# %%
# A guaranteed design (delays up to 2, at most 2 lost per block of 5) and the set-membership estimator.
free = eqrec.design_delay_global(plant, eqrec.delay_classes(max_delay=D, horizon=5, max_lost=2))
mu1 = free.mu1
rng = np.random.default_rng(5)
trace = with_uniform_delays(rng, bernoulli_trace(rng, steps, loss), D)
w = rng.uniform(-1, 1, (steps, plant.nw)) * plant.eta_w
v = rng.uniform(-1, 1, (steps, plant.nv)) * plant.eta_v
x0, xi0 = np.zeros(plant.n), rng.uniform(-mu1, mu1, plant.n)
bounds = {}
for name, est in (("guaranteed (strict=False)", free.design.estimator(strict=False)),
                  ("set-membership (zonotope)", eqrec.ZonotopeEstimator(plant, x0_radius=mu1, max_delay=D))):
    run = closed_loop(plant, est, trace, x0, xi0, w, v)
    assert np.all(np.abs(run.error).max(axis=1)[1:] <= run.bound)
    bounds[name] = run.bound

# %%
# The limit: per step, the largest over the states of the smallest guaranteed error (the bounds above are on
# the largest state error, so they compare with the largest state limit).
limit = eqrec.information_limit(plant, trace, x0_radius=mu1).max(axis=1)  # row t: x(t+1)
print(f"limit at the last step: {limit[-1]:.4f}")
for name, b in bounds.items():
    ratio = b / limit  # both at x(t+1), t = 0..steps-1
    print(f"{name:28s} bound / limit: median {np.median(ratio):.3f}, p95 {np.percentile(ratio, 95):.3f}, "
          f"max {ratio.max():.3f}")

# %%
fig, ax = plt.subplots(figsize=(7, 3.5))
k = np.arange(1, steps + 1)
for name, b in bounds.items():
    ax.step(k, b, where="post", label=name)
ax.step(k, limit, where="post", color="k", ls="--", label="information limit (no estimator does better)")
ax.set_xlabel("step")
ax.set_ylabel(r"bound on $\|x - \hat x\|_\infty$")
ax.legend(fontsize=8)
fig.tight_layout()
