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
solver's :math:`B^{-\top}c_B`, or HiGHS's; so the bound is the optimum when the duals are exact). A solve that ends
without an optimum keeps the multipliers it ended with (any :math:`y` gives a bound; :math:`y = 0` gives the
prediction's own bound :math:`\|X_i\|_1`). The rows, centres and residuals are computed in floating point, so the
bound is evaluated on the computed :math:`\hat X_i, \hat M, \hat r, \hat x` with two allowances, rounded upward:

.. math::
    \hat x_i + \sum_j \max(y_j\underline{\hat b}_j, y_j\overline{\hat b}_j) + \|\hat X_i - y^\top\hat M\|_1
    + e_i + |y|^\top e_{\rm rows} + \kappa u\,\mu ,

where :math:`e_i \ge \|\hat X_i - X_i\|_1 + |\hat x_i - x_i|` and :math:`e_{{\rm rows},k} \ge \|\hat M_k - M_k\|_1 +
|\hat r_k - r_k|` bound the computed data's errors (below; the prior's rows are given data: no error), and
:math:`\kappa u\mu` with :math:`\kappa = 2(k + Q + 8)` (``k`` rows) and :math:`\mu` the magnitudes of the
evaluation (:math:`|\hat X_i|`, :math:`|y|^\top|\hat M|`, :math:`|y|^\top\max(|\underline b|, |\overline b|)`,
the sums and the :math:`e` terms) covers the evaluation's own rounding: a product :math:`y^\top\hat M` of ``k``
terms and a subtraction, each of ``Q`` entries, (:math:`\gamma_{k+1}`), the sums of ``Q`` and ``k`` terms, three
additions, and the magnitudes' own rounding, together below :math:`\gamma_{k+Q+8} \le 1.01(k+Q+8)u` relative to
:math:`\mu`, half of :math:`\kappa u`; plus :math:`\kappa(Q+1)\eta` for products that underflow (:math:`\eta =
2^{-1074}`). Since :math:`X_i\zeta = y^\top r + (X_i - y^\top M)\zeta` for every :math:`\zeta` of the exact set,
the right-hand side bounds :math:`x_i + X_i\zeta` there. So the hull reported always contains the exact one, and
is equal to it up to the duals' accuracy and the allowances.

The computed data's errors: every computed vector of the window obeys a linear recursion *exactly*,
:math:`\hat v_{j+1} = A_j\hat v_j + d_j + \Delta_j`, with :math:`\hat v_j` the computed columns of :math:`\Phi G_0`
and of the noises and the computed centre, and the local rounding of the step bounded componentwise from the
**computed** quantities of that step (``n``-term sums, one addition of the drive :math:`d_j = Bu_j + f`, itself
computed with ``drive_terms`` :math:`= m + 1` terms of magnitude :math:`|B||u_j| + |f|`):

.. math::
    \textstyle\sum_{\rm columns}|\Delta_j| \le \delta_j = 2\gamma_K\bigl(|A_j|(s_j + |\hat x_j|) + |B||u_j| + |f|
    + |E_j|\mathbf 1\bigr) + 2u|E_j|\mathbf 1 + (Q+2)(n+2)\eta , \qquad K = n + n_w + m + 3,

:math:`s_j` the row sums of the computed columns' magnitudes, :math:`\gamma_K \le 1.01Ku`. One
:math:`\gamma_K` covers the estimator's step, :math:`\gamma_{n+1}` for :math:`A_j\hat x_j + \hat d_j` plus
:math:`\gamma_{m+1}` for :math:`\hat d_j` (where :math:`Bu` and :math:`f` cancel, :math:`|\hat d_j|` is far below
the magnitudes of its computation, so those are what enter); the other covers a **simulated true state**
:math:`x(s+1) = \mathrm{fl}(Ax + Bu + f + Ew)` of the same size (:math:`|x(s)| \le s_j + |\hat x_j|` up to terms
of order :math:`u`, which the factor 1.01 and the rounding up below absorb), the convention of every bound of the
package (:mod:`eqrec.bounds.rounding`): the simulation's rounding acts as a small extra noise, carried by the same
products. The :math:`2u|E_j|\mathbf 1` covers ``E`` scaled by the noise bound in floating point (``V`` likewise
in the measured rows), the last term the products' underflow. Hence :math:`\hat v_T - v_T = \sum_{i<T}\Phi(T, i+1)\Delta_i`
exactly, :math:`\Phi(T, i+1) = A_{T-1}\cdots A_{i+1}`, and for any rows :math:`W_0`

