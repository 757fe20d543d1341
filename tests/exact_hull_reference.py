"""Test-only reference: the exact interval hull of the states consistent with the data over the whole horizon, by a
direct dense LP with SciPy's HiGHS (independent of eqrec's LP layer and of the estimators)."""
import numpy as np
from scipy.optimize import linprog

from eqrec.simulate.loop import what_arrived


def simulate(system, trace, xhat0, xi0, w, v):
    """True states x(0..N), outputs y(0..N-1) and what arrives at each step (time-invariant plant, no input)."""
    N = trace.steps
    x = np.zeros((N + 1, system.n))
    x[0] = xhat0 + xi0
    y = np.zeros((N, system.p))
    for t in range(N):
        y[t] = system.C @ x[t] + system.eta_v * system.V @ v[t]
        x[t + 1] = system.A @ x[t] + system.eta_w * system.E @ w[t]
    sched = trace.schedule()
    return x, y, [what_arrived(sched[t], t, y) for t in range(N)]


def exact_hulls(system, trace, xhat0, x0_radius, y, t):
    """``(lower, upper)`` of x(t) (filtered) and of x(t+1) (predicted) given the packets delivered at steps <= t."""
    n, nw, nv = system.n, system.nw, system.nv
    delivered = [tau for tau in range(t + 1) if trace.delays[tau] >= 0 and tau + trace.delays[tau] <= t]
    Q = n + (t + 1) * nw + len(delivered) * nv
    # x(s) = xhat-propagation + X[s] zeta
    X = [np.concatenate([np.diag(np.broadcast_to(x0_radius, (n,)).astype(float)), np.zeros((n, Q - n))], axis=1)]
    xc = [np.asarray(xhat0, float)]
    for s in range(t + 1):
        Xn = system.A @ X[-1]
        Xn[:, n + s * nw:n + (s + 1) * nw] += system.eta_w * system.E
        X.append(Xn)
        xc.append(system.A @ xc[-1])
    rows, rhs = [], []
    for k, tau in enumerate(delivered):
        H = system.C @ X[tau]
        H[:, n + (t + 1) * nw + k * nv:n + (t + 1) * nw + (k + 1) * nv] += system.eta_v * system.V
        rows.append(H)
        rhs.append(y[tau] - system.C @ xc[tau])
    A_eq = np.concatenate(rows) if rows else None
    b_eq = np.concatenate(rhs) if rows else None
    out = []
    for s in (t, t + 1):
        lo, hi = np.empty(n), np.empty(n)
        for i in range(n):
            for sign, store in ((1.0, lo), (-1.0, hi)):
                res = linprog(sign * X[s][i], A_eq=A_eq, b_eq=b_eq, bounds=(-1, 1), method="highs")
                assert res.status == 0, res.message
                store[i] = xc[s][i] + sign * res.fun
        out.append((lo, hi))
    return out
