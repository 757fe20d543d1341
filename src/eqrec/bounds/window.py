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
*Numerical Methods for Least Squares Problems*, SIAM 1996, §4.5), in two stages.

* **Shared solves.**  One weight per column ``q``, the same for every state: first the inverse generator
  lengths :math:`1/\|g_q\|_2` of the prior and :math:`1/\|(X_{\cdot q}, H_{\cdot q})\|_2` of the noise columns,
  then, ``shared`` times, :math:`W_q = 1/\max(a_q, \delta\max_q a_q)` with
  :math:`a_q = \sum_i |R_{iq}| / \|R_i\|_1` (each state's residual relative to its radius, summed over the
  states), then again while the last solve tightened the largest radius by more than a relative ``gain``, at most
  ``extra`` more times.  With shared weights, :math:`\Lambda = X W H^\top (H W H^\top)^{-1}` for all states at
  once: one Kalman recursion over the window (*Cost*, below) serves every state.
* **Per-state solves**, greedily: the state of largest radius (the one that sets the reported bound
  :math:`\max_i \beta_i`), then the state of largest radius among those not yet solved while its radius is within
  a relative ``margin`` of the largest, at most ``states`` of them: from :math:`W_q = 1/\max(|R_{iq}|, \delta\max_q|R_{iq}|)`
  of the state's best residual, solve :math:`\lambda_i = (X_i W H^\top)(H W H^\top)^{-1}` and reweight,
  ``iterations`` times, then again while the last solve tightened the radius by more than ``gain``, at most
  ``extra`` more times.

Warm start
----------
A window that slides by one step asks nearly the same question as the last one, so the shared weights can start
where the last window's ended instead of from the inverse column lengths (the ``carried_*`` arguments of
:func:`window_estimate_sparse`; :data:`COLD`: none).  The last window's relative residuals :math:`a_q` (of its last
shared solve), its :math:`T(0)` and radii give the new window's first :math:`a_q` (:func:`_warm_weights`): on the
new prior's generators :math:`\sum_i |(T(0) g_q)_i| / \rho_i`, the last window's map from its start applied to
them; on the noise of a time, the last window's at the same distance from the window's end, the quantity that
stays put when the window slides (for a measured time, the last window's nearest measured time).  The zonotope
estimator carries them once its window is full and then makes one shared solve instead of two
(``warm_start=True``, :data:`eqrec.estimators.zonotope.SHARED_SOLVES_WARM`), which also skips the Gramian of the
first weights: the iteration continues across steps instead of starting again at each.  The weights still depend
on the arrivals and the filters' generators only (now those of the earlier steps too), never on the measured
values, and every solve's bound is still the exact worst case of its own estimate.  Measured on the tank chains of
``benchmarks/bench_zonotope.py`` and the two carts (150 steps, the same trace, one reweighted per-state solve both
ways): a step 0.78-0.89 times the cost; the largest bound, which the per-state solves refine, the same at the
median (-0.5 % to +0.5 %).  But the cold start keeps, per state, the better of its two solves, and the first one
(the inverse column lengths) is what the states far below the largest bound need: with the warm start their hull
is noisier, on the two carts between 0.76 and 2.5 times the cold start's from step to step (the predicted hull of
the worst state over the exact hull, worst over the checked steps, 5.3 against 2.1; median over the steps 1.73
against 1.55), on the tank chains of 4 and 6 tanks about as tight at the median (1.16, 1.17 against 1.16, 1.22) but
with spikes (1.5, 1.9 against 1.35, 1.4).  So it is an option (``ZonotopeEstimator(warm_start=True)``), not the
default.  Mixing the carried weights with the inverse column lengths (a geometric mean) in one solve was worse
than either.

Every iterate is a valid estimate; per state the one with the smallest radius is kept (so more iterations never
loosen the bound: the shared solves do not depend on ``iterations``, and the per-state sequence with more
iterations extends the one with fewer).  The weights depend on the arrivals and the zonotope only, never on the
measured values, so the estimate is linear in the data given the zonotope.  The relative floor :math:`\delta` of
the residuals bounds the ratio of the weights (``1/δ``) and so the conditioning of each weighted least-squares
problem.