.. math::
    \textstyle\sum_{\rm columns}|W_0(\hat v_T - v_T)| \le \sum_{i<T}|W_0\Phi(T, i+1)|\,\delta_i .

With :math:`W_0 = I` and :math:`T = L` (:math:`T = L-1`) this is :math:`e_i` of the predicted (filtered) rows; with
:math:`W_0 = C_j` and :math:`T = j`, the measured row's error from the earlier times, to which its own rounding
:math:`2\gamma_{n+n_v+2}(|C_j|(s_j + |\hat x_j|) + |y_j| + |V_j|\mathbf 1) + 2u|V_j|\mathbf 1` is added (the rows
:math:`C_j\hat X_j` and the residual :math:`y_j - C_j\hat x_j`, and a simulated :math:`y = \mathrm{fl}(Cx + Vv)`). The factors :math:`|W_0\Phi(T, i+1)|` decay like the true products, not
like :math:`|A|^{T-i}` (the earlier allowance propagated magnitudes through :math:`|A|` and grew like
:math:`\rho(|A|)^L`, above 1 for many plants with :math:`\rho(A) < 1`). They are computed as backward products
:math:`\hat P_{i-1} = \mathrm{fl}(\hat P_i A_i)`, :math:`\hat P_{T-1} = W_0` (:func:`_product_table`, one
table for every time when the window is time-invariant), and the products' own rounding is bounded, not
neglected: after ``k`` products,
:math:`|\hat P - W_0\Phi| \le ((1+\gamma_n)^k - 1)|W_0||A_{T-1}|\cdots|A_{i+1}| + \mathbf 1 z^\top`, so
:math:`|W_0\Phi| \le |\hat P| + 2k(n+1)u\,|W_0||A_{T-1}|\cdots|A_{i+1}| + \mathbf 1 z_k^\top` (the factor
:math:`2k(n+1)u` is about twice the :math:`1.04\,knu` needed, which covers the rounding of its own computation),
with :math:`z_k` the products' underflow (:math:`\le n\eta/2` per entry and product) carried through :math:`|A|`.
Summed against :math:`\delta_i`, these two terms are computed forward in :math:`O(Ln^2)`: with
:math:`a_{j+1} = |A_j|a_j + \delta_j` and :math:`b_{j+1} = |A_j|(b_j + a_j)` (:math:`a_0 = b_0 = 0`),
:math:`\sum_{i<T}(T-1-i)|A_{T-1}|\cdots|A_{i+1}|\delta_i = b_T`, so the rounding term is
:math:`2(n+1)u\,|W_0|b_T`, and the underflow term is at most :math:`2n\eta\sum_{t<T}\mathbf 1^\top a_t`.
The rounding term is of order :math:`u^2\rho(|A|)^k`: tiny,
but kept (``tests/test_window_lp_allowance.py`` builds a product that cancels to 0 in floating point, where only
it covers the error). Each of these bounds is a sum of products of nonnegative floating numbers, at most
``depth = Q + 2n + L + 16`` operations from any leaf to the root (the forward sums :math:`b`, :math:`a` are
deeper, :math:`L(n+2)`: their factors :math:`2(n+1)u` and :math:`2n\eta` are at least 1.9 times what is needed, which
covers that), so rounded to nearest it is at least
:math:`(1-u)^{\rm depth}` times its exact value: it is multiplied by :math:`1 + 2\,{\rm depth}\,u`, an underflow
floor :math:`(L+2)(n+2)(Q+2)\eta` is added, and the result is rounded upward (``np.nextafter``). (All of this
assumes :math:`(Q + n + L + 16)u \le 10^{-3}`, and no overflow.) The data ``A``, ``C``, ``u``, ``y``,
:math:`c_0`, :math:`G_0` and the prior's rows are taken as given; the drive's magnitudes :math:`|B||u| + |f|` are
the caller's (``drive_magnitude``; :class:`eqrec.estimators.exact_set.ExactSetEstimator` passes them).

Measured (``tests/test_window_lp_allowance.py``, the multipliers of the optimum): on the six-state plant of
``tests/test_exact_set.py`` (:math:`\rho(A) = 0.9`, :math:`\rho(|A|) > 1.5`) at windows 40 and 50 the allowance
is at most :math:`1.2\cdot 10^{-10}` and :math:`8\cdot 10^{-12}` of each end's bound, against 0.031 and 0.13
with the magnitudes propagated through :math:`|A|`; on the two carts :math:`3\cdot 10^{-11}` and
:math:`4\cdot 10^{-12}`.

