"""The steady state of the LMV recursion (the limits of Theorems 1-3) and the sweeps built on it.

:func:`steady_state` iterates :func:`eqrec.lmv.recursion.lmv_step` and the smoother lags of
:func:`eqrec.lmv.recursion.smoother_step` to their limits; :func:`steady_variances` gives the steady
prediction, filter and smoother variances of one plant, mechanism and ``eta_bar`` (the project's
Figs. 5-6 sweeps); :func:`qlam_threshold` finds where the zero- and hold-input filters cross in
``Q_lambda``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.errors import NotMeanSquareStable, SolverFailure
from eqrec.lmv.plant import Plant
from eqrec.lmv.model import MultNoiseSystem, check_ms_stable, second_moment_operator, system_of
from eqrec.lmv.recursion import lmv_step, smoother_step, symmetric_part

__all__ = ["SteadyState", "steady_state", "steady_variances", "qlam_threshold"]


@dataclass
class SteadyState:
    """Limits of the recursion: ``q``, ``P(t+1|t)``, ``P(t|t)``, ``P(t|t+j)`` (``j = 1..N``), gains.

    Parameters
    ----------
    q, P_pred, P_filt : numpy.ndarray
        Limits of ``q(t)``, ``P(t+1|t)``, ``P(t|t)``, ``(n, n)``.
    P_smooth : numpy.ndarray
        Limits of ``P(t|t+j)``, ``j = 1..N``, ``(N, n, n)``.
    L, Qe : numpy.ndarray
        Limiting gain ``(n, m)`` and innovation covariance ``(m, m)``.
    iterations : int
        Iterations of eq. (9) until convergence.
    rho : float
        Spectral radius of the second-moment operator (:func:`~eqrec.lmv.model.ms_spectral_radius`).
    """

    q: np.ndarray
    P_pred: np.ndarray
    P_filt: np.ndarray
    P_smooth: np.ndarray
    L: np.ndarray
    Qe: np.ndarray
    iterations: int
    rho: float


def steady_state(sys: MultNoiseSystem, N_smooth: int = 1, tol: float = 1e-12,
                 max_iter: int = 100_000) -> SteadyState:
    """Iterate the Riccati-like recursion (8)-(9) to convergence.

    Raises :class:`NotMeanSquareStable` if ``q`` cannot converge and
    :class:`~eqrec.errors.SolverFailure` if ``P`` has not converged (relative
    change ``< tol``) within ``max_iter`` iterations.  Filter and smoother
    limits follow from Theorem 3 with the limiting ``P``, ``L``, ``Qe``.

    Parameters
    ----------
    sys : MultNoiseSystem
        The system in the common description.
    N_smooth : int, optional
        Largest smoothing lag (default 1).
    tol : float, optional
        Relative change of ``P`` at convergence (default ``1e-12``).
    max_iter : int, optional
        Iteration limit (default 100000).

    Returns
    -------
    SteadyState
        The limits; ``q`` solves the linear fixed-point equation of eq. (8) directly.
    """
    rho = check_ms_stable(sys)
    # q converges geometrically; its limit solves a linear (Lyapunov-like) equation.
    n = sys.n
    Top = second_moment_operator(sys)
    q = np.linalg.solve(np.eye(n * n) - Top, sys.Qu.reshape(-1, order="F")).reshape(n, n, order="F")
    q = symmetric_part(q)
    P = sys.x0_cov.copy()
    for it in range(1, max_iter + 1):
        Pn = lmv_step(sys, P, q)[2]
        done = np.max(np.abs(Pn - P)) <= tol * max(1.0, np.max(np.abs(Pn)))
        P = Pn
        if done:
            break
    else:
        raise SolverFailure(f"{sys.name}: P(t+1|t) did not converge in {max_iter} iterations")
    Qe, L, _ = lmv_step(sys, P, q)
    M, Pj, Ps = P.copy(), P.copy(), []
    F = sys.A - L @ sys.C
    for _ in range(N_smooth + 1):
        _, Pj, M = smoother_step(sys, M, Pj, Qe, F)
        Ps.append(Pj)
    return SteadyState(q, P, Ps[0], np.array(Ps[1:]).reshape(N_smooth, n, n), L, Qe, it, rho)


def steady_variances(plant: Plant, mechanism: str, eta_bar: float, N: int, tol: float,
                     max_iter: int) -> dict[str, np.ndarray]:
    """Steady-state error variances of the plant state under one compensation mechanism (Figs. 5-6).

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    mechanism : str
        ``"zero-input"`` or ``"hold-input"`` (:func:`~eqrec.lmv.model.system_of`).
    eta_bar : float
        Arrival probability.
    N : int
        Smoothing lag (``N >= 1``) of the ``smooth`` entry.
    tol, max_iter : float, int
        Convergence of :func:`steady_state`.

    Returns
    -------
    dict of str to numpy.ndarray
        ``pred``, ``filt``, ``smooth``: the diagonals of the limits of ``P(t+1|t)``, ``P(t|t)`` (Theorem 3,
        eq. (20) with ``j = 0``) and ``P(t|t+N)`` on the plant's ``n`` components (NaN when the system is not
        mean-square stable); ``stable``: a boolean 0-d array.
    """
    nan = np.full(plant.n, np.nan)
    try:
        ss = steady_state(system_of(plant, mechanism, eta_bar), N, tol, max_iter)
    except NotMeanSquareStable:
        return {"pred": nan, "filt": nan, "smooth": nan, "stable": np.array(False)}
    n = plant.n
    return {"pred": np.diag(ss.P_pred)[:n], "filt": np.diag(ss.P_filt)[:n],
            "smooth": np.diag(ss.P_smooth[N - 1])[:n], "stable": np.array(True)}


def qlam_threshold(plant: Plant, eta_bar: float, N: int, tol: float, max_iter: int) -> dict:
    """``Q_lambda`` at which the steady filter-variance traces of both mechanisms are equal (at the plant's
    ``Q_xi``), by Brent's method on ``[0, max(2 Q_lambda, 4)]`` (the crossing in Fig. 6).

    Parameters
    ----------
    plant : Plant
        The plant; its ``Qlam`` is varied, ``Qxi`` kept.
    eta_bar : float
        Arrival probability.
    N : int
        Smoothing lag passed to :func:`steady_variances`.
    tol, max_iter : float, int
        Convergence of :func:`steady_state`.

    Returns
    -------
    dict
        ``Qxi``; the bracket ``lo``, ``hi``; ``root`` (``None`` when one mechanism is lower on the whole
        bracket); ``below``, the mechanism with the lower trace at ``Q_lambda = lo``, and ``above`` the other
        (lower beyond the root).
    """
    from scipy.optimize import brentq

    def diff(ql: float) -> float:
        p = plant.with_(Qlam=ql)
        return float(steady_variances(p, "hold-input", eta_bar, N, tol, max_iter)["filt"].sum()
                     - steady_variances(p, "zero-input", eta_bar, N, tol, max_iter)["filt"].sum())
    lo, hi = 0.0, max(2.0 * plant.Qlam, 4.0)
    dlo, dhi = diff(lo), diff(hi)
    below = "hold-input" if dlo < 0 else "zero-input"
    above = "zero-input" if below == "hold-input" else "hold-input"
    root = None if np.sign(dlo) == np.sign(dhi) else float(brentq(diff, lo, hi, xtol=1e-6))
    return {"Qxi": plant.Qxi, "lo": lo, "hi": hi, "root": root, "below": below, "above": above}
