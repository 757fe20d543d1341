"""
Three tanks with one sensor
===========================

Three tanks in a row, water pumped into the first, only the level of the last one measured, and its packets
delayed by up to two steps.  The guaranteed estimator recovers the two unmeasured levels from the delayed
measurements of the third; the bound it returns at each step holds for every state at once.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.linalg import expm

import eqrec
from eqrec.arrivals.draws import delay_trace
from eqrec.simulate.loop import closed_loop

# %%
# Linearised levels h1, h2, h3 (outflow proportional to the level difference), sampled every 2 s.
a, Ts = 0.15, 2.0
Ac = np.array([[-a, a, 0], [a, -2 * a, a], [0, a, -2 * a]])
Bc = np.array([[0.1], [0], [0]])
big = expm(np.block([[Ac, Bc], [np.zeros((1, 4))]]) * Ts)
plant = eqrec.AffineSystem(A=big[:3, :3], B=big[:3, 3:], C=[[0, 0, 1]], E=np.eye(3), eta_w=0.002, eta_v=0.005)
print("eigenvalues of A:", np.round(np.linalg.eigvals(plant.A), 3))

# %%
# Every delay up to 2 over blocks of T = 6 measurements (729 words, a handful of classes), mu1 free.
free = eqrec.design_delay_global(plant, eqrec.delay_classes(max_delay=2, horizon=6))
print(f"mu1 = {free.mu1:.4f}, largest level inside a block = {free.design.mu2:.4f}")

# %%
# 300 steps with delays 0, 1, 2 drawn with probabilities 0.6, 0.3, 0.1; a sinusoidal pump input.
rng = np.random.default_rng(3)
steps = 300
trace = delay_trace(rng, steps, [0.6, 0.3, 0.1])
w = rng.uniform(-plant.eta_w, plant.eta_w, (steps, 3))
v = rng.uniform(-plant.eta_v, plant.eta_v, (steps, 1))
x0, xi0 = np.array([1.0, 0.8, 0.6]), rng.uniform(-free.mu1, free.mu1, 3)
run = closed_loop(plant, free.design.estimator(), trace, x0, xi0, w, v,
                  u_at=lambda k, xhat: np.array([0.5 + 0.5 * np.sin(0.05 * k)]))
errors = np.abs(run.error).max(axis=1)[1:]
print(f"largest error / bound: {np.max(errors / run.bound):.3f}; mean bound {run.bound.mean():.4f}")
assert np.all(errors <= run.bound)

# %%
# The unmeasured first tank and the error against the bound.
t = np.arange(steps + 1) * Ts
fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
ax1.plot(t, run.x[:, 0], label="level h1 (not measured)")
ax1.plot(t, run.xhat[:, 0], "--", label="estimate")
ax1.set_ylabel("level")
ax1.legend()
ax2.plot(t[1:], errors, label=r"$\|x - \hat x\|_\infty$")
ax2.step(t[1:], run.bound, where="post", label="bound")
ax2.set_xlabel("time [s]")
ax2.legend()
fig.tight_layout()