Cost
----
Building the window costs :math:`O(L n^2 (n + L n_w) + m q_0 n)`, compiled (:func:`_window_kernel`); its error
bounds :math:`O(L n^3)` for the two objectives' backward products and :math:`O(L^2 p n^2)` for the measured rows'
(one backward product from each :math:`C_j`); each LP has
``m`` rows (the measured outputs, and the prior's rows if any) and :math:`q_0 + L n_w + m_v` columns, all bounded
(the simplex handles the unit box implicitly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from eqrec.lp.box_simplex import box_lp_solve

_U = np.finfo(float).eps / 2
#: The smallest positive (subnormal) double: the absolute error of a product that underflows is at most half of it.
_ETA = 2.0 ** -1074

#: The label of a column or row new in every window (the prior's): :func:`window_labels`.
NO_LABEL = np.iinfo(np.int64).min



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
        Bounds of the rounding error of each state's computed row and nominal value,
        :math:`e_i \ge \|\hat X_i - X_i\|_1 + |\hat x_i - x_i|` (module docstring, *Soundness*).
    mag_rows : numpy.ndarray, shape (m + k,)
        Bounds of each constraint row's error, :math:`\|\hat M_k - M_k\|_1 + |\hat r_k - r_k|` (0 for the
        prior's rows, given data).
    kappa : float
        The factor of the bound's evaluation allowance, :math:`2(k + Q + 8)` (``k`` rows).
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
               prior_rows: "tuple[np.ndarray, np.ndarray] | None" = None,
               drive_magnitude: "np.ndarray | None" = None, drive_terms: int = 1) -> WindowSet:
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
    drive_magnitude : numpy.ndarray, shape (L, n), optional
        The magnitudes of the drive's computation, :math:`|B||u| + |f|` per time (default ``|drive|``: a drive
        given exactly). With :math:`B u + f` computed in floating point, its rounding is covered only through
        these: where :math:`Bu` and :math:`f` cancel, ``|drive|`` is far below them (module docstring,
        *Soundness*).
    drive_terms : int, optional
        The number of terms of each drive entry's computation (``m + 1`` for :math:`Bu + f`; default 1).

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
    dmag = np.abs(drive) if drive_magnitude is None else drive_magnitude
    # one step's rounding, the estimator's and a simulated true state's (module docstring, *Soundness*):
    # 2 γ_K with K = n + nw + drive_terms + 2 for the state, n + nv + 2 for a measured row; 1.01 K u >= γ_K
    g_step = 2.0 * 1.01 * (n + nw + int(drive_terms) + 2) * _U
    g_meas = 2.0 * 1.01 * (n + nv + 2) * _U
    xc, xf, X_pred, X_filt, Mm, r, err_meas, err_pred, err_filt = _window_kernel(
        *(np.require(a, float, ("C", "W")) for a in (A, C, E, V, drive, dmag)), measured,
        *(np.require(a, float, ("C", "W")) for a in (Y, c0, G0)), g_step, g_meas)
    blocks, rhs, mags = [], [], []
    lows = []
    if prior_rows is not None and prior_rows[0].shape[0]:
        A0, b0 = np.asarray(prior_rows[0], float), np.asarray(prior_rows[1], float)
        b0_hi = b0 if len(prior_rows) == 2 else np.asarray(prior_rows[2], float)
        blocks.append(np.concatenate([A0, np.zeros((A0.shape[0], Q - q0))], axis=1))
        lows.append(b0)
        rhs.append(b0_hi)
        mags.append(np.zeros(A0.shape[0]))  # given rows: no error of their own (their evaluation: kappa)
    if k_meas:
        blocks.append(Mm)
        lows.append(r)
        rhs.append(r)
        mags.append(err_meas)
    M = np.concatenate(blocks) if blocks else np.zeros((0, Q))
    lower = np.concatenate(lows) if lows else np.zeros(0)
    upper = np.concatenate(rhs) if rhs else np.zeros(0)
    mags = np.concatenate(mags) if mags else np.zeros(0)
    kappa = 2.0 * (M.shape[0] + Q + 8)
    return WindowSet(xc, xf, X_pred, X_filt, M, lower, upper, err_pred, err_filt, mags, kappa)


