r"""Linear minimum-variance (LMV) estimation for systems with multiplicative noises: the recursion
(the steady state is :mod:`eqrec.lmv.steady`).

It runs on the common description :class:`~eqrec.lmv.model.MultNoiseSystem` (see
:mod:`eqrec.lmv.model` for the model and the two compensation mechanisms).

The recursion (general form of Theorem 1, eqs. (4)-(9))::

    q(t+1)   = A q A^T + sum_kl W_kl A_k q A_l^T + Qu                     (8)
    Qe(t)    = C P C^T + sum_kl W_kl C_k q C_l^T + R                       (7)
    L(t)     = (A P C^T + sum_kl W_kl A_k q C_l^T + S) Qe^{-1}             (6)
    xh(t+1|t)= A xh(t|t-1) + L(t) (y(t) - C xh(t|t-1))                     (4),(5)
    P(t+1|t) = A P A^T + sum_kl W_kl A_k q A_l^T + Qu - L Qe L^T           (9)

with ``P = P(t|t-1)``, ``q = q(t) = E[x(t) x(t)^T]`` (raw second moment: the
multiplicative terms see the whole state, not the error).  The N-step
predictor (Theorem 2) is ``xh(t+N|t) = A xh(t+N-1|t)``,
``P(t+N|t) = A P(t+N-1|t) A^T + sum W_kl A_k q(t+N-1) A_l^T + Qu``.  The
filter and N-step smoother (Theorem 3, eqs. (17)-(20))::

    xh(t|t+j) = xh(t|t+j-1) + K(t,j) e(t+j),   K(t,j) = M(t,j) C^T Qe(t+j)^{-1}
    M(t,0)    = P(t|t-1),   M(t,j+1) = M(t,j) (A - L(t+j) C)^T
    P(t|t+j)  = P(t|t+j-1) - K(t,j) Qe(t+j) K(t,j)^T

Findings about the printed formulas (checked by Monte Carlo in the tests and
in ``results/p4/``):

* eq. (9) as printed carries the factor ``eta_bar (1 - eta_bar) Q_lambda`` in
  front of ``L H_1 q H_1^T L^T``; the term comes from ``eta(t) lambda(t)``, whose
  variance is ``E[eta^2] Q_lambda = eta_bar Q_lambda`` (as eq. (7) correctly
  has).  The printed factor under-states the prediction error variance;
  :func:`theorem1_as_printed` reproduces the printed recursion so that the
  discrepancy can be measured.
* eq. (14) (and (23)) print ``+ eta lambda L H x`` where ``- eta lambda L H_1 x``
  is meant, and ``+ (eta - eta_bar) L H x`` for ``- (eta - eta_bar) L H x``:
  sign/index misprints that do not change second moments.
* eq. (15) prints ``Phi xh(t+N|t-1)``; the predictor is
  ``xh(t+N|t) = Phi xh(t+N-1|t)`` (index misprint).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.errors import InputError
from eqrec.lmv.plant import Plant
from eqrec.lmv.model import MultNoiseSystem, check_eta, check_ms_stable, multiplicative_term


__all__ = [
    "LMVResult", "SmootherResult", "lmv_recursion", "filter_smoother", "n_step_predictor",
    "suboptimal_error_cov", "theorem1_as_printed", "lmv_step", "smoother_step",
    "symmetric_part",
]


def symmetric_part(X: np.ndarray) -> np.ndarray:
    """The symmetric part ``(X + X^T) / 2`` of a matrix or a stack of matrices.

    Parameters
    ----------
    X : numpy.ndarray
        Shape ``(..., n, n)``.

    Returns
    -------
    numpy.ndarray
        ``(X + X^T) / 2``, transposing the last two axes.
    """
    return 0.5 * (X + np.swapaxes(X, -1, -2))


def _propagate(sys: MultNoiseSystem, X: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``A X A^T + sum_kl W_kl A_k q A_l^T + Qu``: eq. (8) with ``X = q``, eq. (16) with ``X = P(t+N-1|t)``,
    eq. (9) before its gain term (not symmetrised)."""
    return sys.A @ X @ sys.A.T + sys.mult_A(q) + sys.Qu


