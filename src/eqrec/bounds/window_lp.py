r"""The window with its data: the exact interval hull of the states consistent with the measured values.

The window of :mod:`eqrec.bounds.window` writes every state of the window as linear in the unit uncertainty
:math:`\zeta = (\varepsilon, w(s_0..t), v(\text{measured}))` given a zonotope
:math:`\langle c_0, G_0\rangle \ni x(s_0)`:

.. math::
    x(t+1) = \hat x^{\rm pred} + X\zeta, \qquad x(t) = \hat x^{\rm filt} + X^{\rm f}\zeta, \qquad
    y = \hat y^{\rm pred} + H\zeta ,

and there chooses, per state, weights :math:`\lambda_i` that do not look at the measured values (a linear
estimate).  Here the measured values enter: the set of states consistent with the zonotope at :math:`s_0` (or a
constrained zonotope, ``prior_rows``) and the data is the *constrained zonotope* (Scott, Raimondo, Marseglia,
Braatz, "Constrained zonotopes: a new tool for set-based estimation and fault detection", Automatica 69, 2016)

.. math::
    \{\hat x + X\zeta \;:\; H\zeta = r,\ \ \|\zeta\|_\infty \le 1\}, \qquad r = y - \hat y^{\rm pred},

and its exact interval hull is two linear programs per state, :math:`\max` and :math:`\min` of :math:`X_i\zeta`
(:func:`lp_hull`), solved through the project's LP layer (:func:`eqrec.lp.box_simplex.box_lp_multipliers`: a
compiled dense dual simplex on small windows, a HiGHS model on large ones; every objective warm-started from the
previous one's basis).

Soundness: the bound comes from the dual, not from the primal optimum
---------------------------------------------------------------------
An LP optimum is accurate to the solver's tolerances only, so it is not used as the bound.  For **any** row
multipliers :math:`y` (one per row of the LP, the ranged rows :math:`\underline b \le M\zeta \le \overline b`
with :math:`M` the rows of ``prior_rows`` and :math:`H`), weak duality gives, for every feasible :math:`\zeta`,

.. math::
    X_i\zeta = y^\top M\zeta + (X_i - y^\top M)\zeta
    \le \sum_j \max(y_j\underline b_j,\ y_j\overline b_j) + \|X_i - y^\top M\|_1 ,

and the same with :math:`-X_i` for the lower end. The multipliers are the row duals of each optimum (the dense
solver's :math:`B^{-\top}c_B`, or HiGHS's; so the bound is the optimum when the duals are exact), and the right-hand
side is evaluated in floating point with an allowance :math:`\kappa u\,\mu` rounded upward (``u`` the unit roundoff,
:math:`\mu` the magnitudes of every quantity of the computation: the propagated :math:`|c_0| + \sum|G_0|`, the
drives, the noise row sums, the measured values, :math:`|y|` times the rows' magnitudes; :math:`\kappa =
4(L+2)(n + m + Q)` as in :mod:`eqrec.bounds.window`). A solve that ends without an optimum keeps the multipliers it ended with
(any :math:`y` gives a bound; :math:`y = 0` gives the prediction's own bound :math:`\|X_i\|_1`). So the hull
reported always contains the exact one, and is equal to it up to the duals' accuracy and the allowance.

Cost
----
Building the window costs :math:`O(L n^2 (n + L n_w) + m q_0 n)`, compiled (:func:`_window_kernel`); each LP has
``m`` rows (the measured outputs, and the prior's rows if any) and :math:`q_0 + L n_w + m_v` columns, all bounded
(the simplex handles the unit box implicitly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from eqrec.lp.box_simplex import box_lp_multipliers

_U = np.finfo(float).eps / 2



@dataclass(frozen=True)
class WindowSet:
    r"""The window's constrained zonotope (module docstring).

    Parameters
    ----------
    centre_pred, centre_filt : numpy.ndarray, shape (n,)
        :math:`\hat x^{\rm pred}` (nominal :math:`x(t+1)`) and :math:`\hat x^{\rm filt}` (nominal :math:`x(t)`).
    X_pred, X_filt : numpy.ndarray, shape (n, Q)
        Rows of :math:`x(t+1)` and :math:`x(t)` in :math:`\zeta`.
    M : numpy.ndarray, shape (m + k, Q)
        The constraint rows: the prior's rows (if any), then the measured outputs.
    lower, upper : numpy.ndarray, shape (m + k,)
        Their bounds (the prior's rows' bounds, then :math:`r` for both).
    mag_pred, mag_filt : numpy.ndarray, shape (n,)
        Magnitudes of the computation of each state's row and nominal value (rounding allowance).
    mag_rows : numpy.ndarray, shape (m + k,)
        Magnitudes of each constraint row's computation.
    kappa : float
        The allowance's factor :math:`4(L+2)(n + m + Q)`.
    """

    centre_pred: np.ndarray
    centre_filt: np.ndarray
    X_pred: np.ndarray
    X_filt: np.ndarray
    M: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    mag_pred: np.ndarray
    mag_filt: np.ndarray
    mag_rows: np.ndarray
    kappa: float


def window_set(A: np.ndarray, C: np.ndarray, E: np.ndarray, V: np.ndarray, drive: np.ndarray, measured: np.ndarray,
               Y: np.ndarray, c0: np.ndarray, G0: np.ndarray,
               prior_rows: "tuple[np.ndarray, np.ndarray] | None" = None) -> WindowSet:
    r"""The constrained zonotope of :math:`x(t)` and :math:`x(t+1)` given the zonotope at :math:`s_0` and the data.

    Parameters
    ----------
    A, C, E, V : numpy.ndarray, shapes (L, n, n), (L, p, n), (L, n, nw), (L, p, nv)
        The plant over the window (``E``, ``V`` scaled by the noise bounds; eq. (3) of the prefix-based paper).
    drive : numpy.ndarray, shape (L, n)
        :math:`B u + f` per time.
    measured : numpy.ndarray of bool, shape (L,)
        Which times' outputs are known.
    Y : numpy.ndarray, shape (L, p)
        Their values (rows of unmeasured times ignored).
    c0 : numpy.ndarray, shape (n,)
        Centre of the zonotope of :math:`x(s_0)`.
    G0 : numpy.ndarray, shape (n, q0)
        Its generators.
    prior_rows : tuple of numpy.ndarray, optional
        ``(A0, b0)``, shapes ``(k, q0)`` and ``(k,)``: the prior at :math:`s_0` is the constrained zonotope
        :math:`\{c_0 + G_0\varepsilon : A_0\varepsilon = b_0\}` (:mod:`eqrec.bounds.constrained`); or
        ``(A0, b0_lower, b0_upper)``: ranged rows :math:`b_{0,\rm lower} \le A_0\varepsilon \le b_{0,\rm upper}`
        (the zonotope within a box, ``A0 = G0``: :class:`eqrec.estimators.exact_set.ExactSetEstimator`,
        ``prior="zonotope+box"``); ``None``: the zonotope.

    Returns
    -------
    WindowSet
        The rows and bounds of the set (module docstring).
    """
    L, n = drive.shape
    p, nw, nv, q0 = C.shape[1], E.shape[2], V.shape[2], G0.shape[1]
    measured = np.require(measured, np.bool_, ("C", "W"))
    k_meas = int(np.count_nonzero(measured))
    Q = q0 + L * nw + k_meas * nv
    # C-contiguous and writable, as a frozen system's arrays are not: one compiled kernel serves every plant
    xc, xf, X_pred, X_filt, Mm, r, magy, zm, zf = _window_kernel(
        *(np.require(a, float, ("C", "W")) for a in (A, C, E, V, drive)), measured,
        *(np.require(a, float, ("C", "W")) for a in (Y, c0, G0)))
    blocks, rhs, mags = [], [], []
    lows = []
    if prior_rows is not None and prior_rows[0].shape[0]:
        A0, b0 = np.asarray(prior_rows[0], float), np.asarray(prior_rows[1], float)
        b0_hi = b0 if len(prior_rows) == 2 else np.asarray(prior_rows[2], float)
        blocks.append(np.concatenate([A0, np.zeros((A0.shape[0], Q - q0))], axis=1))
        lows.append(b0)
        rhs.append(b0_hi)
        mags.append(np.maximum(np.abs(b0), np.abs(b0_hi)) + np.abs(A0).sum(axis=1))
    if k_meas:
        blocks.append(Mm)
        lows.append(r)
        rhs.append(r)
        mags.append(magy)
    M = np.concatenate(blocks) if blocks else np.zeros((0, Q))
    lower = np.concatenate(lows) if lows else np.zeros(0)
    upper = np.concatenate(rhs) if rhs else np.zeros(0)
    mags = np.concatenate(mags) if mags else np.zeros(0)
    kappa = 4.0 * (L + 2) * (n + M.shape[0] + Q)
    return WindowSet(xc, xf, X_pred, X_filt, M, lower, upper, zm + np.abs(xc), zf + np.abs(xf), mags, kappa)


@numba.njit(cache=True)
def _window_kernel(A, C, E, V, drive, measured, Y, c0, G0):
    r"""The propagation of :func:`window_set` (compiled): the nominal states, the rows of ``x(t+1)`` and ``x(t)`` in
    :math:`\zeta`, the measured rows and residuals, and the magnitudes of their computation."""
    L, n = drive.shape
    p, nw, nv, q0 = C.shape[1], E.shape[2], V.shape[2], G0.shape[1]
    k_meas = 0
    for j in range(L):
        k_meas += measured[j]
    Q = q0 + L * nw + k_meas * nv
    Phi = np.eye(n)
    NwT = np.zeros((L * nw, n))  # the process-noise columns of the current state, transposed (rows: columns)
    xc = c0.copy()
    zm = np.abs(c0) + np.abs(G0).sum(axis=1)
    Mm = np.zeros((k_meas * p, Q))
    r = np.zeros(k_meas * p)
    magy = np.zeros(k_meas * p)
    Phi_f = Phi.copy()
    NwT_f = NwT.copy()
    xf = xc.copy()
    zf = zm.copy()
    ri = 0
    col_v = q0 + L * nw
    for j in range(L):
        if j == L - 1:
            Phi_f = Phi.copy()
            NwT_f = NwT.copy()
            xf = xc.copy()
            zf = zm.copy()
        if measured[j]:
            Cj = np.ascontiguousarray(C[j])
            yc = Cj @ xc
            Mm[ri:ri + p, :q0] = (Cj @ Phi) @ G0
            if j:
                Mm[ri:ri + p, q0:q0 + j * nw] = (NwT[:j * nw] @ np.ascontiguousarray(Cj.T)).T
            Mm[ri:ri + p, col_v:col_v + nv] = V[j]
            col_v += nv
            r[ri:ri + p] = Y[j] - yc
            magy[ri:ri + p] = np.abs(Cj) @ zm + np.abs(V[j]).sum(axis=1) + np.abs(Y[j]) + np.abs(yc)
            ri += p
        Aj = np.ascontiguousarray(A[j])
        Phi = Aj @ Phi
        if j:
            NwT[:j * nw] = NwT[:j * nw] @ np.ascontiguousarray(Aj.T)
        NwT[j * nw:(j + 1) * nw] = E[j].T
        zm = np.abs(Aj) @ zm + np.abs(drive[j]) + np.abs(E[j]).sum(axis=1)
        xc = Aj @ xc + drive[j]
    X_pred = np.zeros((n, Q))
    X_filt = np.zeros((n, Q))
    X_pred[:, :q0] = Phi @ G0
    X_pred[:, q0:q0 + L * nw] = NwT.T
    X_filt[:, :q0] = Phi_f @ G0
    X_filt[:, q0:q0 + L * nw] = NwT_f.T
    return xc, xf, X_pred, X_filt, Mm, r, magy, zm, zf


def dual_bound(row: np.ndarray, M: np.ndarray, lower: np.ndarray, upper: np.ndarray, y: np.ndarray,
               mag_row: float, mag_rows: np.ndarray, kappa: float) -> float:
    r"""An upper bound of :math:`\max\{c^\top\zeta : \underline b \le M\zeta \le \overline b, |\zeta| \le 1\}`
    from any multipliers ``y`` (weak duality, module docstring), rounded upward.

    Parameters
    ----------
    row : numpy.ndarray, shape (Q,)
        The objective :math:`c`.
    M : numpy.ndarray, shape (k, Q)
        The constraint rows.
    lower, upper : numpy.ndarray, shape (k,)
        Their bounds.
    y : numpy.ndarray, shape (k,)
        Any multipliers.
    mag_row : float
        Magnitude of the objective's computation.
    mag_rows : numpy.ndarray, shape (k,)
        Magnitudes of the rows' computations.
    kappa : float
        The allowance's factor.

    Returns
    -------
    float
        :math:`\sum_j \max(y_j\underline b_j, y_j\overline b_j) + \|c - M^\top y\|_1 + \kappa u\mu`.
    """
    # one objective of bounds_from_multipliers (one implementation of the bound and its allowance)
    return float(bounds_from_multipliers(np.asarray(row, dtype=float)[None], M, lower, upper,
                                         np.asarray(y, dtype=float)[None], np.array([mag_row], dtype=float),
                                         mag_rows, kappa)[0])


def bounds_from_multipliers(rows: np.ndarray, M: np.ndarray, lower: np.ndarray, upper: np.ndarray, y: np.ndarray,
                            mag_rows_obj: np.ndarray, mag_rows: np.ndarray, kappa: float) -> np.ndarray:
    r""":func:`dual_bound` of several objectives at once (the same sums, row by row).

    Parameters
    ----------
    rows : numpy.ndarray, shape (K, Q)
        The objectives.
    M : numpy.ndarray, shape (k, Q)
        The constraint rows.
    lower, upper : numpy.ndarray, shape (k,)
        Their bounds.
    y : numpy.ndarray, shape (K, k)
        Multipliers per objective (any).
    mag_rows_obj : numpy.ndarray, shape (K,)
        Magnitude of each objective's computation.
    mag_rows : numpy.ndarray, shape (k,)
        Magnitudes of the rows' computations.
    kappa : float
        The allowance's factor.

    Returns
    -------
    numpy.ndarray, shape (K,)
        Per objective, the bound of :func:`dual_bound`, rounded upward.
    """
    res = rows - y @ M
    l1 = np.abs(res).sum(axis=1)
    dual = np.maximum(y * lower, y * upper).sum(axis=1)
    ay = np.abs(y)
    mu = mag_rows_obj + ay @ mag_rows + l1 + np.abs(dual) + np.abs(rows).sum(axis=1) + ay @ np.abs(M).sum(axis=1)
    return np.nextafter(dual + l1 + kappa * _U * mu, np.inf)


def lp_hull(ws: WindowSet, which: str = "pred", solver: str = "auto") -> tuple[np.ndarray, np.ndarray, int]:
    r"""Per state, a lower and an upper end of the window set's interval hull, each a guarantee (module docstring).

    Parameters
    ----------
    ws : WindowSet
        The set.
    which : {"pred", "filt"}
        The hull of :math:`x(t+1)` or of :math:`x(t)`.
    solver : str, optional
        The box-LP solver of :func:`eqrec.lp.box_simplex.box_lp_multipliers` (default ``"auto"``: the compiled
        dense dual simplex on small windows, one warm-started HiGHS model on large ones).  Either way each end is
        the weak-duality bound of the multipliers the solve ended with, so the choice changes the tightness only.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (n,)
        :math:`\underline x \le x \le \overline x` for every state of the set (rounded outward).
    fallbacks : int
        How many of the ``2n`` LPs ended without an optimum (their end is the bound of the multipliers the solve
        ended with, still a guarantee).
    """
    centre, X, mag = (ws.centre_pred, ws.X_pred, ws.mag_pred) if which == "pred" else \
        (ws.centre_filt, ws.X_filt, ws.mag_filt)
    n, Q = X.shape
    k = ws.M.shape[0]
    hi = np.empty(n)
    lo = np.empty(n)
    fallbacks = 0
    if k == 0:  # no constraint: the zonotope's own hull
        for i in range(n):
            hi[i] = dual_bound(X[i], ws.M, ws.lower, ws.upper, np.zeros(0), mag[i], ws.mag_rows, ws.kappa)
        lo[:] = -hi
    else:
        # the maxima of the states in order, then the minima in reverse: each objective starts from the basis of
        # the one before, and neighbouring states share more of their optimal vertex than a state's
        # maximum and minimum do
        objectives = np.concatenate([X, -X[::-1]])
        ones = np.ones(Q)
        y, optimal = box_lp_multipliers(ws.M, ws.lower, ws.upper, -ones, ones, objectives, solver)
        fallbacks = int(np.count_nonzero(~optimal))
        bounds = bounds_from_multipliers(objectives, ws.M, ws.lower, ws.upper, y,
                                         np.concatenate([mag, mag[::-1]]), ws.mag_rows, ws.kappa)
        hi[:] = bounds[:n]
        lo[:] = -bounds[n:][::-1]
    upper = np.nextafter(centre + hi + 2 * _U * (np.abs(centre) + np.abs(hi)), np.inf)
    lower = np.nextafter(centre + lo - 2 * _U * (np.abs(centre) + np.abs(lo)), -np.inf)
    return lower, upper, fallbacks
