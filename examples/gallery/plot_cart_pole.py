"""
A cart-pole with one unstable mode
==================================

An inverted pendulum on a cart, linearised upright: one unstable mode, two sensors (cart position, pole angle)
whose packets reach the estimator late or not at all.  We design a guaranteed estimator for "each packet on
time, one step late, or lost, at most one lost in each block of four", close the loop through the estimate with
a state feedback, and check at every step that the error stays inside the bound the estimator returns:
:math:`\\|x(t) - \\hat x(t)\\|_\\infty \\le \\mu(t)`.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.linalg import expm, solve_discrete_are

import eqrec

# %%
# The plant: cart mass M, pole mass m, pole length l, sampled at Ts with a zero-order hold.
M, m, l, g, Ts = 1.0, 0.1, 0.5, 9.81, 0.02
Ac = np.array([[0, 1, 0, 0], [0, 0, -m * g / M, 0], [0, 0, 0, 1], [0, 0, (M + m) * g / (M * l), 0]])
Bc = np.array([[0], [1 / M], [0], [-1 / (M * l)]])
big = expm(np.block([[Ac, Bc], [np.zeros((1, 5))]]) * Ts)
A, B = big[:4, :4], big[:4, 4:]
print("continuous-time eigenvalues:", np.round(np.linalg.eigvals(Ac).real, 3))

plant = eqrec.AffineSystem(A=A, B=B, C=[[1, 0, 0, 0], [0, 0, 1, 0]],
                           E=np.diag([0, Ts, 0, Ts]) + np.diag([Ts ** 2 / 2, 0, Ts ** 2 / 2], 1),
                           eta_w=0.05, eta_v=0.002)

# %%
# The design: every delay up to 1 over blocks of T = 4 measurements, at most one lost per block, at the smallest
# feasible recovery level mu1 (the global optimum of the delayed-data paper's cost).
free = eqrec.design_delay_global(plant, eqrec.delay_classes(max_delay=1, horizon=4, max_lost=1))
design = free.design
print(f"mu1 = {free.mu1:.4f} (block starts), largest level inside a block = {design.mu2:.4f}")

# %%
# The run: a state feedback u = -K x̂ on the estimate; packets drawn at random inside the language.
Q, R = np.diag([1, 0.1, 10, 0.1]), np.array([[0.1]])
P = solve_discrete_are(A, B, Q, R)
K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)

rng = np.random.default_rng(1)
steps, T = 200, 4
est = design.estimator().reset(np.zeros(4))
x = np.array([0.0, 0.0, 0.05, 0.0])          # the pole starts 0.05 rad off; the estimate at 0
xhat, pending = np.zeros(4), []
xs, xhats, bounds = [x], [xhat], []
for k in range(steps):
    u = -K @ xhat
    y = plant.C @ x + rng.uniform(-plant.eta_v, plant.eta_v, 2)
    if k % T == 0:
        lost = rng.integers(T)            # at most one lost in this block
    late = rng.random() < 0.3 and k % T != T - 1
    arrived = [eqrec.Packet(t, yt) for t, yt in pending]
    pending = []
    if k % T != lost:
        if late:
            pending.append((k, y))
        else:
            arrived.append(eqrec.Packet(k, y))
    xhat, bound = est.step(arrived or None, u=u)
    x = A @ x + B @ u + plant.E @ rng.uniform(-plant.eta_w, plant.eta_w, 4)
    xs.append(x)
    xhats.append(xhat)
    bounds.append(bound)
xs, xhats, bounds = np.array(xs), np.array(xhats), np.array(bounds)
errors = np.abs(xs - xhats).max(axis=1)[1:]
print(f"largest error / bound over {steps} steps: {np.max(errors / bounds):.3f} (<= 1: guaranteed)")
assert np.all(errors <= bounds)

# %%
# The pole angle and its estimate, and the error against the bound.
t = np.arange(steps + 1) * Ts
fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
ax1.plot(t, xs[:, 2], label="pole angle θ")
ax1.plot(t, xhats[:, 2], "--", label="estimate θ̂")
ax1.set_ylabel("rad")
ax1.legend()
ax2.plot(t[1:], errors, label=r"$\|x - \hat x\|_\infty$")
ax2.step(t[1:], bounds, where="post", label="bound the estimator returned")
ax2.set_xlabel("time [s]")
ax2.legend()
fig.tight_layout()