@numba.njit(cache=True)
def _window_kernel(A, C, E, V, drive, dmag, measured, Y, c0, G0, g_step, g_meas):
    r"""The propagation of :func:`window_set` (compiled): the nominal states, the rows of ``x(t+1)`` and ``x(t)`` in
    :math:`\zeta`, the measured rows and residuals, and the bounds of their rounding errors (module docstring,
    *Soundness*).

    Written as explicit loops over the small dimensions, with every array allocated once: the state's map of the
    prior's generators :math:`\Phi G_0` and of the process noise (rows: columns) are carried from one time to the
    next; per time the local error bound :math:`\delta_j` (from the computed vectors of that time), then the
    backward products of :func:`_product_table` carry them to the two objectives' times and to each measured
    time."""
    L, n = drive.shape
    p, nw, nv, q0 = C.shape[1], E.shape[2], V.shape[2], G0.shape[1]
    k_meas = 0
    for j in range(L):
        k_meas += measured[j]
    Q = q0 + L * nw + k_meas * nv
    tiny = (Q + 2.0) * (n + 2.0) * _ETA  # the products' underflow, per entry of a row sum (Q columns, n terms)
    PG = G0.copy()  # Φ G0, the prior's generators mapped to the current time
    NwT = np.zeros((L * nw, n))  # the process-noise columns of the current state, transposed (rows: columns)
    xc = c0.copy()
    Mm = np.zeros((k_meas * p, Q))
    r = np.zeros(k_meas * p)
    local_rows = np.zeros(k_meas * p)  # each measured row's own rounding (its errors of earlier times: below)
    meas_time = np.zeros(k_meas, np.int64)
    delta = np.zeros((L, n))  # δ_j: the local rounding of step j (columns' row sums and centre), module docstring
    fa = np.zeros((L + 1, n))
    fb = np.zeros((L + 1, n))
    zsum = np.zeros(L + 1)
    PG_f = PG.copy()
    NwT_f = NwT.copy()
    xf = xc.copy()
    tmp = np.empty(n)
    srow = np.abs(c0) + np.abs(G0).sum(axis=1)  # s_j + |x̂_j|: the computed state's columns' row sums and centre
    snext = np.empty(n)
    tmpq = np.empty((n, q0))
    ri = 0
    mi = 0
    col_v = q0 + L * nw
    for j in range(L):
        if j == L - 1:
            PG_f[:, :] = PG
            NwT_f[:, :] = NwT
            xf[:] = xc
        if measured[j]:
            meas_time[mi] = j
            mi += 1
            for i in range(p):
                row = ri + i
                yc = 0.0
                mag = 0.0
                for b in range(n):
                    yc += C[j, i, b] * xc[b]
                    mag += abs(C[j, i, b]) * srow[b]
                for c in range(q0):
                    acc = 0.0
                    for b in range(n):
                        acc += C[j, i, b] * PG[b, c]
                    Mm[row, c] = acc
                for k in range(j * nw):
                    acc = 0.0
                    for b in range(n):
                        acc += C[j, i, b] * NwT[k, b]
                    Mm[row, q0 + k] = acc
                vs = 0.0
                for c in range(nv):
                    Mm[row, col_v + c] = V[j, i, c]
                    vs += abs(V[j, i, c])
                r[row] = Y[j, i] - yc
                # C_j X̂_j and y - C_j x̂_j in n-term sums (and one subtraction), a simulated y = C x + V v;
                # η V scaled in floating point
                local_rows[row] = g_meas * (mag + abs(Y[j, i]) + vs) + 2.0 * _U * vs + tiny
            col_v += nv
            ri += p
        for a in range(n):  # δ_j = 2γ_K(|A_j|(s_j + |x̂_j|) + |B||u_j| + |f| + |E_j|1) + 2u|E_j|1 (+ underflow)
            acc = dmag[j, a]
            for b in range(n):
                acc += abs(A[j, a, b]) * srow[b]
            es = 0.0
            for c in range(nw):
                es += abs(E[j, a, c])
            delta[j, a] = g_step * (acc + es) + 2.0 * _U * es + tiny
        # the products' rounding and underflow, as forward sums (module docstring): a_{j+1} = |A_j| a_j + δ_j,
        # b_{j+1} = |A_j|(b_j + a_j), Z_{j+1} = Z_j + 1ᵀa_j
        zsum[j + 1] = zsum[j]
        for a in range(n):
            zsum[j + 1] += fa[j, a]
            acc_a = delta[j, a]
            acc_b = 0.0
            for b in range(n):
                acc_a += abs(A[j, a, b]) * fa[j, b]
                acc_b += abs(A[j, a, b]) * (fb[j, b] + fa[j, b])
            fa[j + 1, a] = acc_a
            fb[j + 1, a] = acc_b
        for a in range(n):  # Φ G0 <- A_j Φ G0; the next s + |x̂| summed with the new columns
            sa = 0.0
            for c in range(q0):
                acc = 0.0
                for b in range(n):
                    acc += A[j, a, b] * PG[b, c]
                tmpq[a, c] = acc
                sa += abs(acc)
            snext[a] = sa
        PG[:, :] = tmpq
        for k in range(j * nw):  # each earlier noise column through A_j
            for a in range(n):
                acc = 0.0
                for b in range(n):
                    acc += A[j, a, b] * NwT[k, b]
                tmp[a] = acc
            for a in range(n):
                NwT[k, a] = tmp[a]
                snext[a] += abs(tmp[a])
        for c in range(nw):
            for a in range(n):
                NwT[j * nw + c, a] = E[j, a, c]
                snext[a] += abs(E[j, a, c])
        for a in range(n):  # x̂ <- A_j x̂ + drive
            acc = 0.0
            for b in range(n):
                acc += A[j, a, b] * xc[b]
            tmp[a] = acc + drive[j, a]
        for a in range(n):
            xc[a] = tmp[a]
            srow[a] = snext[a] + abs(tmp[a])
    X_pred = np.zeros((n, Q))
    X_filt = np.zeros((n, Q))
    X_pred[:, :q0] = PG
    X_pred[:, q0:q0 + L * nw] = NwT.T
    X_filt[:, :q0] = PG_f
    X_filt[:, q0:q0 + L * nw] = NwT_f.T
    # every bound below is a sum of products of nonnegative floating numbers, at most `depth` operations from each
    # leaf to the root: rounded to nearest it is >= (1 - u)^depth times its exact value (module docstring)
    depth = Q + 2 * n + L + 16
    up = 1.0 + 2.0 * depth * _U
    floor = (L + 2.0) * (n + 2.0) * (Q + 2.0) * _ETA  # the underflow of these sums' own products
    invariant = True  # a time-invariant window: one table of products serves every time (the same numbers)
    for j in range(1, L):
        for a in range(n):
            for b in range(n):
                invariant = invariant and A[j, a, b] == A[0, a, b]
            for i in range(p):
                invariant = invariant and C[j, i, a] == C[0, i, a]
    eye = np.eye(n)
    theta = 2.0 * (n + 1) * _U  # |W0 Φ| <= |P̂| + k θ |W0||A|...|A| + 1 z^T: the last two summed forward (fb, zsum)
    under = 2.0 * n * _ETA
    table_x = _product_table(eye, A, L, invariant)
    err_pred = _apply_table(table_x, delta, L)
    if not invariant:
        table_x = _product_table(eye, A, L - 1, False)
    err_filt = _apply_table(table_x, delta, L - 1)
    for a in range(n):
        err_pred[a] += theta * fb[L, a] + under * zsum[L]
        err_filt[a] += theta * fb[L - 1, a] + under * zsum[L - 1]
    err_rows = np.empty(k_meas * p)
    if invariant and k_meas:
        table_c = _product_table(C[0].copy(), A, L, True)
    for m in range(k_meas):
        j = meas_time[m]
        if not invariant:
            table_c = _product_table(C[j].copy(), A, j, False)
        prop = _apply_table(table_c, delta, j)
        for i in range(p):
            second = under * zsum[j]
            for b in range(n):
                second += theta * abs(C[j, i, b]) * fb[j, b]
            err_rows[m * p + i] = local_rows[m * p + i] + prop[i] + second
    for vec in (err_pred, err_filt, err_rows):
        for a in range(vec.shape[0]):
            vec[a] = np.nextafter(vec[a] * up + floor, np.inf)
    return xc, xf, X_pred, X_filt, Mm, r, err_rows, err_pred, err_filt


