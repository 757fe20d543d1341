r"""The exact window: the best per-state linear estimate over the last ``L`` steps, given a zonotope at their start.

Given a zonotope :math:`\langle c_0, G_0\rangle \ni x(s_0)` and the plant over the window :math:`s_0..t`
(:math:`L = t + 1 - s_0` steps, eq. (3) of the prefix-based paper with the noise gains of its Remark 1),

.. math::
    x(s+1) = A(s)x(s) + d(s) + E(s)w(s), \quad y(s) = C(s)x(s) + V(s)v(s), \quad \|w\|_\infty, \|v\|_\infty \le 1

(``E``, ``V`` already scaled by :math:`\eta_w, \eta_v`; :math:`d = Bu + f` the known drive), every state of
:math:`x(t+1)` is linear in the unit uncertainty :math:`\zeta = (\varepsilon, w(s_0..t), v(\text{measured}))`:
:math:`x(t+1) = \hat x^{\rm pred} + X\zeta`, and the measured outputs are :math:`y = \hat y^{\rm pred} + H\zeta`
(the rows of :math:`H`: the measured times ``s``, each with its ``p`` outputs).  For state ``i`` and any row
:math:`\lambda_i` (one weight per measured output), the linear estimate

.. math::
    \hat x_i = \hat x^{\rm pred}_i + \lambda_i (y - \hat y^{\rm pred}) \quad\text{has error}\quad
    x_i(t+1) - \hat x_i = (X_i - \lambda_i H)\zeta, \qquad |x_i - \hat x_i| \le \|X_i - \lambda_i H\|_1 ,

for **every** :math:`\lambda_i`: the bound is exact for that estimate (the worst :math:`\zeta` is the sign of the
row) and valid whatever the weights.  The smallest such bound,
:math:`\min_\lambda \|X_i - \lambda H\|_1`, is the radius of information of :math:`x_i(t+1)` given the zonotope at
:math:`s_0` and the window's data (a least-absolute-deviations problem; LP duality), so the window's radius is
never below the information limit of the whole trace and reaches it when the zonotope is exact.

The weights: iteratively reweighted least squares
-------------------------------------------------
The ``L1`` problem is solved approximately by iteratively reweighted least squares (IRLS; e.g. Björck,
*Numerical Methods for Least Squares Problems*, SIAM 1996, §4.5): start from the weights
:math:`1/\|(X_{\cdot q}, H_{\cdot q})\|_2` of each column ``q`` (the reweighted gain of
:mod:`eqrec.estimators.zonotope`, here over the whole window), solve
:math:`\lambda_i = (X_i W H^\top)(H W H^\top)^{-1}`, then set :math:`W_q = 1/\max(|R_{iq}|, \delta\max_q|R_{iq}|)`
from the residual :math:`R_i = X_i - \lambda_i H` and solve again, ``iterations`` times; then again while the last
solve tightened the radius by more than a relative ``gain``, at most ``extra`` more times (the first windows
after a reset, from a box, need more solves than the later ones, from a filtered zonotope).  Every iterate is a
valid estimate; the one with the smallest radius is kept (so more iterations never loosen the bound).  The
weights depend on the arrivals and the zonotope only, never on the measured values, so the estimate is linear in
the data given the zonotope.  The relative floor :math:`\delta` of the residuals bounds the ratio of the weights
(``1/δ``) and so the conditioning of each weighted least-squares problem.

Cost
----
The ``q_0`` generators of :math:`G_0` enter only through the rank-``n`` products
:math:`[A^L; C\Phi] G_0 W G_0^\top [\,\cdot\,]^\top` (``n × n`` per state), and each noise column of ``H`` is
nonzero on a contiguous range of rows (a process noise acts on the later measurements only, a measurement noise
on its own time), so one iteration costs :math:`O(n(n q_0 + \sum_q r_q^2 + m^3))` per state, ``r_q`` the rows
of column ``q``.  The kernel is compiled with Numba (no ``fastmath``: IEEE arithmetic, the same bytes on every
machine).

Floating point
--------------
The reported radius adds :math:`\kappa u\,\mu_i` (``u`` the unit roundoff), where :math:`\mu` bounds the
magnitudes of every quantity of the computation: the propagation of :math:`|c_0| + \sum_q |G_0|` through
:math:`|A|` with the drives and the noise row sums, the measured values, and :math:`|\lambda_i|` times the
magnitudes of the measured rows; :math:`\kappa = 4(L + 2)(n + m + Q)` (:func:`eqrec.bounds.rounding.rounding_allowance`
with ``terms = (L + 2)(n + m + Q)``) covers the ``L`` chained products, the
dot products of length at most ``n + m + Q`` (``Q`` the columns of ``X``), the sums of the radius (Higham,
*Accuracy and Stability of Numerical Algorithms*, eqs. (3.4), (4.4)) and a simulated true state of the same size.
"""

