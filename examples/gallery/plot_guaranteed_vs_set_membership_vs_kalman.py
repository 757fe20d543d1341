"""
Guaranteed vs set-membership vs Kalman on your plant
====================================================

Three estimator families on the same plant, the same packet trace and the same noise: the guaranteed
(equalized-recovery) estimator designed for a loss budget, the set-membership zonotope estimator (no language),
and a time-stamped Kalman filter, whose exact worst case :func:`eqrec.exact_bound` computes on the run's arrivals.
Replace ``plant`` by your own :class:`eqrec.AffineSystem` (or ``eqrec.load_system("my_plant.yaml")``) to compare
them on yours; ``eqrec compare`` does the same from the command line, over many runs.
"""

import matplotlib.pyplot as plt
import numpy as np

import eqrec
from eqrec.arrivals.draws import bernoulli_trace
from eqrec.estimators.kalman import TimestampedKalman
from eqrec.simulate.loop import closed_loop
from eqrec.systems.noise import GaussianDesign

plant = eqrec.batch_reactor()
T, loss, steps = 5, 0.15, 150

# %%
# The guaranteed design: at most m of T measurements lost per block, m from the loss rate.
m = eqrec.loss_coverage(max_delay=0, horizon=T, loss=loss, coverage=0.95)
free = eqrec.design_delay_global(plant, eqrec.delay_classes(max_delay=0, horizon=T, max_lost=m))
mu1 = free.mu1
print(f"m = {m} lost per block of {T}; mu1 = {mu1:.4f}, largest level {free.design.mu2:.4f}")

# %%
# One trace, one noise draw, three estimators; the Kalman filter is designed with a bound = 5 standard deviations.
rng = np.random.default_rng(11)
trace = bernoulli_trace(rng, steps, loss)
w = rng.uniform(-1, 1, (steps, plant.nw)) * plant.eta_w
v = rng.uniform(-1, 1, (steps, plant.nv)) * plant.eta_v
x0, xi0 = np.zeros(plant.n), rng.uniform(-mu1, mu1, plant.n)
estimators = {
    "guaranteed (strict=False)": free.design.estimator(strict=False),
    "set-membership (zonotope)": eqrec.ZonotopeEstimator(plant, x0_radius=mu1),
    "Kalman (time-stamped), exact worst case": eqrec.exact_bound(
        TimestampedKalman(plant, GaussianDesign.from_box(plant, mu1)), plant, mu1, steps=steps),
}
runs = {name: closed_loop(plant, est, trace, x0, xi0, w, v) for name, est in estimators.items()}
for name, run in runs.items():
    err = np.abs(run.error).max(axis=1)[1:]
    rms = np.sqrt(np.mean(run.error[1:] ** 2))
    print(f"{name:42s} rms error {rms:.4f}  max error {err.max():.4f}  median bound {np.median(run.bound):.4f}"
          f"  error <= bound at every step: {bool(np.all(err <= run.bound))}")

# %%
# The bounds side by side (dots: the errors).
fig, ax = plt.subplots(figsize=(7, 4))
for (name, run), colour in zip(runs.items(), ("C0", "C1", "C2")):
    ax.step(np.arange(1, steps + 1), run.bound, where="post", color=colour, label=name)
    ax.plot(np.arange(1, steps + 1), np.abs(run.error).max(axis=1)[1:], ".", ms=2, color=colour)
ax.set_yscale("log")
ax.set_xlabel("step")
ax.set_ylabel(r"bound and $\|x - \hat x\|_\infty$")
ax.legend(fontsize=8)
fig.tight_layout()