@numba.njit(cache=True)
def _product_table(W0, A, T, invariant):
    r""":math:`|\hat P_k|`, :math:`k = 0..T-1`: the backward products :math:`\hat P_k = \mathrm{fl}(\hat P_{k-1}
    A_{T-k})` from :math:`\hat P_0 = W_0` (``k`` factors :math:`A_{T-1}\cdots A_{T-k}`; module docstring,
    *Soundness*: their rounding and underflow are added by the caller).  ``invariant``: every :math:`A_j` is
    :math:`A_0` (the table then serves every :math:`T` up to its length).  Shape ``(T, r, n)``."""
    r, n = W0.shape
    table = np.empty((T, r, n))
    W = W0.copy()
    Wn = np.empty((r, n))
    At = np.empty((n, n))
    for k in range(T):
        for a in range(r):
            for b in range(n):
                table[k, a, b] = abs(W[a, b])
        if k < T - 1:  # P̂_{k+1} = P̂_k A_{T-1-k}
            At[:, :] = A[0] if invariant else A[T - 1 - k]
            for a in range(r):
                for c in range(n):
                    s = 0.0
                    for b in range(n):
                        s += W[a, b] * At[b, c]
                    Wn[a, c] = s
            W[:, :] = Wn
    return table


@numba.njit(cache=True)
def _apply_table(table, delta, T):
    r""":math:`\sum_{i<T}\mathrm{table}[T-1-i]\,\delta_i` per row (:func:`_product_table`; rounded to nearest, the
    caller's factor makes it an upper bound)."""
    r, n = table.shape[1], table.shape[2]
    acc = np.zeros(r)
    for i in range(T):
        k = T - 1 - i
        for a in range(r):
            s = 0.0
            for b in range(n):
                s += table[k, a, b] * delta[i, b]
            acc[a] += s
    return acc


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
        Bound of the objective's error (:math:`\|\hat c - c\|_1`, and its centre's; :attr:`WindowSet.mag_pred`).
    mag_rows : numpy.ndarray, shape (k,)
        Bounds of the rows' errors (:math:`\|\hat M_k - M_k\|_1 + |\hat b_k - b_k|`; :attr:`WindowSet.mag_rows`).
    kappa : float
        The factor of the evaluation's allowance (at least :math:`2(k + Q + 8)`).

    Returns
    -------
    float
        :math:`\sum_j \max(y_j\underline b_j, y_j\overline b_j) + \|c - M^\top y\|_1 + e + |y|^\top e_{\rm rows}
        + \kappa u\mu + \kappa(Q+1)\eta` (module docstring, *Soundness*).
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
        Bound of each objective's error (:func:`dual_bound`).
    mag_rows : numpy.ndarray, shape (k,)
        Bounds of the rows' errors.
    kappa : float
        The factor of the evaluation's allowance (at least :math:`2(k + Q + 8)`).

    Returns
    -------
    numpy.ndarray, shape (K,)
        Per objective, the bound of :func:`dual_bound`, rounded upward.
    """
    res = rows - y @ M
    l1 = np.abs(res).sum(axis=1)
    dual = np.maximum(y * lower, y * upper).sum(axis=1)
    ay = np.abs(y)
    err = mag_rows_obj + ay @ mag_rows  # the computed data's own errors (module docstring, *Soundness*)
    mu = (err + l1 + np.abs(dual) + np.abs(rows).sum(axis=1) + ay @ np.abs(M).sum(axis=1)
          + ay @ np.maximum(np.abs(lower), np.abs(upper)))
    floor = kappa * (M.shape[1] + 1) * _ETA  # the products' underflow
    return np.nextafter(dual + l1 + err + (kappa * _U * mu + floor), np.inf)


@dataclass(frozen=True)
class WindowHull:
    """What :func:`lp_hull_solve` found.

    Parameters
    ----------
    lower, upper : numpy.ndarray, shape (n,)
        The hull's ends, each a guarantee (rounded outward).
    fallbacks : int
        LPs that ended without an optimum (their end is still a guarantee).
    pivots : int
        Simplex pivots (and HiGHS iterations) spent on the ``2n`` LPs.
    basis : tuple of numpy.ndarray of bool or None
        ``(is_basic, at_upper)`` over the LP's columns, then its rows' slacks, after the last objective (a start for
        the next window: :func:`carry_basis`); ``None`` when HiGHS solved them or there were no rows.
    minima_first : bool
        The order the objectives were solved in: the minima first (the last objective a maximum), or the maxima.
    warm : bool
        Whether the given start was used.
    """

    lower: np.ndarray
    upper: np.ndarray
    fallbacks: int
    pivots: int
    basis: "tuple[np.ndarray, np.ndarray] | None"
    minima_first: bool
    warm: bool


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
    res = lp_hull_solve(ws, which, solver)
    return res.lower, res.upper, res.fallbacks


def lp_hull_solve(ws: WindowSet, which: str = "pred", solver: str = "auto",
                  start: "tuple[np.ndarray, np.ndarray] | None" = None, minima_first: bool = False) -> WindowHull:
    r""":func:`lp_hull` from a given basis, in a given order, with the pivots and the final basis.

    Parameters
    ----------
    ws : WindowSet
        The set.
    which : {"pred", "filt"}
        The hull of :math:`x(t+1)` or of :math:`x(t)`.
    solver : str, optional
        As :func:`lp_hull`.
    start : tuple of numpy.ndarray of bool, optional
        ``(wanted, at_upper)`` over the LP's columns, then its rows' slacks: the first objective's start basis
        (:func:`eqrec.lp.box_simplex.box_lp_solve`; any start gives guaranteed ends, a poor one costs pivots);
        ``None``: the slack basis.
    minima_first : bool, optional
        ``False`` (default): the maxima of the states in order, then the minima in reverse (ends with the minimum
        of the first state); ``True``: the minima in order, then the maxima in reverse (ends with its maximum).
        Each objective starts from the basis of the one before, and neighbouring states share more of their
        optimal vertex than a state's maximum and minimum do; alternating the order from one window to the next
        makes a window's first objective the previous window's last.

    Returns
    -------
    WindowHull
        The ends, the fallbacks, the pivots and the final basis.
    """
    centre, X, mag = (ws.centre_pred, ws.X_pred, ws.mag_pred) if which == "pred" else \
        (ws.centre_filt, ws.X_filt, ws.mag_filt)
    n, Q = X.shape
    k = ws.M.shape[0]
    hi = np.empty(n)
    lo = np.empty(n)
    fallbacks = pivots = 0
    basis, warm = None, False
    if k == 0:  # no constraint: the zonotope's own hull
        for i in range(n):
            hi[i] = dual_bound(X[i], ws.M, ws.lower, ws.upper, np.zeros(0), mag[i], ws.mag_rows, ws.kappa)
        lo[:] = -hi
    else:
        sign = -1.0 if minima_first else 1.0
        objectives = np.concatenate([sign * X, -sign * X[::-1]])
        ones = np.ones(Q)
        res = box_lp_solve(ws.M, ws.lower, ws.upper, -ones, ones, objectives, solver, start=start)
        fallbacks = int(np.count_nonzero(~res.optimal))
        pivots, warm = res.pivots, res.warm
        if res.is_basic is not None:
            basis = (res.is_basic, res.at_upper)
        bounds = bounds_from_multipliers(objectives, ws.M, ws.lower, ws.upper, res.y,
                                         np.concatenate([mag, mag[::-1]]), ws.mag_rows, ws.kappa)
        first, second = bounds[:n], bounds[n:][::-1]
        hi[:], lo[:] = (second, -first) if minima_first else (first, -second)
    upper = np.nextafter(centre + hi + 2 * _U * (np.abs(centre) + np.abs(hi)), np.inf)
    lower = np.nextafter(centre + lo - 2 * _U * (np.abs(centre) + np.abs(lo)), -np.inf)
    return WindowHull(lower, upper, fallbacks, pivots, basis, minima_first, warm)


def window_labels(first: int, measured: np.ndarray, p: int, nw: int, nv: int, q0: int,
                  k_prior: int) -> tuple[np.ndarray, np.ndarray]:
    """Labels of the columns and rows of :func:`window_set`'s LP that name the same quantity in every window (the
    prior's: the same place).

    Parameters
    ----------
    first : int
        Absolute time of the window's first step.
    measured : numpy.ndarray of bool, shape (L,)
        Which times' outputs are in the rows.
    p, nw, nv : int
        Outputs, process noises, measurement noises per time.
    q0 : int
        The prior's generators (its columns come first).
    k_prior : int
        The prior's rows (they come first).

    Returns
    -------
    columns : numpy.ndarray of int64, shape (Q,)
        ``w_a(s)``: ``s (nw + nv) + a``; ``v_b(s)``: ``s (nw + nv) + nw + b``; the prior's ``c``-th generator:
        ``-1 - c`` (a different vector in every window, but the filter's reduction keeps its generators in an
        order that changes little from one step to the next, so its basis status is a good guess: two carts,
        window 50, 13 % fewer pivots per step than with the prior's columns new and nonbasic).
    rows : numpy.ndarray of int64, shape (k_prior + p · #measured,)
        ``y_i(s)``: ``s p + i``; the prior's ``i``-th row: ``-1 - i``.
    """
    return _labels_kernel(int(first), np.require(measured, np.bool_, ("C",)), int(p), int(nw), int(nv), int(q0),
                          int(k_prior))


@numba.njit(cache=True)
def _labels_kernel(first, measured, p, nw, nv, q0, k_prior):
    """:func:`window_labels` (compiled)."""
    L = measured.shape[0]
    k_meas = 0
    for j in range(L):
        k_meas += measured[j]
    stride = nw + nv
    columns = np.full(q0 + L * nw + k_meas * nv, NO_LABEL, np.int64)
    rows = np.full(k_prior + k_meas * p, NO_LABEL, np.int64)
    for c in range(q0):  # the prior's generators and rows by their index (negative: never a noise's or output's)
        columns[c] = -1 - c
    for r in range(k_prior):
        rows[r] = -1 - r
    c, r = q0, k_prior
    for j in range(L):
        for a in range(nw):
            columns[c] = (first + j) * stride + a
            c += 1
    for j in range(L):
        if measured[j]:
            for b in range(nv):
                columns[c] = (first + j) * stride + nw + b
                c += 1
            for i in range(p):
                rows[r] = (first + j) * p + i
                r += 1
    return columns, rows


def carry_basis(old_labels: "tuple[np.ndarray, np.ndarray]", old_basis: "tuple[np.ndarray, np.ndarray]",
                new_labels: "tuple[np.ndarray, np.ndarray]") -> tuple[np.ndarray, np.ndarray]:
    """A start for the next window's LP from the last basis of the previous window's (:func:`lp_hull_solve`).

    A column or row with the same label keeps its status (basic, or nonbasic at its upper or lower bound; the
    prior's columns and rows that of the previous prior's in the same place, :func:`window_labels`); a column new
    to the window is nonbasic at its lower bound; a row new to the window (a packet that arrived) has its slack
    basic.  The solver completes the wanted set to a nonsingular basis
    (:func:`eqrec.lp.box_simplex.box_lp_solve`, ``start``); any start gives guaranteed ends.

    Parameters
    ----------
    old_labels : tuple of numpy.ndarray of int64
        ``(columns, rows)`` of the previous LP (:func:`window_labels`).
    old_basis : tuple of numpy.ndarray of bool
        ``(is_basic, at_upper)`` of the previous LP (its columns, then its rows' slacks).
    new_labels : tuple of numpy.ndarray of int64
        ``(columns, rows)`` of the new LP.

    Returns
    -------
    tuple of numpy.ndarray of bool
        ``(wanted, at_upper)`` over the new LP's columns, then its rows' slacks.
    """
    (oc, orow), (nc, nrow) = old_labels, new_labels
    basic, upper = old_basis
    return _carry_kernel(oc, orow, basic, upper, nc, nrow)


@numba.njit(cache=True)
def _carry_kernel(oc, orow, basic, upper, nc, nrow):
    """:func:`carry_basis` (compiled): a column or row keeps the status of the old one with its label; a new
    column is nonbasic at its lower bound, a new row's slack basic; :data:`NO_LABEL` is never matched."""
    Qo, Qn = oc.shape[0], nc.shape[0]
    want = np.zeros(Qn + nrow.shape[0], np.bool_)
    up = np.zeros(Qn + nrow.shape[0], np.bool_)
    for block in range(2):
        old = oc if block == 0 else orow
        new = nc if block == 0 else nrow
        off_o = 0 if block == 0 else Qo
        off_n = 0 if block == 0 else Qn
        order = np.argsort(old)
        srt = old[order]
        for i in range(new.shape[0]):
            lab = new[i]
            found = -1
            if lab != NO_LABEL and srt.shape[0]:
                at = np.searchsorted(srt, lab)
                if at < srt.shape[0] and srt[at] == lab:
                    found = order[at]
            if found >= 0:
                want[off_n + i] = basic[off_o + found]
                up[off_n + i] = upper[off_o + found]
            elif block == 1:  # a row new to the window (or the prior's): its slack basic
                want[off_n + i] = True
    return want, up