from __future__ import annotations

import numba
import numpy as np

from eqrec.bounds.rounding import rounding_allowance_compiled


@numba.njit(cache=True)
def spd_solve(M: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """Solve ``M x = b`` into ``out`` for a symmetric positive definite ``M`` by Cholesky (compiled; the lower
    triangle is read and overwritten by the factor)."""
    m = M.shape[0]
    for a in range(m):
        s = M[a, a]
        for c in range(a):
            s -= M[a, c] * M[a, c]
        d = np.sqrt(s) if s > 0.0 else 1e-300
        M[a, a] = d
        for e in range(a + 1, m):
            s = M[e, a]
            for c in range(a):
                s -= M[e, c] * M[a, c]
            M[e, a] = s / d
    for a in range(m):
        s = b[a]
        for c in range(a):
            s -= M[a, c] * out[c]
        out[a] = s / M[a, a]
    for a in range(m - 1, -1, -1):
        s = out[a]
        for c in range(a + 1, m):
            s -= M[c, a] * out[c]
        out[a] = s / M[a, a]


@numba.njit(cache=True)
def accumulate_product(M: np.ndarray, G: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[:, :q] += M @ G`` for ``G`` of ``q`` columns, row by row, skipping the zero entries of ``M``."""
    for a in range(M.shape[0]):
        for e in range(M.shape[1]):
            f = M[a, e]
            if f != 0.0:
                for q in range(G.shape[1]):
                    out[a, q] += f * G[e, q]


@numba.njit(cache=True)
def _dot(x: np.ndarray, y: np.ndarray, length: int) -> float:  # pragma: no cover - compiled
    """``x · y`` over the first ``length`` entries with four partial sums (a fixed order: the same bytes on every
    machine, and independent chains the processor overlaps)."""
    s0 = s1 = s2 = s3 = 0.0
    q = 0
    while q + 4 <= length:
        s0 += x[q] * y[q]
        s1 += x[q + 1] * y[q + 1]
        s2 += x[q + 2] * y[q + 2]
        s3 += x[q + 3] * y[q + 3]
        q += 4
    while q < length:
        s0 += x[q] * y[q]
        q += 1
    return (s0 + s1) + (s2 + s3)


@numba.njit(cache=True)
def window_estimate(A, C, E, V, drive, measured, Y, c0, G0, iterations, delta, extra,  # pragma: no cover
                    gain):
    r"""Per filter and state, the window's estimate of ``x(t+1)`` and its radius (module docstring).

    Parameters
    ----------
    A, C, E, V : ndarray, shapes (L, n, n), (L, p, n), (L, n, nw), (L, p, nv)
        The plant over the window (``E``, ``V`` scaled by the noise bounds).
    drive : ndarray, shape (L, n)
        The known drive ``B u + f`` at each time of the window.
    measured : ndarray of bool, shape (L,)
        Whether ``y(s)`` is known.
    Y : ndarray, shape (L, p)
        The measured values (read where ``measured``).
    c0 : ndarray, shape (K, n)
        Centres of the ``K`` zonotopes at the window start.
    G0 : ndarray, shape (K, n, q0)
        Their generators.
    iterations : int
        Reweighted solves after the first (``>= 0``).
    delta : float
        Relative floor of the IRLS weights' residuals.
    extra : int
        At most this many more solves, each while the last tightened the radius by more than ``gain``.
    gain : float
        Relative tightening that earns another solve.

    Returns
    -------
    xhat : ndarray, shape (K, n)
        The estimates of ``x(t+1)``.
    radius : ndarray, shape (K, n)
        Their bounds, rounding allowance included.
    lam : ndarray, shape (K, n, m)
        The weights on the measured outputs (time order, ``p`` per time).
    R : ndarray, shape (K, n, q0 + Q)
        The error maps: :math:`x_i(t+1) - \hat x_i = R_i \zeta` (prior generators, then the window's process
        noises by time, then the measurement noises of the measured times), rounding apart.
    """
    L, n = A.shape[0], A.shape[1]
    p, nw, nv = C.shape[1], E.shape[2], V.shape[2]
    K, q0 = G0.shape[0], G0.shape[2]
    times = 0
    for j in range(L):
        if measured[j]:
            times += 1
    m = times * p
    Qn = L * nw + times * nv
    # --- propagation over the window: Phi = Phi(s, s0), Z = effect of w on x(s), rows of H ---------------------
    Phi = np.eye(n)
    Z = np.zeros((n, L * nw))
    CP = np.zeros((m, n))  # C(s) Phi(s, s0) for the measured rows
    Hn = np.zeros((m, Qn))  # noise columns of H: w(s0..t), then v of the measured times
    lo = np.zeros(Qn, dtype=np.int64)  # each noise column is nonzero on rows lo..hi-1
    hi = np.zeros(Qn, dtype=np.int64)
    row = 0
    vcol = L * nw
    for j in range(L):
        if measured[j]:
            for a in range(p):
                for b in range(n):
                    s = 0.0
                    for e in range(n):
                        s += C[j, a, e] * Phi[e, b]
                    CP[row + a, b] = s
                for q in range(j * nw):
                    s = 0.0
                    for e in range(n):
                        s += C[j, a, e] * Z[e, q]
                    Hn[row + a, q] = s
                for q in range(nv):
                    Hn[row + a, vcol + q] = V[j, a, q]
            for q in range(nv):
                lo[vcol + q] = row
                hi[vcol + q] = row + p
            vcol += nv
            row += p
        # Phi <- A Phi ; Z <- A Z, then the new process noise
        newPhi = np.zeros((n, n))
        newZ = np.zeros((n, L * nw))
        for a in range(n):
            for e in range(n):
                aij = A[j, a, e]
                if aij != 0.0:
                    for b in range(n):
                        newPhi[a, b] += aij * Phi[e, b]
                    for q in range(j * nw):
                        newZ[a, q] += aij * Z[e, q]
        for a in range(n):
            for q in range(nw):
                newZ[a, j * nw + q] = E[j, a, q]
        Phi = newPhi
        Z = newZ
    # rows of the process noise columns: the measured rows after its time
    row = 0
    for j in range(L):
        for q in range(nw):
            lo[j * nw + q] = row + (p if measured[j] else 0)
            hi[j * nw + q] = m
        if measured[j]:
            row += p
    xhat = np.empty((K, n))
    radius = np.empty((K, n))
    lam_out = np.zeros((K, n, m))
    R_out = np.zeros((K, n, q0 + Qn))
    for k in range(K):
        # centre and magnitudes over the window
        xc = c0[k].copy()
        zm = np.empty(n)
        for a in range(n):
            s = 0.0
            for q in range(q0):
                s += abs(G0[k, a, q])
            zm[a] = abs(xc[a]) + s
        resid = np.zeros(m)
        magy = np.zeros(m)
        row = 0
        for j in range(L):
            if measured[j]:
                for a in range(p):
                    s = 0.0
                    sm = 0.0
                    for e in range(n):
                        s += C[j, a, e] * xc[e]
                        sm += abs(C[j, a, e]) * zm[e]
                    for q in range(nv):
                        sm += abs(V[j, a, q])
                    resid[row + a] = Y[j, a] - s
                    magy[row + a] = sm + abs(Y[j, a]) + abs(s)
                row += p
            nx = np.empty(n)
            nm = np.empty(n)
            for a in range(n):
                s = drive[j, a]
                sm = abs(drive[j, a])
                for e in range(n):
                    s += A[j, a, e] * xc[e]
                    sm += abs(A[j, a, e]) * zm[e]
                for q in range(nw):
                    sm += abs(E[j, a, q])
                nx[a] = s
                nm[a] = sm
            xc = nx
            zm = nm
        # prior columns: PX = Phi G0 (rows of X), PH = CP G0 (rows of H)
        PX = np.zeros((n, q0))
        PH = np.zeros((m, q0))
        accumulate_product(Phi, G0[k], PX)
        accumulate_product(CP, G0[k], PH)
        # first weights: inverse column lengths of (X, H)
        w0 = np.zeros(q0 + Qn)
        for a in range(n):  # column sums of squares, row by row (contiguous)
            for q in range(q0):
                w0[q] += PX[a, q] * PX[a, q]
        for a in range(m):
            for q in range(q0):
                w0[q] += PH[a, q] * PH[a, q]
        for q in range(q0):
            w0[q] = 1.0 / np.sqrt(w0[q]) if w0[q] > 0.0 else 0.0
        for q in range(Qn):
            s = 0.0
            if q < L * nw:
                for a in range(n):
                    s += Z[a, q] * Z[a, q]
            for a in range(lo[q], hi[q]):
                s += Hn[a, q] * Hn[a, q]
            w0[q0 + q] = 1.0 / np.sqrt(s) if s > 0.0 else 0.0
        W = np.empty(q0 + Qn)
        res = np.empty(q0 + Qn)  # the residual X_i - lam H of the current solve
        absR = np.empty(q0 + Qn)
        M = np.empty((m, m))
        rhs = np.empty(m)
        lam = np.zeros(m)
        S = np.empty((n, n))
        GW = np.empty((n, q0))
        SCt = np.empty((n, m))
        for i in range(n):
            # lambda = 0: the prediction alone
            best = 0.0
            for q in range(q0):
                best += abs(PX[i, q])
                R_out[k, i, q] = PX[i, q]
            for q in range(L * nw):
                best += abs(Z[i, q])
                R_out[k, i, q0 + q] = Z[i, q]
            lam_best = np.zeros(m)
            if m > 0:
                for q in range(q0 + Qn):
                    W[q] = w0[q]
                it = 0
                while True:
                    # S = G0 W G0^T (n x n), then M = CP S CP^T + Hn W Hn^T, rhs = CP S Phi_i^T + Hn W Z_i^T
                    for a in range(n):
                        for q in range(q0):
                            GW[a, q] = G0[k, a, q] * W[q]
                    for a in range(n):
                        for b in range(a + 1):
                            s = _dot(GW[a], G0[k, b], q0)
                            S[a, b] = s
                            S[b, a] = s
                    for a in range(n):
                        for r in range(m):
                            s = 0.0
                            for e in range(n):
                                s += S[a, e] * CP[r, e]
                            SCt[a, r] = s
                    for r in range(m):
                        for c in range(r + 1):
                            s = 0.0
                            for e in range(n):
                                s += CP[r, e] * SCt[e, c]
                            M[r, c] = s
                        s = 0.0
                        for e in range(n):
                            s += Phi[i, e] * SCt[e, r]
                        rhs[r] = s
                    for q in range(Qn):
                        wq = W[q0 + q]
                        if wq == 0.0:
                            continue
                        for r in range(lo[q], hi[q]):
                            hr = Hn[r, q] * wq
                            if hr == 0.0:
                                continue
                            for c in range(lo[q], r + 1):
                                M[r, c] += hr * Hn[c, q]
                            if q < L * nw:
                                rhs[r] += hr * Z[i, q]
                    for r in range(m):  # a relative ridge: M is singular when two measured rows coincide
                        M[r, r] += 1e-14 * M[r, r] + 1e-300
                    spd_solve(M, rhs, lam)
                    # residual R_i = X_i - lam H and its 1-norm
                    v = np.empty(n)
                    for e in range(n):
                        s = Phi[i, e]
                        for r in range(m):
                            s -= lam[r] * CP[r, e]
                        v[e] = s
                    for q in range(q0):
                        res[q] = v[0] * G0[k, 0, q]
                    for e in range(1, n):
                        for q in range(q0):
                            res[q] += v[e] * G0[k, e, q]
                    for q in range(Qn):
                        s = Z[i, q] if q < L * nw else 0.0
                        for r in range(lo[q], hi[q]):
                            s -= lam[r] * Hn[r, q]
                        res[q0 + q] = s
                    rad = 0.0
                    big = 0.0
                    for q in range(q0 + Qn):
                        s = abs(res[q])
                        absR[q] = s
                        rad += s
                        big = max(big, s)
                    improved = rad < best * (1.0 - gain)
                    if rad < best:
                        best = rad
                        lam_best[:] = lam
                        R_out[k, i, :] = res  # the error map of the kept weights
                    it += 1
                    if it > iterations + extra or (it > iterations and not improved):
                        break
                    floor = delta * big
                    for q in range(q0 + Qn):
                        W[q] = 1.0 / max(absR[q], floor) if max(absR[q], floor) > 0.0 else 0.0
            # the estimate, its magnitude and the rounding allowance (module docstring)
            est = xc[i]
            mag = zm[i] + abs(xc[i])
            for r in range(m):
                est += lam_best[r] * resid[r]
                mag += abs(lam_best[r]) * (magy[r] + abs(resid[r]))
            xhat[k, i] = est
            radius[k, i] = rounding_allowance_compiled(best, (L + 2) * (n + m + q0 + Qn), mag)
            lam_out[k, i, :] = lam_best
    return xhat, radius, lam_out, R_out