Cost
----
No column of ``H`` is formed, and neither is :math:`HWH^\top`.  Read as variances, the weights make the weighted
least-squares estimate of :math:`x(t+1)` the Kalman filter's over the window (the filter's estimate of the last
state given every measurement is the best linear one; e.g. Anderson and Moore, *Optimal Filtering*, 1979, §5.2),
for the prior covariance :math:`S = G_0 W G_0^\top`, process noise :math:`E\,\mathrm{diag}(W)E^\top` and
measurement noise :math:`V\,\mathrm{diag}(W)V^\top`.  So a solve is one covariance recursion forward in time
(:func:`_kalman_gains`: the gain :math:`K_s` of each measured time, ``n × p``) and one recursion backwards
(:func:`_residuals`): :math:`T(L) = I`, and at each time :math:`T(s+1)A(s)`, then the weights of the outputs of
a measured time :math:`\lambda_s = T(s+1)A(s)K_s`, :math:`T(s) = T(s+1)A(s) - \lambda_s C(s)`; the residual on
:math:`w(s)` is :math:`T(s+1)E(s)`, on :math:`v(s)` :math:`-\lambda_s V(s)`, on the prior :math:`T(0)G_0`.  The
weights are then used as any others: the estimate is :math:`\hat x^{\rm pred} + \lambda(y - \hat y^{\rm pred})`
and its bound the 1-norm of the residuals, so how they were found changes no guarantee
(``tests/test_zonotope.py`` checks them against :math:`XWH^\top(HWH^\top)^{-1}` from explicit matrices).
A shared solve for all ``n`` states costs :math:`O(n^2 q_0)` (the products with :math:`G_0`, BLAS) and
:math:`O(L(n\,\mathrm{nnz}(A) + p n^2))` for the recursions; a per-state solve the same with one row in the
backward recursion.  The normal equations :math:`HWH^\top` (``m × m``, ``m`` the measured rows) with a Cholesky
factorization, used before 2026-11-30, cost :math:`O(m^3)` besides: measured on the tank chains of
``benchmarks/bench_zonotope.py --part scale`` (n = 30, p = 5, a window of 30 steps, :math:`m \approx 115`,
:math:`q_0 = 400`) the normal equations and the factorization took 76 + 103 µs for a shared solve and 76 + 38 µs
for a per-state one, the Kalman recursion 75 µs; a window 0.73 times the cost, the bounds equal to about
:math:`10^{-13}` (the weights are the same in exact arithmetic).  The recursions run over the nonzeros of ``A``
(:func:`sparse_rows`) and those of ``E`` by column (:func:`sparse_columns`; the terms skipped are exact zeros added
to sums that start from ``+0.0``); a time-invariant plant's nonzeros are found once per estimator
(:func:`window_estimate_sparse`).  The covariances :math:`\Sigma` and the Gramian are symmetric, so the second
product of each propagation forms their lower triangle only and mirrors it.  The prior covariance
:math:`S = G_0 W G_0^\top` only sets the weights, so it is formed in single precision (:func:`_prior_covariance`:
about half the time of the double-precision product; the radii within :math:`10^{-8}` relative of those from it).
Where the time of a full window goes at n = 30 (2026-11-30, before these two changes, which made it 0.93 times the
cost): about 45 µs for the Gramian of the first weights, a shared solve about 0.2 ms (the products with
:math:`G_0` 50 µs, the Kalman recursion 75, the backward recursion for all states 50) and a per-state solve about
0.13 ms (the product with :math:`G_0` 30 µs, the Kalman recursion 75); two shared and three per-state solves a
step at ``iterations=2``.  The rest is compiled with Numba (no ``fastmath``); the bytes are those of the machine's
BLAS (the same on one machine; the rounding allowance below holds for any order of the sums).