def lmv_step(sys: MultNoiseSystem, P: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One step of the Riccati-like recursion of Theorem 1 (general form), shared by
    :func:`lmv_recursion` and :func:`eqrec.lmv.steady.steady_state`.

    Parameters
    ----------
    sys : MultNoiseSystem
        The system in the common description.
    P : numpy.ndarray
        ``P(t|t-1)``, shape ``(n, n)``.
    q : numpy.ndarray
        ``q(t) = E[x(t) x(t)^T]``, shape ``(n, n)``.

    Returns
    -------
    Qe : numpy.ndarray
        Innovation covariance ``Qe(t)``, eq. (7), shape ``(m, m)``.
    L : numpy.ndarray
        Gain ``L(t)``, eq. (6), shape ``(n, m)``.
    P_next : numpy.ndarray
        ``P(t+1|t)``, eq. (9) (with the derived factor ``eta_bar Q_lambda``), shape ``(n, n)``.
    """
    Qe = symmetric_part(sys.C @ P @ sys.C.T + sys.mult_C(q) + sys.R)                                     # (7)
    L = np.linalg.solve(Qe.T, (sys.A @ P @ sys.C.T + sys.mult_AC(q) + sys.S).T).T              # (6)
    return Qe, L, symmetric_part(_propagate(sys, P, q) - L @ Qe @ L.T)                                    # (9)


def moment_step(sys: MultNoiseSystem, q: np.ndarray) -> np.ndarray:
    """The second moment one step on, ``q(t+1)`` from ``q(t)``, eq. (8) (shared by the recursions and
    :class:`eqrec.lmv.estimator.LMVEstimator`).

    Parameters
    ----------
    sys : MultNoiseSystem
        The system in the common description.
    q : numpy.ndarray
        ``q(t) = E[x(t) x(t)^T]``, shape ``(n, n)``.

    Returns
    -------
    numpy.ndarray
        ``q(t+1)``, eq. (8), shape ``(n, n)``.
    """
    return symmetric_part(_propagate(sys, q, q))


def smoother_step(sys: MultNoiseSystem, M: np.ndarray, Pj: np.ndarray, Qe: np.ndarray,
                  F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One lag of the smoother, Theorem 3, eqs. (17)-(20), shared by :func:`filter_smoother` and
    :func:`eqrec.lmv.steady.steady_state`.

    Parameters
    ----------
    sys : MultNoiseSystem
        The system in the common description.
    M : numpy.ndarray
        ``M(t,j)``, shape ``(n, n)``.
    Pj : numpy.ndarray
        ``P(t|t+j-1)``, shape ``(n, n)``.
    Qe : numpy.ndarray
        ``Qe(t+j)``, shape ``(m, m)``.
    F : numpy.ndarray
        ``A - L(t+j) C``, shape ``(n, n)``.

    Returns
    -------
    K : numpy.ndarray
        The gain ``K(t,j) = M(t,j) C^T Qe(t+j)^{-1}``, shape ``(n, m)``.
    P : numpy.ndarray
        ``P(t|t+j)``, shape ``(n, n)``.
    M_next : numpy.ndarray
        ``M(t,j+1) = M(t,j) F^T``, shape ``(n, n)``.
    """
    K = np.linalg.solve(Qe.T, (M @ sys.C.T).T).T
    return K, symmetric_part(Pj - K @ Qe @ K.T), M @ F.T


def _histories(T: int, n: int, m: int, x0_mean: np.ndarray,
               x0_cov: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The arrays of Theorem 1 over ``t = 0..T`` with its initial values: ``q`` and ``P`` (``T+2`` entries,
    ``q(0) = E x(0) E x(0)^T + Cov x(0)``, ``P(0|-1) = Cov x(0)``), ``L`` and ``Qe`` (``T+1``, to fill)."""
    q = np.empty((T + 2, n, n))
    P = np.empty((T + 2, n, n))
    q[0] = np.outer(x0_mean, x0_mean) + x0_cov
    P[0] = x0_cov
    return q, P, np.empty((T + 1, n, m)), np.empty((T + 1, m, m))


@dataclass
class LMVResult:
    """Output of :func:`lmv_recursion` over ``t = 0..T`` (``T+1`` instants).

    Parameters
    ----------
    sys : MultNoiseSystem
        The system the recursion ran on.
    q, P_pred : numpy.ndarray
        ``q[t] = E[x(t) x(t)^T]``, eq. (8); ``P_pred[t] = P(t|t-1)``, eq. (9); ``(T+2, n, n)`` (last: ``T+1``).
    L, Qe : numpy.ndarray
        Gain ``L[t]``, eq. (6), ``(T+1, n, m)``; innovation covariance ``Qe[t]``, eq. (7), ``(T+1, m, m)``.
    """

    sys: MultNoiseSystem
    q: np.ndarray
    P_pred: np.ndarray
    L: np.ndarray
    Qe: np.ndarray

    @property
    def T(self) -> int:
        """Last measurement time ``T``."""
        return self.L.shape[0] - 1


def lmv_recursion(sys: MultNoiseSystem, T: int, check_stability: bool = True) -> LMVResult:
    """One-step LMV predictor, general form of Theorem 1 (eqs. (4)-(9)).

    Initial values ``xh(0|-1) = E[x(0)]``, ``P(0|-1) = Cov x(0)``,
    ``q(0) = E x(0) E x(0)^T + Cov x(0)`` as in Theorem 1.

    Parameters
    ----------
    sys : MultNoiseSystem
        The system in the common description.
    T : int
        Last measurement time; gains for ``t = 0..T``.
    check_stability : bool, optional
        Raise :class:`NotMeanSquareStable` unless mean-square stable (finite anyway on a finite horizon).

    Returns
    -------
    LMVResult
        ``q``, ``P(t|t-1)``, ``L``, ``Qe`` over the horizon.
    """
    if int(T) != T or T < 0:
        raise InputError(f"horizon must be a non-negative integer, got {T}", None, "T")
    T = int(T)
    if check_stability:
        check_ms_stable(sys)
    q, P, L, Qe = _histories(T, sys.n, sys.m, sys.x0_mean, sys.x0_cov)
    for t in range(T + 1):
        Qe[t], L[t], P[t + 1] = lmv_step(sys, P[t], q[t])
        q[t + 1] = moment_step(sys, q[t])
    return LMVResult(sys, q, P, L, Qe)


@dataclass
class SmootherResult:
    """Filter (``j = 0``) and fixed-lag smoothers ``j = 1..N`` (Theorem 3); NaN where ``t + j > T``.

    Parameters
    ----------
    K : numpy.ndarray
        ``K[t, j]``, gain of ``e(t+j)`` in ``xh(t|t+j)``, eq. (18); ``(T+1, N+1, n, m)``.
    P : numpy.ndarray
        ``P[t, j] = P(t|t+j)``, eq. (20); ``(T+1, N+1, n, n)``.
    """

    K: np.ndarray
    P: np.ndarray

    @property
    def P_filt(self) -> np.ndarray:
        """Filter error covariances ``P(t|t)``, ``(T+1, n, n)``."""
        return self.P[:, 0]


def filter_smoother(res: LMVResult, N: int) -> SmootherResult:
    """Filter and ``N``-step smoother, Theorem 3, eqs. (17)-(20), general form.

    Parameters
    ----------
    res : LMVResult
        The one-step predictor, Theorem 1.
    N : int
        Largest lag ``N >= 0`` (``0``: the filter only).

    Returns
    -------
    SmootherResult
        Gains and covariances for ``t = 0..T``, ``j = 0..N``.
    """
    if int(N) != N or N < 0:
        raise InputError(f"smoothing lag must be a non-negative integer, got {N}", None, "N")
    sys, T = res.sys, res.T
    n, m = sys.n, sys.m
    K = np.full((T + 1, N + 1, n, m), np.nan)
    P = np.full((T + 1, N + 1, n, n), np.nan)
    for t in range(T + 1):
        M = res.P_pred[t].copy()
        Pj = res.P_pred[t].copy()
        for j in range(min(N, T - t) + 1):
            s = t + j
            K[t, j], Pj, M = smoother_step(sys, M, Pj, res.Qe[s], sys.A - res.L[s] @ sys.C)
            P[t, j] = Pj
    return SmootherResult(K, P)


def n_step_predictor(res: LMVResult, N: int) -> np.ndarray:
    """Covariances ``P(t+N|t)`` for ``t = 0..T`` (Theorem 2, eq. (16), general form).

    Needs ``q`` up to ``t+N-1``, which is extended here beyond the horizon of ``res`` by eq. (8).

    Parameters
    ----------
    res : LMVResult
        The one-step predictor, Theorem 1.
    N : int
        Prediction steps, ``N >= 1`` (``1``: the one-step predictor).

    Returns
    -------
    numpy.ndarray
        ``Pn[t] = P(t+N|t)``, ``(T+1, n, n)``.
    """
    if int(N) != N or N < 1:
        raise InputError(f"prediction horizon must be an integer >= 1, got {N}", None, "N")
    sys, T = res.sys, res.T
    q = list(res.q)
    while len(q) < T + N + 1:
        q.append(moment_step(sys, q[-1]))
    out = np.empty((T + 1, sys.n, sys.n))
    for t in range(T + 1):
        Pk = res.P_pred[t + 1]
        for k in range(2, N + 1):
            Pk = symmetric_part(_propagate(sys, Pk, q[t + k - 1]))
        out[t] = Pk
    return out


def suboptimal_error_cov(sys: MultNoiseSystem, L: np.ndarray, q: np.ndarray) -> np.ndarray:
    r"""True one-step prediction error covariance of ``xh(t+1) = A xh + L(t)(y - C xh)`` for *any* gains.

    Joseph form: with ``xt = x - xh``,
    ``xt(t+1) = (A - L C) xt + sum_k a_k (A_k - L C_k) x + u - L r``, so::

        P(t+1) = (A - LC) P (A - LC)^T + sum W_kl (A_k - L C_k) q (A_l - L C_l)^T
                 + Qu - L S^T - S L^T + L R L^T.

    Used to measure what an estimator with the gains of the *printed*
    Theorem 1 really achieves.

    Parameters
    ----------
    sys : MultNoiseSystem
        The system; ``P(0) = Cov x(0)``.
    L : numpy.ndarray
        The gains ``L(t)``, ``t = 0..T``, ``(T+1, n, m)``.
    q : numpy.ndarray
        ``E[x(t) x(t)^T]`` for ``t = 0..T`` (or longer), ``(T+1, n, n)``.

    Returns
    -------
    numpy.ndarray
        ``P(t|t-1)`` for ``t = 0..T+1``, ``(T+2, n, n)``.
    """
    T = L.shape[0] - 1
    P = np.empty((T + 2, sys.n, sys.n))
    P[0] = sys.x0_cov
    for t in range(T + 1):
        Lt = L[t]
        F = sys.A - Lt @ sys.C
        Bk = sys.Ak - np.einsum("ij,kjh->kih", Lt, sys.Ck)
        mult = multiplicative_term(sys.W, Bk, q[t], Bk)
        P[t + 1] = symmetric_part(F @ P[t] @ F.T + mult + sys.Qu - Lt @ sys.S.T - sys.S @ Lt.T + Lt @ sys.R @ Lt.T)
    return P


def theorem1_as_printed(plant: Plant, eta_bar: float, T: int) -> dict[str, np.ndarray]:
    """Theorem 1 exactly as printed, eqs. (6)-(9), including the factor of eq. (9).

    The only difference from the zero-input instance of
    :func:`lmv_recursion` is the factor ``eta_bar (1 - eta_bar) Q_lambda``
    (printed) instead of ``eta_bar Q_lambda`` (derived) in eq. (9).

    Written out term by term as printed, not through :func:`lmv_step` and the
    Joseph form of :func:`suboptimal_error_cov` (which give the same numbers up to
    rounding): the stored P4 results of the printed theorem come from this
    arithmetic, to the last bit.

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    eta_bar : float
        Arrival probability.
    T : int
        Last measurement time.

    Returns
    -------
    dict of str to numpy.ndarray
        ``q``, ``P`` (``P[t] = P_z(t|t-1)`` as the paper would report it), ``L``, ``Qe``, shaped as in
        :class:`LMVResult`.
    """
    eb = check_eta(eta_bar)
    Phi, Phi1, G, H, H1 = plant.Phi, plant.Phi1, plant.Gamma, plant.H, plant.H1
    q, P, L, Qe = _histories(T, plant.n, plant.m, plant.sigma0, plant.Sigma0)
    GQG = G @ plant.Qw @ G.T
    for t in range(T + 1):
        qt, Pt = q[t], P[t]
        Qe[t] = (eb * (1 - eb) * H @ qt @ H.T + eb * plant.Qv + eb ** 2 * H @ Pt @ H.T
                 + eb * plant.Qlam * H1 @ qt @ H1.T)                                          # (7)
        Lt = eb * (Phi @ Pt @ H.T + G @ plant.S) @ np.linalg.inv(Qe[t])                        # (6)
        q[t + 1] = Phi @ qt @ Phi.T + plant.Qxi * Phi1 @ qt @ Phi1.T + GQG                      # (8)
        F = Phi - eb * Lt @ H
        P[t + 1] = (F @ Pt @ F.T + plant.Qxi * Phi1 @ qt @ Phi1.T                               # (9)
                    + eb * (1 - eb) * Lt @ H @ qt @ H.T @ Lt.T
                    + eb * (1 - eb) * plant.Qlam * Lt @ H1 @ qt @ H1.T @ Lt.T
                    + eb * Lt @ plant.Qv @ Lt.T + GQG
                    - eb * Lt @ plant.S.T @ G.T - eb * G @ plant.S @ Lt.T)
        L[t] = Lt
    return {"q": q, "P": P, "L": L, "Qe": Qe}