Floating point
--------------
The reported radius adds :math:`\kappa u\,\mu_i` (``u`` the unit roundoff), where :math:`\mu` bounds the
magnitudes of every quantity of the computation: the propagation of :math:`|c_0| + \sum_q |G_0|` through
:math:`|A|` with the drives and the noise row sums, the measured values, and :math:`|\lambda_i|` times the
magnitudes of the measured rows; :math:`\kappa = 4(L + 2)(n + m + Q)` (:func:`eqrec.bounds.rounding.rounding_allowance`
with ``terms = (L + 2)(n + m + Q)``) covers the ``L`` chained products, the
dot products of length at most ``n + m + Q`` (``Q`` the columns of ``X``), the sums of the radius (Higham,
*Accuracy and Stability of Numerical Algorithms*, eqs. (3.4), (4.4): bounds that hold for any order of the sums,
BLAS's included) and a simulated true state of the same size.
"""

from __future__ import annotations

import numba
import numpy as np

from eqrec.bounds.rounding_kernels import rounding_allowance_compiled


@numba.njit(cache=True)
def cholesky_lower(M: np.ndarray, rel: float, fallback: float) -> None:  # pragma: no cover - compiled
    """Overwrite the lower triangle of the symmetric ``M`` by its Cholesky factor ``F`` (:math:`M = FF^\\top`, read
    from the lower triangle).  A pivot not above ``rel`` times its diagonal entry becomes ``fallback`` (``1e-300``:
    kept; ``inf``: that row's column of the factor becomes zero, the row dropped)."""
    m = M.shape[0]
    for a in range(m):
        s = M[a, a]
        for c in range(a):
            s -= M[a, c] * M[a, c]
        d = np.sqrt(s) if s > rel * M[a, a] else fallback
        M[a, a] = d
        for e in range(a + 1, m):
            s = M[e, a]
            for c in range(a):
                s -= M[e, c] * M[a, c]
            M[e, a] = s / d


@numba.njit(cache=True)
def spd_solve(M: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """Solve ``M x = b`` into ``out`` for a symmetric positive definite ``M`` by Cholesky (compiled; the lower
    triangle is read and overwritten by the factor, :func:`cholesky_lower`)."""
    m = M.shape[0]
    cholesky_lower(M, 0.0, 1e-300)
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
def add_abs_rows(X: np.ndarray, cols: int, acc: np.ndarray) -> None:  # pragma: no cover - compiled
    """``acc[a] += |X[a, 0]| + |X[a, 1]| + ... + |X[a, cols - 1]|``, the terms added one by one in that order
    (the same numbers as a loop over ``j`` per row); four rows at a time, so that four independent sums advance
    together instead of one sum waiting for each addition."""
    n = X.shape[0]
    a = 0
    while a + 4 <= n:
        r0, r1, r2, r3 = acc[a], acc[a + 1], acc[a + 2], acc[a + 3]
        for j in range(cols):
            r0 += abs(X[a, j])
            r1 += abs(X[a + 1, j])
            r2 += abs(X[a + 2, j])
            r3 += abs(X[a + 3, j])
        acc[a], acc[a + 1], acc[a + 2], acc[a + 3] = r0, r1, r2, r3
        a += 4
    while a < n:
        r0 = acc[a]
        for j in range(cols):
            r0 += abs(X[a, j])
        acc[a] = r0
        a += 1


@numba.njit(cache=True)
def weighted_products(X: np.ndarray, w: np.ndarray, Y: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``out[a, b] = sum_j (X[a, j] w[j]) Y[b, j]``, each sum from ``0.0`` over ``j`` in increasing order (the same
    numbers as that loop per entry); four rows of ``X`` at a time (independent sums advancing together)."""
    na, nb, q = X.shape[0], Y.shape[0], X.shape[1]
    for b in range(nb):
        a = 0
        while a + 4 <= na:
            r0 = r1 = r2 = r3 = 0.0
            for j in range(q):
                wj = w[j]
                y = Y[b, j]
                r0 += X[a, j] * wj * y
                r1 += X[a + 1, j] * wj * y
                r2 += X[a + 2, j] * wj * y
                r3 += X[a + 3, j] * wj * y
            out[a, b], out[a + 1, b], out[a + 2, b], out[a + 3, b] = r0, r1, r2, r3
            a += 4
        while a < na:
            r0 = 0.0
            for j in range(q):
                r0 += X[a, j] * w[j] * Y[b, j]
            out[a, b] = r0
            a += 1


@numba.njit(cache=True)
def sparse_rows(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """The nonzeros of each ``A[j]`` (``(L, n, n)``) by row: ``ptr`` (``(L, n + 1)``), ``col`` and ``val``
    (``(L, n · n)``), row ``a`` of ``A[j]`` being ``acol[j, aptr[j, a]:aptr[j, a + 1]]`` (columns in increasing
    order) and its values (the window's recursions run over them: a plant's ``A`` is often sparse, e.g. a chain).
    The rows of ``A`` are the columns of its transpose (:func:`sparse_columns`)."""
    return sparse_columns(np.ascontiguousarray(np.transpose(A, (0, 2, 1))))


@numba.njit(cache=True)
def sparse_columns(E: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """The nonzeros of each ``E[j]`` (``(L, n, nw)``) by column: ``ptr`` (``(L, nw + 1)``), ``row`` and ``val``
    (``(L, n · nw)``), column ``q`` of ``E[j]`` being ``erow[j, eptr[j, q]:eptr[j, q + 1]]`` (rows in increasing
    order) and its values (the noise gains of a plant are often diagonal or a few columns)."""
    L, n, nw = E.shape
    eptr = np.zeros((L, nw + 1), dtype=np.int64)
    erow = np.empty((L, n * nw), dtype=np.int64)  # (only the first ptr[j, nw] entries of a row are read)
    evals = np.empty((L, n * nw))
    for j in range(L):
        z = 0
        for q in range(nw):
            for a in range(n):
                f = E[j, a, q]
                if f != 0.0:
                    erow[j, z] = a
                    evals[j, z] = f
                    z += 1
            eptr[j, q + 1] = z
    return eptr, erow, evals


@numba.njit(cache=True)
def _times_sparse(aptr, acol, aval, j, X, cols, out, lower=False):  # pragma: no cover - compiled
    """``out[:, :cols] = A[j] X[:, :cols]`` over the nonzeros of ``A[j]`` by row (:func:`sparse_rows`), each row's
    sum in the order of its nonzeros.  ``lower``: a product known to be symmetric (``cols = n``), only its lower
    triangle computed (row ``a`` up to column ``a``) and mirrored to the upper."""
    for a in range(out.shape[0]):
        if lower:
            cols = a + 1
        z0 = aptr[j, a]
        nz = aptr[j, a + 1] - z0
        if nz == 1:  # rows of one to three nonzeros (a chain, a band) in one pass: the same sums from 0.0
            f0, e0 = aval[j, z0], acol[j, z0]
            for r in range(cols):
                out[a, r] = 0.0 + f0 * X[e0, r]
        elif nz == 2:
            f0, e0, f1, e1 = aval[j, z0], acol[j, z0], aval[j, z0 + 1], acol[j, z0 + 1]
            for r in range(cols):
                out[a, r] = (0.0 + f0 * X[e0, r]) + f1 * X[e1, r]
        elif nz == 3:
            f0, e0, f1, e1 = aval[j, z0], acol[j, z0], aval[j, z0 + 1], acol[j, z0 + 1]
            f2, e2 = aval[j, z0 + 2], acol[j, z0 + 2]
            for r in range(cols):
                out[a, r] = ((0.0 + f0 * X[e0, r]) + f1 * X[e1, r]) + f2 * X[e2, r]
        else:
            for r in range(cols):
                out[a, r] = 0.0
            for z in range(z0, z0 + nz):
                f = aval[j, z]
                e = acol[j, z]
                for r in range(cols):
                    out[a, r] += f * X[e, r]
    if lower:
        for a in range(out.shape[0]):
            for r in range(a):
                out[r, a] = out[a, r]


@numba.njit(cache=True)
def _triangular_rows(F, X, transposed):  # pragma: no cover - compiled
    """Overwrite ``X`` (``p × n``) by :math:`F^{-1}X` (``transposed``: :math:`F^{-\\top}X`) for the lower triangular
    ``F`` (``p × p``), row by row of ``X`` (the loops over its ``n`` columns vectorise)."""
    p, n = X.shape
    for k in range(p):
        a = p - 1 - k if transposed else k
        for c in range(a + 1, p) if transposed else range(a):
            f = F[c, a] if transposed else F[a, c]
            for e in range(n):
                X[a, e] -= f * X[c, e]
        d = F[a, a]
        for e in range(n):
            X[a, e] /= d


@numba.njit(cache=True)
def _power_of_two_scale(m):  # pragma: no cover - compiled
    """``(s, 1/s)`` for the power of two ``s`` that brings ``m > 0`` into ``[0.5, 1)`` (exponent clipped to
    ``±1000``; ``(1, 1)`` for a zero or non-finite ``m``): a scaling that rounds nothing."""
    if not (m > 0.0) or not np.isfinite(m):
        return 1.0, 1.0
    k = min(max(-(int(np.floor(np.log2(m))) + 1), -1000), 1000)
    return 2.0 ** k, 2.0 ** (-k)


@numba.njit(cache=True)
def _single(Gk):  # pragma: no cover - compiled
    r""":math:`G_0^\top` scaled by a power of two into ``[0.5, 1)`` at its largest entry and rounded to single
    precision once per window, the inverse of that scale, and the largest magnitude of each generator
    (:func:`_prior_covariance`)."""
    n, q0 = Gk.shape
    colmax = np.zeros(q0)
    for a in range(n):
        for q in range(q0):
            colmax[q] = max(colmax[q], abs(Gk[a, q]))
    big = 0.0
    for q in range(q0):
        big = max(big, colmax[q])
    s, inv = _power_of_two_scale(big)
    T = np.empty((q0, n), dtype=np.float32)
    for q in range(q0):
        for a in range(n):
            T[q, a] = Gk[a, q] * s
    return T, inv, colmax


@numba.njit(cache=True)
def _prior_covariance(Gk, GkT32, inv, colmax, W, GW32):  # pragma: no cover - compiled
    r"""The Kalman recursion's prior covariance :math:`S = G_0 W G_0^\top` (``Gk``: ``n × q0``; ``W``: the weights,
    the prior's first) in single precision: ``GkT32``, ``inv``, ``colmax`` from :func:`_single`, ``GW32`` a buffer
    (``n × q0``).  :math:`S` only sets the weights, and any weights give a valid bound, exact for its estimate
    (module docstring), so its rounding changes no guarantee; at single precision the product takes about half the
    time (measured at n = 30, 400 generators: the radii within :math:`10^{-8}` relative of those from the
    double-precision product).  Both factors are scaled by powers of two into single precision's range (a prior of
    radius :math:`10^{100}` overflows it otherwise), and the product scaled back in double precision."""
    n, q0 = Gk.shape
    big = 0.0
    for q in range(q0):
        big = max(big, colmax[q] * abs(W[q]))
    s, inv_w = _power_of_two_scale(big)
    for a in range(n):
        for q in range(q0):
            GW32[a, q] = Gk[a, q] * W[q] * s
    S = np.dot(GW32, GkT32).astype(np.float64)
    S *= inv_w  # (two exact scalings: their product may leave the double range where S does not)
    S *= inv
    return S


@numba.njit(cache=True)
def _kalman_gains(A, C, E, V, measured, S, W, q0, K, aptr, acol, aval, eptr, erow, evals):  # pragma: no cover
    r"""The gains of the window's weighted least squares by a Kalman filter over it (module docstring, *Cost*).

    With the column weights ``W`` read as variances (prior :math:`\Sigma(0) = S = G_0 W G_0^\top`, process noise
    :math:`E\,\mathrm{diag}(W)E^\top`, measurement noise :math:`V\,\mathrm{diag}(W)V^\top`), the covariance form of
    the Kalman filter, forward in time: at a measured time ``j`` (its ``tt``-th), :math:`U = \Sigma C^\top`,
    :math:`S_y = CU + V D V^\top = FF^\top` (Cholesky), :math:`K_{tt} = U S_y^{-1}` (``n × p``; its transpose,
    ``p × n``, written to ``K[tt]``), :math:`\Sigma \leftarrow \Sigma - ZZ^\top` with :math:`Z = UF^{-\top}`; then
    :math:`\Sigma \leftarrow A\Sigma A^\top + E D E^\top`.  The filter's estimate of :math:`x(t+1)` is the weighted
    least-squares one, so its weight on the outputs of time ``j`` is :math:`\lambda_j = T(j+1)A(j)K_{tt}` with
    :math:`T` the residual recursion's (:func:`_residuals`, which forms it).  An output whose pivot of :math:`S_y`
    is below :math:`10^{-12}` of its diagonal (a row alike to the earlier ones of its time, with no noise) gets the
    gain 0 (it adds nothing to them; any weights keep the bound valid).  ``aptr``, ``acol``, ``aval``: the nonzeros
    of ``A`` by row (:func:`sparse_rows`); ``eptr``, ``erow``, ``evals``: those of ``E`` by column
    (:func:`sparse_columns`)."""
    L, n = A.shape[0], A.shape[1]
    p, nw, nv = C.shape[1], E.shape[2], V.shape[2]
    Lnw = L * nw
    Sig = S.copy()
    tmp = np.empty((n, n))
    U = np.empty((n, p))
    F = np.empty((p, p))
    Zt = np.empty((p, n))
    tt = 0
    for j in range(L):
        if measured[j]:
            for b in range(n):  # U = Sigma C^T, over the nonzeros of C_j
                for a in range(p):
                    U[b, a] = 0.0
            for a in range(p):
                for e in range(n):
                    f = C[j, a, e]
                    if f != 0.0:
                        for b in range(n):
                            U[b, a] += Sig[b, e] * f
            for a in range(p):  # S_y = C U + V D V^T (lower triangle), a relative ridge on its diagonal
                for c in range(a + 1):
                    s = 0.0
                    for e in range(n):
                        s += C[j, a, e] * U[e, c]
                    for q in range(nv):
                        s += V[j, a, q] * W[q0 + Lnw + tt * nv + q] * V[j, c, q]
                    F[a, c] = s
                F[a, a] += 1e-14 * abs(F[a, a]) + 1e-300
            cholesky_lower(F, 1e-12, np.inf)  # S_y = F F^T; a pivot below 1e-12 of its diagonal: output dropped
            for a in range(p):
                for e in range(n):
                    Zt[a, e] = U[e, a]
            _triangular_rows(F, Zt, False)  # Z^T = F^{-1} U^T
            Kt = K[tt]  # (a view: written in place)
            Kt[:, :] = Zt
            _triangular_rows(F, Kt, True)  # K^T = F^{-T} Z^T
            for b in range(n):  # Sigma -= Z Z^T: the lower triangle, then mirrored
                for a in range(p):
                    f = Zt[a, b]
                    for e in range(b + 1):
                        Sig[b, e] -= f * Zt[a, e]
            for b in range(n):
                for e in range(b):
                    Sig[e, b] = Sig[b, e]
            tt += 1
        # Sigma <- A Sigma A^T + E D E^T (over the nonzeros of A, by row)
        _times_sparse(aptr, acol, aval, j, Sig, n, tmp)  # tmp = A Sigma
        _times_sparse(aptr, acol, aval, j, tmp.T, n, Sig, True)  # Sigma = A (A Sigma)^T (a view; symmetric)
        for q in range(nw):
            w = W[q0 + j * nw + q]
            if w == 0.0:
                continue
            for za in range(eptr[j, q], eptr[j, q + 1]):
                fa = evals[j, za] * w
                if fa != 0.0:
                    a = erow[j, za]
                    for zb in range(eptr[j, q], eptr[j, q + 1]):
                        Sig[a, erow[j, zb]] += fa * evals[j, zb]


@numba.njit(cache=True)
def _residuals(A, C, E, V, measured, K, lamT, TT, RTn, cptr, crow, cval, eptr, erow, evals):  # pragma: no cover
    r"""The noise columns of the residuals :math:`X_i - \lambda_i H` of ``k`` states, backwards in time.

    :math:`T(L) = I` (rows of the states, stored transposed in ``TT``, ``n × k``, on entry), then
    :math:`T(s) = T(s+1)A(s) - \lambda_s C(s)`; the residual on :math:`w(s)` is :math:`T(s+1)E(s)`, on :math:`v(s)`
    :math:`-\lambda_s V(s)`, and on the prior :math:`T(0)G_0` (left to the caller: ``TT`` holds :math:`T(0)^\top` on
    return).  ``K`` (``times × p × n``): the Kalman gains of the measured times, transposed (:func:`_kalman_gains`),
    from which the weights of the states on the outputs of time ``s`` come as :math:`\lambda_s = T(s+1)A(s)K` once
    :math:`T(s+1)A(s)` is known (the weighted least-squares weights: module docstring, *Cost*), written to ``lamT``
    (``m × k``, by measured row); ``RTn`` (``Q × k``): the residuals on the noise columns (process noise by time,
    then the measurement noise of the measured times). ``cptr``, ``crow``, ``cval``: the nonzeros of ``A`` by column
    (:func:`sparse_columns`: the rows of :math:`A^\top`, so that :math:`A^\top X` is :func:`_times_sparse`, each sum
    over the rows of ``A`` in increasing order); ``eptr``, ``erow``, ``evals``: those of ``E`` by column."""
    L, n = A.shape[0], A.shape[1]
    p, nw, nv = C.shape[1], E.shape[2], V.shape[2]
    k = TT.shape[1]
    Lnw = L * nw
    m = lamT.shape[0]
    times = m // p if p > 0 else 0
    newT = np.empty((n, k))
    out = TT
    swapped = False
    rows = m
    tt = times
    for j in range(L - 1, -1, -1):
        for q in range(nw):  # w(j): T(j+1) E(j)
            col = j * nw + q
            for i in range(k):
                RTn[col, i] = 0.0
            for z in range(eptr[j, q], eptr[j, q + 1]):  # the nonzeros of E's column, rows in increasing order
                f = evals[j, z]
                a = erow[j, z]
                for i in range(k):
                    RTn[col, i] += f * TT[a, i]
        _times_sparse(cptr, crow, cval, j, TT, k, newT)  # T <- T A(j), transposed: TT <- A^T TT (A's columns)
        TT, newT = newT, TT  # two buffers, alternately
        swapped = not swapped
        if measured[j]:
            rows -= p
            tt -= 1
            for c in range(p):  # lambda_j = T(j+1) A(j) K_tt, the rows of time j's outputs
                for i in range(k):
                    lamT[rows + c, i] = 0.0
                for a in range(n):
                    f = K[tt, c, a]
                    if f != 0.0:
                        for i in range(k):
                            lamT[rows + c, i] += f * TT[a, i]
            for c in range(p):
                for a in range(n):
                    f = C[j, c, a]
                    if f != 0.0:
                        for i in range(k):
                            TT[a, i] -= f * lamT[rows + c, i]
            for q in range(nv):  # v(j): -lambda_j V(j)
                col = Lnw + tt * nv + q
                for i in range(k):
                    RTn[col, i] = 0.0
                for c in range(p):
                    f = V[j, c, q]
                    if f != 0.0:
                        for i in range(k):
                            RTn[col, i] -= f * lamT[rows + c, i]
    if swapped:  # T(0)^T is in the second buffer
        for a in range(n):
            for i in range(k):
                out[a, i] = TT[a, i]


@numba.njit(cache=True)
def _residuals_one(A, C, E, V, measured, K, lam, t, RT, aptr, acol, aval, eptr, erow, evals):  # pragma: no cover
    """:func:`_residuals` of one state (``k = 1``) on vectors: ``lam`` (``m``) its weights (written), ``t`` (``n``) the row
    :math:`T(L)` on entry and :math:`T(0)` on return, ``RT`` (``Q``) the residuals on the noise columns.  The same
    operations in the same order as :func:`_residuals` (the same numbers), without its loops over the states."""
    L, n = A.shape[0], A.shape[1]
    p, nw, nv = C.shape[1], E.shape[2], V.shape[2]
    Lnw = L * nw
    m = lam.shape[0]
    times = m // p if p > 0 else 0
    cur = t.copy()
    nxt = np.empty(n)
    rows = m
    tt = times
    for j in range(L - 1, -1, -1):
        for q in range(nw):  # w(j): T(j+1) E(j)
            r = 0.0
            for z in range(eptr[j, q], eptr[j, q + 1]):
                r += evals[j, z] * cur[erow[j, z]]
            RT[j * nw + q] = r
        for a in range(n):  # T <- T A(j), transposed: A^T T^T over the nonzeros of A, by row
            nxt[a] = 0.0
        for e in range(n):
            x = cur[e]
            for z in range(aptr[j, e], aptr[j, e + 1]):
                nxt[acol[j, z]] += aval[j, z] * x
        cur, nxt = nxt, cur
        if measured[j]:
            rows -= p
            tt -= 1
            for c in range(p):  # lambda_j = T(j+1) A(j) K_tt
                r = 0.0
                for a in range(n):
                    f = K[tt, c, a]
                    if f != 0.0:
                        r += f * cur[a]
                lam[rows + c] = r
            for c in range(p):
                for a in range(n):
                    f = C[j, c, a]
                    if f != 0.0:
                        cur[a] -= f * lam[rows + c]
            for q in range(nv):  # v(j): -lambda_j V(j)
                r = 0.0
                for c in range(p):
                    f = V[j, c, q]
                    if f != 0.0:
                        r -= f * lam[rows + c]
                RT[Lnw + tt * nv + q] = r
    t[:] = cur


@numba.njit(cache=True)
def _irls_weights(a, delta, out):  # pragma: no cover - compiled
    """The IRLS weights of residual magnitudes ``a`` (module docstring): ``out[q] = 1 / max(|a_q|, delta max|a|)``
    (0 where that is 0); ``out`` may be ``a`` itself."""
    big = 0.0
    for q in range(a.shape[0]):
        big = max(big, abs(a[q]))
    floor = delta * big
    for q in range(a.shape[0]):
        d = max(abs(a[q]), floor)
        out[q] = 1.0 / d if d > 0.0 else 0.0


@numba.njit(cache=True)
def _warm_weights(row, Tm, scale, known_prev, measured, G0, nw, nv, delta, W):  # pragma: no cover - compiled
    r"""First weights of a window from the last step's residuals (module docstring, *Warm start*).

    ``row`` (``q_0' + Q'``): the last window's residual magnitudes over its columns (its prior's, then its noise
    columns), ``known_prev`` its measured times; ``Tm`` (``r × n``) and ``scale`` (``r``): the rows of its
    :math:`T(0)` and their scales.  The new window's magnitudes :math:`a_q`: on the prior,
    :math:`\sum_r \mathrm{scale}_r |(T_m g_q)_r|` (the last window's map from its start applied to the new prior's
    generators); on the noise of a time, the last window's at the same distance from the window's end (the oldest
    when the new window is longer; for a measured time, the last window's nearest measured time, the earlier on a
    tie).  Then :math:`W_q = 1/\max(a_q, \delta\max_q a_q)`, as in the reweightings.  Writes ``W``."""
    n, q0 = G0.shape
    Lp, L = known_prev.shape[0], measured.shape[0]
    times_p = 0
    for j in range(Lp):
        if known_prev[j]:
            times_p += 1
    q0p = row.shape[0] - Lp * nw - times_p * nv
    X = np.dot(Tm, G0)  # (r, q0)
    for q in range(q0):
        W[q] = 0.0
    for r in range(Tm.shape[0]):
        for q in range(q0):
            W[q] += abs(X[r, q]) * scale[r]
    for j in range(L):
        jp = max(Lp - L + j, 0)
        for q in range(nw):
            W[q0 + j * nw + q] = abs(row[q0p + jp * nw + q])
    tt_old = np.full(Lp, -1)
    c = 0
    for jp in range(Lp):
        if known_prev[jp]:
            tt_old[jp] = c
            c += 1
    tt = 0
    for j in range(L):
        if measured[j]:
            target = Lp - L + j
            near = -1
            for jp in range(Lp):
                if known_prev[jp] and (near < 0 or abs(jp - target) < abs(near - target)):
                    near = jp
            for q in range(nv):
                W[q0 + L * nw + tt * nv + q] = abs(row[q0p + Lp * nw + tt_old[near] * nv + q])
            tt += 1
    _irls_weights(W, delta, W)


@numba.njit(cache=True)
def _relative_residuals(RP, resT, rad, out):  # pragma: no cover - compiled
    """``out[q] = sum_i |R_iq| / rad_i`` over the states ``i`` in increasing order (``RP``: the residuals on the prior
    generators, ``(n, q0)``; ``resT``: on the noise columns, transposed, ``(Q, n)``): what the shared reweighting
    and the next window's warm start read (module docstring)."""
    n, q0 = RP.shape
    inv = np.empty(n)
    for i in range(n):
        inv[i] = 1.0 / rad[i] if rad[i] > 0.0 else 0.0
    for q in range(out.shape[0]):
        out[q] = 0.0
    for i in range(n):
        for q in range(q0):
            out[q] += abs(RP[i, q]) * inv[i]
    for q in range(resT.shape[0]):
        for i in range(n):
            out[q0 + q] += abs(resT[q, i]) * inv[i]


#: The carried weights of a window that starts cold (:func:`window_estimate_sparse`'s last four arguments): none.
COLD = (np.empty((0, 0)), np.empty((0, 0, 0)), np.empty((0, 0)), np.empty(0, dtype=np.bool_))


@numba.njit(cache=True)
def window_estimate(A, C, E, V, drive, measured, Y, c0, G0, shared, delta, extra,  # pragma: no cover
                    gain, iterations, margin, states, carried_agg, carried_T0, carried_rad, carried_measured, carry):
    r"""Per filter and state, the window's estimate of ``x(t+1)`` and its radius (module docstring): the
    nonzeros of ``A`` and ``E`` found (:func:`sparse_rows`, :func:`sparse_columns`), then
    :func:`window_estimate_sparse` (same parameters and returns)."""
    aptr, acol, aval = sparse_rows(A)
    eptr, erow, evals = sparse_columns(E)
    cptr, crow, cval = sparse_columns(A)
    return window_estimate_sparse(A, C, E, V, drive, measured, Y, c0, G0, shared, delta, extra, gain, iterations,
                                  margin, states, aptr, acol, aval, eptr, erow, evals, cptr, crow, cval,
                                  carried_agg, carried_T0, carried_rad, carried_measured, carry)


@numba.njit(cache=True)
def window_estimate_sparse(A, C, E, V, drive, measured, Y, c0, G0, shared, delta, extra,  # pragma: no cover
                           gain, iterations, margin, states, aptr, acol, aval, eptr, erow, evals, cptr, crow,
                           cval, carried_agg, carried_T0, carried_rad, carried_measured, carry):
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
    shared : int
        Shared reweighted solves after the first (``>= 0``; one Kalman recursion for all states).
    delta : float
        Relative floor of the IRLS weights' residuals.
    extra : int
        At most this many more solves, shared and per state, each while the last tightened the radius (the
        largest, for the shared ones) by more than ``gain``.
    gain : float
        Relative tightening that earns another solve.
    iterations : int
        Per-state reweighted solves (``>= 0``, then at most ``extra`` more while they tighten) for the states
        solved one by one (module docstring).
    margin : float
        Relative margin of the states solved one by one (``< 0``: none).
    states : int
        At most this many states solved one by one per filter.
    aptr, acol, aval : ndarray
        The nonzeros of ``A`` by row (:func:`sparse_rows`; those of a time-invariant plant's window are found once
        by the caller).
    eptr, erow, evals : ndarray
        The nonzeros of ``E`` by column (:func:`sparse_columns`).
    cptr, crow, cval : ndarray
        The nonzeros of ``A`` by column (:func:`sparse_columns`; the products with :math:`A^\top`).
    carried_agg, carried_T0, carried_rad, carried_measured : ndarray
        The last window's ``agg``, ``T0``, ``rad`` (returned below) and measured times: the shared weights start
        from them (module docstring, *Warm start*; :data:`COLD`, empty arrays: from the inverse column lengths, and
        also when this window measures a time but the last measured none).
    carry : bool
        Whether to return what the next window's warm start reads (``agg``, ``T0``, ``rad``; zeros otherwise).

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
    agg : ndarray, shape (K, q0 + Q)
        The last shared solve's relative residuals :math:`\sum_i |R_{iq}| / \rho_i` (what the next window's warm
        start reads).
    T0 : ndarray, shape (K, n, n)
        That solve's :math:`T(0)` (row ``i``: state ``i``'s map from the window's start).
    rad : ndarray, shape (K, n)
        That solve's radii :math:`\rho_i` (before the per-state solves and the rounding allowance).
    """
    L, n = A.shape[0], A.shape[1]
    p, nw, nv = C.shape[1], E.shape[2], V.shape[2]
    K, q0 = G0.shape[0], G0.shape[2]
    times = 0
    for j in range(L):
        if measured[j]:
            times += 1
    m = times * p
    Lnw = L * nw
    Qn = Lnw + times * nv
    # first weights of the noise columns: inverse lengths of the columns of (X, H), by the backward Gramian
    # O(s) = A^T O(s+1) A + C^T C [measured s], O(L) = I: the column of w(s, q) has length^2 E_q^T O(s+1) E_q
    wn = np.zeros(Qn)
    times_prev = 0
    for j in range(carried_measured.shape[0]):
        if carried_measured[j]:
            times_prev += 1
    warm = carried_measured.shape[0] > 0 and (times == 0 or times_prev > 0)
    if not warm:  # cold: the Gramian's inverse column lengths
        O = np.eye(n)
        tmp = np.empty((n, n))
        tt = times
        for j in range(L - 1, -1, -1):
            for q in range(nw):  # over the nonzeros of E's column (the terms skipped are exact zeros)
                s = 0.0
                for za in range(eptr[j, q], eptr[j, q + 1]):
                    fa = evals[j, za]
                    a = erow[j, za]
                    for zb in range(eptr[j, q], eptr[j, q + 1]):
                        s += fa * O[a, erow[j, zb]] * evals[j, zb]
                wn[j * nw + q] = 1.0 / np.sqrt(s) if s > 0.0 else 0.0
            # O <- A^T O A + C^T C, over the nonzeros of A (the same sums, in the same order)
            _times_sparse(cptr, crow, cval, j, O, n, tmp)  # tmp = A^T O (over A's columns)
            _times_sparse(cptr, crow, cval, j, tmp.T, n, O, True)  # O = A^T tmp^T = (tmp A)^T (a view; symmetric)
            if measured[j]:
                tt -= 1
                for c in range(p):
                    for a in range(n):
                        f = C[j, c, a]
                        if f != 0.0:
                            for b in range(n):
                                O[a, b] += f * C[j, c, b]
                for q in range(nv):
                    s = 0.0
                    for c in range(p):
                        s += V[j, c, q] * V[j, c, q]
                    wn[Lnw + tt * nv + q] = 1.0 / np.sqrt(s) if s > 0.0 else 0.0
    xhat = np.empty((K, n))
    radius = np.empty((K, n))
    lam_out = np.zeros((K, n, m))
    R_out = np.zeros((K, n, q0 + Qn))
    agg_out = np.zeros((K, q0 + Qn))
    T0_out = np.zeros((K, n, n))
    rad_out = np.zeros((K, n))
    Kg = np.zeros((times, p, n))  # the Kalman gains of the measured times, transposed (one solve's)
    for k in range(K):
        Gk = np.ascontiguousarray(G0[k])
        # centre and magnitudes over the window
        xc = c0[k].copy()
        zm = np.empty(n)
        for a in range(n):
            s = 0.0
            for q in range(q0):
                s += abs(Gk[a, q])
            zm[a] = abs(xc[a]) + s
        resid = np.zeros(m)
        magy = np.zeros(m)
        nx = np.empty(n)
        nm = np.empty(n)
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
            for a in range(n):
                s = drive[j, a]
                sm = abs(drive[j, a])
                for z in range(aptr[j, a], aptr[j, a + 1]):  # over the nonzeros of A's row (increasing e)
                    f = aval[j, z]
                    e = acol[j, z]
                    s += f * xc[e]
                    sm += abs(f) * zm[e]
                for q in range(nw):
                    sm += abs(E[j, a, q])
                nx[a] = s
                nm[a] = sm
            xc, nx = nx, xc  # two buffers each, alternately (no allocation per time)
            zm, nm = nm, zm
        best = np.full(n, np.inf)
        lam_best = np.zeros((n, m))
        W = np.empty(q0 + Qn)
        for q in range(q0):  # first weights of the prior: inverse generator lengths
            s = 0.0
            for a in range(n):
                s += Gk[a, q] * Gk[a, q]
            W[q] = 1.0 / np.sqrt(s) if s > 0.0 else 0.0
        for q in range(Qn):
            W[q0 + q] = wn[q]
        if warm:  # the weights carried from the last step
            invr = np.empty(n)
            for i in range(n):
                invr[i] = 1.0 / carried_rad[k, i] if carried_rad[k, i] > 0.0 else 0.0
            _warm_weights(carried_agg[k], carried_T0[k], invr, carried_measured, measured, Gk, nw, nv, delta, W)
        GW = np.empty((n, q0), dtype=np.float32)
        GkT32, inv32, colmax = _single(Gk)
        resT = np.empty((Qn, n))
        lamT = np.zeros((m, n))
        rad = np.empty(n)
        agg = np.empty(q0 + Qn)
        it = 0
        top = np.inf
        # --- shared solves: one Kalman recursion for every state (nothing measured: the prediction alone) -------
        while True:
            if m > 0:
                S = _prior_covariance(Gk, GkT32, inv32, colmax, W, GW)  # G0 W G0^T
                _kalman_gains(A, C, E, V, measured, S, W, q0, Kg, aptr, acol, aval, eptr, erow, evals)
            TT = np.eye(n)
            # the weights of every state (m, n) from the one filter's gains, and their residuals
            _residuals(A, C, E, V, measured, Kg, lamT, TT, resT, cptr, crow, cval, eptr, erow, evals)
            RP = np.dot(np.ascontiguousarray(TT.T), Gk)  # residual on the prior generators, (n, q0)
            rad[:] = 0.0
            add_abs_rows(RP, q0, rad)
            for q in range(Qn):
                for e in range(n):
                    rad[e] += abs(resT[q, e])
            for i in range(n):
                if rad[i] < best[i]:  # keep the best solve per state (every solve is a valid estimate)
                    best[i] = rad[i]
                    for q in range(q0):
                        R_out[k, i, q] = RP[i, q]
                    for q in range(Qn):
                        R_out[k, i, q0 + q] = resT[q, i]
                    for r in range(m):
                        lam_best[i, r] = lamT[r, i]
            newtop = 0.0
            for i in range(n):
                newtop = max(newtop, best[i])
            improved = it > 0 and newtop < top * (1.0 - gain)  # a reweighting tightened the largest radius
            top = newtop
            it += 1
            if m == 0 or it > shared + extra or (it > shared and not improved):
                break
            # shared weights: each state's residual, relative to its radius, summed over the states
            _relative_residuals(RP, resT, rad, agg)
            _irls_weights(agg, delta, W)
        if carry:  # what the next step's first weights start from: the last shared solve's relative residuals
            _relative_residuals(RP, resT, rad, agg_out[k])
            rad_out[k] = rad
            T0_out[k] = TT.T
        # --- per-state solves for the states near the largest radius ----------------------------------------
        if m > 0 and margin >= 0.0:
            lam1 = np.empty(m)
            res = np.empty(q0 + Qn)  # the state's residuals: on the prior, then on the noise columns
            Wi = np.empty(q0 + Qn)
            refined = np.zeros(n, dtype=np.bool_)
            count = 0
            while count < states:  # the unrefined state of largest radius, while within the margin of the largest radius
                i = -1
                top = 0.0
                for e in range(n):
                    top = max(top, best[e])
                    if not refined[e] and (i < 0 or best[e] > best[i]):
                        i = e
                if i < 0 or best[i] < (1.0 - margin) * top:
                    break
                refined[i] = True
                count += 1
                _irls_weights(R_out[k, i], delta, Wi)  # from the state's best residual so far
                sol = 0
                while True:
                    S = _prior_covariance(Gk, GkT32, inv32, colmax, Wi, GW)
                    _kalman_gains(A, C, E, V, measured, S, Wi, q0, Kg, aptr, acol, aval, eptr, erow, evals)
                    T1 = np.zeros((n, 1))
                    T1[i, 0] = 1.0
                    _residuals_one(A, C, E, V, measured, Kg, lam1, T1[:, 0], res[q0:], aptr, acol, aval, eptr, erow,
                                   evals)
                    rp = np.dot(T1.T, Gk)
                    r1 = 0.0
                    for q in range(q0):
                        res[q] = rp[0, q]
                    for q in range(q0 + Qn):
                        r1 += abs(res[q])
                    improved = r1 < best[i] * (1.0 - gain)
                    if r1 < best[i]:
                        best[i] = r1
                        R_out[k, i, :] = res
                        for r in range(m):
                            lam_best[i, r] = lam1[r]
                    sol += 1
                    if sol > iterations + extra or (sol > iterations and not improved):
                        break
                    _irls_weights(res, delta, Wi)
        for i in range(n):
            # the estimate, its magnitude and the rounding allowance (module docstring)
            est = xc[i]
            mag = zm[i] + abs(xc[i])
            for r in range(m):
                est += lam_best[i, r] * resid[r]
                mag += abs(lam_best[i, r]) * (magy[r] + abs(resid[r]))
            xhat[k, i] = est
            radius[k, i] = rounding_allowance_compiled(best[i], (L + 2) * (n + m + q0 + Qn), mag)
            lam_out[k, i, :] = lam_best[i]
    return xhat, radius, lam_out, R_out, agg_out, T0_out, rad_out
